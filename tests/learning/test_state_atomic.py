"""LearningState validates before it mutates (issue 13, case 10): a bad call leaves it exactly as it was."""

import numpy as np
import pytest

import learning.state as state_module
from learning.actions import DemoQuery, FeatureQuery, LabelQuery, NoQuery
from learning.concepts import ConceptModels, FeatureScaler, checked_subset
from learning.state import LearningState

CONCEPTS = ("a", "b", "c")
FEATURES = ("f1", "f2", "f3")
PROBE = np.array([[0.0, 0.0, 0.0], [4.0, 0.0, 0.0], [0.0, 4.0, 1.0], [2.0, 2.0, -1.0]])


def _state(rng) -> LearningState:
    state = LearningState(CONCEPTS, FEATURES, budget=6, turns=10)
    centres = np.array([[0, 0, 0], [4, 0, 0], [0, 4, 0]], dtype=float)
    X = np.vstack([c + rng.normal(0, 0.5, (3, 3)) for c in centres])
    state.observe_scene(0, X)
    state.add_example(X[0], "a", "label")
    state.add_example(X[3], "b", "demo")
    state.record_turn(LabelQuery(0))
    return state


def _snapshot(state: LearningState) -> dict:
    return {
        "examples": [(e.x.tolist(), e.concept, e.source, e.scene_id) for e in state.examples],
        "scaler": (state.scaler.mean.tolist(), state.scaler.std.tolist(), state.scaler._count),
        "predictions": state.probabilities(PROBE).round(12).tolist(),
        "scene": (state.scene_id, state.scene_X.tolist()),
        "versions": (state.version, state.training_version),
        "sets": (set(state.asked_in_scene), set(state.demonstrated_in_scene), set(state.absent_in_scene)),
        "subsets": {c: None if s is None else s.tolist() for c, s in state.feature_subsets.items()},
        "clock": (state.spent, state.turn, list(state.history), state.feature_query_asked),
    }


BAD_CALLS = {
    "scene with a wrong number of features": lambda s: s.observe_scene(1, np.zeros((4, 2))),
    "scene that is one row": lambda s: s.observe_scene(1, np.zeros(3)),
    "scene with NaN": lambda s: s.observe_scene(1, np.array([[1.0, np.nan, 0.0], [0.0, 1.0, 2.0]])),
    "scene with infinity": lambda s: s.observe_scene(1, np.array([[1.0, np.inf, 0.0]])),
    "scene of words": lambda s: s.observe_scene(1, [["x", "y", "z"]]),
    "example of the wrong length": lambda s: s.add_example(np.zeros(4), "a", "label"),
    "example as a matrix": lambda s: s.add_example(np.zeros((2, 3)), "a", "label"),
    "example with NaN": lambda s: s.add_example(np.array([0.0, np.nan, 1.0]), "a", "label"),
    "example of an unknown concept": lambda s: s.add_example(np.zeros(3), "z", "label"),
    "example from an unknown source": lambda s: s.add_example(np.zeros(3), "a", "guess"),
    "no feature indices": lambda s: s.set_feature_subset([]),
    "feature index out of range": lambda s: s.set_feature_subset([0, 3]),
    "negative feature index": lambda s: s.set_feature_subset([-1]),
    "fractional feature index": lambda s: s.set_feature_subset([0.5, 1]),
    "feature names instead of indices": lambda s: s.set_feature_subset(["f1"]),
    "boolean feature mask": lambda s: s.set_feature_subset([True, False, True]),
    "unaffordable turn": lambda s: [s.record_turn(DemoQuery("a")) for _ in range(3)],
    "unknown action kind": lambda s: s.record_turn("ask nicely"),
    "label query outside the scene": lambda s: s.record_turn(LabelQuery(9)),
    "demonstration of an unknown concept": lambda s: s.record_turn(DemoQuery("z")),
}


@pytest.mark.parametrize("name", sorted(BAD_CALLS))
def test_a_bad_call_raises_a_clear_error_and_changes_nothing(name, rng):
    state = _state(rng)
    before = _snapshot(state)
    with pytest.raises(ValueError) as raised:
        BAD_CALLS[name](state)
    assert "Traceback" not in str(raised.value) and len(str(raised.value)) > 20
    if name != "unaffordable turn":  # two demonstrations fit the budget before the third is refused
        assert _snapshot(state) == before
    else:
        assert _snapshot(state)["examples"] == before["examples"] and state.spent == 5 and state.turn == 3
    # the next good calls still work
    state.add_example(np.array([0.1, 3.9, 0.2]), "c", "label")
    state.observe_scene(2, PROBE)
    state.set_feature_subset([0, 1])
    state.record_turn(LabelQuery(1))
    assert state.predict(PROBE[:2]).tolist() == ["a", "b"]


def test_the_issue_sequence_wrong_row_then_nan_scene_keeps_the_state_usable(rng):
    state = _state(rng)
    with pytest.raises(ValueError, match="3 feature values"):
        state.add_example(np.zeros(5), "a", "label")
    with pytest.raises(ValueError, match="NaN or infinite"):
        state.observe_scene(1, np.array([[np.nan, 0.0, 0.0]]))
    state.add_example(np.array([0.0, 4.0, 0.0]), "c", "demo")  # used to fail inside scipy with the bad example kept
    assert np.all(np.isfinite(state.scaler.mean)) and len(state.examples) == 3


def test_the_messages_name_what_was_wrong(rng):
    state = _state(rng)
    with pytest.raises(ValueError, match=r"row 0, column 1"):
        state.observe_scene(1, np.array([[1.0, np.nan, 0.0]]))
    with pytest.raises(ValueError, match="'guess'.*label, demo"):
        state.add_example(np.zeros(3), "a", "guess")
    with pytest.raises(ValueError, match=r"within 0\.\.2, got 7"):
        state.set_feature_subset([1, 7])
    with pytest.raises(ValueError, match="accepted kinds"):
        state.record_turn(object())


def test_a_refit_that_fails_undoes_the_change(rng, monkeypatch):
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
        state.add_example(np.array([1.0, 1.0, 1.0]), "a", "label")
    after = _snapshot(state)
    assert after["examples"] == before["examples"] and after["predictions"] == before["predictions"]
    assert after["versions"][1] == before["versions"][1]


def test_good_calls_still_accept_what_callers_pass(rng):
    state = _state(rng)
    state.set_feature_subset(np.array([2, 0, 2], dtype=np.int64))
    assert state.feature_subsets["a"].tolist() == [0, 2]
    state.add_example([1, 2, 3], "b", "label")  # a list of ints is a row
    state.record_turn(FeatureQuery())
    state.record_turn(NoQuery())
    state.record_turn(LabelQuery(np.int64(2)))
    assert state.turn == 4


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
