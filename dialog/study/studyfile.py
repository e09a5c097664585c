"""The study file (TOML): conditions, participants, their orders, seeds, questionnaire; loaded and validated.

Every field goes through ``learning.datafiles``, so a bad study file is refused
with one line naming the file, the section, the field and what is accepted.
Participants are known by short ids only (never names): ``P01``, ``lab2-07``. The study's name, its
condition names and the participant ids name folders and files, so each must be a name by the one rule
of ``learning.datafiles.check_name`` (a full match: no separators, no leading dot, no newline).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field
from pathlib import Path

from bullet_world.datafiles import available
from dialog.settings import DEFAULTS
from dialog.teachers.scripted import SCRIPTED_OPTIONS
from learning import datafiles as df
from learning.actions import DEFAULT_COSTS
from learning.errors import DataFileError, SettingsError
from learning.limits import maximum
from learning.strategies import PLUGIN_FORM, STRATEGY_NAMES, check_strategy_name, is_plugin_spec

ORDERINGS = ("latin", "given")
ITEM_KINDS = ("likert", "text")
CONDITION_FIELDS = ("name", "instructions", "task", "kitchen", "strategy", "budget", "turns", "change_every",
                    "realtime", "costs", "viewer", "fetch_from_pantry")
PRACTICE = "practice"  # the practice round's name: its files are 0-practice.*; no condition may take it
PRACTICE_FIELDS = tuple(name for name in CONDITION_FIELDS if name != "name")
PRACTICE_TURNS = 10  # a practice round is a few turns
CONSENT_BYTES = 100_000


def check_participant_id(value, where: str = "participant") -> str:
    """A participant id (an id, never a person's name): one folder name by ``learning.datafiles.check_name``."""
    return df.check_name(value, "participant id", where)


@dataclass(frozen=True)
class Condition:
    """One condition of the study: the settings of its teach session and the instructions shown before it."""

    name: str
    instructions: str
    task: str
    kitchen: str
    strategy: str
    budget: float
    turns: int
    change_every: int
    realtime: float | None = None
    costs: dict = field(default_factory=lambda: dict(DEFAULT_COSTS))
    viewer: bool = False
    fetch_from_pantry: bool = True


@dataclass(frozen=True)
class Item:
    """A questionnaire item: a Likert scale of ``points`` with its two anchors, or free text."""

    id: str
    kind: str
    text: str
    points: int = 0
    anchors: tuple[str, str] = ("", "")


@dataclass(frozen=True)
class Consent:
    """The consent text (a file beside the study file) and the SHA-256 of its bytes, which the record keeps."""

    file: str
    text: str
    sha256: str


@dataclass(frozen=True)
class Study:
    path: Path
    name: str
    seed: int
    folder: Path
    conditions: tuple[Condition, ...]
    participants: tuple[str, ...]
    ordering: str
    given_orders: dict
    items: tuple[Item, ...]
    simulated_teacher: dict
    pause: str
    simulated: bool = False  # a dry run (study run --simulated): every record it writes says so
    consent: Consent | None = None  # the informed-consent text shown before anything else
    practice: Condition | None = None  # a few turns before the conditions, recorded apart (named "practice")

    def condition(self, name: str) -> Condition:
        """A condition by name; ``practice`` is the practice round, when the study has one."""
        if name == PRACTICE and self.practice is not None:
            return self.practice
        for condition in self.conditions:
            if condition.name == name:
                return condition
        practice = " (and 'practice', the practice round)" if self.practice is not None else ""
        raise DataFileError(f"{self.path}: no condition '{name}'; the conditions are "
                            f"{', '.join(c.name for c in self.conditions)}{practice}")

    def check_participant(self, participant: str) -> str:
        check_participant_id(participant)
        if participant not in self.participants:
            shown = ", ".join(self.participants[:6]) + (" ..." if len(self.participants) > 6 else "")
            raise DataFileError(f"{self.path}: participant '{participant}' is not in the study; its ids are {shown}")
        return participant


def load_study(path: str | Path) -> Study:
    """The study in ``path``, validated; its folder defaults to ``runs/studies/<name>`` (relative to the cwd)."""
    path = Path(path)
    data = df.read_toml(path, "study")
    where = str(path)
    df.check_keys(data, where, required=("name", "seed", "conditions"),
                  optional=("folder", "participants", "ids", "order", "orders", "pause", "simulated_teacher",
                            "questionnaire", "consent", "practice"))
    name = df.name(data, "name", where, what="study name")
    seed = df.integer(data, "seed", where, low=0)
    conditions = tuple(_condition(table, f"{where} [[conditions]] {index + 1}")
                       for index, table in enumerate(df.tables(data, "conditions", where, nonempty=True)))
    names = [c.name for c in conditions]
    if len(set(names)) != len(names):
        raise DataFileError(f"{where}: condition names must differ, got {names}")
    if len(conditions) > 8:
        raise DataFileError(f"{where}: at most 8 conditions, got {len(conditions)}")
    if PRACTICE in names:
        raise DataFileError(f"{where}: [[conditions]] name 'practice' is taken by the practice round; accepted: "
                            "any other name (the practice round is a [practice] table)")
    participants = _participants(data, where)
    ordering = df.text(data, "order", where, default="latin", choices=ORDERINGS)
    given = _given_orders(data, where, ordering, participants, names)
    items = tuple(_item(table, f"{where} [[questionnaire]] {index + 1}")
                  for index, table in enumerate(df.tables(data, "questionnaire", where, default=[])))
    if len({item.id for item in items}) != len(items):
        raise DataFileError(f"{where}: questionnaire item ids must differ")
    teacher = df.section(data, "simulated_teacher", where, default={})
    df.check_keys(teacher, f"{where} [simulated_teacher]", optional=SCRIPTED_OPTIONS)
    simulated = {key: df.number(teacher, key, f"{where} [simulated_teacher]", low=0,
                                high=None if key == "answer_delay" else 1) for key in teacher}
    folder = Path(df.text(data, "folder", where, default=f"runs/studies/{name}"))
    pause = df.text(data, "pause", where, default="Take a short break. Press Enter when you are ready to go on.")
    consent = _consent(path, data, where) if "consent" in data else None
    practice = _practice(df.section(data, "practice", where), f"{where} [practice]") if "practice" in data else None
    return Study(path, name, seed, folder, conditions, participants, ordering, given, items, simulated, pause,
                 consent=consent, practice=practice)


def _consent(path: Path, data: dict, where: str) -> Consent:
    """``consent = "FILE"``: a UTF-8 text file in the study file's folder, read now (its SHA-256 is recorded)."""
    from dialog.transcripts.records import TEXT_ACCEPTED, text_problem

    name = df.check_name(data["consent"], "'consent'", where)
    file = path.parent / name
    accepted = (f"accepted: the name of a UTF-8 text file of at most {CONSENT_BYTES} bytes beside the study file, "
                "such as consent.md")
    if not file.is_file():
        raise DataFileError(f"{where}: 'consent' names {file}, which is {'not a file' if file.exists() else 'missing'}"
                            f"; {accepted}")
    try:
        raw = file.read_bytes()
    except OSError as error:
        raise DataFileError(f"{where}: 'consent' {file} can't be read ({error.strerror or error}); {accepted}") \
            from None
    if len(raw) > CONSENT_BYTES:
        raise DataFileError(f"{where}: 'consent' {file} has {len(raw)} bytes; {accepted}")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as error:
        raise DataFileError(f"{where}: 'consent' {file} is not UTF-8 text (byte {error.start}); {accepted}") from None
    problem = text_problem(text, "\t\n\r")
    if not text.strip() or problem:
        raise DataFileError(f"{where}: 'consent' {file} " + (f"holds text that is not plain ({problem})" if problem
                            else "is empty") + f"; {accepted} holding {TEXT_ACCEPTED}")
    return Consent(name, text, hashlib.sha256(raw).hexdigest())


def _practice(table: dict, where: str) -> Condition:
    """``[practice]``: a condition's fields but its name; a few turns (its records are left out of the report)."""
    df.check_keys(table, where, required=("strategy",), optional=PRACTICE_FIELDS)
    turns = df.integer(table, "turns", where, default=3, low=1, high=PRACTICE_TURNS)
    return _condition({**table, "name": PRACTICE, "turns": turns,
                       "instructions": df.text(table, "instructions", where, default=PRACTICE_INSTRUCTIONS)}, where)


PRACTICE_INSTRUCTIONS = ("A short practice round first, to try how answering works: nothing you answer here is "
                         "studied.")


def _condition(table: dict, where: str) -> Condition:
    df.check_keys(table, where, required=("name", "strategy"), optional=CONDITION_FIELDS)
    name = df.name(table, "name", where, what="condition name")
    costs = df.section(table, "costs", where, default=dict(DEFAULT_COSTS))
    df.check_keys(costs, f"{where} costs", required=tuple(DEFAULT_COSTS))
    realtime = df.number(table, "realtime", where, default=None, above=0, high=maximum("realtime"))
    return Condition(
        name=name,
        instructions=df.text(table, "instructions", where, default="Teach the robot the words of the task."),
        task=df.text(table, "task", where, default=DEFAULTS.task, choices=available("tasks")),
        kitchen=df.text(table, "kitchen", where, default=DEFAULTS.kitchen, choices=available("kitchens")),
        strategy=_strategy(table, where),
        budget=df.number(table, "budget", where, default=DEFAULTS.budget, low=0, high=maximum("budget")),
        turns=df.integer(table, "turns", where, default=DEFAULTS.turns, low=1, high=500),
        change_every=df.integer(table, "change_every", where, default=DEFAULTS.change_every, low=1),
        realtime=realtime,
        costs={key: df.number(costs, key, f"{where} costs", low=0) for key in DEFAULT_COSTS},
        viewer=df.flag(table, "viewer", where, default=False),
        fetch_from_pantry=df.flag(table, "fetch_from_pantry", where, default=True),
    )


def _strategy(table: dict, where: str) -> str:
    """A condition's strategy: a registered name, or ``module.path:ClassName`` (imported now: it runs the user's
    code, so a bad one is refused before the first participant)."""
    value = df.text(table, "strategy", where)
    if not is_plugin_spec(value):
        if value not in STRATEGY_NAMES:
            raise DataFileError(f"{where}: strategy '{value}' is not one of {', '.join(STRATEGY_NAMES)}, or "
                                f"{PLUGIN_FORM}")
        return value
    try:
        return check_strategy_name(value)
    except SettingsError as error:
        raise DataFileError(f"{where}: {error}") from None


def _participants(data: dict, where: str) -> tuple[str, ...]:
    if ("participants" in data) == ("ids" in data):
        raise DataFileError(f"{where}: give either 'participants' (how many: ids P01, P02, ...) or 'ids' "
                            "(a list of participant ids), not both or neither")
    if "participants" in data:
        count = df.integer(data, "participants", where, low=1, high=999)
        return tuple(f"P{number:02d}" for number in range(1, count + 1))
    ids = df.texts(data, "ids", where, nonempty=True)
    for value in ids:
        check_participant_id(value, f"{where}: ids")
    if len(set(ids)) != len(ids):
        raise DataFileError(f"{where}: 'ids' lists a participant twice")
    return ids


def _given_orders(data: dict, where: str, ordering: str, participants, names) -> dict:
    if ordering == "latin":
        if "orders" in data:
            raise DataFileError(f"{where}: [orders] is only read with order = \"given\"")
        return {}
    orders = df.section(data, "orders", where)
    df.check_keys(orders, f"{where} [orders]", required=participants)
    result = {}
    for participant in participants:
        given = df.texts(orders, participant, f"{where} [orders]", choices=names)
        if sorted(given) != sorted(names):
            raise DataFileError(f"{where} [orders]: {participant} must run every condition once, in some order; "
                                f"got {list(given)} for {names}")
        result[participant] = tuple(given)
    return result


def _item(table: dict, where: str) -> Item:
    kind = df.text(table, "kind", where, choices=ITEM_KINDS)
    if kind == "text":
        df.check_keys(table, where, required=("id", "kind", "text"))
        return Item(df.text(table, "id", where), kind, df.text(table, "text", where))
    df.check_keys(table, where, required=("id", "kind", "text", "anchors"), optional=("points",))
    anchors = df.texts(table, "anchors", where, nonempty=True)
    if len(anchors) != 2:
        raise DataFileError(f"{where}: 'anchors' must name the two ends of the scale, e.g. [\"disagree\", "
                            f"\"agree\"], got {list(anchors)}")
    return Item(df.text(table, "id", where), kind, df.text(table, "text", where),
                df.integer(table, "points", where, default=7, low=2, high=11), (anchors[0], anchors[1]))
