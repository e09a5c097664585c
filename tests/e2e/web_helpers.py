"""Drive a ``--web`` session: start the command, open its page in headless Chromium, answer as a person would."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import threading
import time
from contextlib import contextmanager
from pathlib import Path

from bullet_world.viewer.snapshot import CHROMIUM_FLAGS, find_chromium

TEACHBOT = str(Path(sys.executable).with_name("teachbot"))
URL = re.compile(r"Open the page: (http://\S+)")
IGNORED = ("time", "ended", "seconds")  # clock fields
PAGE_ONLY = ("channels", "page_seconds")  # how a page's answer came


class WebCommand:
    """``teachbot ARGS`` in the background; its output collected; the page's URL once printed."""

    def __init__(self, *args, cwd: Path, timeout_s: float = 90.0):
        env = dict(os.environ, NO_COLOR="1", COLUMNS="200")
        self.process = subprocess.Popen([TEACHBOT, *map(str, args)], cwd=cwd, env=env, stdin=subprocess.PIPE,
                                        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        self.out: list[str] = []
        self.err: list[str] = []
        threading.Thread(target=self._collect, args=(self.process.stdout, self.out), daemon=True).start()
        threading.Thread(target=self._collect, args=(self.process.stderr, self.err), daemon=True).start()
        self.url = self.wait_for(URL, timeout_s).group(1)

    @staticmethod
    def _collect(stream, lines: list[str]) -> None:
        for line in stream:
            lines.append(line)

    def wait_for(self, pattern: re.Pattern, timeout_s: float = 60.0):
        end = time.monotonic() + timeout_s
        while time.monotonic() < end:
            for line in list(self.out):
                found = pattern.search(line)
                if found:
                    return found
            if self.process.poll() is not None and not any(pattern.search(line) for line in self.out):
                time.sleep(0.2)
                if not any(pattern.search(line) for line in self.out):
                    raise AssertionError(f"the command ended ({self.process.returncode}) without "
                                         f"{pattern.pattern!r}:\n{''.join(self.out)}{''.join(self.err)}")
            time.sleep(0.05)
        raise AssertionError(f"no {pattern.pattern!r} in {timeout_s} s:\n{''.join(self.out)}{''.join(self.err)}")

    def finish(self, timeout_s: float = 60.0) -> int:
        code = self.process.wait(timeout_s)
        time.sleep(0.1)
        return code

    def stop(self) -> None:
        if self.process.poll() is None:
            self.process.kill()
            self.process.wait(10)


@contextmanager
def chromium():
    """A headless Debian Chromium driven by playwright (its own browser download is not used)."""
    from playwright.sync_api import sync_playwright

    with sync_playwright() as driver:
        browser = driver.chromium.launch(executable_path=find_chromium(), args=list(CHROMIUM_FLAGS))
        try:
            yield browser
        finally:
            browser.close()


def open_page(browser, url: str, width: int = 1400, height: int = 1000):
    page = browser.new_page(viewport={"width": width, "height": height})
    page.goto(url)
    return page


def wait_for_question(page, after: int = 0, timeout_s: float = 60.0) -> dict:
    """The open question once the robot waits for an answer to a question newer than ``after``; or
    ``{"ended": True}`` once the session is over."""
    page.wait_for_function("(after) => ended || (question && waiting && question.id > after)", arg=after,
                           timeout=timeout_s * 1000)
    return page.evaluate("() => ended ? {ended: true} : question")


def wait_until_waiting(page, timeout_s: float = 30.0) -> None:
    page.wait_for_function("() => ended || waiting", timeout=timeout_s * 1000)


def send_raw(page, message: dict | str) -> None:
    """Send a message as the page's script would (a forged one, too)."""
    text = message if isinstance(message, str) else json.dumps(message)
    page.evaluate("(text) => socket.send(text)", text)


def comparable(record: dict) -> dict:
    """A turn record without its clock fields and the page's channel fields."""
    kept = {key: value for key, value in record.items() if key not in IGNORED}
    if "answer" in kept:
        kept["answer"] = {key: value for key, value in kept["answer"].items()
                          if key not in IGNORED and key not in PAGE_ONLY}
    return kept
