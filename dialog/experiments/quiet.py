"""Quiet turns with budget left, and for DT what made staying quiet win (issue 39: a stall you can see).

A turn is *quiet with budget left* when the strategy asked nothing although the budget still covered its
cheapest query. For a utility-based strategy (DT) each decision carries its terms w_f * (E[f | a*] -
E[f | no query]) per weighted feature (``learning.decision.reasons.utility_terms``; the episode keeps them in
``decision_terms``); their mean over the quiet turns says which feature kept it quiet and by how much.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from learning.actions import DEFAULT_COSTS

SHORT_NAMES = {"classifier_discriminability": "ACD", "class_distribution_uniformity": "CDU",
               "instance_variation": "IV", "prediction_margin": "PM", "budget_consumption": "budget",
               "remaining_time": "time", "non_query_time": "non-query time"}


@dataclass(frozen=True)
class QuietSummary:
    """Quiet turns with budget left over a group of episodes (one strategy in one condition)."""

    episodes: int
    quiet: int  # quiet turns with budget left, all episodes together
    turns: int  # turns played, all episodes together
    terms: dict[str, float]  # mean term per feature over the quiet turns whose decision had terms
    with_terms: int  # how many of the quiet turns had terms (DT: all but those with nothing to choose from)

    @property
    def per_episode(self) -> float:
        return self.quiet / max(self.episodes, 1)

    @property
    def share(self) -> float:
        return self.quiet / max(self.turns, 1)


def quiet_with_budget_left(series: dict, budget: float, costs: dict) -> list[int]:
    """Indexes of the turns on which nothing was asked while the budget left before the turn covered the
    cheapest query (``costs``: the episode's cost table; missing kinds cost as ``DEFAULT_COSTS``)."""
    cheapest = min(float(costs.get(kind, DEFAULT_COSTS[kind])) for kind in ("label", "demo", "feature"))
    questions, spent = series["questions"], series["spent"]
    quiet = []
    for i in range(len(questions)):
        asked_before, spent_before = (questions[i - 1], spent[i - 1]) if i else (0, 0.0)
        if questions[i] == asked_before and budget - spent_before >= cheapest - 1e-9:
            quiet.append(i)
    return quiet


def summarise_quiet(group: list[dict]) -> QuietSummary:
    """The quiet turns with budget left of every episode in ``group`` (results of ``run_episode``)."""
    quiet = turns = with_terms = 0
    sums: dict[str, float] = {}
    for result in group:
        spec, series = result["spec"], result["series"]
        indexes = quiet_with_budget_left(series, float(spec["condition"]["budget"]), dict(spec["costs"]))
        quiet, turns = quiet + len(indexes), turns + len(series["turn"])
        per_turn = result.get("decision_terms") or []
        for i in indexes:
            terms = per_turn[i] if i < len(per_turn) else {}
            if terms:
                with_terms += 1
                for name, value in terms.items():
                    sums[name] = sums.get(name, 0.0) + value
    means = {name: total / with_terms for name, total in sums.items()} if with_terms else {}
    return QuietSummary(len(group), quiet, turns, means, with_terms)


def terms_in_words(summary: QuietSummary) -> str:
    """"CDU -0.0125, ACD +0.0055 (107 turns)": the mean term of each feature, the largest in size first."""
    if not summary.with_terms:
        return "–"
    ordered = sorted(summary.terms.items(), key=lambda item: -abs(item[1]))
    cells = ", ".join(f"{SHORT_NAMES.get(name, name)} {value:+.2g}" for name, value in ordered)
    return f"{cells}; sum {sum(summary.terms.values()):+.2g} ({summary.with_terms} turns)"


def quiet_table(groups: dict, condition: str, strategies: list[str]) -> list[str]:
    """Markdown lines: per strategy of ``condition`` its quiet turns with budget left and what kept DT quiet."""
    lines = ["Quiet turns with budget left (the budget still covered the cheapest question): per episode, share of "
             "all turns, and for DT the mean term w_f (E[f | best question] - E[f | no question]) of each "
             "weighted feature over those turns (negative: it spoke for staying quiet; the terms sum to "
             "EU(best question) - EU(no question)):", "",
             "| strategy | quiet with budget left, per episode | share of turns | what kept it quiet (mean terms) |",
             "|---|---:|---:|---|"]
    for strategy in strategies:
        group = groups.get((condition, strategy))
        if not group:
            continue
        summary = summarise_quiet(group)
        lines.append(f"| {strategy} | {summary.per_episode:.1f} | {summary.share:.0%} | {terms_in_words(summary)} |")
    return lines


def quiet_cells(group: list[dict]) -> dict:
    """The quiet turns with budget left of ``group`` as data (the replication summary's JSON)."""
    summary = summarise_quiet(group)
    return {"quiet_per_episode": summary.per_episode, "quiet_share": summary.share,
            "quiet_terms": {name: float(np.round(value, 8)) for name, value in summary.terms.items()},
            "quiet_turns_with_terms": summary.with_terms}


def quiet_columns(result: dict) -> tuple[int, str]:
    """One episode's quiet turns with budget left and its mean terms on them ("feature=+0.0067;..."; empty for a
    strategy without terms), the last two columns of episodes.csv."""
    summary = summarise_quiet([result])
    return summary.quiet, ";".join(f"{name}={value:+.6f}" for name, value in summary.terms.items())
