"""What a participant must not read in the page (issue 41, item 4; issue 50, item 3): the researcher's words, codes
("1.2", "0.197"), the catalogue's kind names as its data files write them and "the teacher" (the participant is
"you"), checked on the visible text of a screen. The strategy names come from the strategy registry and the task ids
from the task data files, so a new strategy or task is checked without editing this list."""

from __future__ import annotations

import re
from functools import lru_cache
from pathlib import Path

TASKS = Path(__file__).resolve().parents[2] / "bullet_world" / "data" / "tasks"
OBJECTS = TASKS.with_name("objects")
FIXED = ("Transcript", ".jsonl", "teachbot ", "--resume", "utility", "strategy", "the teacher")
DECIMAL = re.compile(r"(?<![\w.])\d+\.\d+(?![\w.])")  # 0.197; not a tree number such as 1.1.2 nor "v1.2"
CODE = re.compile(r"(?<![\w.])\d+(?:\.\d+)+(?![\w.])")  # 1.2, 1.1.2, 0.197: a tree number or a measurement


@lru_cache(maxsize=1)
def researcher_words() -> tuple[re.Pattern, ...]:
    """A pattern for each strategy name and task id, as a whole word ("dt" in "dt-task" is the whole name)."""
    from learning.datafiles import read_toml
    from learning.strategies import STRATEGY_NAMES

    tasks = [read_toml(path, "task")["name"] for path in sorted(TASKS.glob("*.toml"))]
    assert tasks and STRATEGY_NAMES and kind_names()
    return tuple(re.compile(rf"(?<![\w-]){re.escape(name)}(?![\w-])")
                 for name in (*STRATEGY_NAMES, *tasks, *kind_names()))


@lru_cache(maxsize=1)
def kind_names() -> tuple[str, ...]:
    """The object catalogue's kind names as the data files write them where that is not how words are written
    ("instant-noodle-cup"; "pear" is a word like any other)."""
    from learning.datafiles import read_toml

    names = {kind["name"] for path in sorted(OBJECTS.glob("*.toml")) for kind in read_toml(path, "objects")["kind"]}
    return tuple(sorted(name for name in names if re.search(r"[-_]", name)))


def researcher_words_in(text: str) -> list[str]:
    """Every researcher's word ``text`` holds (empty when the text is in a participant's words)."""
    found = [word for word in FIXED if word in text] + CODE.findall(text)
    return found + [pattern.pattern for pattern in researcher_words() if pattern.search(text)]


def visible_text(page) -> str:
    return page.inner_text("body")


def check_screen(page, screen: str, seen: dict, apart: tuple[str, ...] = ()) -> str:
    """The visible text of ``screen`` holds no researcher's word; records that the screen was visited. Lines in
    ``apart`` (the Why answer, once given) are left to their own check, made once where they are asked."""
    text = visible_text(page)
    checked = "\n".join(line for line in text.splitlines() if line.strip() not in apart)
    found = researcher_words_in(checked)
    assert not found, f"the {screen} screen shows {found}:\n{checked}"
    seen[screen] = text
    return text


def decimals_in(text: str) -> list[str]:
    return DECIMAL.findall(text)
