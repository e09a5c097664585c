"""Eq. 7.1 as written: every action, no query included, is scored at its own next state s_{t+1}."""

import json
import re
from pathlib import Path

import numpy as np
import pytest

from learning.actions import NoQuery
from learning.decision.candidates import expected_decision_features
from learning.decision.features import FEATURE_NAMES, state_features
from learning.irl.demonstrations import (
    FORMAT_VERSION,
    DecisionTurn,
    QuestioningEpisode,
    load_episode_dir,
    load_episodes,
    save_episodes,
)
from learning.state import LearningState
from learning.strategies import DecisionTheoreticStrategy
from learning.synthetic import SyntheticTask

TASK = SyntheticTask(n_features=6, n_informative=2, seed=11)
LEARNING = slice(0, FEATURE_NAMES.index("budget_consumption"))
BUDGET, TIME, QUIET = (FEATURE_NAMES.index(n) for n in ("budget_consumption", "remaining_time", "non_query_time"))
ENGINES = ("fast", "reference")
COSTS = {"label": 1, "demo": 2, "feature": 2, "none": 0}
SHIPPED_DEMOS = Path(__file__).resolve().parents[2] / "learning" / "irl" / "expert-demos"


def fresh_episode(seed=0, budget=12.0, turns=9, change_every=3):
    """A state at turn 0 and its scene's true labels."""
    rng = np.random.default_rng(seed)
    state = LearningState(TASK.concepts, TASK.feature_names, budget, turns, dict(COSTS), change_every=change_every)
    X, labels = TASK.sample(8, rng, np.array([0.4, 0.3, 0.2, 0.1]))
    state.add_prior(X, labels)
    scene_X, scene_labels = TASK.sample(6, rng)
    state.observe_scene(0, scene_X)
    return state, scene_labels


def answer(action, scene_labels):
    if action.kind == "label":
        return str(scene_labels[action.object_index])
    if action.kind == "demo":
        shown = [i for i, label in enumerate(scene_labels) if label == action.concept]
        return shown[0] if shown else None
    return None


PLAN = ("none", "none", "label", "none", "demo", "none", "none", "none", "none")  # the quiet run reaches the window


def play(engine, record=None):
    """Play PLAN with the scripted labels; check the no-query row of every turn against eq. 7.1."""
    state, scene_labels = fresh_episode()
    window = state.change_every
    quiet_run = 0
    for kind in PLAN:
        candidates = expected_decision_features(state, engine)
        now = state_features(state)
        np.testing.assert_allclose(candidates.current, now)  # ``current`` stays phi(s)
        quiet = candidates.expected[candidates.no_query_index]
        assert candidates.actions[candidates.no_query_index] == NoQuery()
        np.testing.assert_array_equal(quiet[LEARNING], now[LEARNING])  # nothing is learned by staying quiet
        assert quiet[BUDGET] == pytest.approx(state.spent / state.budget)
        assert quiet[TIME] == pytest.approx((state.turns - state.turn - 1) / state.turns)  # the clock moves on
        assert quiet[QUIET] == pytest.approx(min(quiet_run + 1, window) / window)  # and silence grows
        for action, row in zip(candidates.actions[:-1], candidates.expected[:-1]):
            assert row[TIME] == quiet[TIME] and row[QUIET] == 0.0  # a query: the same clock, t_NQ = 0
            assert row[BUDGET] == pytest.approx((state.spent + state.cost(action)) / state.budget)
        action = next(a for a in candidates.actions if a.kind == kind)
        if record is not None:
            record.append((candidates, candidates.actions.index(action)))
        state.apply(action, answer(action, scene_labels))
        quiet_run = quiet_run + 1 if kind == "none" else 0
    return state


@pytest.mark.parametrize("engine", ENGINES)
def test_the_no_query_row_is_the_next_state_in_both_engines(engine):
    assert len(play(engine).examples) >= 9  # the label (and demo) turns taught something


def test_both_engines_give_the_same_rows():
    fast, reference = [], []
    play("fast", fast)
    play("reference", reference)
    for (a, _), (b, _) in zip(fast, reference):
        assert a.actions == b.actions
        np.testing.assert_allclose(a.expected[-1], b.expected[-1], rtol=0, atol=1e-12)  # no query: exactly
        np.testing.assert_array_equal(a.expected[:, BUDGET:], b.expected[:, BUDGET:])  # one clock for both


@pytest.mark.parametrize("engine", ENGINES)
def test_with_the_budget_spent_no_query_still_moves_the_clock(engine):
    state, _ = fresh_episode(budget=0.0)
    candidates = expected_decision_features(state, engine)
    assert candidates.actions == (NoQuery(),)
    assert candidates.expected[0][TIME] == pytest.approx((state.turns - 1) / state.turns)
    assert candidates.expected[0][QUIET] == pytest.approx(1 / state.change_every)


def test_time_passes_whatever_is_asked_and_silence_has_a_price():
    state, _ = fresh_episode()
    # remaining time is the same on every row: a weight on it alone leaves a tie, which goes to no query
    timed = DecisionTheoreticStrategy({"remaining_time": 5.0}).choose(state, np.random.default_rng(0))
    assert timed.action == NoQuery()
    # a learner that dislikes silence asks: no query's t_NQ rises, a query's is 0
    eager = DecisionTheoreticStrategy({"non_query_time": -1.0}).choose(state, np.random.default_rng(0))
    assert eager.action != NoQuery()


def test_the_explanations_say_in_words_which_weighted_feature_decided():
    """Issue 39: "Why?" names what decided in words; the numbers stay in the decision's terms, for reports."""
    state, _ = fresh_episode()
    state.apply(NoQuery())
    quiet = DecisionTheoreticStrategy({"budget_consumption": -1.0}).choose(state, np.random.default_rng(0))
    assert quiet.action == NoQuery()
    assert "budget" in quiet.explanation and not re.search(r"\d\.\d", quiet.explanation)
    assert dict(quiet.terms)["budget_consumption"] < 0  # EU(best query) - EU(no query), feature by feature
    asking = DecisionTheoreticStrategy({"classifier_discriminability": 1.0}).choose(state, np.random.default_rng(0))
    assert asking.action != NoQuery()
    assert "learn" in asking.explanation and not re.search(r"\d\.\d", asking.explanation)
    assert dict(asking.terms)["classifier_discriminability"] > 0


# -- demonstration files: format version 2, and version 1 converted or refused ----------------------------------
def recorded_episode():
    """An episode as expert mode records it, and its rows as version 1 wrote them (no query at phi(s))."""
    record = []
    play("fast", record)
    turns = [DecisionTurn(c.expected, chosen, tuple(a.kind for a in c.actions)) for c, chosen in record]
    metadata = {"turns": 9, "change_every": 3, "window_factor": 1.0, "costs": COSTS, "engine": "fast"}
    episode = QuestioningEpisode(FEATURE_NAMES, turns, "recorded", metadata)
    old_rows = [np.vstack([c.expected[:-1], c.current]) for c, _ in record]
    return episode, old_rows


def as_version_1(document, old_rows, metadata=None):
    document.pop("format_version")
    document["version"] = 1
    for turn, rows in zip(document["episodes"][0]["turns"], old_rows):
        turn["phi"] = rows.tolist()
    if metadata is not None:
        document["episodes"][0]["metadata"] = metadata
    return document


def test_new_files_carry_format_version_2(tmp_path):
    episode, _ = recorded_episode()
    document = json.loads(save_episodes(tmp_path / "d.json", [episode]).read_text())
    assert FORMAT_VERSION == 2 and document["format_version"] == 2 and "version" not in document
    with np.load(save_episodes(tmp_path / "d.npz", [episode])) as arrays:
        assert int(arrays["format_version"]) == 2


def test_a_version_1_json_file_is_converted_exactly(tmp_path):
    episode, old_rows = recorded_episode()
    path = save_episodes(tmp_path / "old.json", [episode])
    path.write_text(json.dumps(as_version_1(json.loads(path.read_text()), old_rows)))
    (loaded,) = load_episodes(path)
    assert loaded.metadata["converted_from_format_version"] == 1
    for new, converted in zip(episode.turns, loaded.turns):
        np.testing.assert_allclose(converted.phi, new.phi, rtol=0, atol=1e-12)
        assert (converted.chosen, converted.kinds) == (new.chosen, new.kinds)


def test_a_version_1_npz_file_is_converted_exactly(tmp_path):
    episode, old_rows = recorded_episode()
    path = save_episodes(tmp_path / "old.npz", [episode])
    with np.load(path) as data:
        arrays = {key: data[key] for key in data.files}
    arrays["version"] = arrays.pop("format_version")
    arrays["version"][...] = 1
    arrays["phi"] = np.vstack(old_rows)
    np.savez(path, **arrays)
    (loaded,) = load_episodes(path)
    np.testing.assert_allclose(np.vstack([t.phi for t in loaded.turns]), np.vstack([t.phi for t in episode.turns]),
                               rtol=0, atol=1e-12)


@pytest.mark.parametrize("metadata, reason", [
    ({"source": "synthetic", "turns": 9, "change_every": 3}, "does not record window_factor, costs"),
    ({"turns": 9, "change_every": 3, "window_factor": 1.0, "costs": {**COSTS, "none": 1}}, "a free no query"),
    ({"turns": 9, "change_every": 5, "window_factor": 1.0, "costs": COSTS}, "are not k / 9 and q / 5"),
])
def test_a_version_1_file_that_cannot_be_converted_is_refused(tmp_path, metadata, reason):
    episode, old_rows = recorded_episode()
    path = save_episodes(tmp_path / "old.json", [episode])
    path.write_text(json.dumps(as_version_1(json.loads(path.read_text()), old_rows, metadata)))
    with pytest.raises(ValueError) as error:
        load_episodes(path)
    message = str(error.value)
    assert message.startswith(str(path)) and "\n" not in message
    assert "format version 1" in message and reason in message
    assert "scripts/make_expert_demos.py" in message and "teachbot expert" in message


def test_an_unknown_version_or_two_version_fields_are_refused(tmp_path):
    episode, _ = recorded_episode()
    path = save_episodes(tmp_path / "d.json", [episode])
    document = json.loads(path.read_text())
    path.write_text(json.dumps({**document, "version": 1}))
    with pytest.raises(ValueError, match="both 'format_version' and 'version'"):
        load_episodes(path)
    path.write_text(json.dumps({**document, "format_version": 3}))
    with pytest.raises(ValueError, match="version 3 is not supported; accepted: 2 .*make_expert_demos"):
        load_episodes(path)


def test_the_shipped_demonstrations_load_with_no_query_at_the_next_state():
    episodes = load_episode_dir(SHIPPED_DEMOS)
    assert episodes
    for episode in episodes:
        for turn in episode.turns:
            rows = turn.phi
            assert np.all(rows[:, TIME] == rows[turn.no_query_index, TIME])  # one clock for every candidate
            assert np.all(np.delete(rows[:, QUIET], turn.no_query_index) == 0.0)
            assert rows[turn.no_query_index, QUIET] > 0.0  # at least this quiet turn

