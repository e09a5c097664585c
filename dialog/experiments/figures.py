"""Figures of an episodes suite: learning curves and question timing, one style per strategy.

Every strategy keeps one colour, line style and marker across all figures
(distinct for up to ten strategies), every panel has its own legend, the
parts of a curve that fewer episodes reach are drawn faded, and a timing plot
names the episode it shows. Figures are built as ``matplotlib.figure.Figure``
objects (no pyplot state), so tests can inspect them.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.ticker import MaxNLocator

from dialog.experiments.analysis import group_results
from dialog.experiments.suite import Condition, Suite
from learning.significance import mean_and_standard_error

COLOURS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22",
           "#17becf")  # matplotlib's tab10: ten colours told apart also in print
LINE_STYLES = ("-", "--", "-.", ":")
MARKERS = ("o", "s", "^", "D", "v", "P", "X", "*", "<", ">")
FEWER_ALPHA = 0.35  # curve segments where not every episode contributes



def pyplot():
    """matplotlib's pyplot on the Agg backend (no display on this machine): the one place it is set up."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt

def strategy_styles(strategies) -> dict[str, dict]:
    """A distinct (colour, line style, marker) for each strategy, in the suite's order."""
    return {name: {"color": COLOURS[i % len(COLOURS)], "linestyle": LINE_STYLES[i % len(LINE_STYLES)],
                   "marker": MARKERS[i % len(MARKERS)]} for i, name in enumerate(strategies)}


def accuracy_curves(group: list[dict], x_key: str, length: int) -> np.ndarray:
    """Accuracy indexed by questions asked (last value at each count) or by turn, padded with NaN."""
    curves = np.full((len(group), length), np.nan)
    for row, result in enumerate(group):
        series = result["series"]
        accuracy = np.asarray(series["accuracy"], dtype=float)
        if x_key == "turn":
            curves[row, :len(accuracy)] = accuracy[:length]
        else:
            for turn, asked in enumerate(series["questions"]):
                if asked < length:
                    curves[row, asked] = accuracy[turn]
    return curves


def _draw_curve(axis, x: np.ndarray, curves: np.ndarray, label: str, style: dict) -> bool:
    """Mean ± standard error; faded where fewer episodes contribute. True when some part is faded."""
    mean, error = mean_and_standard_error(curves)
    counts = np.sum(np.isfinite(curves), axis=0)
    everyone = counts == len(curves)
    markevery = max(1, len(x) // 8)
    axis.plot(x, np.where(everyone, mean, np.nan), label=label, markevery=markevery, markersize=4, **style)
    axis.plot(x, np.where(counts > 0, mean, np.nan), alpha=FEWER_ALPHA, color=style["color"],
              linestyle=style["linestyle"])
    axis.fill_between(x, mean - error, mean + error, alpha=0.12, color=style["color"], linewidth=0)
    return bool(np.any((counts > 0) & ~everyone))


def seconds_curves(group: list[dict], grid: np.ndarray) -> np.ndarray:
    """(episodes x len(grid)) embodied costs: the accuracy of the last turn each episode ended by each second."""
    curves = np.full((len(group), len(grid)), np.nan)
    for row, result in enumerate(group):
        ended = np.asarray(result["series"].get("seconds", []), dtype=float)
        accuracy = np.asarray(result["series"]["accuracy"], dtype=float)
        done = np.searchsorted(ended, grid, side="right")  # turns ended by each moment
        curves[row, done > 0] = accuracy[done[done > 0] - 1]
    return curves


def learning_curve_figure(results: list[dict], suite: Suite, condition: Condition) -> Figure:
    """Accuracy against questions asked (left) and turns (right; seconds with embodied costs) for every strategy
    of one condition."""
    figure = Figure(figsize=(12, 4.8))
    axes = figure.subplots(1, 2)
    groups, styles = group_results(results), strategy_styles(suite.strategies)
    faded = [False, False]
    for strategy in suite.strategies:
        group = groups.get((condition.name, strategy), [])
        if not group:
            continue
        asked = int(max(r["series"]["questions"][-1] for r in group)) + 1
        if condition.seconds is not None:  # embodied costs: the right panel against seconds
            faded[0] |= _draw_curve(axes[0], np.arange(asked), accuracy_curves(group, "questions", asked), strategy,
                                    styles[strategy])
            grid = np.linspace(0.0, condition.seconds, 121)
            faded[1] |= _draw_curve(axes[1], grid, seconds_curves(group, grid), strategy, styles[strategy])
            continue
        for panel, (key, length) in enumerate((("questions", asked), ("turn", condition.turns))):
            x = np.arange(length) if key == "questions" else np.arange(1, length + 1)
            faded[panel] |= _draw_curve(axes[panel], x, accuracy_curves(group, key, length), strategy,
                                        styles[strategy])
    right = "turn" if condition.seconds is None else "seconds (embodied costs)"
    for axis, label, fewer in zip(axes, ("questions asked", right), faded):
        axis.set_xlabel(label)
        axis.set_ylabel("held-out accuracy")
        axis.grid(alpha=0.3)
        handles, labels = axis.get_legend_handles_labels()
        if fewer:
            handles.append(Line2D([], [], color="0.3", alpha=FEWER_ALPHA, linewidth=2))
            labels.append("faded: fewer episodes reach it")
        axis.legend(handles, labels, fontsize=7, loc="lower right", ncol=2 if len(labels) > 5 else 1)
    episodes = suite.datasets * len(suite.seeds)
    allocation = f"{condition.turns} turns" if condition.seconds is None else f"{condition.seconds:g} s"
    figure.suptitle(f"{suite.name}: {condition.name} (budget {condition.budget:g}, {allocation}, change "
                    f"every {condition.change_every}); mean ± standard error over {episodes} episodes per strategy")
    figure.tight_layout()
    return figure


def timing_figure(results: list[dict], suite: Suite, condition: Condition) -> Figure:
    """The turns on which each strategy asked, in one episode (the first data set and seed), as figure 6.7."""
    figure = Figure(figsize=(12, 1.2 + 0.45 * len(suite.strategies)))
    axis = figure.subplots()
    groups, styles = group_results(results), strategy_styles(suite.strategies)
    for change in range(1, condition.turns + 1, condition.change_every):
        axis.axvline(change, color="0.85", linewidth=0.8, zorder=0)
    shown = None
    for row, strategy in enumerate(suite.strategies):
        group = groups.get((condition.name, strategy), [])
        if not group:
            continue
        first = group[0]
        shown = shown or (first["spec"]["dataset"], first["spec"]["seed"])
        series = first["series"]
        asked = np.diff(np.concatenate([[0], series["questions"]])) > 0
        turns = np.asarray(series["turn"])[asked]
        style = styles[strategy]
        axis.scatter(turns, np.full(len(turns), row), s=14, color=style["color"], marker=style["marker"],
                     label=f"{strategy} ({len(turns)} questions)")
    axis.set_yticks(range(len(suite.strategies)), suite.strategies, fontsize=8)
    axis.set_ylim(-0.7, len(suite.strategies) - 0.3)
    axis.set_xlim(0, condition.turns + 1)
    axis.set_xlabel("turn (grey lines: the scene changes)")
    axis.xaxis.set_major_locator(MaxNLocator(integer=True))  # turns are whole numbers
    episode = f"the episode of data set {shown[0]}, seed {shown[1]}" if shown else "no episode"
    axis.set_title(f"{suite.name}: {condition.name}: turns on which each strategy asked, in {episode} "
                   "(the same scenes for every strategy)", fontsize=9)
    axis.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0)
    figure.tight_layout()
    return figure


def save_figures(results: list[dict], suite: Suite, out: Path) -> list[Path]:
    """``curves-CONDITION.png`` and ``timing-CONDITION.png`` for every condition."""
    paths = []
    for condition in suite.conditions:
        for stem, build in (("curves", learning_curve_figure), ("timing", timing_figure)):
            path = out / f"{stem}-{condition.name}.png"
            build(results, suite, condition).savefig(path, dpi=110)
            paths.append(path)
    return paths
