"""A recipes suite (kind = "recipes"): the chapter-4 experiments in parallel, summaries and finding tests.

A recipes suite's ``strategies`` are the *arms* of the study (``ARMS``), its
conditions are recipes and its checkpoints are numbers of training
demonstrations m. Summaries are ``CheckpointSummary`` rows (condition =
recipe, strategy = arm), so the stored baselines and ``--check`` work as for
episode suites. See ``dialog/suites/recipes.toml`` and docs/recipes.md.

Each trained grounding is one trial, its value the mean accuracy over the
recipe's parameters on held-out demonstrations (thesis §4.3.4); an execution
trial's value is the share of steps carried out correctly. Findings are
one-tailed Mann-Whitney U tests between arms, optionally at different m
(``than_at``) and with a non-inferiority ``margin`` (better + margin > than).
"""

from __future__ import annotations

import os
import zlib
from collections import defaultdict
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, replace

import numpy as np

from bullet_world.catalogue import load_kitchen
from bullet_world.recipes.world import RecipeWorld
from dialog.experiments.analysis import CheckpointSummary, FindingResult
from dialog.experiments.kitchens import kitchen_list
from dialog.experiments.recipes import kitchen_pairs
from dialog.experiments.recipes import study as science
from dialog.experiments.runner import _progress
from dialog.experiments.suite import Suite, SuiteError
from dialog.recipe_session import recipe_steps
from dialog.threads import one_blas_thread
from learning.errors import DataFileError
from learning.recipes.format import load_builtin_recipe
from learning.significance import mann_whitney, mean_and_standard_error
from robot.grasping import GRASP_MODES

ARMS = ("cross-validation", "most-varied", "least-varied", "situated", "elsewhere", "execution", "kitchen-pairs")
OPTIONS = ("recipes", "kitchens", "demos", "cv_repeats", "transfer_demos", "transfer_m", "transfer_repeats",
           "execution_trials", "grasp", "tau", "tested_in", "pairs_of_kitchens", "pair_executions")
DEFAULTS = {"recipes": ["serve-pasta", "serve-salad"], "kitchens": ["kitchen-1", "kitchen-2", "kitchen-3"],
            "demos": 12, "cv_repeats": 12, "transfer_demos": 6, "transfer_m": [2, 5], "transfer_repeats": 10,
            "execution_trials": 0, "grasp": "friction", "tau": 3.0, "tested_in": 5, "pairs_of_kitchens": 0,
            "pair_executions": 0}
COUNTS = ("demos", "cv_repeats", "transfer_demos", "transfer_repeats", "execution_trials", "tested_in",
          "pairs_of_kitchens", "pair_executions")
MAY_BE_ZERO = ("execution_trials", "pairs_of_kitchens", "pair_executions")


@dataclass(frozen=True)
class RecipeStudy:
    """A recipes suite's validated settings."""

    arms: tuple[str, ...]
    recipes: tuple[str, ...]
    kitchens: tuple[str, ...]
    seeds: tuple[int, ...]
    demos: int
    cv_m: tuple[int, ...]
    cv_repeats: int
    transfer_demos: int
    transfer_m: tuple[int, ...]
    transfer_repeats: int
    execution_trials: int
    grasp: str
    tau: float
    tested_in: int = 5            # the kitchen-pairs arm (kitchen_pairs.py): test kitchens per training set,
    pairs_of_kitchens: int = 0    # seeded pairs of training kitchens,
    pair_executions: int = 0      # and single ordered pairs carried out with the arm

    def checkpoints(self, arm: str) -> tuple[int, ...]:
        """The values of m at which ``arm`` is measured."""
        return {"cross-validation": self.cv_m, "most-varied": (2,), "least-varied": (2,), "situated": self.transfer_m,
                "elsewhere": self.transfer_m, "execution": (self.demos,), "kitchen-pairs": self.transfer_m}[arm]

    def runs(self, *arms: str) -> bool:
        return any(arm in self.arms for arm in arms)

    @property
    def collected(self) -> int:
        """Demonstrations per recipe and kitchen: the transfer uses the first ``transfer_demos`` of them."""
        within = self.demos if self.runs("cross-validation", "most-varied", "least-varied", "execution") else 0
        return max(within, self.transfer_demos if self.runs("situated", "elsewhere", "kitchen-pairs") else 0)


def load_study(suite: Suite) -> RecipeStudy:
    """Check a recipes suite's arms, options and findings; a problem is a ``SuiteError`` naming the file."""
    where = suite.path or suite.name
    unknown = sorted(set(suite.options) - set(OPTIONS))
    if unknown:
        raise SuiteError(f"{where} [options]: unknown option '{unknown[0]}'; accepted: {', '.join(OPTIONS)}")
    bad_arms = [arm for arm in suite.strategies if arm not in ARMS]
    if bad_arms:
        raise SuiteError(f"{where}: unknown arms {bad_arms} in 'strategies'; a recipes suite accepts: "
                         f"{', '.join(ARMS)}")
    options = {**DEFAULTS, **suite.options}
    counts = {key: _whole(options, key, where) for key in COUNTS}
    lists = {"recipes": _names(options, "recipes", where), "kitchens": _kitchens(options, where)}
    study = RecipeStudy(
        arms=tuple(suite.strategies), recipes=lists["recipes"], kitchens=lists["kitchens"], seeds=tuple(suite.seeds),
        demos=counts["demos"], cv_m=_ms(suite.checkpoints, "checkpoints", where), cv_repeats=counts["cv_repeats"],
        transfer_demos=counts["transfer_demos"], transfer_m=_ms(options["transfer_m"], "transfer_m", where),
        transfer_repeats=counts["transfer_repeats"], execution_trials=counts["execution_trials"],
        grasp=str(options["grasp"]), tau=float(options["tau"]), tested_in=counts["tested_in"],
        pairs_of_kitchens=counts["pairs_of_kitchens"], pair_executions=counts["pair_executions"])
    _check_values(study, where)
    _check_findings(suite, study, where)
    return study


def _whole(options: dict, key: str, where: str) -> int:
    value = options[key]
    least = 0 if key in MAY_BE_ZERO else 1
    if not isinstance(value, int) or isinstance(value, bool) or value < least:
        raise SuiteError(f"{where} [options]: '{key}' must be a whole number >= {least}, got {value!r}")
    return value


def _names(options: dict, key: str, where: str) -> tuple[str, ...]:
    value = options[key]
    if not isinstance(value, list) or not value or not all(isinstance(v, str) for v in value):
        raise SuiteError(f"{where} [options]: '{key}' must be a non-empty list of names, got {value!r}")
    return tuple(value)


def _kitchens(options: dict, where: str) -> tuple[str, ...]:
    """The suite's kitchens (``dialog.experiments.kitchens.kitchen_list``: names, paths or a generator seed range)."""
    try:
        return kitchen_list(options["kitchens"], f"{where} [options]")
    except DataFileError as error:
        raise SuiteError(str(error)) from None


def _ms(values, key: str, where: str) -> tuple[int, ...]:
    if not isinstance(values, (list, tuple)) or not values or not all(
            isinstance(v, int) and not isinstance(v, bool) and v >= 1 for v in values):
        raise SuiteError(f"{where}: '{key}' must be a non-empty list of whole numbers >= 1 (demonstrations m), "
                         f"got {values!r}")
    return tuple(sorted(set(values)))


def _check_values(study: RecipeStudy, where: str) -> None:
    for recipe in study.recipes:
        try:
            load_builtin_recipe(recipe)
        except ValueError as error:
            raise SuiteError(f"{where} [options] recipes: {error}") from None
    for kitchen in study.kitchens:
        try:
            load_kitchen(kitchen)
        except (ValueError, FileNotFoundError) as error:
            raise SuiteError(f"{where} [options] kitchens: {error}") from None
    if study.grasp not in GRASP_MODES:
        raise SuiteError(f"{where} [options]: grasp '{study.grasp}' is not one of {', '.join(GRASP_MODES)}")
    if not np.isfinite(study.tau) or study.tau <= 0:
        raise SuiteError(f"{where} [options]: 'tau' must be a positive number, got {study.tau}")
    if study.runs("cross-validation") and max(study.cv_m) >= study.demos:
        raise SuiteError(f"{where}: checkpoints (m) must lie in 1..{study.demos - 1} with demos = {study.demos} "
                         f"(one demonstration at least is held out), got {list(study.cv_m)}")
    if study.runs("most-varied", "least-varied") and study.demos < 3:
        raise SuiteError(f"{where} [options]: the varied-pairs arms train on pairs and test on the rest; "
                         f"they need demos >= 3, got {study.demos}")
    if study.runs("situated", "elsewhere"):
        if len(study.kitchens) < 2:
            raise SuiteError(f"{where} [options]: transfer between kitchens needs at least two kitchens, "
                             f"got {list(study.kitchens)}")
        if max(study.transfer_m) >= study.transfer_demos:
            raise SuiteError(f"{where} [options]: 'transfer_m' must lie in 1..{study.transfer_demos - 1} with "
                             f"transfer_demos = {study.transfer_demos}, got {list(study.transfer_m)}")


def _check_findings(suite: Suite, study: RecipeStudy, where: str) -> None:
    for finding in suite.findings:
        here = f"{where} finding '{finding.id}'"
        if finding.condition not in study.recipes:
            raise SuiteError(f"{here}: condition '{finding.condition}' must be one of the suite's recipes "
                             f"{list(study.recipes)}")
        for arm, at in ((finding.better, finding.at), *((t, finding.than_at or finding.at) for t in finding.than)):
            if at not in study.checkpoints(arm):
                raise SuiteError(f"{here}: arm '{arm}' is measured at m = {list(study.checkpoints(arm))}, not {at}")


# ---------------------------------------------------------------------------------------------- running
def job_rng(seed: int, *names) -> np.random.Generator:
    """One generator per job, from the suite's seed and the job's identity (not from the order of running)."""
    return np.random.default_rng([seed, *(zlib.crc32(str(name).encode()) for name in names)])


def run_job(job: dict) -> dict:
    """One unit of work in a worker process: collect demonstrations (and execute), or evaluate groundings."""
    recipe = load_builtin_recipe(job["recipe"])
    seed, kind = job["seed"], job["kind"]
    with one_blas_thread():
        if kind == "collect":
            with RecipeWorld(recipe_steps(recipe), task=recipe.name, kitchen=job["kitchen"], seed=seed) as world:
                demos = world.demonstrate(job["count"], science.demonstration_rng(seed))
                executions = science.execution_runs(
                    recipe, world, demos[:job["execution_m"]], job["trials"], job_rng(seed, recipe.name,
                    job["kitchen"], "execution"), job["grasp"], job["tau"]) if job["trials"] else []
            return {**job, "demos": demos, "runs": executions}
        if kind in ("kitchen-pairs", "pair-execution"):
            run = kitchen_pairs.run_trials if kind == "kitchen-pairs" else kitchen_pairs.run_execution
            return {**{k: v for k, v in job.items() if k != "demos"}, "runs": run(job, recipe, science, job_rng)}
        if kind == "cv":
            runs = science.cross_validation_runs(recipe, job["demos"], job["m"], job["repeats"],
                                                 job_rng(seed, recipe.name, job["kitchen"], "cv"))
        elif kind == "pairs":
            runs = science.pair_runs(recipe, job["demos"], job_rng(seed, recipe.name, job["kitchen"], "pairs"))
        else:
            runs = science.transfer_runs(recipe, job["demos"], [job["m"]], job["repeats"],
                                         job_rng(seed, recipe.name, job["kitchen"], "transfer", job["m"]),
                                         test_kitchens=[job["kitchen"]])
    return {**{k: v for k, v in job.items() if k != "demos"}, "runs": runs}


def _run_all(jobs: list[dict], workers: int, advance) -> list[dict]:
    """Results in the order of ``jobs`` (so the outcome never depends on scheduling)."""
    results: list[dict | None] = [None] * len(jobs)
    if workers == 1:
        for index, job in enumerate(jobs):
            results[index] = run_job(job)
            advance(_label(job))
        return results
    with ProcessPoolExecutor(max_workers=workers) as pool:
        futures = {pool.submit(run_job, job): index for index, job in enumerate(jobs)}
        for future in as_completed(futures):
            index = futures[future]
            results[index] = future.result()
            advance(_label(jobs[index]))
    return results


def _label(job: dict) -> str:
    return f"{job['kind']} {job['recipe']} {job['kitchen']}" + (f" m={job['m']}" if job["kind"] == "transfer" else "")


def run_recipe_suite(study: RecipeStudy, workers: int | None = None, progress: bool = True) -> dict:
    """Every trial of the study: {"collect": [...], "cv": [...], "pairs": [...], "transfer": [...]} job results."""
    workers = max(1, workers or os.cpu_count() or 1)
    collect = [{"kind": "collect", "seed": seed, "recipe": recipe, "kitchen": kitchen, "count": study.collected,
                "trials": study.execution_trials if study.runs("execution") else 0, "execution_m": study.demos,
                "grasp": study.grasp, "tau": study.tau}
               for seed in study.seeds for recipe in study.recipes for kitchen in study.kitchens]
    with _progress(len(collect), progress, "collections") as advance:
        collected = _run_all(collect, min(workers, len(collect)), advance)
    demos = {(c["seed"], c["recipe"], c["kitchen"]): c["demos"] for c in collected}
    jobs = []
    for (seed, recipe, kitchen), shown in demos.items():
        within = shown[:study.demos]
        if study.runs("cross-validation"):
            jobs.append({"kind": "cv", "seed": seed, "recipe": recipe, "kitchen": kitchen, "demos": within,
                         "m": study.cv_m, "repeats": study.cv_repeats})
        if study.runs("most-varied", "least-varied"):
            jobs.append({"kind": "pairs", "seed": seed, "recipe": recipe, "kitchen": kitchen, "demos": within})
        if study.runs("situated", "elsewhere"):
            every = {k: demos[(seed, recipe, k)][:study.transfer_demos] for k in study.kitchens}
            jobs += [{"kind": "transfer", "seed": seed, "recipe": recipe, "kitchen": kitchen, "demos": every, "m": m,
                      "repeats": study.transfer_repeats} for m in study.transfer_m]
        if study.runs("kitchen-pairs") and kitchen == study.kitchens[0]:  # one set of jobs a recipe and seed
            every = {k: demos[(seed, recipe, k)] for k in study.kitchens}
            jobs += kitchen_pairs.jobs(study, seed, recipe, every, job_rng)
    jobs.sort(key=lambda job: -_cost(job))  # longest first: the pool ends together
    with _progress(len(jobs), progress, "trials") as advance:
        done = _run_all(jobs, min(workers, max(1, len(jobs))), advance)
    grouped: dict[str, list[dict]] = {"collect": [{k: v for k, v in c.items() if k != "demos"} for c in collected],
                                      "cv": [], "pairs": [], "transfer": [], "kitchen-pairs": [],
                                      "pair-execution": []}
    for result in sorted(done, key=lambda r: (r["seed"], r["recipe"], r["kitchen"], r.get("m") if r["kind"] ==
                                              "transfer" else 0)):
        grouped[result["kind"]].append(result)
    return grouped


def _cost(job: dict) -> float:
    if job["kind"] == "pair-execution":
        return 400.0
    if job["kind"] == "kitchen-pairs":
        return sum(job["m"]) * len(job["train"]) * len(job["tests"])
    if job["kind"] == "transfer":
        return job["m"] * job["repeats"] * 3
    if job["kind"] == "cv":
        return sum(job["m"]) * job["repeats"] / 4
    return len(job["demos"]) ** 2 / 2


def trial_count(results: dict) -> int:
    """Groundings trained and tested, plus recipes carried out with the arm."""
    return sum(len(r["runs"]) for kind in ("collect", "cv", "pairs", "transfer", "kitchen-pairs", "pair-execution")
               for r in results.get(kind, ()))


# ------------------------------------------------------------------------------------ summaries, findings
def run_mean(run: dict) -> float:
    return float(np.mean(list(run["accuracy"].values())))


def summarise_study(results: dict, study: RecipeStudy) -> list[CheckpointSummary]:
    """One ``CheckpointSummary`` per (recipe, arm); rows are trials, columns the arm's values of m."""
    summaries = []
    for recipe in study.recipes:
        per_arm: dict[str, dict[tuple, dict[int, float]]] = defaultdict(lambda: defaultdict(dict))
        for result in (r for r in results["cv"] if r["recipe"] == recipe):
            for run in result["runs"]:
                per_arm["cross-validation"][(result["seed"], result["kitchen"], run["repeat"])][run["m"]] = \
                    run_mean(run)
        for result in (r for r in results["pairs"] if r["recipe"] == recipe):
            least, most = science.varied_thirds(result["runs"])
            for arm, runs in (("least-varied", least), ("most-varied", most)):
                for run in runs:
                    per_arm[arm][(result["seed"], result["kitchen"], run["pair"])][2] = run_mean(run)
        for result in (r for r in results["transfer"] if r["recipe"] == recipe):
            for run in result["runs"]:
                arm = "situated" if run["situated"] else "elsewhere"
                key = (result["seed"], run["test"], tuple(run["train"]), run["repeat"])
                per_arm[arm][key][run["m"]] = run_mean(run)
        for result in (r for r in results.get("kitchen-pairs", ()) if r["recipe"] == recipe):
            for run in result["runs"]:
                key = (result["seed"], tuple(run["train"]), run["test"])
                per_arm["kitchen-pairs"][key][run["m"]] = run_mean(run)
        for result in (r for r in results["collect"] if r["recipe"] == recipe):
            for run in result["runs"]:
                per_arm["execution"][(result["seed"], result["kitchen"], run["trial"])][run["m"]] = \
                    run["success_rate"]
        for arm in (a for a in ARMS if a in study.arms and per_arm.get(a)):
            checkpoints = study.checkpoints(arm)
            values = np.array([[row.get(m, np.nan) for m in checkpoints] for row in per_arm[arm].values()])
            mean, error = mean_and_standard_error(values)
            summaries.append(CheckpointSummary(recipe, arm, checkpoints, mean, error, values))
    return summaries


def evaluate_recipe_findings(summaries: list[CheckpointSummary], suite: Suite) -> list[FindingResult]:
    """One-tailed Mann-Whitney U per finding: ``better`` at ``at`` (+ margin) against each ``than`` at
    ``than_at`` (default ``at``). The comparison reports the arms' own means (without the margin)."""
    lookup = {(s.condition, s.strategy): s for s in summaries}
    outcomes = []
    for finding in suite.findings:
        than_at = finding.than_at or finding.at
        arms = [(finding.better, finding.at), *((other, than_at) for other in finding.than)]
        missing = [f"{arm} at m = {m}" for arm, m in arms if _column(lookup, finding.condition, arm, m) is None]
        if missing:
            outcomes.append(FindingResult(finding, (), f"no trials of {', '.join(missing)} in {finding.condition}"))
            continue
        better = _column(lookup, finding.condition, finding.better, finding.at)
        comparisons = []
        for other in finding.than:
            values = _column(lookup, finding.condition, other, than_at)
            test = mann_whitney(f"{finding.better} m={finding.at}", better + finding.margin,
                                f"{other} m={than_at}", values, finding.alternative)
            comparisons.append(replace(test, mean_a=float(np.mean(better))))
        outcomes.append(FindingResult(finding, tuple(comparisons)))
    return outcomes


def _column(lookup: dict, recipe: str, arm: str, m: int) -> np.ndarray | None:
    summary = lookup.get((recipe, arm))
    if summary is None or m not in summary.checkpoints:
        return None
    values = summary.values[:, summary.checkpoints.index(m)]
    return values[np.isfinite(values)]
