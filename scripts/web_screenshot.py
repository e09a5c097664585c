"""The picture of the teaching page in docs/web.md and the README: a real ``teach --web`` session, mid-question.

    python scripts/web_screenshot.py docs/img/web-teach.png     # answers by clicks until a "show me" question

The session (seed 0, dt-task) is answered in headless Chromium by clicks until the
first "show me" question is open; the page is then photographed as it is.
"""

from __future__ import annotations

import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from bullet_world.viewer.snapshot import CHROMIUM_FLAGS, find_chromium

TEACHBOT = str(Path(sys.executable).with_name("teachbot"))


def main(argv=None) -> int:
    out = Path((argv or sys.argv[1:] or ["docs/img/web-teach.png"])[0]).resolve()
    from playwright.sync_api import sync_playwright

    with tempfile.TemporaryDirectory(prefix="teachbot-web-shot-") as folder:
        process = subprocess.Popen([TEACHBOT, "teach", "--web", "--seed", "0", "--turns", "30", "--transcript",
                                    "runs/shot.jsonl"], cwd=folder, stdout=subprocess.PIPE, text=True)
        try:
            url = next(m.group(1) for line in process.stdout if (m := re.search(r"Open the page: (\S+)", line)))
            with sync_playwright() as driver:
                browser = driver.chromium.launch(executable_path=find_chromium(), args=list(CHROMIUM_FLAGS))
                page = browser.new_page(viewport={"width": 1400, "height": 1040})
                page.goto(url)
                while True:
                    page.wait_for_function("() => question && waiting", timeout=120_000)
                    question = page.evaluate("() => question")
                    if question["expects"] == "demo":
                        break
                    if question["expects"] == "label":
                        page.locator("#answers button").nth(question["turn"] % 4).click()
                    else:
                        for number in ("1.1", "1.2", "1.5"):
                            page.locator(f"#features input[data-number='{number}']").check()
                        page.get_by_role("button", name="use these").click()
                    page.wait_for_function("(id) => question && question.id !== id", arg=question["id"])
                page.wait_for_function("() => document.getElementById('picture').complete")
                time.sleep(2.0)  # the 3D view settles
                out.parent.mkdir(parents=True, exist_ok=True)
                page.screenshot(path=str(out), full_page=True)
                print(f"{out}: turn {question['turn']}, {question['text']}")
                browser.close()
        finally:
            process.kill()
            process.wait()
    return 0


if __name__ == "__main__":
    if find_chromium() is None:
        raise SystemExit("no Chromium found: apt-get install -y chromium")
    sys.exit(main())
