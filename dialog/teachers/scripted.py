"""The simulated teachers: scripted (seeded imperfections), oracle, replay (the interface: dialog.teachers.protocol).

- :class:`ScriptedTeacher`: an oracle from the hidden ground truth, with a
  mislabel rate, a "don't know" rate, a feature-answer quality and an answer
  delay, all drawn from one seeded generator.
- :class:`ReplayTeacher`: the lines of a recorded transcript, turn by turn.
- ``dialog.teachers.terminal.TerminalTeacher``: a person at the terminal.

Every teacher is a :class:`~dialog.teachers.protocol.Teacher` (``show``, ``listen``, ``tell``); one that
can skip answers on resume is also :class:`~dialog.teachers.protocol.FastForwards`.
"""

from __future__ import annotations

import numpy as np

from dialog.clock import VirtualClock
from dialog.language.questions import Prompt, article
from learning.errors import SettingsError

DELAY_SHAPE = 4.0  # answer delays are gamma-distributed with this shape around the mean


def relevant_feature_indices(prompt: Prompt) -> list[int]:
    """The features that matter for the task: ``Task.relevant_features`` or, without it, every object feature."""
    tree = prompt.feature_tree
    names = tree.feature_names
    if prompt.relevant_features:
        chosen = [names.index(n) for n in prompt.relevant_features if n in names]
        if chosen:
            return chosen
    chosen = [i for i in range(len(names)) if tree.group_of(i).startswith("object")]
    return chosen or list(range(len(names)))


class ScriptedTeacher:
    """An oracle teacher with seeded imperfections.

    mislabel_rate: chance that a label names a wrong concept (and that a
    demonstration shows an object of another concept). dont_know_rate: chance
    of answering "I don't know". feature_quality q in [0, 1]: each relevant
    feature is chosen with probability q, and about (1 - q) x as many irrelevant
    ones are added. The feature answer's quality model (thesis §5.4's partial
    and noisy teachers; all three default to the exact answer): feature_recall r
    names round(r x |relevant|) of the relevant features (at least one, drawn
    at random: a partial answer), feature_noise n adds round(n x |relevant|)
    irrelevant ones (a noisy answer), feature_dont_know_rate is the chance of
    "I don't know" to the feature question. answer_delay: mean seconds per answer (gamma distributed),
    spent on the injected clock; answer_delays: a mean per query kind instead
    (label, demo, feature), as embodied costs set them (dialog/embodied.py).
    """

    def __init__(self, rng: np.random.Generator, mislabel_rate: float = 0.0, dont_know_rate: float = 0.0,
                 feature_quality: float = 1.0, answer_delay: float = 0.0, clock=None,
                 answer_delays: dict | None = None, feature_recall: float = 1.0, feature_noise: float = 0.0,
                 feature_dont_know_rate: float = 0.0):
        for name, value in (("mislabel rate", mislabel_rate), ("don't-know rate", dont_know_rate),
                            ("feature quality", feature_quality), ("feature recall", feature_recall),
                            ("feature noise", feature_noise), ("feature don't-know rate", feature_dont_know_rate)):
            if not 0.0 <= float(value) <= 1.0:
                raise SettingsError(f"{name} must be between 0 and 1, got {value}")
        self.feature_model = {"feature_recall": float(feature_recall), "feature_noise": float(feature_noise),
                              "feature_dont_know_rate": float(feature_dont_know_rate)}
        if self.feature_model != FEATURE_MODEL_EXACT and feature_quality != 1.0:
            raise SettingsError("feature_quality is the older one-number model of the feature answer; give it or "
                                "feature_recall / feature_noise / feature_dont_know_rate, not both")
        if answer_delay < 0:
            raise SettingsError(f"answer delay must be zero or more seconds, got {answer_delay}")
        self.rng = rng
        self.mislabel_rate, self.dont_know_rate = float(mislabel_rate), float(dont_know_rate)
        self.feature_quality, self.answer_delay = float(feature_quality), float(answer_delay)
        self.clock = clock or VirtualClock()
        self.answer_delays = None if answer_delays is None else {k: float(v) for k, v in answer_delays.items()}
        self.heard: list[str] = []
        self.mislabels = 0

    def options(self) -> dict:
        changed = {k: v for k, v in self.feature_model.items() if v != FEATURE_MODEL_EXACT[k]}  # recorded if set
        return {"kind": "scripted", "mislabel_rate": self.mislabel_rate, "dont_know_rate": self.dont_know_rate,
                "feature_quality": self.feature_quality, "answer_delay": self.answer_delay, **changed}

    def show(self, prompt: Prompt) -> None:
        pass

    def tell(self, text: str) -> None:
        self.heard.append(text)
        del self.heard[:-20]

    def listen(self, prompt: Prompt, deadline: float | None) -> str | None:
        text, delay = self.compose(prompt)
        self.clock.sleep(delay)
        return text

    def fast_forward(self, prompt: Prompt) -> None:
        """Draw this question's answer without giving it (keeps the generator in step on resume)."""
        self.compose(prompt)

    def compose(self, prompt: Prompt) -> tuple[str, float]:
        """The answer text and its delay; the generator is used in the same order every time."""
        rng = self.rng
        dont_know = rng.random() < self.dont_know_rate
        wrong = rng.random() < self.mislabel_rate
        mean = self.answer_delay if self.answer_delays is None else \
            self.answer_delays.get(prompt.action.kind, self.answer_delay)
        delay = float(rng.gamma(DELAY_SHAPE, mean / DELAY_SHAPE)) if mean > 0 else 0.0
        if dont_know:
            return "I don't know", delay
        truth = prompt.scene.truth
        kind = prompt.action.kind
        if kind == "label":
            concept = truth.concepts[prompt.action.object_index]
            if wrong and len(prompt.concepts) > 1:
                others = [c for c in prompt.concepts if c != concept]
                concept = others[int(rng.integers(len(others)))]
                self.mislabels += 1
            return article(concept), delay
        if kind == "demo":
            concept = prompt.action.concept
            members = [i for i, c in enumerate(truth.concepts) if (c == concept) != wrong]
            if not members:
                return f"there is no {concept} here", delay
            if wrong:
                self.mislabels += 1
            return f"number {members[int(rng.integers(len(members)))] + 1}", delay
        if kind == "feature":
            if self.feature_model["feature_dont_know_rate"] and rng.random() < self.feature_model[
                    "feature_dont_know_rate"]:
                return "I don't know", delay
            return ", ".join(prompt.feature_tree.numbers_for(self._feature_choice(prompt))), delay
        raise ValueError(f"a scripted teacher cannot answer a '{kind}' question")

    def _feature_choice(self, prompt: Prompt) -> list[int]:
        relevant = relevant_feature_indices(prompt)
        everything = range(len(prompt.feature_tree.feature_names))
        irrelevant = [i for i in everything if i not in set(relevant)]
        if self.feature_model != FEATURE_MODEL_EXACT:
            return self._modelled_feature_choice(relevant, irrelevant)
        keep = [i for i in relevant if self.rng.random() < self.feature_quality]
        if not keep:
            keep = [relevant[int(self.rng.integers(len(relevant)))]]
        extra_rate = (1.0 - self.feature_quality) * len(relevant) / max(len(irrelevant), 1)
        keep += [i for i in irrelevant if self.rng.random() < extra_rate]
        return sorted(keep)

    def _modelled_feature_choice(self, relevant: list[int], irrelevant: list[int]) -> list[int]:
        """A partial (feature_recall) and/or noisy (feature_noise) feature answer, drawn from the teacher's rng."""
        named = max(1, int(round(self.feature_model["feature_recall"] * len(relevant))))
        added = min(len(irrelevant), int(round(self.feature_model["feature_noise"] * len(relevant))))
        keep = [int(i) for i in self.rng.choice(relevant, size=named, replace=False)]
        if added:
            keep += [int(i) for i in self.rng.choice(irrelevant, size=added, replace=False)]
        return sorted(keep)


class OracleTeacher(ScriptedTeacher):
    """A perfect scripted teacher: always right, never unsure, answers at once (or, with embodied costs, after
    its ``answer_delays``)."""

    def __init__(self, rng: np.random.Generator, clock=None, answer_delays: dict | None = None):
        super().__init__(rng, clock=clock, answer_delays=answer_delays)


class ReplayTeacher:
    """Answers with the lines recorded in a transcript, turn by turn; None when a turn's lines run out."""

    def __init__(self, records: list[dict]):
        self.lines = {int(r["turn"]): list(r.get("answer", {}).get("lines", [])) for r in records}
        self.heard: list[str] = []

    def options(self) -> dict:
        return {"kind": "replay"}

    def show(self, prompt: Prompt) -> None:
        pass

    def tell(self, text: str) -> None:
        self.heard.append(text)
        del self.heard[:-20]

    def listen(self, prompt: Prompt, deadline: float | None) -> str | None:
        pending = self.lines.get(prompt.turn, [])
        return pending.pop(0) if pending else None


# the feature answer's quality model (ScriptedTeacher): its defaults are the exact answer
FEATURE_MODEL_EXACT = {"feature_recall": 1.0, "feature_noise": 0.0, "feature_dont_know_rate": 0.0}
SCRIPTED_OPTIONS = ("mislabel_rate", "dont_know_rate", "feature_quality", "answer_delay", *FEATURE_MODEL_EXACT)
