"""The largest value each size, count and time accepts: ``learning/data/limits.toml``, read here and only here.

Every reader of a setting (the command line, suites, study files, the Gymnasium environment, the library)
checks its value against these maxima before any work starts, so an allocation this machine cannot finish
in a day, or hold in its memory, is refused in one line that names the limit instead of running for days::

    check_limit("turns", 100_000_000, "--turns")
    # SettingsError: --turns: 100000000 is beyond the limit of 10000 turns in one episode (learning/data/limits.toml)
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache
from pathlib import Path

from learning.datafiles import check_keys, number, read_toml, text
from learning.errors import SettingsError, TeachbotError

__all__ = ["LIMITS_FILE", "Limit", "check_limit", "check_questions", "limit", "maximum"]

LIMITS_FILE = Path(__file__).resolve().parent / "data" / "limits.toml"
NAMES = ("turns", "questions", "seconds", "realtime", "budget", "datasets", "seeds", "concepts", "scene_objects",
         "checkpoints", "training_steps", "workers", "weight")


@dataclass(frozen=True)
class Limit:
    """One maximum: its name, the largest value accepted and what it counts (said in the refusal)."""

    name: str
    maximum: float
    what: str

    def refusal(self, label: str, value) -> str:
        shown = f"{value:g}" if isinstance(value, float) else f"{value}"
        return f"{label}: {shown} is beyond the limit of {self.maximum:g} {self.what} (learning/data/limits.toml)"


@cache
def _limits() -> dict[str, Limit]:
    data = read_toml(LIMITS_FILE, "limits")
    check_keys(data, str(LIMITS_FILE), required=NAMES)
    found = {}
    for name in NAMES:
        where = f"{LIMITS_FILE} [{name}]"
        check_keys(data[name], where, required=("maximum", "what"))
        found[name] = Limit(name, number(data[name], "maximum", where, above=0), text(data[name], "what", where))
    return found


def limit(name: str) -> Limit:
    """The limit called ``name`` (one of NAMES)."""
    return _limits()[name]


def maximum(name: str) -> float:
    """The largest value accepted for ``name``; an int when the file gives a whole number."""
    value = limit(name).maximum
    return int(value) if float(value).is_integer() else value


def check_limit(name: str, value, label: str | None = None, error: type[TeachbotError] = SettingsError) -> None:
    """Refuse ``value`` above the limit ``name`` with one ``error`` line naming ``label`` (default: the name)."""
    found = limit(name)
    if value > found.maximum:
        raise error(found.refusal(label or name, value))


def check_questions(turns: int, budget: float, costs: dict) -> None:
    """Refuse an episode that could pay for more questions than the limit: each answered question adds an
    example that every later turn refits on (GP fits grow with the cube of the examples), whereas a quiet turn
    costs little, so the limit is on min(turns, budget / the cheapest question), not on turns alone."""
    prices = [float(cost) for kind, cost in costs.items() if kind != "none"]
    cheapest = min(prices) if prices else 0.0
    questions = turns if cheapest <= 0 else min(turns, int(budget // cheapest))
    found = limit("questions")
    if questions > found.maximum:
        raise SettingsError(f"questions: {turns} turns with a budget of {budget:g} can pay for {questions} questions, "
                            f"beyond the limit of {found.maximum:g} questions in one episode "
                            "(learning/data/limits.toml); give fewer turns or a smaller budget")
