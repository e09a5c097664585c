"""A trained questioning policy as files a user can read and load without pickle: TOML settings + NPZ weights.

``teachbot train-questioner --out questioner.toml`` writes two files::

    questioner.toml      # what the policy is: format, layers, activation, observation layout, provenance
    questioner.npz       # its weights: w0, b0, w1, b1, ... (numpy arrays, loaded with allow_pickle=False)

The TOML names the NPZ beside it and its SHA-256, so a changed or swapped
weights file is refused. The network is the actor of a masked PPO policy: an MLP
with ``activation`` between its layers and no activation after the last, whose
output is one logit per action slot (learning/rl/observation.py). Running it
needs numpy alone: ``QuestionerPolicy.logits`` is the whole forward pass.
"""

from __future__ import annotations

import hashlib
import io
import os
import zipfile
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from learning.datafiles import check_keys, flag, integer, numbers, read_toml, section, text, texts
from learning.decision.features import FEATURE_NAMES
from learning.decision.weights_file import check_bare_key, toml_value
from learning.errors import DataFileError
from learning.limits import limit as limit_of
from learning.limits import maximum
from learning.rl.observation import ALLOCATION_NAMES, ObservationLayout

FORMAT = "teachbot-questioner"
VERSION = 1


def _relu(x: np.ndarray) -> np.ndarray:
    return np.maximum(x, 0.0)


ACTIVATIONS: dict[str, Callable[[np.ndarray], np.ndarray]] = {"tanh": np.tanh, "relu": _relu}


@dataclass(frozen=True, eq=False)
class QuestionerPolicy:
    """An MLP from observations to one logit per action slot, with the layout it was trained on."""

    layout: ObservationLayout
    weights: tuple[np.ndarray, ...]  # (out, in) matrices, one per layer
    biases: tuple[np.ndarray, ...]
    activation: str = "tanh"
    provenance: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.activation not in ACTIVATIONS:
            raise DataFileError(f"activation '{self.activation}' is not accepted; accepted: {', '.join(ACTIVATIONS)}")
        if not self.weights or len(self.weights) != len(self.biases):
            raise DataFileError("a policy needs one bias per weight matrix and at least one layer")
        width = self.layout.size
        for k, (w, b) in enumerate(zip(self.weights, self.biases)):
            if w.ndim != 2 or w.shape[1] != width or b.shape != (w.shape[0],):
                raise DataFileError(f"layer {k}: weights {w.shape} and bias {b.shape} do not take {width} inputs")
            if not (np.all(np.isfinite(w)) and np.all(np.isfinite(b))):
                raise DataFileError(f"layer {k}: weights must be finite numbers")
            width = w.shape[0]
        if width != self.layout.n_actions:
            raise DataFileError(f"the last layer gives {width} logits; the layout has {self.layout.n_actions} slots")

    @property
    def layers(self) -> list[int]:
        return [self.layout.size, *(w.shape[0] for w in self.weights)]

    def logits(self, observation: np.ndarray) -> np.ndarray:
        """The forward pass: one logit per slot for one observation (or a batch, rows)."""
        h = np.asarray(observation, dtype=np.float64)
        act = ACTIVATIONS[self.activation]
        for k, (w, b) in enumerate(zip(self.weights, self.biases)):
            h = h @ w.T + b
            if k < len(self.weights) - 1:
                h = act(h)
        return h

    def masked_logits(self, observation: np.ndarray, mask: np.ndarray) -> np.ndarray:
        """The logits with every slot the mask closes at -inf."""
        return np.where(np.asarray(mask, dtype=bool), self.logits(observation), -np.inf)

    def best_slot(self, observation: np.ndarray, mask: np.ndarray) -> int:
        """The allowed slot with the highest logit (ties to the lower slot: no query first)."""
        return int(np.argmax(self.masked_logits(observation, mask)))


def policy_digest(path: str | Path) -> str:
    """SHA-256 of a policy's TOML file (which records its weights' SHA-256, so this names both)."""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def save_policy(path: str | Path, policy: QuestionerPolicy, comment: str = "") -> Path:
    """Write ``path`` (.toml) and its weights (the same name, .npz), each written beside and renamed into place."""
    path = Path(path)
    if path.suffix != ".toml":
        raise DataFileError(f"{path}: a questioner policy file must end in .toml (its weights go beside it, .npz)")
    arrays = {f"w{k}": w for k, w in enumerate(policy.weights)} | {f"b{k}": b for k, b in enumerate(policy.biases)}
    buffer = io.BytesIO()
    np.savez(buffer, allow_pickle=False, **arrays)
    data = buffer.getvalue()
    npz = path.with_suffix(".npz")
    lines = [f"# {line}".rstrip() for line in comment.splitlines()] if comment else []
    lines += ["[policy]", f"format = {toml_value(FORMAT)}", f"version = {VERSION}",
              f"weights = {toml_value(npz.name)}", f"sha256 = {toml_value(hashlib.sha256(data).hexdigest())}",
              f"activation = {toml_value(policy.activation)}", f"layers = {toml_value(policy.layers)}", "",
              "[observation]"]
    lines += [f"{key} = {toml_value(value)}" for key, value in policy.layout.record().items()]
    if policy.provenance:
        lines += ["", "[provenance]"]
        for key, value in policy.provenance.items():
            if not check_bare_key(key):
                raise DataFileError(f"provenance key {key!r} is not accepted; use letters, digits, '_' or '-'")
            lines.append(f"{key} = {toml_value(value)}")
    _write_atomically(npz, data)
    _write_atomically(path, ("\n".join(lines) + "\n").encode("utf-8"))
    return path


def _write_atomically(path: Path, data: bytes) -> None:
    partial = path.with_name(f".{path.name}.partial")
    try:
        partial.write_bytes(data)
        os.replace(partial, path)
    except BaseException:
        partial.unlink(missing_ok=True)
        raise


def load_policy(path: str | Path) -> QuestionerPolicy:
    """Read a policy file and its weights; anything wrong is one DataFileError naming the file and the field."""
    path = Path(path)
    if not path.is_file():
        raise DataFileError(f"{path}: no questioner policy file there (train one with teachbot train-questioner; "
                            "give the .toml it wrote)")
    data = read_toml(path, "questioner policy")
    where = str(path)
    check_keys(data, where, required=("policy", "observation"), optional=("provenance",))
    table, here = section(data, "policy", where), f"{where} [policy]"
    check_keys(table, here, required=("format", "version", "weights", "sha256", "activation", "layers"))
    if text(table, "format", here) != FORMAT or integer(table, "version", here) != VERSION:
        raise DataFileError(f"{here}: format must be '{FORMAT}' version {VERSION}, got "
                            f"'{table['format']}' version {table['version']}")
    observed, there = section(data, "observation", where), f"{where} [observation]"
    check_keys(observed, there, required=("concepts", "max_objects", "whatif", "features"),
               optional=("allocation", "allocation_features"))
    if tuple(texts(observed, "features", there)) != FEATURE_NAMES:
        raise DataFileError(f"{there}: features must be {list(FEATURE_NAMES)} (the decision features, in order)")
    allocation = flag(observed, "allocation", there) if "allocation" in observed else False
    if allocation and tuple(texts(observed, "allocation_features", there) if "allocation_features" in observed
                            else ()) != ALLOCATION_NAMES:
        raise DataFileError(f"{there}: allocation_features must be {list(ALLOCATION_NAMES)} (the allocation's "
                            "features, in order) when allocation is true")
    npz = weights_beside(path, text(table, "weights", here), here)
    raw = npz.read_bytes()
    if hashlib.sha256(raw).hexdigest() != text(table, "sha256", here):
        raise DataFileError(f"{npz}: its SHA-256 is not the one {path.name} records; the weights changed since the "
                            "policy was saved (train again, or restore the file)")
    layers = numbers(table, "layers", here, whole=True, low=1)
    if len(layers) < 2:
        raise DataFileError(f"{here}: layers must list the input width and each layer's width (at least two "
                            f"numbers), got {list(layers)}")
    concepts = texts(observed, "concepts", there, nonempty=True)
    if len(concepts) > maximum("concepts"):
        raise DataFileError(f"{there}: {len(concepts)} concepts are beyond the limit of {maximum('concepts')} "
                            "(learning/data/limits.toml)")
    weights, biases = read_arrays(npz, raw, len(layers) - 2)
    try:
        layout = ObservationLayout(tuple(concepts),
                                   integer(observed, "max_objects", there, low=1, high=maximum("scene_objects")),
                                   flag(observed, "whatif", there), allocation)
        policy = QuestionerPolicy(layout, weights, biases, text(table, "activation", here, choices=ACTIVATIONS),
                                  dict(section(data, "provenance", where, {})))
    except DataFileError as error:
        message = str(error)
        raise DataFileError(message if message.startswith(where) else f"{npz}: {message}") from None
    except ValueError as error:  # the layout's own checks (SettingsError)
        raise DataFileError(f"{there}: {error}") from None
    if list(layers) != policy.layers:
        raise DataFileError(f"{here}: layers {list(layers)} do not match the weights' {policy.layers}")
    return policy


def weights_beside(path: Path, name: str, here: str) -> Path:
    """The weights file ``name`` that a policy's TOML names: a plain file name in the TOML's own folder, not a
    path ('../x', '/etc/passwd', '.'), and not a symbolic link that leads out of that folder."""
    folder = path.parent
    plain = name not in (".", "..") and "/" not in name and "\\" not in name and "\x00" not in name
    if not plain or not name.endswith(".npz"):
        raise DataFileError(f"{here}: weights {name!r} is not accepted; it must be the name of the .npz file beside "
                            f"{path.name} (a file name ending in .npz, no folder)")
    npz = folder / name
    if not npz.is_file():
        raise DataFileError(f"{here}: weights file '{name}' is not beside {path.name}; keep the .toml and its .npz "
                            "together")
    if not npz.resolve().is_relative_to(folder.resolve()):
        raise DataFileError(f"{npz}: is a link to {npz.resolve()}, outside the policy's folder {folder}; copy the "
                            "weights into the folder instead")
    return npz


def read_arrays(npz: Path, raw: bytes, last: int) -> tuple[tuple[np.ndarray, ...], tuple[np.ndarray, ...]]:
    """w0, b0 .. w{last}, b{last} from the NPZ's bytes (never a pickle): real floats, finite, each within the
    limit of a weight; anything else is one DataFileError naming the file."""
    expected = sorted(f"{kind}{k}" for k in range(last + 1) for kind in "wb")
    accepted = f"an NPZ of the arrays {', '.join(expected)} (real floats)"
    if not raw.startswith(b"PK"):
        raise DataFileError(f"{npz}: not an NPZ archive (a .npz is a zip of .npy arrays; got "
                            f"{'an empty file' if not raw else 'something else'}); expected {accepted}")
    arrays = {}
    try:
        with np.load(io.BytesIO(raw), allow_pickle=False) as archive:
            if sorted(archive.files) != expected:
                raise DataFileError(f"{npz}: holds the arrays {sorted(archive.files)}; expected {accepted}")
            for name in expected:
                arrays[name] = archive[name]
    except DataFileError:
        raise
    except (KeyError, ValueError, OSError, EOFError, zipfile.BadZipFile, NotImplementedError) as error:
        raise DataFileError(f"{npz}: is damaged or not {accepted}: {error}") from None
    limit = maximum("weight")
    for name, array in arrays.items():
        if array.dtype.kind != "f":
            raise DataFileError(f"{npz}: array {name} holds {array.dtype} values; expected real floats")
        if not np.all(np.isfinite(array)):
            raise DataFileError(f"{npz}: array {name} holds NaN or infinite values; weights must be finite")
        if array.size and float(np.max(np.abs(array))) > limit:
            raise DataFileError(f"{npz}: array {name} holds {float(np.max(np.abs(array))):g}, beyond the limit of "
                                f"{limit:g} {limit_of('weight').what} (learning/data/limits.toml)")
    weights = tuple(np.array(arrays[f"w{k}"], dtype=np.float64) for k in range(last + 1))
    biases = tuple(np.array(arrays[f"b{k}"], dtype=np.float64) for k in range(last + 1))
    return weights, biases
