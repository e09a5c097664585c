"""A learned questioner: the fixed observation slots, the policy file (TOML + NPZ, no pickle), and rl:FILE."""

import numpy as np
import pytest

from learning.actions import DemoQuery, FeatureQuery, LabelQuery, NoQuery
from learning.decision.candidates import expected_decision_features
from learning.errors import DataFileError, SettingsError
from learning.rl.observation import N_FEATURES, ObservationLayout
from learning.rl.policy_file import QuestionerPolicy, load_policy, save_policy
from learning.state import LearningState
from learning.strategies import make_strategy
from learning.strategies.rl_questioner import RLQuestionerStrategy

CONCEPTS = ("a", "b", "c")


def scene_state(rng, objects=6, budget=10.0):
    state = LearningState(CONCEPTS, ["f1", "f2", "f3"], budget=budget, turns=10)
    centres = np.array([[0, 0, 0], [4, 0, 0], [0, 4, 0]], dtype=float)
    state.observe_scene(0, centres[np.arange(objects) % 3] + rng.normal(0, 0.5, (objects, 3)))
    return state


def random_policy(layout, rng, hidden=(5,)):
    sizes = [layout.size, *hidden, layout.n_actions]
    weights = tuple(rng.normal(0, 1, (sizes[k + 1], sizes[k])) for k in range(len(sizes) - 1))
    biases = tuple(rng.normal(0, 1, sizes[k + 1]) for k in range(len(sizes) - 1))
    return QuestionerPolicy(layout, weights, biases, "tanh", {"method": "test", "seed": 1})


def preferring(layout, slot, rng):
    """A one-layer policy whose logits rank ``slot`` first, then the slots in order."""
    weights = np.zeros((layout.n_actions, layout.size))
    bias = -np.arange(layout.n_actions, dtype=float)
    bias[slot] = 100.0
    return QuestionerPolicy(layout, (weights,), (bias,))


def test_the_observation_holds_phi_each_slots_expected_features_and_the_mask(rng):
    state = scene_state(rng)
    layout = ObservationLayout(CONCEPTS, max_objects=8)
    observation = layout.encode(state)
    assert observation.vector.shape == (layout.size,) == (N_FEATURES * (1 + 13) + 13,)
    assert observation.vector.dtype == np.float32 and 0 <= observation.vector.min() <= observation.vector.max() <= 1
    assert list(observation.mask) == [True] * 11 + [False, False]  # 6 objects of 8 slots
    assert observation.actions[:5] == (NoQuery(), FeatureQuery(), DemoQuery("a"), DemoQuery("b"), DemoQuery("c"))
    assert observation.actions[5] == LabelQuery(0) and observation.actions[11] is None
    expected = expected_decision_features(state)
    rows = observation.vector[N_FEATURES:N_FEATURES * 14].reshape(13, N_FEATURES)
    for action, row in zip(expected.actions, expected.expected):
        np.testing.assert_allclose(rows[layout.slot_of(action)], row, atol=1e-6)
    assert not rows[11:].any()
    short = ObservationLayout(CONCEPTS, max_objects=8, whatif=False).encode(state)
    assert short.vector.shape == (N_FEATURES + 13,)


def test_the_layout_refuses_other_concepts_or_larger_scenes(rng):
    state = scene_state(rng, objects=6)
    with pytest.raises(SettingsError, match="at most 4 objects; this scene has 6"):
        ObservationLayout(CONCEPTS, max_objects=4).encode(state)
    with pytest.raises(SettingsError, match=r"trained for the concepts \['x', 'y'\]"):
        ObservationLayout(("x", "y"), max_objects=8).encode(state)


def test_a_policy_file_round_trips_without_pickle(rng, tmp_path):
    layout = ObservationLayout(CONCEPTS, max_objects=8)
    policy = random_policy(layout, rng)
    path = save_policy(tmp_path / "q.toml", policy, "a comment")
    loaded = load_policy(path)
    x = rng.uniform(0, 1, layout.size)
    np.testing.assert_allclose(loaded.logits(x), policy.logits(x))
    assert loaded.layout == layout and loaded.provenance == {"method": "test", "seed": 1}
    assert loaded.layers == [layout.size, 5, layout.n_actions]
    with np.load(tmp_path / "q.npz", allow_pickle=False) as arrays:
        assert sorted(arrays.files) == ["b0", "b1", "w0", "w1"]


def test_bad_policy_files_are_one_message(rng, tmp_path):
    layout = ObservationLayout(CONCEPTS, max_objects=8)
    path = save_policy(tmp_path / "q.toml", random_policy(layout, rng))
    with pytest.raises(DataFileError, match="no questioner policy file there"):
        load_policy(tmp_path / "missing.toml")
    npz = tmp_path / "q.npz"
    npz.write_bytes(npz.read_bytes() + b"x")
    with pytest.raises(DataFileError, match="SHA-256 is not the one q.toml records"):
        load_policy(path)
    path = save_policy(tmp_path / "q.toml", random_policy(layout, rng))
    path.write_text(path.read_text().replace("whatif = true", "whatif = false"))
    with pytest.raises(DataFileError, match="do not take"):
        load_policy(path)
    with pytest.raises(DataFileError, match="must end in .toml"):
        save_policy(tmp_path / "q.json", random_policy(layout, rng))


def test_the_strategy_takes_the_best_allowed_slot(rng, tmp_path):
    state = scene_state(rng, objects=6)
    layout = ObservationLayout(CONCEPTS, max_objects=8)
    assert RLQuestionerStrategy(preferring(layout, 3, rng)).choose(state, rng).action == DemoQuery("b")
    assert RLQuestionerStrategy(preferring(layout, 7, rng)).choose(state, rng).action == LabelQuery(2)
    masked = RLQuestionerStrategy(preferring(layout, 12, rng))  # object 8 is not in this scene: the next best
    decision = masked.choose(state, rng)
    assert decision.action == NoQuery() and "stay quiet" in decision.explanation
    broke = scene_state(rng, budget=0.0)
    assert RLQuestionerStrategy(preferring(layout, 3, rng)).choose(broke, rng).action == NoQuery()
    path = save_policy(tmp_path / "q.toml", preferring(layout, 1, rng))
    by_name = make_strategy(f"rl:{path}")
    assert by_name.name == f"rl:{path}" and by_name.choose(state, rng).action == FeatureQuery()
    assert by_name.header_fields()["policy"]["file"] == str(path.resolve())
    with pytest.raises(DataFileError, match="no questioner policy file"):
        make_strategy("rl:nowhere.toml")


# -- issue 24, item 5: the weights file a policy names, its arrays, and never a pickle ------------------------
def _hostile(tmp_path, rng, arrays_bytes=None, weights=None, edit=None):
    """A policy whose TOML names ``weights`` and records the SHA-256 of ``arrays_bytes`` (as a hostile edit
    would, so the digest check does not stand in for the others); returns load_policy's refusal."""
    import hashlib
    import re

    path = save_policy(tmp_path / "q.toml", random_policy(ObservationLayout(CONCEPTS, max_objects=8), rng))
    if arrays_bytes is not None:
        (tmp_path / "q.npz").write_bytes(arrays_bytes)
    digest = hashlib.sha256((tmp_path / (weights or "q.npz")).read_bytes()
                            if (tmp_path / (weights or "q.npz")).is_file() else b"").hexdigest()
    text = re.sub(r'sha256 = ".*"', f'sha256 = "{digest}"', path.read_text())
    if weights is not None:
        text = re.sub(r'weights = ".*"', f'weights = "{weights}"', text)
    path.write_text(edit(text) if edit else text)
    with pytest.raises(DataFileError) as raised:
        load_policy(path)
    message = str(raised.value)
    assert str(tmp_path / "q.") in message and "\n" not in message, message  # names the file
    return message


def _npz(arrays: dict) -> bytes:
    import io

    buffer = io.BytesIO()
    np.savez(buffer, **arrays)
    return buffer.getvalue()


@pytest.mark.parametrize("weights", ["../../etc/passwd", "/etc/passwd", ".", "..", "sub/q.npz", "q.toml"])
def test_a_policy_names_only_the_npz_beside_it(rng, tmp_path, weights):
    assert "it must be the name of the .npz file beside q.toml" in _hostile(tmp_path, rng, weights=weights)


def test_a_weights_link_out_of_the_policy_folder_is_refused(rng, tmp_path):
    import os

    outside = tmp_path / "elsewhere"
    outside.mkdir()
    inside = tmp_path / "policy"
    inside.mkdir()
    save_policy(outside / "q.toml", random_policy(ObservationLayout(CONCEPTS, max_objects=8), rng))
    path = save_policy(inside / "q.toml", random_policy(ObservationLayout(CONCEPTS, max_objects=8), rng))
    (inside / "q.npz").unlink()
    os.symlink(outside / "q.npz", inside / "q.npz")
    import hashlib
    import re

    digest = hashlib.sha256((outside / "q.npz").read_bytes()).hexdigest()
    path.write_text(re.sub(r'sha256 = ".*"', f'sha256 = "{digest}"', path.read_text()))
    with pytest.raises(DataFileError, match="is a link to .* outside the policy's folder"):
        load_policy(path)


def test_damaged_or_foreign_weights_files_are_refused_naming_the_file(rng, tmp_path):
    layout = ObservationLayout(CONCEPTS, max_objects=8)
    policy = random_policy(layout, rng)
    arrays = {f"w{k}": w for k, w in enumerate(policy.weights)} | {f"b{k}": b for k, b in enumerate(policy.biases)}
    good = _npz(arrays)
    assert "got an empty file" in _hostile(tmp_path, rng, b"")
    damaged = bytearray(good)
    damaged[good.index(b"NUMPY") + 130] ^= 0xFF
    assert "Bad CRC-32" in _hostile(tmp_path, rng, bytes(damaged))
    import io

    npy = io.BytesIO()
    np.save(npy, policy.weights[0])
    assert "not an NPZ archive" in _hostile(tmp_path, rng, npy.getvalue())
    assert "array w0 holds complex128 values; expected real floats" in _hostile(
        tmp_path, rng, _npz(arrays | {"w0": policy.weights[0] * (1 + 1j)}))
    assert "array b0 holds int64 values" in _hostile(tmp_path, rng, _npz(arrays | {"b0": np.zeros(5, dtype=int)}))
    assert "array w1 holds 1e+308, beyond the limit of 1e+06" in _hostile(
        tmp_path, rng, _npz(arrays | {"w1": np.full_like(policy.weights[1], 1e308)}))
    assert "holds the arrays ['b0', 'b1', 'w0', 'w1', 'x']" in _hostile(tmp_path, rng, _npz(arrays | {"x": np.ones(1)}))
    assert "do not take" in _hostile(tmp_path, rng, _npz(arrays | {"w0": policy.weights[0][:, :3]}))
    pickled = io.BytesIO()
    np.savez(pickled, **(arrays | {"w0": np.array([{"a": 1}], dtype=object)}))
    assert "is damaged or not an NPZ" in _hostile(tmp_path, rng, pickled.getvalue())
    assert "activation 'sigmoid' is not one of" in _hostile(
        tmp_path, rng, edit=lambda text: text.replace('activation = "tanh"', 'activation = "sigmoid"'))
    assert "at least two numbers" in _hostile(
        tmp_path, rng, edit=lambda text: text.replace(f"layers = {policy.layers}".replace("'", ""),
                                                       f"layers = [{layout.size}]"))


def test_no_source_file_loads_a_pickle():
    """np.load is always called with allow_pickle=False; nothing calls pickle.load, torch.load or joblib.load."""
    import re
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    sources = [p for folder in ("bullet_world", "dialog", "learning", "robot", "scripts")
               for p in (root / folder).rglob("*.py")]
    assert len(sources) > 100
    for path in sources:
        text = path.read_text(encoding="utf-8")
        for call in re.finditer(r"\b(?:np|numpy)\.load\(([^()]*(?:\([^()]*\)[^()]*)*)\)", text):
            assert "allow_pickle=False" in call.group(1), f"{path}: {call.group(0)}"
        assert not re.search(r"\b(?:pickle|torch|joblib|dill|cloudpickle)\.loads?\(", text), path
