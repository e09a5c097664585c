"""``teachbot teach --web`` in real headless Chromium: a whole session by buttons, clicks and checkboxes.

The session: labels by button, ``why`` and ``undo`` as buttons, the feature
question by checkboxes, "show me" by clicking the object in the camera picture
where the camera projects it, a reload and a second tab mid-session, forged and
wrong-token messages, a quit and a resume. The transcript must equal the same
answers typed at the terminal, field for field, but for the clock fields and
the page's channel fields.

On every screen of that session (each question kind, Why, Help, Undo, the
reload, Quit, the resumed page, the end) the page speaks a participant's words
(issue 41, item 4; ``tests/e2e/plain_words.py``): no strategy, task id, file,
command or utility number; what the researcher needs is at the terminal.
"""

from __future__ import annotations

import json
import re
import subprocess
import urllib.error
import urllib.request

import pytest

from bullet_world.viewer.snapshot import find_chromium
from dialog.environment import SimulatedKitchen
from dialog.manager import episode_generators
from dialog.transcripts.jsonl import read_session
from tests.e2e.plain_words import check_screen, decimals_in, researcher_words_in
from tests.e2e.teach_helpers import PRINTED
from tests.e2e.web_helpers import TEACHBOT, WebCommand, chromium, comparable, open_page, send_raw, wait_for_question

pytestmark = [
    pytest.mark.e2e, pytest.mark.browser,
    pytest.mark.skipif(find_chromium() is None,
                       reason="no Chromium at /usr/bin/chromium: install it with apt-get install -y chromium"),
]
pytest.importorskip("playwright.sync_api", reason="needs playwright (pip install playwright; the browser is chromium)")

SEED, TURNS, CHANGE_EVERY = 0, 8, 5
OPTIONS = ("--seed", SEED, "--turns", TURNS, "--change-every", CHANGE_EVERY, "--strategy", "dt-task")


class Truth:
    """The session's scenes rebuilt from the same seed: each object's concept and where the camera sees it."""

    def __init__(self, scenes: int):
        self.env = SimulatedKitchen(seed=SEED, pictures=True)
        rng = episode_generators(SEED)["scenes"]
        self.scenes = [self.env.next_scene(rng) for _ in range(scenes)]
        self.pixels = [self.env.picture_pixels(scene) for scene in self.scenes]

    def scene(self, turn: int):
        return (turn - 1) // CHANGE_EVERY

    def concept(self, turn: int, number: int) -> str:
        return self.scenes[self.scene(turn)].truth.concepts[number - 1]

    def example(self, turn: int, concept: str) -> tuple[int, tuple[float, float]] | None:
        """An object of ``concept`` in the turn's scene: its number and its place as shares of the picture."""
        index = self.scene(turn)
        concepts = self.scenes[index].truth.concepts
        pixels, width, height = self.pixels[index]
        for i, name in enumerate(concepts):
            if name == concept:
                return i + 1, (pixels[i][0] / width, pixels[i][1] / height)
        return None

    def close(self):
        self.env.close()


def click_picture(page, share: tuple[float, float]) -> None:
    box = page.locator("#picture").bounding_box()
    page.locator("#picture").click(position={"x": share[0] * box["width"], "y": share[1] * box["height"]})


def answer(page, question: dict, truth: Truth, keyboard: bool = False) -> str:
    """Answer ``question`` as a person in the page would, by button (or its key), click or checkboxes; returns
    how."""
    if question["expects"] == "label":
        concept = truth.concept(question["turn"], question["object"])
        if keyboard:  # the concept buttons have keys 1, 2, ...
            page.keyboard.press(str(question["concepts"].index(concept) + 1))
        else:
            page.get_by_role("button", name=concept, exact=False).first.click()
        return "button"
    if question["expects"] == "demo":
        concept = question["text"].split("show me ")[1].split("?")[0].split(" ", 1)[1]
        example = truth.example(question["turn"], concept)
        if example is None:
            page.get_by_role("button", name="none here").click()
            return "button"
        page.wait_for_function("() => document.getElementById('picture').complete")
        click_picture(page, example[1])
        return "click"
    labels = page.locator("#features label, #features summary").all_text_contents()
    assert labels and not [label for label in labels if re.match(r"\s*\d+(\.\d+)+", label)], labels
    assert not [label for label in labels if re.search(r"metres|radians|\(0", label)], labels  # no units, scales
    colour = page.locator("#features summary", has_text="its colour")
    assert colour.is_hidden()  # folded: the groups first, their details one click away
    page.locator("#features summary", has_text="how it looks").locator("span").click()
    assert colour.is_visible() and not page.is_checked("#features input[data-number='1.1']")
    assert "Tick" in question["text"] and "numbers" not in question["text"]
    for number in ("1.1", "1.2", "1.5"):
        page.locator(f"#features input[data-number='{number}']").check()
    page.get_by_role("button", name="use these").click()
    # the conversation says what was ticked in words, not as "1.1, 1.2, 1.5" (issue 50)
    page.wait_for_function("() => document.getElementById('conversation').textContent.includes("
                           "'You: how it looks, its shape and size, how heavy it is')")
    return "button"


def refused_after(page, message) -> str:
    page.evaluate("() => { document.getElementById('refused').textContent = ''; }")
    send_raw(page, message)
    page.wait_for_function("() => document.getElementById('refused').textContent !== ''")
    return page.inner_text("#refused")


def http_status(url: str, headers: dict | None = None) -> int:
    try:
        with urllib.request.urlopen(urllib.request.Request(url, headers=headers or {}), timeout=10) as response:
            return response.status
    except urllib.error.HTTPError as error:
        return error.code


def budget_shown(page) -> float:
    return float(re.search(r"budget left ([0-9.]+)", page.inner_text("#meta")).group(1))


def conversation(page) -> str:
    return page.inner_text("#conversation")


def test_a_whole_session_in_the_browser_equals_the_same_answers_typed(tmp_path):
    web, terminal = tmp_path / "web", tmp_path / "terminal"
    web.mkdir()
    terminal.mkdir()
    truth = Truth(scenes=2)
    channels = []
    seen: dict[str, str] = {}  # each screen visited: its visible text (checked for the researcher's words)
    asked: list[str] = []      # the questions of the first run, as the page showed them
    why = ""
    budgets = {}
    try:
        with chromium() as browser:
            first = WebCommand("teach", "--web", *OPTIONS, "--transcript", "runs/t.jsonl", cwd=web)
            try:
                base, token = first.url.split("?token=")
                assert http_status(first.url) == 200
                assert http_status(base + "?token=wrong") == 403
                assert http_status(base) == 403
                assert http_status(f"{base}static/app.js") == 403
                assert http_status(first.url, {"Host": "evil.example:80"}) == 403

                page = open_page(browser, first.url)
                question = wait_for_question(page)
                assert question["turn"] == 1
                # a forged message, a stale one, a malformed one: refused, the question stays open
                assert "concept \"DROP TABLE\"" in refused_after(page, {"type": "concept", "concept": "DROP TABLE",
                                                                      "question": question["id"]})
                assert "open question" in refused_after(page, {"type": "concept", "concept": "fruit",
                                                               "question": question["id"] + 5})
                assert "not JSON" in refused_after(page, "{not json")
                assert "object pick for a label question" in refused_after(page, {"type": "pick", "object": 3,
                                                              "question": question["id"]})
                # a websocket with a wrong token or from a foreign page is refused
                assert page.evaluate("""(url) => new Promise(done => { const s = new WebSocket(url);
                    s.onopen = () => done('open'); s.onerror = () => done('refused'); })""",
                                     base.replace("http", "ws") + "ws?token=wrong") == "refused"
                assert "Help the robot learn what the words of this kitchen task mean" in page.inner_text("body")
                done_turns = 0
                while done_turns < 5:
                    asked.append(question["text"])
                    check_screen(page, f"{question['expects']} question", seen, (why,))
                    if question["turn"] == 2:
                        page.get_by_role("button", name="Why?").click()  # a reply; the question stays open
                        page.wait_for_function("() => waiting && document.getElementById('conversation')"
                                               ".textContent.includes('Why I ask')")
                        why = page.locator("#conversation li.robot").last.inner_text().strip()
                        seen["why"] = page.inner_text("body")  # checked with the Why sentence at the end
                    if question["turn"] == 3:
                        page.reload()  # a reload rejoins the session: the same question, still waiting
                        again = wait_for_question(page)
                        assert again["id"] == question["id"] and again["text"] == question["text"]
                        assert asked[0] in conversation(page) and "Why I ask" in conversation(page)
                        check_screen(page, "reloaded page", seen, (why,))
                        second = open_page(browser, first.url)  # so does a second tab
                        assert wait_for_question(second)["text"] == question["text"]
                        second.close()
                        budgets["before undo"] = budget_shown(page)
                        page.get_by_role("button", name="Undo").click()  # takes back turn 2's answer
                        page.wait_for_function("() => waiting && document.getElementById('conversation')"
                                               ".textContent.includes('Taken back')")
                        budgets["after undo"] = budget_shown(page)  # at once, before the next answer
                        check_screen(page, "undo", seen, (why,))
                    if question["turn"] == 4:
                        page.get_by_role("button", name="Help").click()
                        page.wait_for_function("() => waiting && document.getElementById('conversation')"
                                               ".textContent.includes('\"Why?\" asks my reason')")
                        check_screen(page, "help", seen, (why,))
                    channels.append(answer(page, question, truth, keyboard=question["turn"] == 1))
                    done_turns += 1
                    question = wait_for_question(page, after=question["id"])
                # a stray key cannot end it (issue 50): a click on the page background, then q, asks first
                page.mouse.click(5, page.viewport_size["height"] - 5)
                page.keyboard.press("q")
                assert page.is_visible("#confirm") and "Stop this session?" in page.inner_text("#confirm")
                assert page.evaluate("() => document.activeElement.id") == "confirm-go-on"  # the default
                page.keyboard.press("Enter")  # Go on
                assert page.is_hidden("#confirm") and page.evaluate("() => waiting && !ended")
                page.keyboard.press("q")
                page.keyboard.press("Escape")  # Go on, too
                assert page.is_hidden("#confirm") and page.evaluate("() => waiting && !ended")
                assert page.evaluate("() => question.id") == question["id"]
                page.get_by_role("button", name="Quit").click()
                page.keyboard.press("y")  # meant: the session ends as before
                page.wait_for_function("() => ended")
                assert "saved after 5 of 8 turns" in check_screen(page, "quit", seen, (why,))
                assert first.finish() == 0
                assert any("Session saved after 5 of 8 turns" in line for line in first.out)
                terminal_text = "".join(first.out)  # the researcher's: the strategy, the file, the command
                assert "strategy dt-task" in terminal_text and "Transcript: runs/t.jsonl" in terminal_text
                assert f"{PRINTED} teach --resume runs/t.jsonl --web" in terminal_text
            finally:
                first.stop()

            second_run = WebCommand("teach", "--web", "--resume", "runs/t.jsonl", cwd=web)
            try:
                page = open_page(browser, second_run.url)
                question = wait_for_question(page)
                assert question["turn"] == 6
                shown = conversation(page)  # the conversation so far, from the transcript
                assert all(text in shown for text in asked), (asked, shown)
                check_screen(page, "resumed page", seen, (why,))
                while not question.get("ended"):
                    check_screen(page, f"{question['expects']} question", seen, (why,))
                    channels.append(answer(page, question, truth))
                    question = wait_for_question(page, after=question["id"])
                assert "The robot now names" in check_screen(page, "end", seen, (why,))
                assert second_run.finish() == 0
            finally:
                second_run.stop()
    finally:
        truth.close()

    header, records = read_session(web / "runs/t.jsonl")
    assert [r["turn"] for r in records] == list(range(1, TURNS + 1))
    assert records[2]["undid"] == [2]
    assert budgets["after undo"] == budgets["before undo"] + records[1]["cost"] > budgets["before undo"]
    assert {"label question", "demo question", "feature question", "why", "undo", "help", "reloaded page", "quit",
            "resumed page", "end"} <= set(seen), sorted(seen)
    assert "click" in channels and "button" in channels
    for record in records:
        assert len(record["answer"]["channels"]) == len(record["answer"]["lines"])
    assert any("click" in r["answer"]["channels"] for r in records)

    lines = [line for r in records for line in r["answer"]["lines"]]
    typed = subprocess.run([TEACHBOT, "teach", *map(str, OPTIONS), "--transcript", "runs/t.jsonl"], cwd=terminal,
                           input="\n".join(lines) + "\n", capture_output=True, text=True, timeout=120)
    assert typed.returncode == 0, typed.stderr
    _, at_terminal = read_session(terminal / "runs/t.jsonl")
    assert "channels" not in json.dumps(at_terminal)
    assert [comparable(r) for r in records] == [comparable(r) for r in at_terminal]
    # "Why?" answers in a sentence without utility numbers (the Why line is left out of the checks of each screen
    # above and checked here, once). Last, so that every check above is made first: the strategies' reasons in
    # plain words come with issue 39's rewrite (branch w39stall); until it is merged this assertion fails.
    assert why.startswith("Robot: Why I ask: ") and why.rstrip().endswith((".", ")"))
    assert not researcher_words_in(seen["why"]) and not decimals_in(why), why
