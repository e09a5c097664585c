"""The pictures of docs/studies.md's pilot walk-through: a real ``study run --web`` of the example study.

    python scripts/study_screenshots.py docs/img      # writes docs/img/study-*.png

Participant P01 of dialog/data/studies/example.toml (records in a temporary folder) is played in headless
Chromium by clicks, as tests/e2e/test_web_study.py plays it; each kind of screen is photographed the first time
it opens: the consent, the practice round's instructions, a question of each kind, the quit confirmation, the
questionnaire, the break between sessions and the end.
"""

from __future__ import annotations

import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from bullet_world.viewer.snapshot import CHROMIUM_FLAGS, find_chromium

ROOT = Path(__file__).resolve().parents[1]
TEACHBOT = str(Path(sys.executable).with_name("teachbot"))
STUDY = ROOT / "dialog/data/studies/example.toml"
SCREENS = {"Before we begin": "consent", "Practice round": "practice", "Session 1 of 3": "instructions",
           "A few questions about this session": "questionnaire", "A short break": "break"}
READY = """() => ended || (question && waiting && document.getElementById('screen').hidden)
    || (!document.getElementById('screen').hidden && !document.querySelector('#screen form > button').disabled)"""


def shoot(page, folder: Path, name: str, taken: set) -> None:
    if name in taken:
        return
    taken.add(name)
    time.sleep(0.5 if name not in ("label", "demo", "feature") else 2.0)  # the 3D view settles
    path = folder / f"study-{name}.png"
    page.screenshot(path=str(path), full_page=True)
    print(path)


def play(page, folder: Path) -> None:
    taken: set[str] = set()
    answered = 0
    while True:
        page.wait_for_function(READY, timeout=180_000)
        if page.evaluate("() => ended"):
            shoot(page, folder, "end", taken)
            return
        if not page.locator("#screen").is_hidden():
            title = page.inner_text("#screen h2")
            if title in SCREENS:
                shoot(page, folder, SCREENS[title], taken)
            for group in page.locator("#screen fieldset").all():
                radios = group.locator("input[type=radio]")
                if radios.count():
                    radios.nth(radios.count() - 2).check()
            page.locator("#screen form > button").first.click()
            continue
        question = page.evaluate("() => question")
        if question["expects"] == "demo":
            page.wait_for_function("() => document.getElementById('picture').complete")
        shoot(page, folder, question["expects"], taken)
        if "quit" not in taken:
            page.mouse.click(5, 5)
            page.keyboard.press("q")
            shoot(page, folder, "quit", taken)
            page.keyboard.press("Escape")
        if question["expects"] == "label":
            page.locator("#answers button").nth(answered % len(question["concepts"])).click()
        elif question["expects"] == "demo":
            page.get_by_role("button", name=f"object {answered % question['objects'] + 1}", exact=True).click()
        else:
            page.locator("#features summary", has_text="how it looks").locator("span").click()
            time.sleep(0.3)
            page.screenshot(path=str(folder / "study-feature-open.png"), full_page=True)
            page.locator("#features input[data-number='1.1']").check()
            page.get_by_role("button", name="use these").click()
        answered += 1
        page.wait_for_function("(id) => ended || !waiting || (question && question.id !== id)", arg=question["id"])


def main(argv=None) -> int:
    folder = Path((argv or sys.argv[1:] or ["docs/img"])[0]).resolve()
    folder.mkdir(parents=True, exist_ok=True)
    from playwright.sync_api import sync_playwright

    with tempfile.TemporaryDirectory(prefix="teachbot-study-shots-") as records:
        process = subprocess.Popen([TEACHBOT, "study", "run", str(STUDY), "--participant", "P01", "--folder",
                                    records, "--web"], cwd=records, stdout=subprocess.PIPE, text=True)
        try:
            assert process.stdout is not None
            url = next(m.group(1) for line in process.stdout if (m := re.search(r"Open the page: (\S+)", line)))
            with sync_playwright() as driver:
                browser = driver.chromium.launch(executable_path=find_chromium(), args=list(CHROMIUM_FLAGS))
                page = browser.new_page(viewport={"width": 1400, "height": 1000})
                page.goto(url)
                play(page, folder)
                browser.close()
        finally:
            process.kill()
            process.wait()
    return 0


if __name__ == "__main__":
    if find_chromium() is None:
        raise SystemExit("no Chromium found: apt-get install -y chromium")
    sys.exit(main())
