"""Demonstration data, the DT choice rule and the weights file (thesis eq. 7.1, 7.2; §7.3.2)."""

import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from learning.decision.weights_file import DecisionWeights, load_weights, save_weights, weights_to_toml
from learning.irl.demonstrations import (
    DecisionTurn,
    QuestioningEpisode,
    load_episode_dir,
    load_episodes,
    save_episodes,
    turn_with_no_query,
)
from learning.irl.policy import agreement, greedy_choice, policy_probabilities, sample_choice

NAMES = ("acd", "cdu", "budget")


def make_episode(rng, name="e", n_turns=4, with_kinds=True):
    turns = []
    for _ in range(n_turns):
        n_queries = int(rng.integers(2, 6))
        kinds = ["label"] * (n_queries - 1) + ["demo"] if with_kinds else None
        turns.append(turn_with_no_query(rng.uniform(0, 1, 3), rng.uniform(0, 1, (n_queries, 3)),
                                        int(rng.integers(n_queries)) if rng.random() < 0.7 else None, kinds,
                                        [f"q{i}" for i in range(n_queries)] if with_kinds else None))
    return QuestioningEpisode(NAMES, turns, name, {"budget": 15, "task": "prepare-lunch"})


def assert_same_episodes(a, b):
    assert len(a) == len(b)
    for x, y in zip(a, b):
        assert (x.feature_names, x.name, x.metadata) == (y.feature_names, y.name, y.metadata)
        assert len(x.turns) == len(y.turns)
        for s, t in zip(x.turns, y.turns):
            assert np.array_equal(s.phi, t.phi) and s.chosen == t.chosen
            assert (s.kinds, s.labels) == (t.kinds, t.labels)


# -- the data model ----------------------------------------------------------------------------------------------
@pytest.mark.parametrize("phi, chosen, kinds, message", [
    ([1.0, 2.0], 0, None, "2-D"),
    (np.zeros((0, 3)), 0, None, "at least one action"),
    ([[0.0, np.nan]], 0, None, "finite"),
    ([["a", "b"]], 0, None, "numeric"),
    ([[0.0], [1.0]], 2, None, "index in 0..1"),
    ([[0.0], [1.0]], True, None, "index in 0..1"),
    ([[0.0], [1.0]], 0, ["label"], "2 strings"),
    ([[0.0], [1.0]], 0, ["label", "shout"], "unknown action kind 'shout'; accepted: label, demo, feature, none"),
    ([[0.0], [1.0]], 0, ["none", "none"], "at most one no-query"),
])
def test_a_bad_turn_is_refused_with_a_clear_message(phi, chosen, kinds, message):
    with pytest.raises(ValueError, match=message):
        DecisionTurn(phi, chosen, kinds)


@pytest.mark.parametrize("names, message", [
    (("a", "a"), "distinct; repeated: a"),
    (("a", "has space"), "not accepted"),
    ((), "non-empty"),
    ("abc", "non-empty list"),
])
def test_bad_feature_names_are_refused(names, message):
    with pytest.raises(ValueError, match=message):
        QuestioningEpisode(names, [DecisionTurn([[0.0, 1.0]], 0)])


def test_an_episode_checks_columns_turns_and_metadata():
    with pytest.raises(ValueError, match="2 feature columns, but the episode names 3"):
        QuestioningEpisode(NAMES, [DecisionTurn([[0.0, 1.0]], 0)], "x")
    with pytest.raises(ValueError, match="no turns"):
        QuestioningEpisode(NAMES, [], "x")
    with pytest.raises(ValueError, match="JSON-compatible"):
        QuestioningEpisode(NAMES, [DecisionTurn([[0.0, 1.0, 2.0]], 0)], "x", {"bad": math.nan})
    with pytest.raises(ValueError, match="metadata must be a table"):
        QuestioningEpisode(NAMES, [DecisionTurn([[0.0, 1.0, 2.0]], 0)], "x", [1, 2])


def test_no_query_is_the_last_candidate_with_the_state_features():
    state, queries = np.array([0.2, 0.4, 0.1]), np.array([[0.3, 0.5, 0.2], [0.1, 0.9, 0.3]])
    turn = turn_with_no_query(state, queries, None, ["label", "demo"], ["x", "y"])
    assert np.array_equal(turn.phi[-1], state) and np.array_equal(turn.phi[:2], queries)
    assert turn.chosen == 2 == turn.no_query_index
    assert turn.kinds == ("label", "demo", "none") and turn.labels == ("x", "y", "no query")
    assert turn_with_no_query(state, queries, 1).chosen == 1
    with pytest.raises(ValueError, match="None \\(no query\\) or an index in 0..1"):
        turn_with_no_query(state, queries, 2)
    with pytest.raises(ValueError, match="\\(n_queries x 3\\)"):
        turn_with_no_query(state, queries[:, :2], None)


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n_queries=st.integers(1, 8), copy_state=st.booleans())
def test_argmax_with_no_query_is_the_dt_rule(seed, n_queries, copy_state):
    """a* = argmax EU(a) is taken only if EU(a*) > U(s) (thesis §6.3, §7.3.1): argmax over queries + NQ, ties to NQ."""
    rng = np.random.default_rng(seed)
    state, queries, w = rng.uniform(0, 1, 4), rng.uniform(0, 1, (n_queries, 4)), rng.normal(size=4)
    if copy_state:  # a query that changes nothing ties with no query
        queries[0] = state
        queries[1:] = np.where((queries[1:] @ w > state @ w)[:, None], state - 0.1 * np.sign(w), queries[1:])
    turn = turn_with_no_query(state, queries, None, ["label"] * n_queries)
    eu = queries @ w
    best = int(np.argmax(eu))
    expected = best if eu[best] > state @ w + 1e-12 else n_queries
    assert greedy_choice(turn, w) == expected


def test_agreement_skips_forced_turns_and_needs_a_choice():
    w = np.array([1.0, 0.0, -1.0])
    forced = DecisionTurn([[0.0, 0.0, 0.0]], 0, ["none"])
    good = DecisionTurn([[1.0, 0.0, 0.0], [0.0, 0.0, 0.0]], 0)
    bad = DecisionTurn([[1.0, 0.0, 0.0], [0.0, 0.0, 0.0]], 1)
    assert agreement([QuestioningEpisode(NAMES, [forced, good, bad, good])], w) == pytest.approx(2 / 3)
    with pytest.raises(ValueError, match="no turn offers a choice"):
        agreement([QuestioningEpisode(NAMES, [forced])], w)


def test_the_maxent_policy_is_a_softmax_of_utilities():
    phi, w = np.array([[1.0, 0.0], [0.0, 1.0], [0.0, 0.0]]), np.array([2.0, 1.0])
    p = policy_probabilities(phi, w)
    assert p == pytest.approx(np.exp([2.0, 1.0, 0.0]) / np.exp([2.0, 1.0, 0.0]).sum())
    assert policy_probabilities(phi, 1e4 * w) == pytest.approx([1.0, 0.0, 0.0])  # no overflow
    draws = [sample_choice(phi, w, np.random.default_rng(3)) for _ in range(2)]
    assert draws[0] == draws[1]
    counts = np.bincount([sample_choice(phi, w, r) for r in [np.random.default_rng(0)] for _ in range(4000)],
                         minlength=3)
    assert counts / 4000 == pytest.approx(p, abs=0.03)


def test_feature_counts_sum_the_chosen_rows():
    turns = [DecisionTurn([[1.0, 2.0, 3.0], [0.0, 0.0, 0.0]], 0), DecisionTurn([[5.0, 5.0, 5.0], [1.0, 1.0, 1.0]], 1)]
    assert QuestioningEpisode(NAMES, turns).feature_counts() == pytest.approx([2.0, 3.0, 4.0])


# -- files --------------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("suffix", [".json", ".npz"])
def test_episodes_round_trip_exactly(tmp_path, suffix):
    rng = np.random.default_rng(4)
    episodes = [make_episode(rng, "a"), make_episode(rng, "b", n_turns=2)]
    path = save_episodes(tmp_path / f"demos{suffix}", episodes)
    assert_same_episodes(load_episodes(path), episodes)


def test_npz_without_kinds_round_trips_and_mixed_kinds_go_to_json(tmp_path):
    rng = np.random.default_rng(5)
    plain = [make_episode(rng, "p", with_kinds=False)]
    assert_same_episodes(load_episodes(save_episodes(tmp_path / "p.npz", plain)), plain)
    mixed = [make_episode(rng, "k"), make_episode(rng, "p", with_kinds=False)]
    with pytest.raises(ValueError, match="every turn or on none"):
        save_episodes(tmp_path / "m.npz", mixed)
    assert_same_episodes(load_episodes(save_episodes(tmp_path / "m.json", mixed)), mixed)


def test_a_directory_of_demonstrations_loads_in_name_order(tmp_path):
    rng = np.random.default_rng(6)
    save_episodes(tmp_path / "b.npz", [make_episode(rng, "second")])
    save_episodes(tmp_path / "a.json", [make_episode(rng, "first")])
    (tmp_path / "notes.txt").write_text("ignored")
    assert [e.name for e in load_episode_dir(tmp_path)] == ["first", "second"]
    other = QuestioningEpisode(("x", "y", "z"), [DecisionTurn([[0.0, 1.0, 2.0], [1.0, 1.0, 1.0]], 0)], "other")
    save_episodes(tmp_path / "c.json", [other])
    with pytest.raises(ValueError, match="all must match"):
        load_episode_dir(tmp_path)
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(ValueError, match="no demonstration files"):
        load_episode_dir(empty)
    with pytest.raises(FileNotFoundError, match="does not exist"):
        load_episode_dir(tmp_path / "missing")


def _json_document(tmp_path):
    path = save_episodes(tmp_path / "d.json", [make_episode(np.random.default_rng(7))])
    return path, json.loads(path.read_text())


@pytest.mark.parametrize("change, message", [
    (lambda d: d.update(format="something-else"), "not a demonstration file"),
    (lambda d: d.update(format_version=9), "version 9 is not supported; accepted: 2"),
    (lambda d: d.pop("feature_names"), "missing field 'feature_names'"),
    (lambda d: d.update(episodes=[]), "non-empty list"),
    (lambda d: d["episodes"][0].update(extra=1), "unknown field 'extra'"),
    (lambda d: d["episodes"][0]["turns"][1].update(chosen=99), "episode 0, turn 1: chosen action must be"),
    (lambda d: d["episodes"][0]["turns"][2].pop("phi"), "episode 0, turn 2: expected an object with 'phi'"),
    (lambda d: d["episodes"][0]["turns"][0].update(kinds=["label"]), "episode 0, turn 0: action kinds"),
])
def test_a_broken_json_file_names_the_file_and_the_problem(tmp_path, change, message):
    path, document = _json_document(tmp_path)
    change(document)
    path.write_text(json.dumps(document))
    with pytest.raises(ValueError, match=message) as error:
        load_episodes(path)
    assert str(error.value).startswith(str(path))


def test_unreadable_files_are_refused(tmp_path):
    with pytest.raises(FileNotFoundError, match="does not exist"):
        load_episodes(tmp_path / "nope.json")
    (tmp_path / "bad.json").write_text("{not json")
    with pytest.raises(ValueError, match="not valid JSON"):
        load_episodes(tmp_path / "bad.json")
    (tmp_path / "deep.json").write_text("[" * 100000)  # found by scripts/fuzz_files.py: a RecursionError before
    with pytest.raises(ValueError, match="deep.json: not valid JSON for a demonstration file .*nested too deeply"):
        load_episodes(tmp_path / "deep.json")
    (tmp_path / "demos.csv").write_text("1,2")
    with pytest.raises(ValueError, match="accepted: .json, .npz"):
        load_episodes(tmp_path / "demos.csv")
    with pytest.raises(ValueError, match="accepted: .json, .npz"):
        save_episodes(tmp_path / "demos.pkl", [make_episode(np.random.default_rng(0))])
    np.savez(tmp_path / "pickled.npz", phi=np.array([{"a": 1}], dtype=object))
    with pytest.raises(ValueError, match="without pickled objects"):
        load_episodes(tmp_path / "pickled.npz")


def test_an_npz_with_inconsistent_offsets_is_refused(tmp_path):
    path = save_episodes(tmp_path / "d.npz", [make_episode(np.random.default_rng(8))])
    with np.load(path) as data:
        arrays = {key: data[key] for key in data.files}
    arrays["turn_offsets"] = arrays["turn_offsets"][::-1]
    np.savez(path, **arrays)
    with pytest.raises(ValueError, match="turn_offsets"):
        load_episodes(path)
    arrays.pop("turn_offsets")
    np.savez(path, **arrays)
    with pytest.raises(ValueError, match="missing array 'turn_offsets'"):
        load_episodes(path)


# -- the weights file ------------------------------------------------------------------------------------------
def test_weights_round_trip_through_toml_exactly(tmp_path):
    values = [0.1, -2.5e-7, 123456.789, 0.0, 3.0]  # within the weights' limit of 1e6 (learning/data/limits.toml)
    provenance = {"method": 'maxent "irl"\n', "iterations": 41, "converged": True, "note": "é\x7f", "l2": 1e-3}
    weights = DecisionWeights(("a", "b_c", "d-e", "f1", "g"), values, provenance)
    path = save_weights(tmp_path / "w.toml", weights, comment="learned from 3 episodes\nsecond line")
    text = path.read_text()
    assert text.startswith("# learned from 3 episodes\n# second line\n[weights]\na = 0.1\n")
    loaded = load_weights(path)
    assert loaded.feature_names == weights.feature_names and loaded.values.tolist() == values
    assert loaded.provenance == provenance
    reordered = load_weights(path, ["g", "a", "b_c", "d-e", "f1"])
    assert reordered.feature_names[0] == "g" and reordered.values[0] == 3.0
    assert weights.vector(["g", "a", "b_c", "d-e", "f1"]).tolist() == [3.0, 0.1, -2.5e-7, 123456.789, 0.0]


@pytest.mark.parametrize("text, message", [
    ("[weights]\na = 1.0\n", "missing \\['b'\\], unknown \\[\\]"),
    ("[weights]\na = 1.0\nb = 2.0\nc = 3.0\n", "unknown \\['c'\\]"),
    ("[weights]\na = 1.0\nb = 'high'\n", "weight 'b' must be a finite number, got 'high'"),
    ("[weights]\na = 1.0\nb = true\n", "weight 'b' must be a finite number"),
    ("[weights]\na = 1.0\nb = inf\n", "weight 'b' must be a finite number"),
    ("a = 1.0\n", "unknown table or key 'a'"),
    ("[provenance]\nx = 1\n", "non-empty \\[weights\\] table"),
    ("[weights]\na = 1.0\nb = 2.0\n[provenance]\nx = [1, 2]\n", "x must be a string, number or boolean"),
    ("[weights\n", "not valid TOML"),
])
def test_a_bad_weights_file_is_refused_with_its_path(tmp_path, text, message):
    path = tmp_path / "w.toml"
    path.write_text(text)
    with pytest.raises(ValueError, match=message) as error:
        load_weights(path, ["a", "b"])
    assert str(error.value).startswith(str(path))


def test_weights_check_their_own_shape_and_file_name(tmp_path):
    with pytest.raises(ValueError, match="expected 2 values"):
        DecisionWeights(("a", "b"), [1.0])
    with pytest.raises(ValueError, match="finite"):
        DecisionWeights(("a", "b"), [1.0, math.inf])
    with pytest.raises(ValueError, match="must end in .toml"):
        save_weights(tmp_path / "w.json", DecisionWeights(("a",), [1.0]))
    with pytest.raises(FileNotFoundError, match="does not exist"):
        load_weights(tmp_path / "missing.toml")
    assert weights_to_toml(DecisionWeights(("a",), [1.0])) == "[weights]\na = 1.0\n"
