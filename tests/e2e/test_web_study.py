"""``teachbot study run --web``: a participant does the example study in headless Chromium with clicks only, and the
files pass ``study status`` and ``study report`` as a terminal session's do. Every screen (the instructions, each
question kind, the questionnaire, the pause, the end) is in a participant's words (issue 41, item 4): the header
says which screen it is, its text names its button, and nothing names a condition, strategy, task or file."""

from __future__ import annotations

import csv
import dataclasses
import json
import subprocess
from pathlib import Path

import pytest

from bullet_world.viewer.snapshot import find_chromium
from dialog.study.files import session_files
from dialog.study.studyfile import load_study
from dialog.transcripts.jsonl import read_session
from tests.e2e.plain_words import check_screen
from tests.e2e.web_helpers import TEACHBOT, WebCommand, chromium, open_page

pytestmark = [
    pytest.mark.e2e, pytest.mark.browser,
    pytest.mark.skipif(find_chromium() is None,
                       reason="no Chromium at /usr/bin/chromium: install it with apt-get install -y chromium"),
]
pytest.importorskip("playwright.sync_api", reason="needs playwright (pip install playwright; the browser is chromium)")

EXAMPLE = Path(__file__).resolve().parents[2] / "dialog/data/studies/example.toml"
READY = """() => ended || (question && waiting && document.getElementById('screen').hidden)
    || (!document.getElementById('screen').hidden && !document.querySelector('#screen form > button').disabled)"""


def click_through(page, titles: list[str], seen: dict | None = None) -> int:
    """Answer every screen and question by clicking until the run ends; returns the questions answered. Each
    screen's visible text is checked for the researcher's words (``seen``: each kind of screen's last text)."""
    answered, seen = 0, {} if seen is None else seen
    fresh = False  # the first question of a session is next
    while True:
        page.wait_for_function(READY, timeout=120_000)
        if page.evaluate("() => ended"):
            check_screen(page, "end", seen)
            assert page.is_hidden("#views") and page.is_hidden("#commands") and page.is_hidden("#typed")
            return answered
        if not page.locator("#screen").is_hidden():
            # between sessions: no kitchen, no stale picture, no greyed answer controls (issue 50)
            assert page.is_hidden("#views") and page.is_hidden("#ask")
            titles.append(page.inner_text("#screen h2"))
            fresh = titles[-1].startswith(("Session", "Practice"))
            kind = {"A short break": "pause", "A few questions about this session": "questionnaire",
                    "Before we begin": "consent"}.get(titles[-1], "instructions")
            check_screen(page, kind, seen)
            seen[f"{kind}: {titles[-1]}"] = seen[kind]
            assert page.inner_text("#status") == titles[-1]  # the header says what the screen is
            button = page.locator("#screen form > button").first.inner_text()  # the consent's: "I agree"
            assert "Press Enter" not in seen[kind] and ("Press" not in seen[kind] or f'"{button}"' in seen[kind])
            for group in page.locator("#screen fieldset").all():
                radios = group.locator("input[type=radio]")
                if radios.count():
                    radios.nth(radios.count() - 2).check()  # one below the top of the scale
            page.locator("#screen form > button").first.click()
            continue
        question = page.evaluate("() => question")
        check_screen(page, f"{question['expects']} question", seen)
        if fresh:  # a new session's conversation starts empty: nothing answered yet (the transcript keeps all)
            assert "You: " not in page.inner_text("#conversation"), page.inner_text("#conversation")
            fresh = False
        if question["expects"] == "feature":  # no earlier question's ring stays on the picture
            assert page.is_hidden("#picture")
        if question["expects"] == "label":
            page.locator("#answers button").nth(answered % len(question["concepts"])).click()
        elif question["expects"] == "demo":
            page.get_by_role("button", name=f"object {answered % question['objects'] + 1}", exact=True).click()
        else:
            page.locator("#features input[data-number='1.1']").check()
            page.get_by_role("button", name="use these").click()
        answered += 1
        page.wait_for_function("(id) => ended || !waiting || (question && question.id !== id)", arg=question["id"])


def test_a_participant_does_the_example_study_in_the_browser_with_clicks_only(tmp_path):
    folder = tmp_path / "records"
    command = WebCommand("study", "run", EXAMPLE, "--participant", "P01", "--folder", folder, "--web", "--no-viewer",
                         cwd=tmp_path)
    titles: list[str] = []
    seen: dict[str, str] = {}
    try:
        with chromium() as browser:
            page = open_page(browser, command.url)
            answered = click_through(page, titles, seen)
        assert command.finish(120) == 0, "".join(command.err)
    finally:
        command.stop()
    study = load_study(EXAMPLE)
    shown = "".join(command.out) + "".join(titles)
    assert titles[:3] == ["Before we begin", "Practice round", "Session 1 of 3"] and "Session 3 of 3" in titles
    assert "A short break" not in titles[:3]  # no break after the practice round
    assert not any(condition.name in title for condition in study.conditions for title in titles)
    assert "budget" not in shown.lower()
    assert answered >= 3
    assert {"consent", "instructions", "label question", "questionnaire", "pause", "end"} <= set(seen), sorted(seen)
    assert "Do you agree to take part?" in seen["consent"]
    assert 'Press "Go on"' in seen["pause"]
    assert any('press "Why?"' in text for key, text in seen.items() if key.startswith("instructions: "))

    from dialog.study.design import assigned_orders

    for position, name in enumerate(assigned_orders(study)["P01"], start=1):
        files = session_files(dataclasses.replace(study, folder=folder), "P01", position, name)
        _, records = read_session(files.transcript)
        assert len(records) == study.condition(name).turns
        asked = [r for r in records if r["action"]["kind"] != "none"]
        assert all(set(r["answer"]["channels"]) <= {"button", "click"} for r in asked)
        assert files.questionnaire.exists()
    person = folder / "P01"
    assert json.loads((person / "consent.json").read_text())["consent"]["given"] == "page"
    assert len(read_session(person / "0-practice.jsonl")[1]) == study.practice.turns

    status = subprocess.run([TEACHBOT, "study", "status", EXAMPLE, "--folder", folder], capture_output=True,
                            text=True, timeout=120)
    assert status.returncode == 0, status.stderr
    assert "P01" in status.stdout and "3 done" in status.stdout
    report = subprocess.run([TEACHBOT, "study", "report", EXAMPLE, "--folder", folder, "--out", tmp_path / "report"],
                            capture_output=True, text=True, timeout=300)
    assert report.returncode == 0, report.stderr
    text = (tmp_path / "report" / "report.md").read_text()
    assert "Answers given in the page" in text and "| page seconds (median) |" in text
    with open(tmp_path / "report" / "turns.csv") as handle:
        rows = list(csv.DictReader(handle))
    assert {row["channel"] for row in rows if row["action"] != "none"} <= {"button", "click"}
    assert all(float(row["page_seconds"]) >= 0 for row in rows if row["channel"])
