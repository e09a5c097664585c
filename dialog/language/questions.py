"""What the robot says: the question for each action, its details, help texts (thesis §6.3.1, §8.2.5)."""

from __future__ import annotations

import sys
from dataclasses import dataclass, field
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from dialog.environment import KnowsRelevantFeatures, SupportsLocations, SupportsPictures, SupportsViewpoint
from dialog.language.describe import SceneDescriber
from dialog.language.feature_tree import FeatureTree
from learning.actions import Action
from learning.errors import OutputPathError

EXPECTS = {"label": "label", "demo": "demo", "feature": "feature"}


@dataclass
class Prompt:
    """One question as every teacher sees it.

    ``scene`` carries the hidden ground truth, which only scripted teachers may
    read; ``relevant_features`` likewise (the task's features that matter).
    """

    turn: int
    turns: int
    budget_left: float
    action: Action
    text: str
    explanation: str
    scene: object
    concepts: tuple[str, ...]
    details: list[str] = field(default_factory=list)
    picture: str | None = None
    feature_tree: object = None
    description: str = ""
    deadline: float | None = None
    relevant_features: tuple[str, ...] | None = None

    @property
    def expects(self) -> str:
        return EXPECTS[self.action.kind]

    @property
    def object_index(self) -> int | None:
        return getattr(self.action, "object_index", None)


def article(word: str) -> str:
    return f"an {word}" if word[:1].lower() in "aeiou" else f"a {word}"


def label_question(description: str, number: int) -> str:
    return f"What is {description}, number {number}? I'm pointing at it."


def demo_question(concept: str, n_objects: int) -> str:
    return (f"Can you show me {article(concept)}? Tell me its number (1 to {n_objects}), "
            f"or say 'none' if there is no {concept} here.")


def feature_question(concepts) -> str:
    names = ", ".join(concepts[:-1]) + f" and {concepts[-1]}" if len(concepts) > 1 else concepts[0]
    return (f"Which features tell {names} apart? Give the numbers of the groups or features to use, "
            "or start with 'ignore' to name the ones that don't matter.")


def question_text(action: Action, object_number: int | None = None, description: str = "this object",
                  concepts=(), n_objects: int = 0) -> str:
    """The question for ``action`` (empty for no query)."""
    if action.kind == "label":
        return label_question(description, object_number if object_number is not None else action.object_index + 1)
    if action.kind == "demo":
        return demo_question(action.concept, n_objects)
    if action.kind == "feature":
        return feature_question(tuple(concepts) or ("the things",))
    return ""


COMMON_HELP = ("You can also say: 'why' (why I ask), 'undo' (take back your last answer), 'skip' (no answer "
               "this time), 'don't know', 'help', or 'quit' (stop; the session is saved and can be resumed).")


def help_text(prompt: Prompt) -> str:
    """What the teacher may answer to this question."""
    if prompt.expects == "label":
        concepts = ", ".join(f"{i + 1} {c}" for i, c in enumerate(prompt.concepts))
        body = (f"Name what the thing I point at is: one of {concepts}. Synonyms, plurals and small typos "
                "are fine; a number picks from that list.")
    elif prompt.expects == "demo":
        body = ("Give the number of one object that is an example (see the table or the picture), or say "
                "'none' if there is none here.")
    else:
        body = ("Give tree numbers (1.2 chooses a whole group, 1.2.3 one feature), ranges (1.1-1.3), names "
                "('colour, size') or 'all'. Start with 'ignore' to list the ones to leave out instead. "
                "'more 1.2' lists the features of group 1.2 (so does a group's name when only the groups are "
                "shown); 'use 1.2' or '1.2' then chooses it.")
    return f"{body} {COMMON_HELP}"


def acknowledgement(prompt: Prompt, kind: str, value, feature_names=()) -> str:
    """The robot's short reply once an answer is understood."""
    if kind == "answer" and prompt.expects == "label":
        return f"Thanks: number {prompt.object_index + 1} is {article(value)}."
    if kind == "answer" and prompt.expects == "demo":
        return f"Thanks: number {value + 1} is {article(prompt.action.concept)}."
    if kind == "answer" and prompt.expects == "feature":
        return f"Thanks: I'll use {len(value)} of {len(feature_names)} features from now on."
    if kind == "absent":
        return f"All right, there is no {prompt.action.concept} here."
    if kind == "late":
        return "Too late: I had to move on."
    if kind in ("skip", "dont_know"):
        return "All right, let's move on."
    return ""


class Questioner:
    """Builds each question's prompt: text, object table, numbered picture, feature tree."""

    def __init__(self, environment, state, pictures: str | None = None):
        self.env, self.state, self.pictures = environment, state, pictures
        self._tree: FeatureTree | None = None
        self._describer: SceneDescriber | None = None
        self._pictured: set[int] = set()
        self._tabled: set[int] = set()  # scenes whose whole object table the teacher has seen
        # the environment's optional abilities, checked once
        self.locations = environment.locations if isinstance(environment, SupportsLocations) else None
        self.viewpoint = environment.viewpoint if isinstance(environment, SupportsViewpoint) else None
        self.draws_pictures = isinstance(environment, SupportsPictures)
        self.relevant_features = (environment.relevant_features if isinstance(environment, KnowsRelevantFeatures)
                                  else None)

    def feature_tree(self) -> FeatureTree:
        if self._tree is None:
            self._tree = FeatureTree(self.env.feature_names)
        return self._tree

    def describe_fetched(self, x, position) -> str:
        """An object fetched from the pantry in the words the robot uses for any object ("the red round thing
        near the pantry"), from what it measured of it (``x``) and where it stood (``position``, x and y)."""
        row = np.asarray(x, dtype=float).reshape(1, -1)
        names = tuple(self.env.feature_names)
        colour = [row[0, names.index(f"colour.{c}")] if f"colour.{c}" in names else 0.0
                  for c in ("red", "green", "blue")]
        xy = list(position or (0.0, 0.0))[:2]
        one = SimpleNamespace(X=row, feature_names=names, n_objects=1, positions=np.array([[*xy, 0.0]]),
                              colours=np.array([colour]), feature=lambda name: row[:, names.index(name)])
        return SceneDescriber(one, self.locations, self.viewpoint).describe(0, distinct=False)

    def describer(self, scene) -> SceneDescriber:
        if self._describer is None or self._describer.scene is not scene:
            self._describer = SceneDescriber(scene, self.locations, self.viewpoint)
        return self._describer

    def picture(self, scene, number: int, highlight: int | None) -> str | None:
        """Path of the numbered picture (``highlight`` ringed), written by the environment; None without one."""
        if self.pictures is None or not self.draws_pictures:
            return None
        if highlight is None:
            path = Path(self.pictures) / f"scene-{scene.scene_id:03d}.png"
            if scene.scene_id in self._pictured:
                return str(path)
            self._pictured.add(scene.scene_id)
        else:
            path = Path(self.pictures) / f"scene-{scene.scene_id:03d}-turn-{number:03d}-object-{highlight + 1}.png"
        try:
            return str(self.env.scene_picture(scene, path, highlight))
        except OutputPathError as error:  # pictures are optional: one warning, and the session goes on without
            print(f"warning: {error}; going on without scene pictures", file=sys.stderr, flush=True)
            self.pictures = None
            return None

    def prompt(self, scene, action: Action, explanation: str, number: int, deadline: float | None,
               pictures: bool = True) -> Prompt:
        """The prompt for ``action``: a label query shows the whole table once per scene, then its object's row."""
        details, picture, description = [], None, ""
        describer = self.describer(scene)
        if action.kind == "label":
            description = describer.describe(action.object_index)
            text = label_question(description, action.object_index + 1)
            picture = self.picture(scene, number, action.object_index) if pictures else None
            first = scene.scene_id not in self._tabled
            details = describer.table_lines(None if first else [action.object_index])
            self._tabled.add(scene.scene_id)
        elif action.kind == "demo":
            text = demo_question(action.concept, scene.n_objects)
            picture = self.picture(scene, number, None) if pictures else None
            details = describer.table_lines()
            self._tabled.add(scene.scene_id)
        else:
            text = feature_question(self.state.concepts)
            details = self.feature_tree().overview()
        if picture:
            details = [f"Picture: {picture}", *details]
        return Prompt(number, self.state.turns, self.state.remaining_budget, action, text, explanation, scene,
                      self.state.concepts, details, picture,
                      self.feature_tree() if action.kind == "feature" else None, description, deadline,
                      self.relevant_features)
