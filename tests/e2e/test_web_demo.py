"""``demo --pace`` and ``demo --web``: a scripted episode a person can follow, with the very same transcript."""

from __future__ import annotations

import subprocess
import time

import pytest

from bullet_world.viewer.snapshot import find_chromium
from tests.e2e.web_helpers import TEACHBOT, WebCommand, chromium

pytestmark = pytest.mark.e2e

# (page time in ms, turn) of each question message as the page receives it: timed in the browser, so the test
# process's own event delivery adds nothing
QUESTION_CLOCK = """
window.questionsShown = [];
const OpenSocket = window.WebSocket;
window.WebSocket = function (...args) {
  const socket = new OpenSocket(...args);
  socket.addEventListener("message", (event) => {
    try {
      const message = JSON.parse(event.data);
      if (message.type === "question") window.questionsShown.push([performance.now(), message.question.turn]);
    } catch (error) { /* not JSON: not a question */ }
  });
  return socket;
};
window.WebSocket.prototype = OpenSocket.prototype;
Object.assign(window.WebSocket, {CONNECTING: 0, OPEN: 1, CLOSING: 2, CLOSED: 3});
"""


def demo(cwd, *args) -> tuple[float, subprocess.CompletedProcess]:
    started = time.monotonic()
    done = subprocess.run([TEACHBOT, "demo", "--turns", "4", *map(str, args)], cwd=cwd, capture_output=True,
                          text=True, timeout=180)
    return time.monotonic() - started, done


def test_pace_makes_each_turn_last_its_seconds_and_changes_nothing_recorded(tmp_path):
    """Issue 23, case 8: the episode is played at a speed a person can follow; the transcript stays the same."""
    fast, plain = demo(tmp_path, "--transcript", "fast.jsonl")
    slow, paced = demo(tmp_path, "--transcript", "slow.jsonl", "--pace", "1.5")
    assert plain.returncode == paced.returncode == 0, plain.stderr + paced.stderr
    assert slow >= 4 * 1.5  # each of the 4 turns lasts at least 1.5 s of wall time
    # (the unpaced run's time is not compared: on a loaded machine it took 7 s; that it does not wait is
    # pace_of's default, checked below without a clock)
    assert (tmp_path / "fast.jsonl").read_bytes() == (tmp_path / "slow.jsonl").read_bytes()


def test_only_a_watched_episode_is_paced_by_default():
    import argparse

    from dialog.viewer import DEFAULT_PACE_S, pace_of

    assert pace_of(argparse.Namespace(pace=None, viewer=False, web=False)) == 0.0
    assert pace_of(argparse.Namespace(pace=None, viewer=False, web=True)) == DEFAULT_PACE_S == 1.5
    assert pace_of(argparse.Namespace(pace=0.25, viewer=True, web=False)) == 0.25


@pytest.mark.browser
@pytest.mark.skipif(find_chromium() is None, reason="no Chromium at /usr/bin/chromium: apt-get install -y chromium")
def test_demo_web_shows_the_scripted_episode_turn_by_turn(tmp_path):
    pytest.importorskip("playwright.sync_api", reason="needs playwright")
    command = WebCommand("demo", "--web", "--turns", "4", "--transcript", "web.jsonl", cwd=tmp_path)
    try:
        with chromium() as browser:
            page = browser.new_page(viewport={"width": 1400, "height": 1000})
            page.add_init_script(QUESTION_CLOCK)
            page.goto(command.url)
            page.wait_for_function("() => question && question.picture", timeout=120_000)
            page.wait_for_function("() => $('picture').complete && $('picture').naturalWidth > 0", timeout=30_000)
            picture_shown = page.locator("#picture").is_visible()
            page.wait_for_function("() => ended", timeout=120_000)
            assert page.locator("#typed").is_hidden() and page.locator("#commands").is_hidden()  # watched only
            conversation = page.inner_text("#conversation")
            ended_text = page.inner_text("#question-text")
            assert command.finish() == 0
            page.wait_for_timeout(500)  # the server's last messages have arrived
            after_close = page.inner_text("#question-text")
            shown = page.evaluate("() => window.questionsShown")
        out = "".join(command.out)
    finally:
        command.stop()
    assert [turn for _, turn in shown] == [1, 2, 3, 4]
    # The default pace with a page is 1.5 s. The Pacer sends turn 4's question at least 0.5 x 1.5 s after turn 4
    # began, and turns 2..4 begin 1.5 s apart after turn 1's question was sent: 3.75 s from question 1 to 4 at
    # the server. Measured where the page receives them (a loaded browser may take in a frame late), 3.0 s still
    # holds only with pacing: unpaced, the four questions come well within a second of each other.
    assert (shown[-1][0] - shown[0][0]) / 1000.0 > 3.0, shown
    # issue 42, case 3: the camera picture, the teacher named as such, the summary at the end, each line once
    assert picture_shown
    assert conversation.count("Teacher: ") == 4 and "You: " not in conversation and conversation.count("What is") >= 1
    assert ended_text.startswith("Accuracy on pack-lunchbox held-out scenes") and after_close == ended_text
    assert out.count("-- turn 1: the robot looks at a new scene") == 1
    assert len([line for line in out.splitlines() if line.startswith("Turn ")]) == 4
    _, plain = demo(tmp_path, "--transcript", "plain.jsonl")
    assert (tmp_path / "web.jsonl").read_bytes() == (tmp_path / "plain.jsonl").read_bytes()
