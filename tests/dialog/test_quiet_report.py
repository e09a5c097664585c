"""Quiet turns with budget left and what kept DT quiet (dialog/experiments/quiet.py), on hand-made episodes."""

from __future__ import annotations

import pytest

from dialog.experiments.quiet import quiet_columns, quiet_table, quiet_with_budget_left, summarise_quiet


def episode(asked: list[int], spent: list[float], terms: list[dict], budget: float = 3, strategy: str = "dt-iros"):
    """A hand-made episode result: cumulative questions and spending per turn, each turn's decision terms."""
    return {"spec": {"condition": {"name": "static", "budget": budget}, "strategy": strategy,
                     "costs": (("demo", 2), ("feature", 2), ("label", 1), ("none", 0))},
            "series": {"turn": list(range(1, len(asked) + 1)), "questions": asked, "spent": spent},
            "decision_terms": terms}


CDU = "class_distribution_uniformity"
ACD = "classifier_discriminability"


def test_a_quiet_turn_counts_only_while_the_budget_covers_the_cheapest_question():
    # turns: ask (1), quiet, quiet, ask (2 -> 3 spent), quiet with nothing left
    series = {"questions": [1, 1, 1, 2, 2], "spent": [1.0, 1.0, 1.0, 3.0, 3.0]}
    assert quiet_with_budget_left(series, 3, {"label": 1, "demo": 2, "feature": 2}) == [1, 2]
    assert quiet_with_budget_left(series, 3, {"label": 3, "demo": 3, "feature": 3}) == []


def test_the_mean_terms_over_the_quiet_turns_say_what_kept_dt_quiet():
    quiet = {ACD: 0.004, CDU: -0.0125}
    first = episode([1, 1, 1, 2, 2], [1, 1, 1, 3, 3], [{ACD: 0.05}, quiet, {ACD: 0.006, CDU: -0.0125}, {}, {}])
    second = episode([0, 0], [0, 0], [quiet, {}])  # the second quiet turn had nothing to choose from
    summary = summarise_quiet([first, second])
    assert (summary.quiet, summary.turns, summary.with_terms) == (4, 7, 3)
    assert summary.per_episode == 2 and summary.share == pytest.approx(4 / 7)
    assert summary.terms[ACD] == pytest.approx(0.014 / 3) and summary.terms[CDU] == pytest.approx(-0.0125)
    assert quiet_columns(first) == (2, "classifier_discriminability=+0.005000;class_distribution_uniformity=-0.012500")
    lines = quiet_table({("static", "dt-iros"): [first, second], ("static", "active"): [
        episode([1, 2], [1, 2], [{}, {}], strategy="active")]}, "static", ["dt-iros", "active"])
    assert "| dt-iros | 2.0 | 57% | CDU -0.013, ACD +0.0047; sum -0.0078 (3 turns) |" in lines
    assert "| active | 0.0 | 0% | – |" in lines


def test_an_episode_keeps_dts_terms_beside_the_transcript_and_none_for_other_strategies(tmp_path):
    from dataclasses import replace

    from dialog.experiments.episodes import run_episode
    from dialog.experiments.fingerprint import fingerprint_episodes
    from dialog.transcripts.jsonl import read_transcript

    specs = {e.label: e.spec for e in fingerprint_episodes(transcripts=tmp_path)}
    for label, weighted in (("smoke/dt-task/d0", True), ("smoke/active/d0", False)):
        spec = replace(specs[label], transcript=str(tmp_path / f"{label.replace('/', '-')}.jsonl"))
        result = run_episode(spec)
        terms = result["decision_terms"]
        assert len(terms) == len(result["series"]["turn"])
        if weighted:  # a term per weighted feature on every turn DT chose from candidates
            assert sum(bool(t) for t in terms) > len(terms) // 2
            assert all(set(t) <= {"classifier_discriminability", "class_distribution_uniformity",
                                  "instance_variation", "prediction_margin"} for t in terms)
        else:
            assert not any(terms)
        assert all("terms" not in record for record in read_transcript(spec.transcript))
