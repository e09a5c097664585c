"""LearningState validates before it mutates (issue 13, case 10; issue 14): a bad call leaves it exactly as it was,
its parts are read-only, and apply/undo are the only ways an answer changes it."""

import numpy as np
import pytest

import learning.state as state_module
from learning.actions import DemoQuery, FeatureQuery, LabelQuery, NoQuery
from learning.answers import Change, DemoRow
from learning.concepts import ConceptModels, FeatureScaler, checked_subset
from learning.state import LearningState

CONCEPTS = ("a", "b", "c")
FEATURES = ("f1", "f2", "f3")
PROBE = np.array([[0.0, 0.0, 0.0], [4.0, 0.0, 0.0], [0.0, 4.0, 1.0], [2.0, 2.0, -1.0]])


def _state(rng) -> LearningState:
    state = LearningState(CONCEPTS, FEATURES, budget=10, turns=20)
    centres = np.array([[0, 0, 0], [4, 0, 0], [0, 4, 0]], dtype=float)
    X = np.vstack([c + rng.normal(0, 0.5, (3, 3)) for c in centres])
    state.observe_scene(0, X)
    state.apply(LabelQuery(0), "a")
    state.apply(DemoQuery("b"), 3)
    return state


def _snapshot(state: LearningState) -> dict:
    return {
        "examples": [(e.x.tolist(), e.concept, e.source, e.scene_id) for e in state.examples],
        "scaler": (state.scaler.mean.tolist(), state.scaler.std.tolist(), state.scaler._count),
        "predictions": state.probabilities(PROBE).round(12).tolist(),
        "scene": (state.scene_id, state.scene_X.tolist()),
        "versions": (state.version, state.training_version),
        "sets": (state.asked_in_scene, state.demonstrated_in_scene, state.absent_in_scene),
        "subsets": {c: None if s is None else s.tolist() for c, s in state.feature_subsets.items()},
        "progress": state.progress,
    }


BAD_CALLS = {
    "scene with a wrong number of features": lambda s: s.observe_scene(1, np.zeros((4, 2))),
    "scene that is one row": lambda s: s.observe_scene(1, np.zeros(3)),
    "scene with NaN": lambda s: s.observe_scene(1, np.array([[1.0, np.nan, 0.0], [0.0, 1.0, 2.0]])),
    "scene with infinity": lambda s: s.observe_scene(1, np.array([[1.0, np.inf, 0.0]])),
    "scene of words": lambda s: s.observe_scene(1, [["x", "y", "z"]]),
    "demonstrated row of the wrong length": lambda s: s.apply(DemoQuery("a"), DemoRow(np.zeros(4))),
    "demonstrated row as a matrix": lambda s: s.apply(DemoQuery("a"), DemoRow(np.zeros((2, 3)))),
    "demonstrated row with NaN": lambda s: s.apply(DemoQuery("a"), DemoRow([0.0, np.nan, 1.0])),
    "demonstrated row of words": lambda s: s.apply(DemoQuery("a"), DemoRow(["x", "y", "z"])),
    "label of an unknown concept": lambda s: s.apply(LabelQuery(1), "z"),
    "demonstration outside the scene": lambda s: s.apply(DemoQuery("a"), 9),
    "demonstration as a boolean": lambda s: s.apply(DemoQuery("a"), True),
    "no feature indices": lambda s: s.apply(FeatureQuery(), []),
    "feature index out of range": lambda s: s.apply(FeatureQuery(), [0, 3]),
    "negative feature index": lambda s: s.apply(FeatureQuery(), [-1]),
    "fractional feature index": lambda s: s.apply(FeatureQuery(), [0.5, 1]),
    "unknown feature name": lambda s: s.apply(FeatureQuery(), ["f1", "f9"]),
    "boolean feature mask": lambda s: s.apply(FeatureQuery(), [True, False, True]),
    "an answer after no query": lambda s: s.apply(NoQuery(), 0),
    "unaffordable turn": lambda s: [s.apply(DemoQuery("a"), 1) for _ in range(4)],
    "unknown action kind": lambda s: s.apply("ask nicely"),
    "label query outside the scene": lambda s: s.apply(LabelQuery(9), "a"),
    "demonstration of an unknown concept": lambda s: s.apply(DemoQuery("z"), None),
    "undo of an answer that taught nothing": lambda s: s.undo(Change("skipped")),
    "undo of an example never added": lambda s: s.undo(Change("example", concept="a")),
    "progress beyond the budget": lambda s: s.place_progress(spent=11),
    "progress of an unknown field": lambda s: s.place_progress(budget=3),
    "history of unknown kinds": lambda s: s.place_progress(history=["label", "chat"]),
    "prior examples without concepts": lambda s: s.add_prior(np.zeros((2, 3)), ["a"]),
    "prior examples of unknown concepts": lambda s: s.add_prior(np.zeros((1, 3)), ["zebra"]),
}


@pytest.mark.parametrize("name", sorted(BAD_CALLS))
def test_a_bad_call_raises_a_clear_error_and_changes_nothing(name, rng):
    state = _state(rng)
    before = _snapshot(state)
    with pytest.raises(ValueError) as raised:
        BAD_CALLS[name](state)
    assert "Traceback" not in str(raised.value) and len(str(raised.value)) > 20
    if name != "unaffordable turn":  # three demonstrations fit the budget before the fourth is refused
        assert _snapshot(state) == before
    else:
        assert len(state.examples) == 5 and state.spent == 9 and state.turn == 5
    # the next good calls still work
    state.place_progress(spent=0)
    state.observe_scene(2, PROBE)
    state.apply(LabelQuery(2), "c")
    state.apply(FeatureQuery(), [0, 1])
    assert state.predict(PROBE[:2]).tolist() == ["a", "b"]


def test_the_issue_sequence_wrong_row_then_nan_scene_keeps_the_state_usable(rng):
    state = _state(rng)
    with pytest.raises(ValueError, match="3 feature values"):
        state.apply(DemoQuery("a"), DemoRow(np.zeros(5)))
    with pytest.raises(ValueError, match="NaN or infinite"):
        state.observe_scene(1, np.array([[np.nan, 0.0, 0.0]]))
    state.apply(DemoQuery("c"), DemoRow([0.0, 4.0, 0.0]))  # used to fail inside scipy with the bad example kept
    assert np.all(np.isfinite(state.scaler.mean)) and len(state.examples) == 3


def test_the_messages_name_what_was_wrong(rng):
    state = _state(rng)
    with pytest.raises(ValueError, match=r"row 0, column 1"):
        state.observe_scene(1, np.array([[1.0, np.nan, 0.0]]))
    with pytest.raises(ValueError, match=r"'z'"):
        state.apply(LabelQuery(0), "z")
    with pytest.raises(ValueError, match=r"within 0\.\.2, got 7"):
        state.apply(FeatureQuery(), [1, 7])
    with pytest.raises(ValueError, match="accepted kinds"):
        state.apply(object())
    with pytest.raises(ValueError, match="costs 2 but only 1 is left"):
        state.place_progress(spent=9)
        state.apply(DemoQuery("a"), 0)


def test_a_refit_that_fails_undoes_the_change_and_charges_nothing(rng, monkeypatch):
    state = _state(rng)
    before = _snapshot(state)
    real_fit = ConceptModels.fit
    calls = {"n": 0}

    def failing_once(self, *args):
        calls["n"] += 1
        if calls["n"] == 1:
            raise np.linalg.LinAlgError("not positive definite")
        return real_fit(self, *args)

    monkeypatch.setattr(state_module.ConceptModels, "fit", failing_once)
    with pytest.raises(np.linalg.LinAlgError):
        state.apply(LabelQuery(1), "a")
    after = _snapshot(state)
    assert after["examples"] == before["examples"] and after["predictions"] == before["predictions"]
    assert after["versions"][1] == before["versions"][1]
    assert after["progress"] == before["progress"] and after["sets"] == before["sets"]


def test_good_calls_still_accept_what_callers_pass(rng):
    state = _state(rng)
    change = state.apply(FeatureQuery(), np.array([2, 0, 2], dtype=np.int64))
    assert state.feature_subsets["a"].tolist() == [0, 2] and change.features == (0, 2)
    assert state.apply(DemoQuery("b"), DemoRow([1, 2, 3])).object is None  # a list of ints is a row
    state.apply(NoQuery())
    state.apply(LabelQuery(np.int64(2)), None)
    state.apply(DemoQuery("c"), np.int64(6))
    assert state.turn == 7 and state.history[-5:] == ("feature", "demo", "none", "label", "demo")


def test_the_parts_are_read_only(rng):
    state = _state(rng)
    for name in ("spent", "turn", "history", "scene_X", "examples", "feature_subsets", "absent_in_scene",
                 "feature_query_asked", "budget", "scene_id"):
        with pytest.raises(AttributeError):
            setattr(state, name, getattr(state, name))
    state.apply(FeatureQuery(), [0, 2])
    for array in (state.scene_X, state.examples[0].x, state.feature_subsets["a"], state.probabilities()):
        with pytest.raises(ValueError, match="read-only"):
            array[0] = 1.0
    with pytest.raises(TypeError):
        state.feature_subsets["a"] = None
    state.scaler.update(PROBE)  # a copy: the state's scaler is unchanged
    assert _snapshot(state)["scaler"][2] == 9


def test_apply_records_the_turn_in_the_right_order(rng):
    state = _state(rng)
    assert state.progress.spent == 3 and state.history == ("label", "demo") and state.turn == 2
    assert "b" not in state.absent_in_scene and state.demonstrated_in_scene == {3}  # shown, so not absent
    assert state.asked_in_scene == {0} and state.last_query_scene_id == 0
    assert state.apply(DemoQuery("c"), None).kind == "absent" and state.absent_in_scene == {"c"}
    assert state.apply(LabelQuery(4), None).kind == "skipped" and 4 in state.asked_in_scene
    state.observe_scene(1, PROBE)  # a new scene forgets what was said about the old one
    assert state.absent_in_scene == state.asked_in_scene == state.demonstrated_in_scene == frozenset()
    assert state.apply(NoQuery()).kind == "none" and state.quiet_run() == 1 and state.last_query_scene_id == 0


def test_undo_takes_back_the_answer_and_its_budget_but_not_the_turn(rng):
    state = _state(rng)
    before = _snapshot(state)
    shown = state.apply(DemoQuery("c"), 6)
    features = state.apply(FeatureQuery(), ["f2"])
    assert 6 in state.demonstrated_in_scene and state.feature_subsets["a"].tolist() == [1]
    state.undo(features)
    state.undo(shown)
    after = _snapshot(state)
    for key in ("examples", "predictions", "subsets", "scaler"):
        assert after[key] == before[key], key
    assert 6 not in state.demonstrated_in_scene and 3 in state.demonstrated_in_scene
    assert state.turn == 4 and state.spent == 3 and not state.feature_query_asked  # 2 + 2 given back, FQ re-opened
    with pytest.raises(ValueError, match="already taken back"):
        state.undo(shown)
    fetched = state.apply(DemoQuery("a"), DemoRow(state.scene_X[1]))  # a row equal to object 1 marks it shown
    assert fetched.object is None and 1 in state.demonstrated_in_scene
    state.undo(fetched)
    assert 1 not in state.demonstrated_in_scene


def test_prior_examples_join_the_scaler_and_may_set_features():
    state = LearningState(CONCEPTS, FEATURES, budget=4, turns=4)
    state.add_prior(PROBE[:3], ["a", "b", "c"], features=["f1", 1])
    assert len(state.examples) == 3 and state.scaler._count == 3 and state.turn == 0 and state.spent == 0
    assert all(s.tolist() == [0, 1] for s in state.feature_subsets.values())
    state.place_progress(turn=2, history=["none", "label"], feature_query_asked=True)
    assert state.quiet_run() == 0 and state.feature_query_asked and state.turn == 2


def test_scaler_and_models_check_caller_arrays_before_changing():
    scaler = FeatureScaler(2)
    scaler.update(np.array([[0.0, 1.0], [2.0, 3.0]]))
    mean = scaler.mean.copy()
    for bad in (np.array([[np.nan, 1.0]]), np.zeros((1, 3)), np.zeros(2)):
        with pytest.raises(ValueError):
            scaler.update(bad)
    assert np.array_equal(scaler.mean, mean) and scaler._count == 2
    with pytest.raises(ValueError, match="2 features"):
        scaler.transform(np.zeros((1, 3)))

    models = ConceptModels(("a", "b"), length_scale=1.0).fit(np.array([[0.0], [3.0]]), ["a", "b"], {})
    p_before = models.predict(np.array([[0.0], [3.0]]))
    for X, labels, subsets in ((np.array([[np.nan], [1.0]]), ["a", "b"], {}),
                               (np.array([[0.0], [1.0]]), ["a"], {}),
                               (np.array([[0.0], [1.0]]), ["a", "zebra"], {}),
                               (np.array([[0.0], [1.0]]), ["a", "b"], {"a": np.array([4])})):
        with pytest.raises(ValueError):
            models.fit(X, labels, subsets)
    assert np.array_equal(models.predict(np.array([[0.0], [3.0]])), p_before)


def test_checked_subset_sorts_and_deduplicates():
    assert checked_subset([3, 1, 3], 5).tolist() == [1, 3]
    assert checked_subset(np.int64(2), 5).tolist() == [2]
