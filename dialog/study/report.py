"""``teachbot study report``: tidy CSV tables, a Markdown report with paired tests, and PNG plots.

Only finished sessions (every turn recorded, questionnaire answered) enter the
comparisons; every session that is missing, unfinished or aborted is listed.
"""

from __future__ import annotations

from collections import defaultdict
from itertools import combinations
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

from dialog import software_version
from dialog.experiments.figures import COLOURS, LINE_STYLES
from dialog.output_paths import check_writable, writing
from dialog.study.atomic import write_atomically
from dialog.study.paired import paired_test
from dialog.study.tables import ANSWER_COLUMNS, TURN_COLUMNS, collect, write_csv
from learning.errors import TranscriptError
from learning.significance import mean_and_standard_error

KINDS = ("label", "demo", "feature", "none")


def _sessions(tables) -> dict:
    """(participant, condition) -> that finished session's turn rows, in order."""
    sessions = defaultdict(list)
    for row in tables.turns:
        if row["state"] == "done":
            sessions[(row["participant"], row["condition"])].append(row)
    return sessions


def _fmt(value, spec: str = ".3f") -> str:
    """One number in one column's format (fixed decimals, so a column lines up: 0.160 beside 0.098); "–" for none."""
    return "–" if value is None or (isinstance(value, float) and np.isnan(value)) else format(value, spec)


def _p(value) -> str:
    """A p value: three decimals, below 0.001 said as such."""
    return "–" if value is None or np.isnan(value) else ("< 0.001" if value < 0.001 else f"{value:.3f}")


def _table(header, rows) -> list[str]:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    return lines + ["| " + " | ".join(str(cell) for cell in row) + " |" for row in rows]


def _tests(names, values: dict, what: str) -> list[str]:
    """Markdown rows of Wilcoxon tests between every pair of conditions for ``values[condition][participant]``."""
    rows = []
    for a, b in combinations(names, 2):
        test = paired_test(a, values.get(a, {}), b, values.get(b, {}))
        rows.append([what, f"{a} vs {b}", test.n, _fmt(test.median_difference, "+.3f"), _fmt(test.statistic, ".1f"),
                     _p(test.p), _fmt(test.effect, "+.2f")])
    return rows


def curve_figure(study, sessions) -> Figure:
    """Held-out accuracy per turn for each condition: the participants' mean and their full range."""
    figure = Figure(figsize=(6.4, 4.0), dpi=110)
    axis = figure.add_subplot()
    for index, condition in enumerate(study.conditions):
        curves = [[row["accuracy"] for row in rows] for (_, name), rows in sessions.items() if name == condition.name]
        if not curves:
            continue
        array = np.array(curves, dtype=float)
        mean, _ = mean_and_standard_error(array)
        turns = np.arange(1, array.shape[1] + 1)
        colour = COLOURS[index % len(COLOURS)]
        axis.fill_between(turns, array.min(axis=0), array.max(axis=0), color=colour, alpha=0.15, linewidth=0)
        axis.plot(turns, mean, color=colour, linestyle=LINE_STYLES[index % len(LINE_STYLES)], marker="o",
                  markersize=3, label=f"{condition.name} (n={len(curves)})")
    axis.set_xlabel("turn")
    axis.xaxis.set_major_locator(MaxNLocator(integer=True))  # turns are whole numbers
    axis.set_ylabel("held-out accuracy")
    axis.set_title(f"Study '{study.name}': learning curves (mean, band = range over participants)", fontsize=9)
    axis.set_ylim(0, 1)
    axis.grid(alpha=0.3)
    if axis.get_legend_handles_labels()[0]:
        axis.legend(fontsize=8)
    else:
        axis.text(0.5, 0.5, "no finished sessions yet", ha="center", transform=axis.transAxes)
    figure.tight_layout()
    return figure


def final_figure(study, final: dict) -> Figure:
    """Final accuracy per participant under each condition, one line per participant, and the median."""
    figure = Figure(figsize=(6.4, 4.0), dpi=110)
    axis = figure.add_subplot()
    names = [c.name for c in study.conditions]
    participants = sorted({p for values in final.values() for p in values})
    for participant in participants:
        xs = [i for i, name in enumerate(names) if participant in final.get(name, {})]
        axis.plot(xs, [final[names[i]][participant] for i in xs], color="#999999", alpha=0.6, marker=".")
    for i, name in enumerate(names):
        values = list(final.get(name, {}).values())
        if values:
            axis.hlines(np.median(values), i - 0.25, i + 0.25, color=COLOURS[i % len(COLOURS)], linewidth=3)
    axis.set_xticks(range(len(names)), names)
    axis.set_ylabel("final held-out accuracy")
    axis.set_ylim(0, 1)
    axis.set_title(f"Study '{study.name}': final accuracy per participant (bar = median)", fontsize=9)
    axis.grid(alpha=0.3, axis="y")
    figure.tight_layout()
    return figure


def write_report(study, out: Path, allow_mixed: bool = False) -> list[Path]:
    """Write turns.csv, questionnaire.csv, report.md and the two plots into ``out``; returns their paths.
    Simulated (dry-run) and real sessions in one folder are refused unless ``allow_mixed``."""
    out = Path(out)
    check_writable(out, "study report", folder=True)
    tables = collect(study)
    simulated, real = tables.simulated_sessions()
    if simulated and real and not allow_mixed:
        raise TranscriptError(f"{study.folder} holds {simulated} simulated (dry-run) and {real} real sessions; a "
                              "report over both would mix a scripted teacher's answers with participants'. Move the "
                              "dry run away, or report both with --allow-mixed (every row says which it is)")
    names = [c.name for c in study.conditions]
    sessions = _sessions(tables)
    done = {(c.participant, c.condition) for c in tables.cells if c.state.state == "done"}
    final = {name: {p: rows[-1]["accuracy"] for (p, c), rows in sessions.items() if c == name and (p, c) in done}
             for name in names}
    out.mkdir(parents=True, exist_ok=True)
    paths = [out / "turns.csv", out / "questionnaire.csv", out / "report.md", out / f"study-{study.name}-curves.png",
             out / f"study-{study.name}-final.png"]
    write_csv(paths[0], TURN_COLUMNS, tables.turns)
    write_csv(paths[1], ANSWER_COLUMNS, tables.answers)
    for figure, path in ((curve_figure(study, sessions), paths[3]), (final_figure(study, final), paths[4])):
        with writing(path, "study plot"):
            figure.savefig(path)
    write_atomically(paths[2], "\n".join(report_lines(study, tables, sessions, final, paths[3:])) + "\n",
                     "study report")
    return paths


def report_lines(study, tables, sessions, final, figures) -> list[str]:
    names = [c.name for c in study.conditions]
    finished = sorted({p for values in final.values() for p in values})
    lines = [f"# Study '{study.name}'", "",
             f"{len(study.participants)} participants planned, {len(finished)} with at least one finished session; "
             f"{sum(c.state.state == 'done' for c in tables.cells)} of {len(tables.cells)} sessions finished. "
             f"Report by {software_version()}. Tables: `turns.csv` (one row per recorded turn), "
             "`questionnaire.csv` (one row per answer).", ""]
    lines += opening_report_lines(study)
    simulated, real = tables.simulated_sessions()
    if simulated:
        lines += [f"**{'All' if not real else simulated} of the {simulated + real} recorded sessions "
                  f"{'are' if simulated != 1 else 'is'} simulated: a scripted teacher played the participant "
                  "(study run --simulated), a dry run of the pipeline, not data.** The `simulated` column of both "
                  "tables says which.", ""]
    lines += ["## Final accuracy and questions", ""]
    rows = []
    for name in names:
        group = [rows_ for (p, c), rows_ in sessions.items() if c == name and p in final[name]]
        values = list(final[name].values())
        asked = [row for rows_ in group for row in rows_ if row["action"] != "none"]
        kinds = {kind: sum(row["action"] == kind for rows_ in group for row in rows_) / max(len(group), 1)
                 for kind in KINDS}
        rows.append([name, len(values), _fmt(np.mean(values) if values else None),
                     _fmt(np.std(values, ddof=1) if len(values) > 1 else None),
                     " / ".join(f"{kinds[k]:.1f}" for k in KINDS),
                     _fmt(np.mean([r["answer_seconds"] for r in asked]) if asked else None),
                     sum(r["refused"] for r in asked)])
    lines += _table(["condition", "n", "final accuracy (mean)", "sd", "questions per session label/demo/feature/none",
                     "answer seconds (mean)", "refused answers"], rows)
    lines += channel_lines(tables, names)
    lines += ["", f"![learning curves]({figures[0].name})", "", f"![final accuracy]({figures[1].name})", ""]
    lines += questionnaire_lines(study, tables, names)
    likert = _likert_values(study, tables)
    lines += ["## Paired tests between conditions", "",
              "Wilcoxon signed-rank over the participants who finished both conditions (two-sided); effect = matched-"
              "pairs rank-biserial r (+1: every participant higher under the first condition); n = participants.", ""]
    test_rows = _tests(names, final, "final accuracy")
    for item, values in likert.items():
        test_rows += _tests(names, values, item)
    lines += _table(["measure", "conditions", "n", "median difference", "W", "p", "effect r"], test_rows)
    lines += [""] + order_lines(study, tables, final) + [""] + missing_lines(tables)
    return lines


def opening_report_lines(study) -> list[str]:
    """How many consented and how many practice rounds are recorded: counted, and left out of every table."""
    from dialog.study.consent import consent_state
    from dialog.study.files import session_state_of

    lines = []
    if study.consent is not None:
        states = [consent_state(study, participant) for participant in study.participants]
        counts = {state: states.count(state) for state in dict.fromkeys(states)}
        lines += ["Consent (" + study.consent.file + "): " + ", ".join(f"{n} {state}" for state, n in counts.items())
                  + ".", ""]
    if study.practice is not None:
        states = [session_state_of(study, participant, 0, "practice").state for participant in study.participants]
        lines += [f"Practice rounds: {states.count('done')} finished, {states.count('running')} unfinished "
                  f"({study.practice.turns} turns each, `0-practice.jsonl` in a participant's folder); they are "
                  "left out of every table and test below.", ""]
    return lines


def _likert_values(study, tables) -> dict:
    values: dict = {item.id: defaultdict(dict) for item in study.items if item.kind == "likert"}
    done = {(c.participant, c.condition) for c in tables.cells if c.state.state == "done"}
    for row in tables.answers:
        if row["item"] in values and row["value"] is not None and (row["participant"], row["condition"]) in done:
            values[row["item"]][row["condition"]][row["participant"]] = float(row["value"])
    return values


def channel_lines(tables, names) -> list[str]:
    """Per condition, how the answers taken came in the page's sessions (``--web``), and the page's answer times;
    nothing when every session was at the terminal."""
    rows = []
    for name in names:
        taken = [r for r in tables.turns if r["condition"] == name and r.get("channel")]
        if taken:
            seconds = [r["page_seconds"] for r in taken if r.get("page_seconds") is not None]
            counts = [sum(r["channel"] == channel for r in taken) for channel in ("click", "button", "typed")]
            rows.append([name, len(taken), *counts, _fmt(float(np.median(seconds)) if seconds else None)])
    if not rows:
        return []
    return ["", "Answers given in the page (`--web`): how each answer taken came, and the seconds from the question "
                "being shown in the page to it (median).", ""] + _table(
        ["condition", "answers", "click", "button", "typed", "page seconds (median)"], rows)


def questionnaire_lines(study, tables, names) -> list[str]:
    likert = _likert_values(study, tables)
    if not likert:
        return []
    rows = []
    for item in study.items:
        if item.kind != "likert":
            continue
        cells = []
        for name in names:
            values = list(likert[item.id].get(name, {}).values())
            spread = np.std(values, ddof=1) if len(values) > 1 else 0.0
            cells.append(f"{np.mean(values):.2f} ({spread:.2f}, n={len(values)})" if values else "–")
        rows.append([f"{item.id} (1 = {item.anchors[0]}, {item.points} = {item.anchors[1]})", *cells])
    texts = sum(1 for row in tables.answers if row["kind"] == "text" and row["value"])
    return ["## Questionnaire", "", "Mean (sd, n) per Likert item."
            f" {texts} free-text answers are in `questionnaire.csv`.", ""] + _table(["item", *names], rows) + [""]


def order_lines(study, tables, final) -> list[str]:
    """Final accuracy by session position, and each participant's first session against their later ones."""
    by_position = defaultdict(list)
    first, later = {}, defaultdict(list)
    for cell in tables.cells:
        value = final.get(cell.condition, {}).get(cell.participant)
        if value is None:
            continue
        by_position[cell.position].append(value)
        if cell.position == 1:
            first[cell.participant] = value
        else:
            later[cell.participant].append(value)
    rows = [[position, len(values), _fmt(np.mean(values))] for position, values in sorted(by_position.items())]
    test = paired_test("first", first, "later", {p: float(np.mean(v)) for p, v in later.items() if v})
    return (["## Order effects", ""] + _table(["session position", "n", "final accuracy (mean)"], rows) +
            ["", f"First session against the mean of the later ones: n = {test.n}, median difference "
             f"{_fmt(test.median_difference, '+.3f')}, W = {_fmt(test.statistic, '.1f')}, p = {_p(test.p)}, "
             f"r = {_fmt(test.effect, '+.2f')}."])


def missing_lines(tables) -> list[str]:
    rows = [[c.participant, c.position, c.condition, c.state.state if c.state.state != "running"
             else f"unfinished ({c.state.turns_done} turns)", c.state.reason]
            for c in tables.cells if c.state.state != "done"]
    if not rows:
        return ["## Missing or aborted sessions", "", "None: every planned session is finished."]
    return ["## Missing or aborted sessions", ""] + _table(["participant", "position", "condition", "state",
                                                             "reason"], rows)
