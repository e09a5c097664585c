"""Screenshots of a meshcat page in headless Chromium (Debian's ``chromium``, driven by playwright).

Used by ``teachbot view --screenshot``, by the browser test and for the
pictures in ``docs/viewer.md``. playwright is a development dependency; its
own browser download is not needed: the system's Chromium is launched.
"""

from __future__ import annotations

import shutil
import tempfile
import time
from pathlib import Path

from learning.errors import SetupError

CHROMIUM_CANDIDATES = ("/usr/bin/chromium", "/usr/bin/chromium-browser", "/usr/bin/google-chrome")
CHROMIUM_FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
                  "--disable-component-update", "--disable-sync", "--no-first-run", "--use-angle=swiftshader",
                  "--enable-unsafe-swiftshader")
# How many meshes and sprites are drawn right now (0 until meshcat has built the scene).
COUNT_DRAWN_JS = """() => {
    if (typeof viewer === "undefined" || !viewer.scene) { return 0; }
    let drawn = 0;
    viewer.scene.traverseVisible(o => { if (o.isMesh || o.isSprite) { drawn += 1; } });
    return drawn;
}"""
HIDE_CONTROLS_CSS = ".dg { display: none !important; }"


def find_chromium() -> str | None:
    """The first Chromium executable found on this machine, or None."""
    for candidate in CHROMIUM_CANDIDATES:
        if Path(candidate).is_file():
            return candidate
    return shutil.which("chromium")


class SnapshotError(SetupError):
    """The page could not be opened, or never showed a scene."""


def screenshot(url: str, path: str | Path, *, min_drawn: int = 1, width: int = 1280, height: int = 800,
               timeout_s: float = 60.0, settle_s: float = 1.0, hide_controls: bool = True,
               animation_time: float | None = None, executable: str | None = None) -> dict:
    """Open ``url``, wait until at least ``min_drawn`` meshes/sprites are drawn and the count is stable
    for ``settle_s``, optionally seek the page's animation to ``animation_time`` seconds, save a PNG.

    Returns ``{"path", "drawn", "seconds"}``.
    """
    try:
        from playwright.sync_api import Error as PlaywrightError
        from playwright.sync_api import sync_playwright
    except ImportError:
        raise SnapshotError("screenshots need playwright (pip install playwright); the browser is the "
                            "system's chromium") from None
    executable = executable or find_chromium()
    if executable is None:
        raise SnapshotError(f"no Chromium found (looked for {', '.join(CHROMIUM_CANDIDATES)}); "
                            "install it with: apt-get install -y chromium")
    started = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="teachbot-chromium-") as profile, sync_playwright() as driver:
        try:
            context = driver.chromium.launch_persistent_context(
                profile, executable_path=executable, headless=True, args=list(CHROMIUM_FLAGS),
                viewport={"width": width, "height": height})
        except PlaywrightError as error:
            raise SnapshotError(f"could not start {executable}: {str(error).splitlines()[0]}") from None
        try:
            page = context.new_page()
            page.goto(url, wait_until="load", timeout=timeout_s * 1000)
            drawn = _wait_for_scene(page, min_drawn, started + timeout_s, settle_s)
            if hide_controls:
                page.add_style_tag(content=HIDE_CONTROLS_CSS)
            if animation_time is not None:
                page.evaluate("t => { viewer.animator.play(); viewer.animator.pause(); viewer.animator.seek(t); }",
                              animation_time)  # play() first: a page that does not autoplay has no active tracks
            page.wait_for_timeout(300)
            Path(path).parent.mkdir(parents=True, exist_ok=True)
            page.screenshot(path=str(path))
        except PlaywrightError as error:
            raise SnapshotError(f"browser error on {url}: {str(error).splitlines()[0]}") from None
        finally:
            context.close()
    return {"path": str(path), "drawn": drawn, "seconds": round(time.perf_counter() - started, 2)}


def _wait_for_scene(page, min_drawn: int, deadline: float, settle_s: float) -> int:
    """Poll the number of drawn objects until it reaches ``min_drawn`` and stops changing."""
    last, stable_since = -1, time.perf_counter()
    while True:
        drawn = int(page.evaluate(COUNT_DRAWN_JS))
        now = time.perf_counter()
        if drawn != last:
            last, stable_since = drawn, now
        elif drawn >= min_drawn and now - stable_since >= settle_s:
            return drawn
        if now > deadline:
            raise SnapshotError(f"the page drew {drawn} objects, expected at least {min_drawn}")
        page.wait_for_timeout(200)
