"""The docs' results tables, written from a ``make experiments`` run (issue 26 item 6).

``scripts/experiments.py`` runs the suites listed in ``docs/experiments.toml`` and
records what it ran in ``manifest.json``; this module turns those results into
Markdown tables and puts each between its markers in the docs::

    <!-- experiments:begin ch7:findings -->
    ...generated table...
    <sub>stamp: commit ..., command ..., cores ...</sub>
    <!-- experiments:end ch7:findings -->

Everything between the markers is replaced; everything outside them is left
as it is. A table is only ever written from a run's files, never typed.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

import tomllib

from dialog.experiments.report import _fmt_p as format_p
from dialog.experiments.report import numbers_in_words
from learning.errors import SettingsError

BEGIN = re.compile(r"<!-- experiments:begin (?P<name>[\w.:-]+) -->")
BEGIN_LINE = "<!-- experiments:begin {name} -->"
END = "<!-- experiments:end {name} -->"
STAMP_PREFIX = "<sub>Made by `make experiments`"
SUMMARIES = ("summary:findings", "summary:demo-share", "summary:wall-times", "summary:suites")
README_BLOCKS = ("summary:demo", "summary:study")  # the plan's `readme` run (dialog/experiments/readme_tables.py)
PARTS = ("results", "findings", "report")  # SUITE:PART blocks: episodes suites write the first two, others "report"


@dataclass(frozen=True)
class Run:
    """One suite of the record: its name, strategies (None: the suite's) and the figures it copies."""

    suite: str
    strategies: tuple[str, ...] | None = None
    figures: tuple[tuple[str, str, str], ...] = ()


@dataclass(frozen=True)
class Plan:
    """``docs/experiments.toml``: the runs, their data seeds and seeds, and the docs they fill."""

    docs: tuple[str, ...]
    data_seeds: tuple[int, ...]
    seeds: tuple[int, ...]
    runs: tuple[Run, ...]
    thesis_demo_share: dict[str, float] = field(default_factory=dict)
    readme: str | None = None  # the README's demo and study tables: their file (docs/readme-tables.toml)


def load_plan(path: Path) -> Plan:
    """Read and check the plan; one message naming the file and what is wrong."""
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as error:
        raise SettingsError(f"{path}: cannot read the experiments plan ({error})") from None
    unknown = set(data) - {"docs", "data_seeds", "seeds", "run", "thesis_demo_share", "readme"}
    if unknown:
        raise SettingsError(f"{path}: unknown keys {', '.join(sorted(unknown))} (expected docs, data_seeds, seeds, "
                            "run, thesis_demo_share, readme)")
    readme = data.get("readme")
    if readme is not None and not isinstance(readme, str):
        raise SettingsError(f"{path}: readme must be the path of the README tables' file, got {readme!r}")
    runs = []
    for index, entry in enumerate(data.get("run", []), 1):
        if not isinstance(entry, dict) or not isinstance(entry.get("suite"), str):
            raise SettingsError(f"{path}: run {index} needs suite = \"NAME\"")
        extra = set(entry) - {"suite", "strategies", "figures"}
        if extra:
            raise SettingsError(f"{path}: run {index} ({entry['suite']}): unknown keys {', '.join(sorted(extra))} "
                                "(expected suite, strategies, figures)")
        figures = tuple(tuple(map(str, f)) for f in entry.get("figures", []))
        if any(len(f) != 3 for f in figures):
            raise SettingsError(f"{path}: run {index} ({entry['suite']}): each figure is [report file, docs image "
                                "name, caption]")
        strategies = entry.get("strategies")
        runs.append(Run(entry["suite"], tuple(strategies) if strategies else None, figures))
    if not runs:
        raise SettingsError(f"{path}: no [[run]] entries")
    return Plan(tuple(data.get("docs", [])), tuple(data.get("data_seeds", [0])), tuple(data.get("seeds", [0])),
                tuple(runs), {str(k): float(v) for k, v in data.get("thesis_demo_share", {}).items()}, readme)


def stamp(manifest: dict, command: str) -> str:
    """The line under every generated table: where it came from."""
    commit = manifest["commit"][:10] + (" with uncommitted changes" if manifest.get("dirty") else "")
    return (f"{STAMP_PREFIX} at commit {commit}, {manifest['date']}, {manifest['cores']} cores: "
            f"`{command}`.</sub>")


def markdown_table(header: list[str], rows: list[list[str]], right_from: int = 1) -> list[str]:
    """A Markdown table's lines: ``header``, then ``rows`` (cells already formatted as text); the columns from
    ``right_from`` on are aligned right (numbers)."""
    rule = ["---" if i < right_from else "---:" for i in range(len(header))]
    return [f"| {' | '.join(cells)} |" for cells in (header, rule, *rows)]


def blocks_in(text: str) -> list[str]:
    """The names of the generated blocks in ``text``, in order; refuses an unclosed or doubled block."""
    names = [m.group("name") for m in BEGIN.finditer(text)]
    for name in names:
        if names.count(name) > 1:
            raise SettingsError(f"the block '{name}' appears twice")
        if END.format(name=name) not in text:
            raise SettingsError(f"the block '{name}' has no '{END.format(name=name)}'")
    return names


def splice(text: str, tables: dict[str, str]) -> tuple[str, list[str]]:
    """``text`` with the body of every block named in ``tables`` replaced; returns the names it replaced."""
    replaced = []
    for name in blocks_in(text):
        if name not in tables:
            continue
        begin = BEGIN_LINE.format(name=name)
        start = text.index(begin) + len(begin)
        end = text.index(END.format(name=name), start)
        text = text[:start] + "\n" + tables[name].rstrip("\n") + "\n" + text[end:]
        replaced.append(name)
    return text, replaced


def unstamped_tables(text: str, allowed: str = "<!-- not-results") -> list[int]:
    """Line numbers (1-based) of Markdown tables outside every generated block that are not marked as a
    description by a ``<!-- not-results: why -->`` line just above them, and of generated blocks that
    end without a stamp."""
    lines = text.splitlines()
    inside, stamped, bad = None, False, []
    for index, line in enumerate(lines):
        begin = BEGIN.search(line)
        if begin:
            inside, stamped = begin.group("name"), False
        elif inside and line.strip() == END.format(name=inside):
            if not stamped:
                bad.append(index + 1)
            inside = None
        elif inside:
            stamped = stamped or line.startswith(STAMP_PREFIX)
        elif re.match(r"^\|(\s*:?-{3,}:?\s*\|)+\s*$", line) and not _comment_just_above(lines, index - 1, allowed):
            bad.append(index)  # the header line, 1-based
    return bad


def _comment_just_above(lines: list[str], header_index: int, allowed: str) -> bool:
    """The line above a table's header (index of the header, 0-based) is a not-results note (blank lines
    between them allowed)."""
    index = header_index - 1
    while index >= 0 and not lines[index].strip():
        index -= 1
    return index >= 0 and lines[index].startswith(allowed)


# -- tables from one episodes suite's replication.json --------------------------------------------------

def _condition_line(condition: dict, at: int | None, axis: str) -> str:
    limit = f"{condition['seconds']:g} s" if condition.get("seconds") else f"{condition['turns']} turns"
    if condition.get("until_budget_spent"):
        limit = f"until the budget is spent (bound {condition['turns']} turns)"
    teacher = {k: v for k, v in condition.get("teacher", {}).items() if k != "kind"}
    told = (", teacher " + ", ".join(f"{k.replace('_', ' ')} {v}" for k, v in sorted(teacher.items()))) if teacher \
        else ""
    return (f"`{condition['name']}`: budget {condition['budget']:g}, {limit}, a new scene every "
            f"{condition['change_every']} turns, {condition['objects_per_scene']} objects a scene{told}; "
            f"compared after {at} {axis}")


def results_table(replication: dict) -> str:
    """Accuracy (mean ± standard error over every episode of every data seed) per strategy and condition,
    then questions asked and the demonstration share of the spent budget."""
    conditions = replication["conditions"]
    strategies = list(dict.fromkeys(row["strategy"] for c in conditions for row in c["strategies"]))
    cell = {(c["name"], row["strategy"]): row for c in conditions for row in c["strategies"]}
    axis = {"questions": "questions", "seconds": "seconds"}.get(replication["axis"], "turns")
    lines = ["Conditions: " + "; ".join(_condition_line(c, next((r["at"] for r in c["strategies"]), None), axis)
                                         for c in conditions) + ".", "",
             f"Held-out accuracy, mean ± standard error over {_episodes_per_cell(conditions)} episodes a cell "
             f"(data seeds {numbers_in_words(replication['data_seeds'])}, {replication['datasets']} training pools "
             f"each, episode seeds {numbers_in_words(replication['seeds'])}):", "",
             "| strategy | " + " | ".join(c["name"] for c in conditions) + " |", "|---" * (len(conditions) + 1) + "|"]
    for strategy in strategies:
        cells = [f"{r['pooled']['mean']:.3f} ± {r['pooled']['error']:.3f}" if (r := cell.get((c["name"], strategy)))
                 else "–" for c in conditions]
        lines.append(f"| {strategy} | " + " | ".join(cells) + " |")
    lines += ["", "Questions asked (mean) and the share of the spent budget that went on demonstrations; where a "
                  "condition runs until the budget is spent, the turns taken (mean / median) and how many episodes "
                  "reached the bound:", "",
              "| strategy | " + " | ".join(c["name"] for c in conditions) + " |", "|---" * (len(conditions) + 1) + "|"]
    for strategy in strategies:
        cells = [f"{r['pooled']['questions']:.1f} q, {r['pooled']['demo_share']:.0%}"
                 + (_turns_cell(r["pooled"]) if c.get("until_budget_spent") else "")
                 if (r := cell.get((c["name"], strategy))) else "–" for c in conditions]
        lines.append(f"| {strategy} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def _turns_cell(pooled: dict) -> str:
    """, 155 / 140 turns, 2 at the bound" for a condition that runs until its budget is spent."""
    return f", {pooled['turns_mean']:.0f} / {pooled['turns_median']:g} turns, {pooled['at_bound']} at the bound"


def _episodes_per_cell(conditions: list[dict]) -> str:
    counts = sorted({row["pooled"]["episodes"] for c in conditions for row in c["strategies"]})
    return "/".join(map(str, counts))


def _effect_cell(comparison: dict) -> str:
    """"vs a +0.050 [+0.010, +0.090] (5 clusters), r +0.40": the pooled mean difference, its interval with the
    number of clusters (data seeds) it resampled where the record has it, and r."""
    difference = f"vs {comparison['than']} {comparison['mean'] - comparison['mean_than']:+.3f}"
    if comparison["effect_r"] is None:
        return difference
    clusters = comparison.get("clusters")
    counted = "" if clusters is None else f" ({clusters} cluster{'s' if clusters != 1 else ''})"
    interval = f" [{comparison['ci'][0]:+.3f}, {comparison['ci'][1]:+.3f}]" if comparison["ci"] else " no interval"
    return f"{difference}{interval}{counted}, r {comparison['effect_r']:+.2f}"


def _seed_cell(cell: dict | None) -> str:
    if not cell or not cell["tested"]:
        return "–"
    return f"{'+' if cell['direction'] else '−'} {format_p(cell['p'])}"


def verdict_words(holds: bool) -> str:
    return "**holds**" if holds else "does not hold"


def finding_verdict(cell: dict) -> str:
    if not cell["tested"]:
        return "not tested"
    return verdict_words(cell["holds"])


def findings_table(replication: dict) -> str:
    """Every planned finding: per data seed its direction and uncorrected p, pooled the paired test
    (Holm-corrected over the suite's findings), its effects, and the verdict."""
    seeds = [str(s) for s in replication["data_seeds"]]
    lines = ["Per data seed: `+` when every comparison of the finding points its way, `−` when one does not, "
             "with the largest one-tailed Wilcoxon p of its comparisons (uncorrected; "
             f"{replication['datasets'] * len(replication['seeds'])} pairs a data seed). "
             "Pooled: the same paired tests over every data seed's episodes, Holm-corrected over the suite's "
             "findings, with each comparison's mean difference, its 95 % cluster-bootstrap interval (whole data "
             "seeds resampled, their number beside it) and the rank-biserial r.", "",
             "| finding | " + " | ".join(f"data seed {s}" for s in seeds)
             + " | pooled pairs | pooled effects | Holm p | holds? |", "|---" * (len(seeds) + 5) + "|"]
    for finding in replication["findings"]:
        pooled = finding["pooled"]
        if pooled["tested"]:
            effects = "; ".join(_effect_cell(c) for c in pooled["comparisons"])
            tail = f"{pooled['pairs']} | {effects} | {format_p(pooled['p_holm'])} | {finding_verdict(pooled)}"
        else:
            tail = f"– | {pooled['why']} | – | not tested"
        lines.append(f"| {finding['id']}: {finding['text']} | "
                     + " | ".join(_seed_cell(finding["by_data_seed"].get(s)) for s in seeds) + f" | {tail} |")
    return "\n".join(lines)


def report_tables(report: str) -> str:
    """A non-episodes suite (chapter 5, recipes): the first table under each section of its report.md,
    with the section's heading in bold above it."""
    out, heading, taken = [], "", False
    lines = report.splitlines()
    for index, line in enumerate(lines):
        if line.startswith("## "):
            heading, taken = line[3:].strip(), False
        elif line.startswith("|") and not taken and heading:
            end = index
            while end < len(lines) and lines[end].startswith("|"):
                end += 1
            out += [f"**{heading}**", "", *lines[index:end], ""]
            taken = True
    return "\n".join(out).rstrip()


def report_findings(report: str) -> list[dict]:
    """The findings of a non-episodes suite's report: id, text and whether every comparison held."""
    findings: dict[str, dict] = {}
    in_findings = False
    for line in report.splitlines():
        if line.startswith("## "):
            in_findings = "finding" in line.lower()
        elif in_findings and line.startswith("| ") and not line.startswith("| finding") and ": " in line:
            cells = [c.strip() for c in line.strip("|").split("|")]
            ident, _, text = cells[0].partition(": ")
            entry = findings.setdefault(ident, {"id": ident, "text": text, "holds": True})
            entry["holds"] = entry["holds"] and cells[-1] == "yes"
    return list(findings.values())
