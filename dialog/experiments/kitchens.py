"""Suites over several kitchens (issue 52): how a suite names them, and whether the strategies' ranking holds.

A suite names kitchens as a list of names or kitchen-file paths, or as ``{ generated = [FIRST, LAST], also =
[...] }``: the generator's kitchens of those seeds (``bullet_world.generation.cached_kitchens``, written once to
the cache) and more. A recipes suite trains and tests across them (``[options] kitchens``); an episodes suite
(``kitchens = ...`` at the top) runs once in each (``regress``: ``<results>/kitchen-NAME/``) and ``kitchens.md``
ranks the strategies per kitchen by their mean score at the condition's last checkpoint, with the agreement
across kitchens: Kendall's W (``learning.significance.kendalls_w``).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from learning.errors import DataFileError
from learning.significance import kendalls_w, ranks_high_first

RESAMPLES = 2_000


def kitchen_list(value, where: str, key: str = "kitchens") -> tuple[str, ...]:
    """The kitchens a suite names (see the module doc); a bad value is one ``DataFileError`` line."""
    if isinstance(value, dict):
        unknown = sorted(set(value) - {"generated", "also"})
        seeds = value.get("generated")
        if unknown or not (isinstance(seeds, list) and len(seeds) == 2 and all(
                isinstance(s, int) and not isinstance(s, bool) and s >= 0 for s in seeds) and seeds[0] <= seeds[1]):
            raise DataFileError(f"{where}: '{key}' as a table must be {{ generated = [FIRST, LAST] }} (seeds FIRST "
                                f"<= LAST, whole numbers >= 0), optionally with also = [names], got {value!r}")
        from bullet_world.generation import cached_kitchens

        also = kitchen_list_of_names(value.get("also", []), where, f"{key}.also", empty=True)
        return kitchen_list_of_names([*cached_kitchens(seeds[0], seeds[1]), *also], where, key)
    return kitchen_list_of_names(value, where, key)


def suite_kitchens(table: dict, kind: str, where: str) -> tuple[str, ...]:
    """An episodes suite's top-level ``kitchens``, or none; a bad one is one ``DataFileError`` line."""
    if "kitchens" not in table:
        return ()
    if kind != "episodes":
        raise DataFileError(f"{where}: 'kitchens' runs an episodes suite in each kitchen; a suite of kind '{kind}' "
                            "names one 'kitchen' (a recipes suite lists its kitchens under [options])")
    if "kitchen" in table:
        raise DataFileError(f"{where}: give 'kitchen' (one) or 'kitchens' (a run in each), not both")
    return kitchen_list(table["kitchens"], where)


def kitchen_list_of_names(value, where: str, key: str, empty: bool = False) -> tuple[str, ...]:
    if not isinstance(value, list) or (not value and not empty) or not all(isinstance(v, str) and v for v in value):
        raise DataFileError(f"{where}: '{key}' must be a non-empty list of kitchen names or paths, or "
                            f"{{ generated = [FIRST, LAST] }}, got {value!r}")
    names = [label(v) for v in value]
    if len(set(names)) != len(names):
        twice = sorted({n for n in names if names.count(n) > 1})
        raise DataFileError(f"{where}: '{key}' names a kitchen twice ({', '.join(twice)}; a kitchen file is known by "
                            f"its name without .toml): {value!r}")
    return tuple(value)


def label(kitchen: str) -> str:
    """A kitchen's short name: ``generated-7200`` for a generated file's path, the name of a shipped one."""
    return Path(kitchen).stem if kitchen.endswith(".toml") else kitchen


def rank_agreement(means: dict[str, dict[str, float]], strategies, rng: np.random.Generator,
                   resamples: int = RESAMPLES) -> dict:
    """Per kitchen each strategy's rank by its mean (1 the best; ties share the mean rank), and Kendall's W over
    the kitchens with its bootstrap interval and Friedman's test."""
    kitchens = list(means)
    table = np.array([[means[k][s] for s in strategies] for k in kitchens], dtype=float)
    ranks = np.array([ranks_high_first(row) for row in table])
    agreement = kendalls_w(ranks, rng, resamples) if len(kitchens) >= 2 else {}
    return {"kitchens": kitchens, "strategies": list(strategies), "means": table.tolist(), "ranks": ranks.tolist(),
            **agreement}


def read_replication(folder: Path) -> dict:
    """A ``regress --data-seeds`` run's ``replication.json``."""
    return json.loads((folder / "replication.json").read_text(encoding="utf-8"))


def pooled_means(replication: dict) -> dict[str, dict[str, float]]:
    """{condition: {strategy: mean at its last checkpoint, pooled over the data seeds}} of ``read_replication``."""
    return {c["name"]: {row["strategy"]: row["pooled"]["mean"] for row in c["strategies"]}
            for c in replication["conditions"]}


def write_rankings(suite_name: str, by_condition: dict[str, dict], out: Path, command: str) -> Path:
    """``kitchens.md`` and ``kitchens.json``: per condition the ranks per kitchen and Kendall's W."""
    lines = [f"# `{suite_name}` across kitchens", "", f"Command: `{command}`. Each kitchen's own report is in "
             "`kitchen-NAME/`; a strategy's score is its mean at the condition's last checkpoint (pooled over the "
             "data seeds where there are several), rank 1 the best.", ""]
    for condition, result in by_condition.items():
        lines += [f"## Condition `{condition}`", ""]
        if "w" in result:
            lines += [f"Kendall's W {result['w']:.3f} [95 % CI {result['ci'][0]:.3f}, {result['ci'][1]:.3f}] over "
                      f"{len(result['kitchens'])} kitchens; Friedman chi-squared {result['chi2']:.1f} "
                      f"(df {result['df']}), p {result['p']:.2g}.", ""]
        lines += ["| strategy | " + " | ".join(label(k) for k in result["kitchens"]) + " |",
                  "|---|" + "---:|" * len(result["kitchens"])]
        for j, strategy in enumerate(result["strategies"]):
            cells = [f"{result['ranks'][i][j]:g} ({result['means'][i][j]:.3f})" for i in range(len(result["kitchens"]))]
            lines.append(f"| {strategy} | " + " | ".join(cells) + " |")
        lines.append("")
    path = out / "kitchens.md"
    path.write_text("\n".join(lines), encoding="utf-8")
    (out / "kitchens.json").write_text(json.dumps({"suite": suite_name, "command": command,
                                                   "conditions": by_condition}, indent=1) + "\n", encoding="utf-8")
    return path
