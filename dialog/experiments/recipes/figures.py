"""Plots and Markdown tables of the chapter-4 experiments (shapes of thesis figures 4.6 and 4.8).

Shared by ``scripts/recipe_experiments.py`` and the recipes regression suite.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from dialog.experiments.figures import pyplot  # noqa: F401  (used by the recipe reports too)

# Objects dashed, locations solid (the object curves often coincide: lighting decides them).
OBJECT_STYLES = tuple({"linestyle": "--", "marker": m, "markersize": 5, "alpha": 0.8} for m in ("o", "s", "^"))
LOCATION_STYLES = tuple({"linestyle": "-", "marker": m, "markersize": 3} for m in ("o", "v", "D", "x"))


def plot_cross_validation(curves: dict[str, dict[str, list[float]]], objects: tuple[str, ...], path: Path,
                          recipe: str = "serve-pasta", m_values: list[int] | None = None) -> None:
    """Figure 4.6 shape: accuracy of every parameter against m, one panel per kitchen."""
    plt = pyplot()
    figure, axes = plt.subplots(1, len(curves), figsize=(4.6 * len(curves), 3.8), squeeze=False, sharey=True)
    for axis, (kitchen, per_parameter) in zip(axes[0], curves.items()):
        for number, (name, values) in enumerate(per_parameter.items()):
            styles = OBJECT_STYLES if name in objects else LOCATION_STYLES
            x = m_values or list(range(1, len(values) + 1))
            axis.plot(x, values, label=name, **styles[number % len(styles)])
        axis.set_title(f"{recipe}, {kitchen}")
        axis.set_xlabel("training demonstrations m")
        axis.set_ylim(-0.02, 1.02)
        axis.grid(alpha=0.3)
        axis.legend(fontsize=7, loc="lower right", title="dashed: objects, solid: locations", title_fontsize=7)
    axes[0][0].set_ylabel("accuracy on held-out demonstrations")
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)


def plot_transfer(rows: list[dict], test_kitchen: str, path: Path, recipe: str = "serve-salad") -> None:
    """Figure 4.8 shape: accuracy per parameter in ``test_kitchen`` for models from every set of kitchens."""
    plt = pyplot()
    m_values = sorted({row["m"] for row in rows})
    figure, axes = plt.subplots(1, len(m_values), figsize=(6.5 * len(m_values), 3.8), squeeze=False, sharey=True)
    for axis, m in zip(axes[0], m_values):
        chosen = [row for row in rows if row["m"] == m and row["test"] == test_kitchen]
        chosen.sort(key=lambda row: (row["situated"], len(row["train"]), row["train"]))
        parameters = list(chosen[0]["accuracy"])
        width = 0.8 / len(chosen)
        blues, reds = plt.cm.Blues, plt.cm.Reds
        n_out = sum(not row["situated"] for row in chosen)
        for index, row in enumerate(chosen):
            shade = 0.45 + 0.5 * ((index if not row["situated"] else index - n_out) + 1) / (len(chosen) + 1)
            colour = (reds if row["situated"] else blues)(shade)
            label = "+".join(k.replace("kitchen-", "K") for k in row["train"])
            positions = np.arange(len(parameters)) + (index - (len(chosen) - 1) / 2) * width
            axis.bar(positions, [row["accuracy"][p] for p in parameters], width, color=colour, label=label)
        axis.set_xticks(range(len(parameters)), parameters, fontsize=8)
        axis.set_title(f"{recipe} tested in {test_kitchen}, {m} demos per training kitchen")
        axis.set_ylim(0, 1.05)
        axis.grid(axis="y", alpha=0.3)
        axis.legend(loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=min(len(chosen), 7), fontsize=7,
                    title="trained in (blue: without the test kitchen, red: with it)", title_fontsize=7)
    axes[0][0].set_ylabel("accuracy")
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)


def markdown_cv(kitchen: str, per_parameter: dict[str, list[float]], recipe: str = "serve-pasta",
                m_values: list[int] | None = None) -> str:
    """Accuracy per parameter against m, one row per parameter."""
    count = len(next(iter(per_parameter.values())))
    m_values = m_values or list(range(1, count + 1))
    lines = [f"{recipe}, {kitchen}: accuracy per parameter vs. training demonstrations m", "",
             "| parameter | " + " | ".join(f"m={m}" for m in m_values) + " |",
             "|---|" + "---:|" * count]
    lines += [f"| {name} | " + " | ".join(f"{v:.2f}" for v in values) + " |" for name, values in per_parameter.items()]
    return "\n".join(lines)


def markdown_transfer(rows: list[dict]) -> str:
    """One row per (m, training kitchens, test kitchen); bold where the test kitchen was trained in."""
    parameters = list(rows[0]["accuracy"])
    lines = ["| m | trained in | tested in | " + " | ".join(parameters) + " | mean |",
             "|---:|---|---|" + "---:|" * (len(parameters) + 1)]
    for row in rows:
        values = " | ".join(f"{row['accuracy'][p]:.2f}" for p in parameters)
        mark = "**" if row["situated"] else ""
        lines.append(f"| {row['m']} | {mark}{'+'.join(row['train'])}{mark} | {row['test']} | {values} | "
                     f"{row['mean']:.2f} |")
    return "\n".join(lines)
