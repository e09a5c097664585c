"""The person at the page: the session's side of ``--web`` (a :class:`~dialog.teachers.scripted.Teacher`).

The dialog runs in the main thread as for ``teach``; the web server
(:mod:`dialog.web.server`) runs in its own thread and hands each message from a
page to :meth:`WebTeacher.submit`, which checks it (:mod:`dialog.web.messages`)
against the question now open and queues the line it stands for. ``listen``
takes that line, so the same conversation and grammar read it. Everything the
page shows (the conversation so far, the question now) is kept here, so a
reload or a second tab gets the same state: there is one session, not one per
tab.
"""

from __future__ import annotations

import queue
import sys
import threading

import numpy as np

from dialog.language.questions import Prompt
from dialog.web import words
from dialog.web.messages import Asked, PageAnswer, decode, read_message, read_screen
from learning.errors import MessageError

CLICK_RADIUS = 0.06  # a click resolves to the nearest object centre within this share of the picture's width
POLL_S = 0.2         # how often a waiting ``listen`` looks at the deadline and Ctrl-C


class WebTeacher:
    """A person answering in the browser: buttons, clicks on the camera picture, checkboxes or typed lines."""

    def __init__(self, clock=None, locate=None, log=None, echo=None):
        self.clock, self.echo = clock, echo  # echo: where the session's own lines are printed too (the terminal)
        self.locate = locate  # scene -> (pixels (n, 2), width, height) of the camera picture, or None
        self.log = log or sys.stderr
        self.broadcast = lambda message: None  # set by the server: send to every open page
        self._lock = threading.Lock()
        self._answers: queue.Queue[PageAnswer] = queue.Queue()
        self._question = 0
        self._asked: Asked | None = None
        self._waiting = False
        self._shown: Prompt | None = None
        self._pixels: tuple | None = None
        self._last: PageAnswer | None = None
        self.conversation: list[dict] = []
        self.current: dict | None = None
        self.pictures: dict[int, str] = {}
        self.ended = False
        self.end_text = ""  # what the page says once the session is over (the summary, or why it stopped)
        self.refused = 0
        self.nodes: dict[str, int] = {}
        self.view = 0  # which 3D view the page shows (a study's next session brings a new one)
        self.has_view = False
        self.show_budget = True  # a study hides it from its participants
        self._screen: dict | None = None  # an open study screen (instructions, pause, questionnaire)
        self._screen_answers: queue.Queue[list] = queue.Queue()
        self._labels: dict[str, str] = {}  # the open feature question's checkbox words, by tree number

    def options(self) -> dict:
        return {"kind": "terminal"}

    # -- the page's state -------------------------------------------------------------------------
    def snapshot(self) -> dict:
        """Everything a page that (re)connects shows."""
        with self._lock:
            return {"type": "state", "conversation": list(self.conversation), "question": self.current,
                    "waiting": self._waiting, "ended": self.ended, "nodes": dict(self.nodes),
                    "screen": self._screen, "view": self.view if self.has_view else 0, "end_text": self.end_text}

    def _post(self, message: dict) -> None:
        self.broadcast(message)

    def _note(self, who: str, text: str) -> None:
        entry = {"who": who, "text": text}
        with self._lock:
            self.conversation.append(entry)
            del self.conversation[:-200]
        self._post({"type": "line", **entry})

    # -- the Teacher interface --------------------------------------------------------------------
    def show(self, prompt: Prompt) -> None:
        if prompt is self._shown:  # asked again after an undo: the same question stays on the page
            return
        self._shown = prompt
        with self._lock:
            self._question += 1
            tree = prompt.feature_tree
            numbers = frozenset(tree.by_number) if tree is not None else frozenset()
            n_objects = int(getattr(prompt.scene, "n_objects", 0))
            self._asked = Asked(self._question, prompt.expects, tuple(prompt.concepts), n_objects, numbers)
            self._pixels = self.locate(prompt.scene) if self.locate is not None and prompt.picture else None
            rows = _tree_rows(tree) if tree is not None else []
            self._labels = {row["number"]: row["label"] for row in rows}
            if prompt.picture:
                self.pictures[self._question] = prompt.picture
            self.current = {
                "id": self._question, "turn": prompt.turn, "turns": prompt.turns,
                "budget_left": prompt.budget_left if self.show_budget else None, "expects": prompt.expects,
                "text": words.question_text(prompt.expects, prompt.text, prompt.concepts),
                "concepts": list(prompt.concepts), "objects": n_objects,
                "object": None if prompt.object_index is None else prompt.object_index + 1,
                "picture": bool(prompt.picture), "details": [line for line in prompt.details
                                                             if not line.startswith("Picture:")],
                "features": rows,
                "seconds_left": None if prompt.deadline is None or self.clock is None
                else round(max(0.0, prompt.deadline - self.clock.now()), 1),
                "help": words.help_text(prompt),
            }
            question = dict(self.current)
        self._note("robot", question["text"])
        self._post({"type": "question", "question": question})

    def listen(self, prompt: Prompt, deadline: float | None) -> str | None:
        with self._lock:
            self._waiting = True
            question = self._question
        self._post({"type": "waiting", "question": question})
        try:
            while True:
                left = None if deadline is None or self.clock is None else deadline - self.clock.now()
                if left is not None and left <= 0:
                    return None  # too late: the conversation counts it as late
                try:
                    answer = self._answers.get(timeout=POLL_S if left is None else min(POLL_S, left))
                except queue.Empty:
                    continue
                self._last = answer
                shown = words.answer_words(answer.line, self._labels) if prompt.expects == "feature" else answer.line
                self._note("teacher", shown)  # in words: what was ticked, not its tree numbers
                return answer.line
        finally:
            with self._lock:
                self._waiting = False

    def watch(self, turn: int, kind: str, text: str, number: int | None, picture: str | None = None) -> None:
        """A scripted episode's question with its camera picture, shown without answer controls (``demo --web``)."""
        with self._lock:
            self._question += 1
            if picture:
                self.pictures[self._question] = picture
            self.current = {"id": self._question, "turn": turn, "turns": None, "budget_left": None,
                            "expects": kind, "text": text, "object": number, "watch": True, "concepts": [],
                            "objects": 0, "picture": bool(picture), "details": [], "features": [],
                            "seconds_left": None, "help": ""}
            question = dict(self.current)
        self._note("robot", text)
        self._post({"type": "question", "question": question})

    def heard(self, text: str) -> None:
        """A scripted teacher's answer, shown as the teacher's line ("Teacher: ", not the person's "You: ")."""
        self._note("scripted", text)

    def help_for(self, prompt: Prompt) -> str:
        """The help the page gives: its buttons, not the terminal's typed commands."""
        return words.help_text(prompt)

    def budget_changed(self, budget_left: float) -> None:
        """An undo gave budget back: the open question's budget line says so at once."""
        with self._lock:
            if self.current is None or not self.show_budget:
                return
            self.current["budget_left"] = budget_left
            question = self.current["id"]
        self._post({"type": "budget", "question": question, "budget_left": budget_left})

    def recall(self, records: list[dict], concepts, feature_names=None) -> None:
        """A resumed session's earlier turns as the page's conversation so far: each question and its answers (a
        feature answer in the checkboxes' words, given the session's ``feature_names``)."""
        labels = {}
        if feature_names:
            from dialog.language.feature_tree import FeatureTree

            labels = {row["number"]: row["label"] for row in _tree_rows(FeatureTree(list(feature_names)))}
        for record in records:
            action = record.get("action") or {}
            if action.get("kind") in (None, "none") or not record.get("question"):
                continue
            answer = record.get("answer") or {}
            self._note("robot", words.question_text(action["kind"], record["question"], concepts))
            for line in answer.get("lines") or [answer.get("raw") or ""]:
                self._note("teacher", words.answer_words(line, labels) if action["kind"] == "feature" else line)

    def researcher(self, text: str) -> None:
        """A line for the researcher only (the strategy, files, the command that continues): the terminal."""
        if self.echo is not None:
            print(text, file=self.echo, flush=True)

    def answer_channel(self) -> dict:
        last = self._last
        return {"channel": last.channel, "page_seconds": last.page_seconds} if last else {"channel": "typed"}

    def tell(self, text: str) -> None:
        shown = self._shown
        if shown is not None and shown.expects == "feature" and shown.text in text:  # "Now: ...", "All right. ..."
            text = text.replace(shown.text, words.question_text("feature", shown.text, shown.concepts))
        self._note("robot", text)

    def say(self, text: str, echo: bool = True) -> None:
        """A line from the session itself (progress, the summary); printed at the terminal too unless not ``echo``
        (a line the terminal gets from elsewhere)."""
        if echo and self.echo is not None:
            print(text, file=self.echo, flush=True)
        self._note("session", words.for_participant(text.strip()))

    def new_session(self) -> None:
        """A study's next session: the page's conversation starts empty (the transcripts keep every line)."""
        with self._lock:
            self.conversation.clear()
            self.current, self._asked, self._shown = None, None, None
        self._post({"type": "clear"})

    def new_view(self, available: bool) -> None:
        """A new 3D view (another kitchen's meshcat mirror) for the page to connect to."""
        with self._lock:
            self.view += 1
            self.has_view = available
            view = self.view if available else 0
        self._post({"type": "view", "view": view})

    def set_nodes(self, nodes: dict[str, int]) -> None:
        """Which 3D-view node is which object (numbered from 1), for clicks in the 3D view."""
        with self._lock:
            self.nodes = dict(nodes)
        self._post({"type": "nodes", "nodes": dict(nodes)})

    def end(self, text: str = "") -> None:
        """The session is over: the page says so (``text``: the summary, or why it stopped) and takes no more
        answers. A later call without text keeps what the page says."""
        with self._lock:
            if self.ended and not text:
                return
            self.ended, self.current, self._asked = True, None, None
            self.end_text = text or self.end_text
            text = self.end_text
        self._post({"type": "ended", "text": text})

    def ask_screen(self, title: str, text: str = "", button: str = "Continue", items: list | None = None) -> list:
        """Show a study screen (instructions, a pause, the questionnaire) and wait for its form: the values of
        its ``items`` (None where left out). A terminal's "Press Enter" in ``text`` names the button instead."""
        with self._lock:
            self._question += 1
            self._screen = {"id": self._question, "title": title, "text": words.for_page(text, button),
                            "button": button,
                            "items": list(items or [])}
            self.current, self._asked = None, None
            screen = dict(self._screen)
        self._post({"type": "screen", "screen": screen})
        while True:
            try:
                return self._screen_answers.get(timeout=POLL_S)
            except queue.Empty:
                continue

    def ask_choice(self, title: str, text: str, choices: tuple[str, ...]) -> str:
        """Show a study screen that ends with one of ``choices`` (a button each; the consent's "I agree" and "I do
        not agree") and wait for the one pressed."""
        with self._lock:
            self._question += 1
            self._screen = {"id": self._question, "title": title, "text": text, "button": "", "items": [],
                            "choices": list(choices)}
            self.current, self._asked = None, None
            screen = dict(self._screen)
        self._post({"type": "screen", "screen": screen})
        while True:
            try:
                return self._screen_answers.get(timeout=POLL_S)[0]
            except queue.Empty:
                continue

    # -- from the server's thread -----------------------------------------------------------------
    def submit(self, raw: str | bytes) -> str | None:
        """Check one message from a page; queue its line. Returns None, or the reason it was refused (logged)."""
        try:
            message = decode(raw)
            if message.get("type") == "screen":
                with self._lock:
                    values = read_screen(message, self._screen)
                    self._screen = None
                self._screen_answers.put(values)
                return None
            with self._lock:
                if self.ended:
                    raise MessageError("an answer after the session ended; accepted: nothing more")
                asked = self._asked if self._waiting else None  # not waiting: the robot is busy replying
                answer = read_message(message, asked, self._resolve_click)
                self._waiting = False  # one answer per listen: a double click is not two answers
            self._answers.put(answer)
            return None
        except MessageError as error:
            self.refused += 1
            print(f"web: refused a message from the page: {error}", file=self.log, flush=True)
            return str(error)

    def _resolve_click(self, x: float, y: float) -> int | None:
        """The object whose picture centre is nearest the click (x, y as shares of the picture), if close."""
        if self._pixels is None:
            return None
        pixels, width, height = self._pixels
        if len(pixels) == 0:
            return None
        point = np.array([x * width, y * height])
        distances = np.hypot(*(np.asarray(pixels, dtype=float) - point).T)
        distances[~np.isfinite(distances)] = np.inf
        index = int(np.argmin(distances))
        return index if distances[index] <= CLICK_RADIUS * width else None

    def picture_path(self, question: int) -> str | None:
        with self._lock:
            return self.pictures.get(question)


def _tree_rows(tree) -> list[dict]:
    """The feature tree as rows for checkboxes: number, name, the words the page shows (a group's from
    dialog/data/feature-groups.toml, a feature's own description), depth, whether a group."""
    rows: list[dict] = []

    def walk(nodes, depth: int, path: str) -> None:
        for node in nodes:
            group = node.feature is None
            here = f"{path}/{node.name}" if path else node.name
            rows.append({"number": node.number, "name": node.name,
                         "label": words.group_label(here) if group
                         else words.plain_feature(node.name, node.description or node.name),
                         "depth": depth, "group": group})
            walk(node.children, depth + 1, here)

    walk(tree.roots, 0, "")
    return rows
