"""The rollout check's arithmetic (issue 49): episode figures from series, the summary and the pass/fail rule."""

from dataclasses import replace

import pytest

from learning.errors import DataFileError
from learning.irl.rollout_check import (
    CHECK_FILE,
    EpisodeRollout,
    episode_rollout,
    judge,
    load_check_settings,
    spending_turns,
    summarise,
)

SETTINGS = load_check_settings()


def rollout(first, demo, accuracy, label=3, feature=None, turns=10, seed=31):
    feature = int(first is not None) if feature is None else feature
    quiet = turns - label - demo - feature
    return EpisodeRollout(seed, 0, turns, first, {"label": label, "demo": demo, "feature": feature, "none": quiet},
                          (1.0, 2.0, 3.0, 4.0), accuracy)


def test_the_shipped_settings_are_calibration_data_and_the_thresholds_of_issue_49():
    s = SETTINGS
    assert s.data_seed >= 101 and s.episodes >= 20 and not set(s.seeds) & set(range(1, 31))
    assert (s.feature_query_by_turn, s.feature_query_share, s.demo_difference, s.accuracy_difference) == \
        (5, 0.8, 1.0, 0.03)
    assert s.allocation == "dialog/suites/ch7-training.toml" and s.expert == "scripted-expert" and s.workers == 2


def test_episode_figures_come_from_the_cumulative_series():
    series = {"turn": [1, 2, 3, 4, 5, 6, 7, 8], "feature": [0, 0, 1, 1, 1, 1, 1, 1],
              "label": [1, 1, 1, 2, 2, 3, 3, 3], "demo": [0, 1, 1, 1, 1, 1, 1, 1],
              "questions": [1, 2, 3, 4, 4, 5, 5, 5], "spent": [1, 3, 5, 6, 6, 7, 7, 7]}
    e = episode_rollout(series, 0.75, 31, 2, 8, (0.25, 0.5, 0.75, 1.0))
    assert e.first_feature_turn == 3 and e.counts == {"label": 3, "demo": 1, "feature": 1, "none": 3}
    assert e.spent_at == (3.0, 6.0, 7.0, 7.0) and e.accuracy == 0.75 and (e.seed, e.dataset, e.turns) == (31, 2, 8)
    never = episode_rollout({**series, "feature": [0] * 8}, 0.5, 31, 0, 8, (1.0,))
    assert never.first_feature_turn is None
    assert spending_turns((0.25, 0.5, 0.75, 1.0), 30) == [8, 15, 23, 30]


def test_the_check_passes_when_all_three_criteria_hold():
    expert = [rollout(2, 1, 0.80), rollout(4, 1, 0.78)]
    checked = [rollout(3, 2, 0.82), rollout(5, 1, 0.79), rollout(1, 1, 0.80), rollout(2, 2, 0.78)]
    verdict = judge(checked, expert, SETTINGS)
    assert verdict["passes"] and [c["passes"] for c in verdict["criteria"]] == [True, True, True]
    assert verdict["checked_summary"]["feature_query_share"] == 1.0
    assert verdict["criteria"][1]["value"] == pytest.approx(0.5)  # 1.5 demos against 1.0
    assert verdict["criteria"][2]["value"] == pytest.approx(0.7975 - 0.79)


@pytest.mark.parametrize("checked, failing", [
    # (a) 3 of 5 episodes ask by turn 5: 60 % < 80 %; one never asks, one asks at turn 6
    ([rollout(1, 1, 0.8), rollout(2, 1, 0.8), rollout(5, 1, 0.8), rollout(6, 1, 0.8), rollout(None, 1, 0.8)], 0),
    # (b) 2.5 demonstrations a episode against the expert's 1
    ([rollout(1, 2, 0.8), rollout(1, 3, 0.8)], 1),
    # (c) ahead of the expert by 0.05: "within 0.03" holds on either side
    ([rollout(1, 1, 0.85), rollout(1, 1, 0.85)], 2),
    ([rollout(1, 1, 0.70), rollout(1, 1, 0.70)], 2),
])
def test_each_criterion_fails_on_its_own(checked, failing):
    expert = [rollout(2, 1, 0.80), rollout(3, 1, 0.80)]
    verdict = judge(checked, expert, SETTINGS)
    assert not verdict["passes"]
    assert [c["passes"] for c in verdict["criteria"]] == [i != failing for i in range(3)]


def test_exactly_at_a_threshold_passes():
    expert = [rollout(2, 1, 0.80)] * 2
    checked = [rollout(1, 2, 0.83)] * 4 + [rollout(None, 2, 0.83)]  # 80 % early, +1 demo, +0.03 accuracy
    assert judge(checked, expert, SETTINGS)["passes"]


def test_summary_means_and_the_first_feature_turn_where_asked():
    s = summarise([rollout(2, 1, 0.8), rollout(None, 3, 0.6)], by_turn=5)
    assert s["feature_query_share"] == 0.5 and s["feature_query_never"] == 1 and s["first_feature_turn_mean"] == 2
    assert s["questions"]["demo"] == 2.0 and s["accuracy"] == pytest.approx(0.7) and s["spent_at"] == [1, 2, 3, 4]


def test_settings_refuse_the_demonstrations_seeds_and_reported_data(tmp_path):
    with pytest.raises(ValueError, match="one of the expert demonstrations' seeds 1-30"):
        SETTINGS.overridden(seeds=(30, 31))
    with pytest.raises(ValueError, match="data seed >= 101"):
        SETTINGS.overridden(data_seed=100)
    assert SETTINGS.overridden(turns=8, seeds=(40,)).episodes == SETTINGS.datasets
    bad = tmp_path / "check.toml"
    bad.write_text(CHECK_FILE.read_text().replace("feature_query_share = 0.8", "feature_query_share = 1.5"))
    with pytest.raises(DataFileError, match="feature_query_share"):
        load_check_settings(bad)
    bad.write_text(CHECK_FILE.read_text().replace("data_seed = 101", "data_seed = 0"))
    with pytest.raises(DataFileError, match="calibration data"):
        load_check_settings(bad)
    assert replace(SETTINGS, seeds=(31,)).episodes == SETTINGS.datasets
