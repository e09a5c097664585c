"""What the page says in a participant's words (docs/web.md, "What the participant sees").

The terminal's texts speak of typing ("give the numbers", "press Enter", "type 'why'"); the page has
buttons and checkboxes instead, so its feature question, help and study screens say what to press. Nothing
here names a strategy, a task id, a file or a command: those are for the researcher, at the terminal.
"""

from __future__ import annotations

import re
from functools import lru_cache
from pathlib import Path

from dialog.language.questions import Prompt
from learning.datafiles import read_toml, section
from learning.errors import DataFileError

GROUP_WORDS = Path(__file__).resolve().parents[1] / "data" / "feature-groups.toml"
COMMANDS_HELP = ("\"Why?\" asks my reason for the question, \"Undo\" takes back your last answer, \"Skip\" leaves "
                 "this question unanswered, \"Quit\" stops (what you taught is kept). You can always type an "
                 "answer instead.")


@lru_cache(maxsize=1)
def group_words() -> dict[str, str]:
    """Each feature group's path ("object/appearance/colour") in plain words ("its colour")."""
    table = section(read_toml(GROUP_WORDS, "feature group words"), "groups", str(GROUP_WORDS))
    return {str(path): str(words) for path, words in table.items()}


@lru_cache(maxsize=1)
def plain_rules() -> tuple[list[tuple[re.Pattern, str]], dict[str, str]]:
    """The patterns that take a feature description's units and scales out, and whole descriptions by name."""
    where = str(GROUP_WORDS)
    plain = section(read_toml(GROUP_WORDS, "feature group words"), "plain", where)
    rules = []
    for pair in plain.get("patterns", []):
        if not (isinstance(pair, list) and len(pair) == 2 and all(isinstance(part, str) for part in pair)):
            raise DataFileError(f"{where}: [plain] patterns holds {pair!r}; accepted: [\"regular expression\", "
                                "\"replacement\"] pairs")
        try:
            rules.append((re.compile(pair[0]), pair[1]))
        except re.error as error:
            raise DataFileError(f"{where}: [plain] pattern {pair[0]!r} is not a regular expression ({error})") \
                from None
    features = section(plain, "features", f"{where} [plain]", default={})
    return rules, {str(name): str(text) for name, text in features.items()}


def plain_feature(name: str, description: str) -> str:
    """A feature's description without the units and scales a participant need not know."""
    rules, whole = plain_rules()
    if name in whole:
        return whole[name]
    for pattern, replacement in rules:
        description = pattern.sub(replacement, description)
    return description


def answer_words(line: str, labels: dict[str, str]) -> str:
    """A feature answer from the checkboxes ("1.1, 1.2", "ignore 2") in the boxes' words ("how it looks, its
    shape and size"; "these don't matter: ..."); any other line as it is."""
    found = re.fullmatch(r"(ignore )?((?:\d+(?:\.\d+)*)(?:, \d+(?:\.\d+)*)*)", line.strip())
    numbers = found.group(2).split(", ") if found else []
    if not numbers or any(number not in labels for number in numbers):
        return line
    said = ", ".join(labels[number] for number in numbers)
    return f"these don't matter: {said}" if found.group(1) else said


def for_participant(text: str) -> str:
    """A session line about the person at the page said to them: "you stopped", not "the teacher ended"."""
    return re.sub(r"the teacher ended the session \([^)]*\)", "you stopped the session", text)


def group_label(path: str) -> str:
    """A group's words; a group the file lacks shows its own name, its dots and dashes as spaces."""
    return group_words().get(path) or re.sub(r"[._/-]+", " ", path.rsplit("/", 1)[-1])


def _names(concepts) -> str:
    concepts = list(concepts) or ["the things"]
    return ", ".join(concepts[:-1]) + f" and {concepts[-1]}" if len(concepts) > 1 else concepts[0]


def feature_question(concepts) -> str:
    """The feature question as the page asks it: tick boxes, then one of its two buttons."""
    return (f"What tells {_names(concepts)} apart? Tick what matters and press \"use these\", or tick what "
            "does not matter and press \"ignore these\".")


def question_text(kind: str, text: str, concepts) -> str:
    """The question's words on the page: the terminal's, but for the feature question."""
    return feature_question(concepts) if kind == "feature" else text


def help_text(prompt: Prompt) -> str:
    """What the participant may answer, naming the page's buttons."""
    if prompt.expects == "label":
        body = "Press the word that names the thing I point at, or \"don't know\"."
    elif prompt.expects == "demo":
        body = ("Click one object that is an example, in the camera picture or the 3D view, or press its number; "
                "press \"none here\" if there is none.")
    else:
        body = ("Tick the groups or single features that tell the words apart and press \"use these\"; or tick "
                "the ones that do not matter and press \"ignore these\". Ticking a group ticks everything in it.")
    return f"{body} {COMMANDS_HELP}"


def intro(concepts, turns: int) -> str:
    """The page's opening line: what the participant does."""
    return (f"Help the robot learn what the words of this kitchen task mean: {_names(concepts)}. It asks you "
            f"about the objects it sees, up to {turns} times; answer with the buttons, by clicking an object, or by "
            "typing. \"Help\" says what you can answer.")


def for_page(text: str, button: str) -> str:
    """A study text written for the terminal ("Press Enter", "type 'why'") told in the page's terms."""
    text = re.sub(r"\b([Pp])ress Enter\b", lambda found: f"{found.group(1)}ress \"{button}\"", text)
    return re.sub(r"\btype '(\w+)'", lambda found: f"press \"{_button(found.group(1))}\"", text)


def _button(command: str) -> str:
    return "Why?" if command.lower() == "why" else command.capitalize()
