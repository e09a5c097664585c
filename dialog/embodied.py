"""Embodied query costs (thesis §8.2.2): what each part of a turn takes, in seconds, from two data files.

``dialog/data/embodied-costs.toml`` holds the durations set by hand (the arm's joint speed, saying each
question, the teacher's expected answer time per query kind, a quiet turn), each documented there;
``dialog/data/pointing-time.toml`` holds the motion-time models measured on the real arm by
``scripts/fit_motion_time.py``: seconds = sum_k c_k term_k(distance, |bearing|) with non-negative
coefficients (so a farther object, or one more to the side, never takes less), clipped to the measured
range; one from rest (the first gesture in a scene) and one from the object pointed at last (the arm
does not rest between gestures within a scene), on the differences of the two objects' distances and
bearings; plus the measured mean seconds of a pantry fetch, with its provenance.

:class:`EmbodiedCosts` turns a scene's measured ``location.robot.distance`` and ``location.robot.bearing``
into each object's expected pointing seconds, and makes the learner's
:class:`~learning.decision.embodied.SecondsClock` every turn.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from learning.datafiles import check_keys, number, numbers, read_toml, section, texts
from learning.decision.embodied import SecondsClock
from learning.errors import DataFileError
from learning.strategies import TURNS_SUFFIX  # NAME+turns itself is decoded by make_strategy

DATA = Path(__file__).resolve().parent / "data"
COSTS_FILE = DATA / "embodied-costs.toml"
POINTING_FILE = DATA / "pointing-time.toml"
DISTANCE, BEARING = "location.robot.distance", "location.robot.bearing"
QUERY_KINDS = ("label", "demo", "feature")
# The motion model's terms, by name: d = distance (m), b = |bearing| (rad).
TERMS = {
    "1": lambda d, b: np.ones_like(d),
    "distance": lambda d, b: d,
    "abs_bearing": lambda d, b: b,
    "distance^2": lambda d, b: d * d,
    "abs_bearing^2": lambda d, b: b * b,
    "distance*abs_bearing": lambda d, b: d * b,
}


def term_matrix(names, distance, abs_bearing) -> np.ndarray:
    """(n, len(names)) the motion model's terms of each (distance, |bearing|)."""
    d, b = np.asarray(distance, dtype=float), np.asarray(abs_bearing, dtype=float)
    return np.stack([TERMS[name](d, b) for name in names], axis=-1)


@dataclass(frozen=True)
class PointingModel:
    """seconds = coefficients . terms(distance, |bearing|), distance and |bearing| clipped to the measured range."""

    terms: tuple[str, ...]
    coefficients: tuple[float, ...]
    distance_range: tuple[float, float]
    bearing_range: tuple[float, float]  # of |bearing|
    joint_speed: float

    def seconds(self, distance, bearing) -> np.ndarray:
        d = np.clip(np.asarray(distance, dtype=float), *self.distance_range)
        b = np.clip(np.abs(np.asarray(bearing, dtype=float)), *self.bearing_range)
        return np.maximum(term_matrix(self.terms, d, b) @ np.asarray(self.coefficients), 0.0)


@dataclass(frozen=True)
class EmbodiedCosts:
    """The durations of embodied query costs (seconds) and the pointing-time model."""

    joint_speed: float
    speaking: dict
    answer: dict
    quiet: float
    fetch: float
    pointing: PointingModel
    turn_length: float = 10.0  # a nominal turn's seconds: the world changes every change_every of them
    onward: PointingModel | None = None  # from the previously pointed object (None: always from rest)

    def scene_seconds(self, change_every: int) -> float:
        """With embodied costs a new scene comes every ``change_every`` nominal turns, in seconds."""
        return change_every * self.turn_length

    def turn_seconds(self) -> dict[str, float]:
        """Each kind's expected seconds apart from the arm: saying the question and the answer; a quiet turn."""
        return {**{kind: self.speaking[kind] + self.answer[kind] for kind in QUERY_KINDS}, "none": self.quiet}

    def pointing_seconds(self, X: np.ndarray, feature_names, last: int | None = None) -> np.ndarray:
        """Each scene object's expected pointing seconds from its measured distance and bearing to the robot:
        from rest, or (``last``) from above scene object ``last``, where the arm pointed last."""
        names = list(feature_names)
        missing = [name for name in (DISTANCE, BEARING) if name not in names]
        if missing:
            raise DataFileError(f"embodied costs need the features {', '.join(missing)} in every scene")
        X = np.asarray(X, dtype=float)
        distance, bearing = X[:, names.index(DISTANCE)], X[:, names.index(BEARING)]
        if last is None or self.onward is None:
            return self.pointing.seconds(distance, bearing)
        return self.onward.seconds(np.abs(distance - distance[last]), np.abs(bearing - bearing[last]))

    def clock(self, allocation: float, elapsed: float, pointing: np.ndarray, can_fetch: bool) -> SecondsClock:
        return SecondsClock(float(allocation), float(elapsed), self.turn_seconds(), pointing,
                            self.fetch if can_fetch else 0.0)

    def record(self) -> dict:
        """What a transcript header keeps of the model (to tell runs apart)."""
        return {"joint_speed": self.joint_speed, "speaking": dict(self.speaking), "answer": dict(self.answer),
                "quiet": self.quiet, "fetch": self.fetch, "pointing": list(self.pointing.coefficients),
                "pointing_onward": None if self.onward is None else list(self.onward.coefficients),
                "turn_seconds": self.turn_length}


def _kinds(table: dict, key: str, where: str) -> dict[str, float]:
    part, here = section(table, key, where), f"{where} [{key}]"
    check_keys(part, here, required=QUERY_KINDS)
    return {kind: number(part, kind, here, low=0.0) for kind in QUERY_KINDS}


MODEL_FIELDS = ("terms", "coefficients", "distance_range", "bearing_range", "joint_speed")
MODEL_FIGURES = ("n", "seconds_range", "rms_residual_seconds", "max_abs_residual_seconds", "r_squared",
                 "held_out_kitchen_rms_seconds")  # how well it fits: recorded, not used


def load_pointing_model(path: str | Path = POINTING_FILE) -> tuple[PointingModel, float]:
    """The motion-time model from rest and the mean pantry-fetch seconds of ``pointing-time.toml``."""
    models, fetch = load_pointing_models(path)
    return models[0], fetch


def load_pointing_models(path: str | Path = POINTING_FILE) -> tuple[tuple[PointingModel, PointingModel], float]:
    """The models from rest ([model]) and from the previous object ([from_previous]), and the fetch seconds."""
    where = str(path)
    table = read_toml(path, "pointing-time model")
    check_keys(table, where, required=("model", "from_previous", "fetch", "provenance"))
    models = (_pointing_table(table, "model", where), _pointing_table(table, "from_previous", where))
    fetch, here_fetch = section(table, "fetch", where), f"{where} [fetch]"
    check_keys(fetch, here_fetch, required=("mean_seconds",), optional=("n", "sd_seconds"))
    return models, number(fetch, "mean_seconds", here_fetch, low=0.0)


def _pointing_table(table: dict, name: str, where: str) -> PointingModel:
    model, here = section(table, name, where), f"{where} [{name}]"
    check_keys(model, here, required=MODEL_FIELDS, optional=MODEL_FIGURES)
    terms = texts(model, "terms", here, nonempty=True)
    unknown = [t for t in terms if t not in TERMS]
    if unknown:
        raise DataFileError(f"{here}: unknown terms {unknown}; accepted: {', '.join(TERMS)}")
    coefficients = numbers(model, "coefficients", here, length=len(terms), low=0.0)
    ranges = [numbers(model, key, here, length=2, low=0.0) for key in ("distance_range", "bearing_range")]
    for key, (low, high) in zip(("distance_range", "bearing_range"), ranges):
        if low > high:
            raise DataFileError(f"{here}: '{key}' must be [low, high] with low <= high, got [{low}, {high}]")
    return PointingModel(tuple(terms), tuple(float(c) for c in coefficients), tuple(ranges[0]), tuple(ranges[1]),
                         number(model, "joint_speed", here, above=0.0))


@lru_cache(maxsize=4)
def load_embodied_costs(costs_path: str | Path = COSTS_FILE,
                        pointing_path: str | Path = POINTING_FILE) -> EmbodiedCosts:
    """Both data files, checked field by field; the model must have been measured at the arm's joint speed."""
    where = str(costs_path)
    table = read_toml(costs_path, "embodied costs")
    check_keys(table, where, required=("arm", "speaking", "answer", "quiet", "allocation", "world"))
    arm, quiet, world = section(table, "arm", where), section(table, "quiet", where), section(table, "world", where)
    check_keys(world, f"{where} [world]", required=("turn_seconds",))
    check_keys(arm, f"{where} [arm]", required=("joint_speed",))
    check_keys(quiet, f"{where} [quiet]", required=("seconds",))
    joint_speed = number(arm, "joint_speed", f"{where} [arm]", above=0.0)
    (pointing, onward), fetch = load_pointing_models(pointing_path)
    for model in (pointing, onward):
        if abs(model.joint_speed - joint_speed) > 1e-9:
            raise DataFileError(f"{pointing_path}: the pointing-time model was measured at a joint speed of "
                                f"{model.joint_speed:g} rad/s, {where} sets {joint_speed:g}; refit it with "
                                "scripts/fit_motion_time.py")
    return EmbodiedCosts(joint_speed, _kinds(table, "speaking", where), _kinds(table, "answer", where),
                         number(quiet, "seconds", f"{where} [quiet]", above=0.0), fetch, pointing,
                         number(world, "turn_seconds", f"{where} [world]", above=0.0), onward)


def strategy_names_with_variants(names) -> tuple[str, ...]:
    """The strategy names and, for every DT one, its ``NAME+turns`` variant (DT that ignores embodied costs)."""
    return (*names, *(f"{n}{TURNS_SUFFIX}" for n in names if str(n).startswith("dt")))


def default_allocation(path: str | Path = COSTS_FILE) -> float:
    """The seconds allocation of ``--embodied-costs`` without ``--time Ns`` ([allocation] default_seconds)."""
    where = str(path)
    table = read_toml(path, "embodied costs")
    part = section(table, "allocation", where)
    check_keys(part, f"{where} [allocation]", required=("default_seconds",))
    return number(part, "default_seconds", f"{where} [allocation]", above=0.0)
