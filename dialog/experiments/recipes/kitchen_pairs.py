"""The kitchen-pairs arm of a recipes suite: transfer against the distance between kitchens (issue 52 item 3).

The thesis trains a recipe in some of its three kitchens and tests it in another (§4.4.2, figure 4.8) and
finds no transfer. With many kitchens (``kitchens = { generated = [FIRST, LAST] }``) the question becomes
whether transfer falls with how different two kitchens are (``bullet_world.recipes.distance``, eq. 4.4's spirit):

* single: each kitchen trains (m of its first demonstrations) and is tested in ``tested_in`` other kitchens,
  drawn by seed; parameter match is the share of the test kitchen's demonstrations whose parameter the
  grounding gets right (§4.3.4), averaged over the parameters;
* paired: ``pairs_of_kitchens`` seeded pairs train together (m from each), each tested in ``tested_in`` third
  kitchens; its distance is the nearer training kitchen's;
* executed: ``pair_executions`` single ordered pairs at the largest m, drawn evenly across distance quintiles,
  carried out with the arm in the test kitchen (success: every step done right).

The plan's criterion (docs/kitchen-transfer-plan.toml) is ``analyse``: Spearman's rho of distance against
match with a permutation p that shuffles whole training kitchens, and the match per distance quintile with a
bootstrap band over training kitchens.
"""

from __future__ import annotations

import warnings
from functools import cache

import numpy as np
from scipy.stats import ConstantInputWarning, spearmanr

from bullet_world.recipes.distance import kitchen_distance
from dialog.experiments.kitchens import label
from dialog.recipe_session import recipe_steps
from learning.recipes.format import load_builtin_recipe

QUANTILES = 5


@cache
def distance(recipe: str, first: str, second: str) -> float:
    return kitchen_distance(recipe_steps(load_builtin_recipe(recipe)), recipe, first, second).total


def _rng(job_rng, seed: int, *names) -> np.random.Generator:
    """The suite's per-job generator, kitchens named by their short names (``label``): a generated kitchen's
    draws do not depend on where the cache put its file."""
    return job_rng(seed, *(label(str(name)) for name in names))


def _draw(rng: np.random.Generator, pool: list[str], count: int) -> list[str]:
    return [pool[i] for i in sorted(rng.choice(len(pool), size=min(count, len(pool)), replace=False).tolist())]


def training_sets(study, seed: int, job_rng) -> list[tuple[tuple[str, ...], list[str]]]:
    """(training kitchens, test kitchens) for every single kitchen and every seeded pair; the same draws for
    every recipe and m, so the arms compare like with like."""
    kitchens = list(study.kitchens)
    sets = [((k,), _draw(_rng(job_rng, seed, "tested-in", k), [o for o in kitchens if o != k], study.tested_in))
            for k in kitchens]
    every_pair = [(a, b) for i, a in enumerate(kitchens) for b in kitchens[i + 1:]]
    chosen = _rng(job_rng, seed, "kitchen pairs").choice(len(every_pair), size=min(study.pairs_of_kitchens,
                                                                               len(every_pair)), replace=False)
    for a, b in (every_pair[i] for i in sorted(chosen.tolist())):
        rest = [o for o in kitchens if o not in (a, b)]
        sets.append(((a, b), _draw(_rng(job_rng, seed, "tested-in", a, b), rest, study.tested_in)))
    return sets


def chosen_demos(job_rng, seed: int, recipe: str, kitchen: str, m: int, available: int) -> list[int]:
    return sorted(_rng(job_rng, seed, recipe, "kitchen-pairs", kitchen, m).choice(available, size=m,
                                                                             replace=False).tolist())


def jobs(study, seed: int, recipe: str, demos: dict, job_rng) -> list[dict]:
    """The trial jobs of one recipe: one per training set (every m in it), then the executed pairs."""
    trials = [{"kind": "kitchen-pairs", "seed": seed, "recipe": recipe, "kitchen": "+".join(train),
               "train": train, "tests": tests, "m": study.transfer_m,
               "demos": {k: demos[k][:study.transfer_demos] for k in (*train, *tests)}}
              for train, tests in training_sets(study, seed, job_rng)]
    if not study.pair_executions:
        return trials
    m = max(study.transfer_m)
    singles = [(t["train"][0], test) for t in trials if len(t["train"]) == 1 for test in t["tests"]]
    distances = np.array([distance(recipe, a, b) for a, b in singles])
    rng, picked = _rng(job_rng, seed, recipe, "executions"), []
    # fifths by rank (ties by order), so that every fifth has members however many distances tie
    for q, members in enumerate(np.array_split(np.argsort(distances, kind="stable"), QUANTILES)):
        share = study.pair_executions // QUANTILES + (q < study.pair_executions % QUANTILES)
        picked += sorted(rng.choice(members, size=min(share, len(members)), replace=False).tolist())
    executions = []
    for index in picked:
        a, b = singles[index]
        chosen = chosen_demos(job_rng, seed, recipe, a, m, study.transfer_demos)
        executions.append({"kind": "pair-execution", "seed": seed, "recipe": recipe, "kitchen": b, "train": (a,),
                           "test": b, "m": m, "grasp": study.grasp, "tau": study.tau,
                           "demos": [demos[a][i] for i in chosen]})
    return trials + executions


def run_trials(job: dict, recipe, science, job_rng) -> list[dict]:
    """Every m and test kitchen of one training set: its parameter match, with the distance."""
    rows = []
    for m in job["m"]:
        train = [job["demos"][k][i] for k in job["train"]
                 for i in chosen_demos(job_rng, job["seed"], recipe.name, k, m, len(job["demos"][k]))]
        for test in job["tests"]:
            rng = _rng(job_rng, job["seed"], recipe.name, "kitchen-pairs", *job["train"], test, m)
            rows.append({"m": m, "train": list(job["train"]), "test": test,
                         "distance": min(distance(recipe.name, k, test) for k in job["train"]),
                         "accuracy": science.accuracy(recipe, train, job["demos"][test], rng)})
    return rows


def run_execution(job: dict, recipe, science, job_rng) -> list[dict]:
    """The grounding from the training kitchen carried out once with the arm in the test kitchen."""
    from bullet_world.recipes.world import RecipeWorld

    with RecipeWorld(recipe_steps(recipe), task=recipe.name, kitchen=job["test"], seed=job["seed"]) as world:
        (run,) = science.execution_runs(recipe, world, job["demos"], 1,
                                        _rng(job_rng, job["seed"], recipe.name, "pair-execution", job["train"][0],
                                             job["test"]), job["grasp"], job["tau"])
    return [{**run, "train": list(job["train"]), "test": job["test"], "m": job["m"],
             "distance": distance(recipe.name, job["train"][0], job["test"]),
             "success": all(step["success"] for step in run["steps"])}]


def _quintiles(values: np.ndarray, edges: np.ndarray | None = None) -> np.ndarray:
    edges = np.quantile(values, np.linspace(0, 1, QUANTILES + 1)[1:-1]) if edges is None else edges
    return np.searchsorted(edges, values, side="right")


def analyse(rows: list[dict], m: int, permutations: int, bootstrap: int, rng: np.random.Generator,
            alpha: float = 0.05) -> dict:
    """The plan's criterion on the single ordered pairs at ``m``: Spearman's rho of distance against mean
    parameter match, its one-sided (less) permutation p with whole training kitchens' scores shuffled among
    them, and the mean match per distance quintile with a 95 % bootstrap band over training kitchens. ``rows``
    are ``summary``'s: kitchens by their short names, ``match`` the mean over the recipe's parameters."""
    singles = [r for r in rows if r["m"] == m and len(r["train"]) == 1]
    trainers = sorted({r["train"][0] for r in singles})
    blocks = {k: sorted((r for r in singles if r["train"][0] == k), key=lambda r: r["test"]) for k in trainers}
    size = {len(b) for b in blocks.values()}
    if len(size) != 1:
        raise ValueError(f"every training kitchen needs as many test kitchens, got {sorted(size)}")
    d = np.array([[r["distance"] for r in blocks[k]] for k in trainers])
    match = np.array([[r["match"] for r in blocks[k]] for k in trainers])
    with warnings.catch_warnings():  # a constant column (a few pairs only) has no rho: NaN, never "falls"
        warnings.simplefilter("ignore", ConstantInputWarning)
        rho = float(spearmanr(d.ravel(), match.ravel()).statistic)
        shuffled = np.array([spearmanr(d.ravel(), match[rng.permutation(len(trainers))].ravel()).statistic
                             for _ in range(permutations)])
    p = float((1 + np.sum(shuffled <= rho)) / (1 + permutations))
    edges = np.quantile(d.ravel(), np.linspace(0, 1, QUANTILES + 1)[1:-1])
    bands = np.quantile(d.ravel(), np.linspace(0, 1, QUANTILES + 1))

    def curve(rows_d: np.ndarray, rows_match: np.ndarray) -> np.ndarray:
        q = _quintiles(rows_d.ravel(), edges)
        return np.array([rows_match.ravel()[q == i].mean() if np.any(q == i) else np.nan for i in range(QUANTILES)])

    means, q = curve(d, match), _quintiles(d.ravel(), edges)
    resampled = []
    for _ in range(bootstrap):
        pick = rng.integers(0, len(trainers), len(trainers))
        resampled.append(curve(d[pick], match[pick]))
    with warnings.catch_warnings():  # a quintile no resample reaches (a few pairs only) stays NaN
        warnings.simplefilter("ignore", RuntimeWarning)
        low, high = np.nanquantile(np.array(resampled), [0.025, 0.975], axis=0)
    return {"m": m, "pairs": int(match.size), "training_kitchens": len(trainers), "rho": rho, "p": p,
            "falls": bool(rho < 0 and p < alpha), "edges": bands.tolist(), "means": means.tolist(),
            "low": low.tolist(), "high": high.tolist(),
            "centres": [float(np.mean(d.ravel()[q == i])) if np.any(q == i) else float("nan")
                        for i in range(QUANTILES)]}


PERMUTATIONS, BOOTSTRAP, ALPHA = 10_000, 2_000, 0.05  # fixed by docs/kitchen-transfer-plan.toml [criterion]


def summary(results: dict, recipe: str, study) -> dict:
    """Every row of the arm for ``recipe`` (short kitchen names) and the plan's analysis at each m."""
    rows = [{"m": run["m"], "train": [label(k) for k in run["train"]], "test": label(run["test"]),
             "distance": run["distance"], "match": float(np.mean(list(run["accuracy"].values()))),
             "accuracy": run["accuracy"]}
            for r in results.get("kitchen-pairs", ()) if r["recipe"] == recipe for run in r["runs"]]
    rows.sort(key=lambda r: (r["m"], len(r["train"]), r["train"], r["test"]))  # by name, wherever the files are
    executed = [run for r in results.get("pair-execution", ()) if r["recipe"] == recipe for run in r["runs"]]
    rng = np.random.default_rng(list(map(ord, recipe)))
    analyses = [analyse(rows, m, PERMUTATIONS, BOOTSTRAP, rng, ALPHA) for m in study.transfer_m]
    paired = {m: [r["match"] for r in rows if r["m"] == m and len(r["train"]) == 2] for m in study.transfer_m}
    return {"recipe": recipe, "analyses": analyses,
            "paired": {str(m): {"trials": len(v), "mean": float(np.mean(v)) if v else None} for m, v in paired.items()},
            "rows": rows,
            "executions": [{"train": label(r["train"][0]), "test": label(r["test"]), "m": r["m"],
                            "distance": r["distance"], "success": r["success"],
                            "steps": [s["status"] for s in r["steps"]]} for r in executed]}


def section(results: dict, recipe: str, study, out) -> list[str]:
    """The report's lines for the arm (and ``kitchen-pairs-RECIPE.json``, ``kitchen-pairs-RECIPE.png``)."""
    import json

    data = summary(results, recipe, study)
    (out / f"kitchen-pairs-{recipe}.json").write_text(json.dumps(data, indent=1) + "\n", encoding="utf-8")
    plot(data, out / f"kitchen-pairs-{recipe}.png")
    lines = ["### Transfer against the distance between kitchens (kitchen-pairs)", "",
             f"![match against distance](kitchen-pairs-{recipe}.png)", "",
             "| m | ordered pairs | Spearman rho | permutation p (less) | falls with distance? | match per distance "
             "quintile [95 % band] |", "|---:|---:|---:|---:|---|---|"]
    for a in data["analyses"]:
        cells = "; ".join(f"{lo_d:.1f}-{hi_d:.1f}: {mean:.3f} [{low:.3f}, {high:.3f}]" for lo_d, hi_d, mean, low, high
                          in zip(a["edges"], a["edges"][1:], a["means"], a["low"], a["high"]))
        lines.append(f"| {a['m']} | {a['pairs']} | {a['rho']:.3f} | {a['p']:.4f} | {'yes' if a['falls'] else 'no'} | "
                     f"{cells} |")
    for m, paired in data["paired"].items():
        if paired["trials"]:
            lines.append(f"\nTrained in a pair of kitchens, m = {m} from each: mean match {paired['mean']:.3f} over "
                         f"{paired['trials']} tests (distance: the nearer training kitchen's).")
    if data["executions"]:
        done = [e["success"] for e in data["executions"]]
        lines.append(f"\nCarried out with the arm in the test kitchen: {sum(done)} of {len(done)} ordered pairs "
                     "succeeded (every step right).")
    return lines + [""]


def plot(data: dict, path, elsewhere: dict | None = None) -> None:
    """Match against distance per ordered pair, the quintile curve with its band, the executed pairs, and (when
    given) the recipes suite's elsewhere arm in the shipped three as a grey band."""
    from dialog.experiments.recipes.figures import pyplot

    plt = pyplot()
    figure, axis = plt.subplots(figsize=(7.0, 4.0))
    for a, colour in zip(data["analyses"], ("tab:blue", "tab:red", "tab:green")):
        singles = [r for r in data["rows"] if r["m"] == a["m"] and len(r["train"]) == 1]
        axis.scatter([r["distance"] for r in singles], [r["match"] for r in singles], s=8, alpha=0.35, color=colour)
        axis.plot(a["centres"], a["means"], "-o", color=colour, label=f"m = {a['m']}: rho {a['rho']:.2f}, "
                                                                      f"p {a['p']:.4f}")
        axis.fill_between(a["centres"], a["low"], a["high"], color=colour, alpha=0.2)
    if elsewhere is not None:
        axis.axhspan(*elsewhere["ci"], color="grey", alpha=0.3,
                     label=f"elsewhere arm, shipped kitchens (m = 5): {elsewhere['mean']:.3f}")
    executed = data["executions"]
    if executed:
        axis.scatter([e["distance"] for e in executed], [1.03 if e["success"] else -0.03 for e in executed],
                     marker="|", color="black", label="executed: success (top) / failure (bottom)")
    axis.set_xlabel("distance between kitchens d (locations moved / 0.1 m + roles whose dish differs)")
    axis.set_ylabel("parameter match in the test kitchen")
    axis.set_ylim(-0.06, 1.06)
    axis.grid(alpha=0.3)
    axis.legend(fontsize=8)
    axis.set_title(f"{data['recipe']}: trained in one kitchen, tested in another")
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)
