"""The person at the terminal in expert mode: the scene, the candidates with their features, one command a turn.

Commands (case does not matter): ``LQ 4`` (or just ``4``) label object 4; ``DQ fruit`` (or ``DQ 3``) ask for
a demonstration; ``FSQ`` the feature query; ``none`` stay quiet; ``table`` show the scene again; ``help``;
``quit`` (or end of input) ends the session, keeping the turns so far.
"""

from __future__ import annotations

import sys

from rich.console import Console
from rich.table import Table

from dialog.expert.episode import ExpertQuit, ExpertView, action_label
from dialog.language.describe import SceneDescriber
from dialog.teachers.terminal import LineReader
from learning.actions import Action, DemoQuery, FeatureQuery, LabelQuery, NoQuery
from learning.decision.features import label_distribution

SHORT_NAMES = ("ACD", "CDU", "IV", "PM", "budget", "time", "quiet")  # FEATURE_NAMES order
COLUMN_MEANINGS = {  # what each column of the candidates table says, in words (thesis §6.4.2, §7.3.1)
    "command": "what to type to ask this question",
    "question": "the question in words",
    "robot's guess": "the concept the robot thinks the object is, and how sure it is (no guess yet: all tied)",
    "cost": "budget units this question spends",
    "ACD": "classifier discriminability: how well the concept models tell this scene's objects apart",
    "CDU": "class-distribution uniformity: how evenly the examples so far spread over the concepts",
    "IV": "instance variation: how much the objects of the scene differ in what the robot predicts",
    "PM": "prediction margin: how far ahead each object's best concept is of the second best",
    "budget": "budget consumption: the fraction of the question budget spent",
    "time": "remaining time: the fraction of the turns still to come",
    "quiet": "non-query time: how long the robot has stayed quiet (1 after a whole window of silence)",
}
COMMANDS = ("Type one of: LQ <object number> (or just the number), DQ <concept name or number>, FSQ, none, "
            "table (the scene again), help, quit.")
HELP = COMMANDS  # the short form, repeated after a command that cannot be taken
TIE_MARGIN = 1e-6  # the top concepts closer than this: the robot has no guess yet
TABLE_KEY = ("ACD discriminability · CDU class uniformity · IV instance variation · PM prediction margin · "
             "budget spent · time left · quiet time; 'help' explains each")


def help_text() -> str:
    """The commands, and every column of the candidates table explained."""
    lines = [COMMANDS, "Columns (the 'none' row is the next turn if the robot stays quiet: one turn on, quiet "
                       "time up, nothing learned; query rows show each feature's expected change against it; "
                       "all features lie in 0..1):"]
    lines += [f"  {name:<14} {meaning}" for name, meaning in COLUMN_MEANINGS.items()]
    return "\n".join(lines)


def guess_text(probabilities, concepts) -> str:
    """"fruit 0.62" for one object's concept distribution, or "no guess yet" when the top concepts tie."""
    order = sorted(range(len(concepts)), key=lambda i: -float(probabilities[i]))
    if len(order) > 1 and float(probabilities[order[0]]) - float(probabilities[order[1]]) <= TIE_MARGIN:
        return "no guess yet"
    return f"{concepts[order[0]]} {float(probabilities[order[0]]):.2f}"


class ExpertInputError(ValueError):
    """A command that cannot be taken this turn; the message says what is accepted."""


def parse_command(text: str, view: ExpertView) -> Action | str:
    """The action a typed line names, or "help" / "table" / "quit"; ExpertInputError for anything else."""
    words = text.strip().lower().split()
    if not words:
        raise ExpertInputError(f"Nothing typed. {HELP}")
    head, rest = words[0], " ".join(words[1:])
    if head in ("help", "?", "h"):
        return "help"
    if head in ("table", "scene"):
        return "table"
    if head in ("quit", "exit", "q"):
        return "quit"
    candidates = view.candidates.actions
    if head in ("none", "nq", "quiet", "nothing"):
        return NoQuery()
    if head in ("fsq", "feature", "features"):
        if FeatureQuery() not in candidates:
            why = "it was already asked" if view.state.feature_query_asked else "the budget left does not cover it"
            raise ExpertInputError(f"FSQ is not available: {why}.")
        return FeatureQuery()
    if head.isdigit() or head in ("lq", "label"):
        number = head if head.isdigit() else rest
        if not number.isdigit():
            raise ExpertInputError(f"'{text.strip()}': give the object's number, e.g. LQ 4.")
        index, n_objects = int(number) - 1, len(view.state.scene_X)
        if not 0 <= index < n_objects:
            raise ExpertInputError(f"There is no object {number}; this scene has objects 1 to {n_objects}.")
        if LabelQuery(index) not in candidates:
            why = ("it is already labelled in this scene" if index in view.state.labelled_in_scene
                   else "the budget left does not cover a label query")
            raise ExpertInputError(f"LQ {number} is not available: {why}.")
        return LabelQuery(index)
    if head in ("dq", "demo"):
        concepts = view.state.concepts
        if rest.isdigit() and 1 <= int(rest) <= len(concepts):
            concept = concepts[int(rest) - 1]
        else:
            matches = [c for c in concepts if c.startswith(rest)] if rest else []
            if len(matches) != 1:
                raise ExpertInputError(f"'{text.strip()}': name one concept: {', '.join(concepts)} (or 1 to "
                                       f"{len(concepts)}).")
            concept = matches[0]
        if DemoQuery(concept) not in candidates:
            raise ExpertInputError(f"DQ {concept} is not available: the teacher could not show one in this scene or "
                                   "the budget left does not cover it.")
        return DemoQuery(concept)
    raise ExpertInputError(f"'{text.strip()}' is not a command. {HELP}")


class PersonChooser:
    """Shows the scene and the candidates table, reads one command per turn from injected streams."""

    name = "person"

    def __init__(self, input_stream=None, output_stream=None, locations: dict | None = None, viewpoint=None):
        self.reader = LineReader(input_stream if input_stream is not None else sys.stdin)
        self.console = Console(file=output_stream if output_stream is not None else sys.stdout, highlight=False,
                               markup=False, emoji=False, soft_wrap=False, width=160)
        self.locations = locations or {}
        self.viewpoint = viewpoint  # the teacher's (left, right, front, back in the object descriptions)
        self.scene = None

    def say(self, text: str) -> None:
        self.console.print(text)

    def on_scene(self, scene) -> None:
        self.scene = scene
        self.show_scene()

    def show_scene(self) -> None:
        if self.scene is not None:
            for line in SceneDescriber(self.scene, self.locations, self.viewpoint).table_lines():
                self.console.print(f"  {line}")

    def table(self, view: ExpertView) -> Table:
        """Every candidate: its command, cost and the seven expected decision features (queries as change
        against staying quiet)."""
        candidates, state = view.candidates, view.state
        table = Table(title=f"Turn {view.turn} of {state.turns} · budget left {state.remaining_budget:g} of "
                            f"{state.budget:g} · query rows: change of E[phi] against staying quiet",
                      caption=TABLE_KEY, caption_justify="left", title_justify="left", pad_edge=False)
        for column in COLUMN_MEANINGS:
            table.add_column(column, justify="right" if column in ("cost", *SHORT_NAMES) else "left")
        quiet = candidates.expected[candidates.no_query_index]
        Q = label_distribution(state.probabilities()) if len(state.scene_X) else None
        describer = SceneDescriber(self.scene, self.locations, self.viewpoint) if self.scene is not None else None
        for row, action in zip(candidates.expected, candidates.actions):
            guess = ""
            if action.kind == "label":
                command = f"LQ {action.object_index + 1}"
                guess = guess_text(Q[action.object_index], state.concepts)
                what = describer.describe(action.object_index) if describer else action_label(action)
            elif action.kind == "demo":
                command, what = f"DQ {action.concept}", f"show me a {action.concept}"
            elif action.kind == "feature":
                command, what = "FSQ", "which features matter?"
            else:
                command, what = "none", "stay quiet"
            values = (row if action.kind == "none" else row - quiet)[:len(SHORT_NAMES)]  # the thesis's seven
            cells = [f"{v:.3f}" if action.kind == "none" else f"{v:+.3f}" for v in values]
            table.add_row(command, what, guess, f"{state.cost(action):g}", *cells)
        return table

    def choose(self, view: ExpertView) -> Action:
        self.console.print(self.table(view))
        while True:
            self.console.print("expert> ", end="")
            self.console.file.flush()
            line = self.reader.readline()
            if line is None:
                self.console.print()
                raise ExpertQuit("end of input")
            try:
                choice = parse_command(line, view)
            except ExpertInputError as error:
                self.console.print(str(error))
                continue
            if choice == "help":
                self.console.print(help_text())
            elif choice == "table":
                self.show_scene()
                self.console.print(self.table(view))
            elif choice == "quit":
                raise ExpertQuit("quit")
            else:
                return choice
