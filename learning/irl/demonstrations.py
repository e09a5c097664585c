"""Expert questioning demonstrations as plain arrays, for inverse RL (thesis §7.3.2).

A questioning episode is a sequence of turns. At turn t the learner faces the
candidate actions A_t (|Y| demo queries, |X| label queries, the feature-subset
query, no query) and, for each candidate a, the decision-feature vector it
expects after taking it,

    Phi_t[a] = sum_{s'} P(s' | a, s_t) phi(s')          (thesis eq. 7.1, 7.2)

so that EU(a | s_t) = w . Phi_t[a] for the linear utility U(s) = w . phi(s).
No query is scored at its next state too (eq. 7.1): the classifiers and the
budget of s_t, the clock one turn on and one more quiet turn. The expert's
choice is the index of one row. Nothing here knows about the
simulator or the dialog: whoever records an episode fills these arrays.

Files (no pickle): JSON (readable, for a few episodes) or NPZ (compact). Both
hold a list of episodes that share one tuple of feature names, and a
``format_version``: 2 since the no-query row is at the next state. Files of
version 1 (field ``version``, no query at phi(s_t)) are converted exactly on
loading when they hold what that needs (``learning.irl.format_upgrade``), and
refused otherwise, with a message saying how to record new ones.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from learning.actions import ACTION_KINDS
from learning.datafiles import MissingDataFileError
from learning.decision.features import check_feature_names
from learning.errors import DataFileError
from learning.irl.format_upgrade import NotConvertible, upgrade_episodes

FORMAT_NAME = "teachbot-irl-demonstrations"
FORMAT_VERSION = 2  # 2: no query scored at the next state (eq. 7.1); 1: at the current state
LEGACY_VERSIONS = (1,)  # read and converted on loading
VERSION_KEY, LEGACY_VERSION_KEY = "format_version", "version"  # version 1 named its field "version"
MAKE_NEW = "record new ones with scripts/make_expert_demos.py or `teachbot expert`"
NO_QUERY_KIND = "none"
ACCEPTED_SUFFIXES = (".json", ".npz")


def _optional_strings(values, n_actions: int, what: str) -> tuple[str, ...] | None:
    return None if values is None else _strings(values, n_actions, what)


def _strings(values, n_actions: int, what: str) -> tuple[str, ...]:
    if isinstance(values, str) or not isinstance(values, Sequence | np.ndarray):
        raise ValueError(f"action {what} must be a list of {n_actions} strings, got {type(values).__name__}")
    values = tuple(values)
    if len(values) != n_actions or not all(isinstance(v, str) for v in values):
        raise ValueError(f"action {what} must be a list of {n_actions} strings (one per candidate action), "
                         f"got {len(values)} entries")
    return values


@dataclass(frozen=True, eq=False)
class DecisionTurn:
    """One turn: candidate features Phi (n_actions x k), the expert's choice, optional kinds and labels."""

    phi: np.ndarray
    chosen: int
    kinds: tuple[str, ...] | None = None
    labels: tuple[str, ...] | None = None

    def __post_init__(self) -> None:
        try:
            phi = np.array(self.phi, dtype=np.float64)
        except (TypeError, ValueError):
            raise ValueError("turn features Phi must be a numeric (n_actions x k) matrix") from None
        if phi.ndim != 2 or phi.shape[0] < 1 or phi.shape[1] < 1:
            raise ValueError(f"turn features Phi must be a 2-D (n_actions x k) matrix with at least one action "
                             f"and one feature, got shape {phi.shape}")
        if not np.all(np.isfinite(phi)):
            raise ValueError("turn features Phi must be finite numbers (no NaN or infinity)")
        phi.setflags(write=False)
        object.__setattr__(self, "phi", phi)
        chosen = self.chosen
        if isinstance(chosen, bool) or not isinstance(chosen, int | np.integer) or not 0 <= chosen < phi.shape[0]:
            raise ValueError(f"chosen action must be an integer index in 0..{phi.shape[0] - 1}, got {chosen!r}")
        object.__setattr__(self, "chosen", int(chosen))
        kinds = _optional_strings(self.kinds, phi.shape[0], "kinds")
        if kinds is not None:
            unknown = sorted(set(kinds) - set(ACTION_KINDS))
            if unknown:
                raise ValueError(f"unknown action kind {unknown[0]!r}; accepted: {', '.join(ACTION_KINDS)}")
            if kinds.count(NO_QUERY_KIND) > 1:
                raise ValueError("a turn has at most one no-query ('none') action")
        object.__setattr__(self, "kinds", kinds)
        object.__setattr__(self, "labels", _optional_strings(self.labels, phi.shape[0], "labels"))

    @property
    def n_actions(self) -> int:
        return self.phi.shape[0]

    @property
    def no_query_index(self) -> int | None:
        """Index of the no-query action, if the action kinds are known and include it."""
        if self.kinds is None or NO_QUERY_KIND not in self.kinds:
            return None
        return self.kinds.index(NO_QUERY_KIND)

    def utilities(self, weights: np.ndarray) -> np.ndarray:
        """EU(a | s_t) = w . Phi_t[a] for every candidate (thesis eq. 7.1, 7.2)."""
        return self.phi @ np.asarray(weights, dtype=np.float64)


def turn_with_no_query(quiet_phi, query_phi, chosen: int | None, query_kinds=None,
                       query_labels=None) -> DecisionTurn:
    """A turn whose last candidate is no query with row ``quiet_phi``; ``chosen=None`` means the expert kept quiet.

    ``quiet_phi`` is phi(s_{t+1}) after a quiet turn (eq. 7.1). With it among the candidates, argmax over
    all of them is the DT rule "take a* only if EU(a*) > EU(no query)" (thesis §7.3.1), ties going to NQ.
    """
    quiet_phi = np.asarray(quiet_phi, dtype=np.float64)
    query_phi = np.asarray(query_phi, dtype=np.float64)
    if quiet_phi.ndim != 1:
        raise ValueError(f"no-query features must be a vector, got shape {quiet_phi.shape}")
    if query_phi.ndim != 2 or query_phi.shape[1] != quiet_phi.shape[0]:
        raise ValueError(f"query features must be a (n_queries x {quiet_phi.shape[0]}) matrix, "
                         f"got shape {query_phi.shape}")
    n_queries = query_phi.shape[0]
    if chosen is not None and (isinstance(chosen, bool) or not isinstance(chosen, int | np.integer)
                               or not 0 <= chosen < n_queries):
        raise ValueError(f"chosen query must be None (no query) or an index in 0..{n_queries - 1}, got {chosen!r}")
    kinds = None
    if query_kinds is not None:
        kinds = (*_strings(query_kinds, n_queries, "kinds"), NO_QUERY_KIND)
    labels = None
    if query_labels is not None:
        labels = (*_strings(query_labels, n_queries, "labels"), "no query")
    return DecisionTurn(np.vstack([query_phi, quiet_phi[None, :]]), n_queries if chosen is None else int(chosen),
                        kinds, labels)


@dataclass(frozen=True, eq=False)
class QuestioningEpisode:
    """One expert (or learner) questioning episode: named decision features and its turns in order."""

    feature_names: tuple[str, ...]
    turns: tuple[DecisionTurn, ...]
    name: str = ""
    metadata: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        names = check_feature_names(self.feature_names, f"episode {self.name!r}")
        object.__setattr__(self, "feature_names", names)
        turns = tuple(self.turns)
        if not turns:
            raise ValueError(f"episode {self.name!r} has no turns; an episode needs at least one")
        for t, turn in enumerate(turns):
            if not isinstance(turn, DecisionTurn):
                raise ValueError(f"episode {self.name!r}, turn {t}: expected a DecisionTurn, got {type(turn).__name__}")
            if turn.phi.shape[1] != len(names):
                raise ValueError(f"episode {self.name!r}, turn {t}: Phi has {turn.phi.shape[1]} feature columns, "
                                 f"but the episode names {len(names)} features")
        object.__setattr__(self, "turns", turns)
        if not isinstance(self.name, str):
            raise ValueError(f"episode name must be a string, got {type(self.name).__name__}")
        if not isinstance(self.metadata, dict):
            raise ValueError(f"episode {self.name!r}: metadata must be a table (dict), "
                             f"got {type(self.metadata).__name__}")
        try:
            metadata = json.loads(json.dumps(self.metadata, allow_nan=False))
        except (TypeError, ValueError):
            raise ValueError(f"episode {self.name!r}: metadata must be a JSON-compatible table "
                             "(strings, finite numbers, booleans, lists, tables)") from None
        object.__setattr__(self, "metadata", metadata)

    def feature_counts(self) -> np.ndarray:
        """phi_E(tau): the sum over turns of the chosen action's features (thesis §2.5.2, eq. 7.6)."""
        return np.sum([turn.phi[turn.chosen] for turn in self.turns], axis=0)


def common_feature_names(episodes: Sequence[QuestioningEpisode], what: str = "episodes") -> tuple[str, ...]:
    """The one tuple of feature names every episode shares; a clear error otherwise."""
    episodes = list(episodes)
    if not episodes:
        raise ValueError(f"no {what}: at least one questioning episode is needed")
    for episode in episodes:
        if not isinstance(episode, QuestioningEpisode):
            raise ValueError(f"{what}: expected QuestioningEpisode objects, got {type(episode).__name__}")
    names = episodes[0].feature_names
    for episode in episodes[1:]:
        if episode.feature_names != names:
            raise ValueError(f"{what}: episode {episode.name!r} has features {list(episode.feature_names)}, "
                             f"but episode {episodes[0].name!r} has {list(names)}; all must match")
    return names


# -- files ---------------------------------------------------------------------------------------------------------
def save_episodes(path: str | Path, episodes: Sequence[QuestioningEpisode]) -> Path:
    """Write episodes to ``.json`` or ``.npz`` (chosen by the suffix); returns the path."""
    path = Path(path)
    names = common_feature_names(episodes)
    if path.suffix == ".json":
        document = {"format": FORMAT_NAME, VERSION_KEY: FORMAT_VERSION, "feature_names": list(names),
                    "episodes": [_episode_to_json(e) for e in episodes]}
        path.write_text(json.dumps(document, indent=1, allow_nan=False) + "\n", encoding="utf-8")
    elif path.suffix == ".npz":
        np.savez_compressed(path, allow_pickle=False, **_episodes_to_arrays(names, episodes))
    else:
        raise ValueError(f"{path}: unknown demonstration file type {path.suffix!r}; accepted: .json, .npz")
    return path


def load_episodes(path: str | Path) -> list[QuestioningEpisode]:
    """Read a ``.json`` or ``.npz`` demonstration file; bad content raises a one-line ValueError naming the file."""
    path = Path(path)
    if not path.is_file():
        raise MissingDataFileError(f"demonstration file {path} does not exist")
    try:
        if path.suffix == ".json":
            return _episodes_from_json(path)
        if path.suffix == ".npz":
            return _episodes_from_npz(path)
    except ValueError as error:
        message = str(error)
        raise DataFileError(message if message.startswith(str(path)) else f"{path}: {message}") from None
    raise DataFileError(f"{path}: unknown demonstration file type {path.suffix!r}; accepted: .json, .npz")


def load_episode_dir(directory: str | Path) -> list[QuestioningEpisode]:
    """Every ``*.json`` and ``*.npz`` demonstration file in a directory, in name order; names must agree."""
    directory = Path(directory)
    if not directory.is_dir():
        raise MissingDataFileError(f"demonstration directory {directory} does not exist")
    files = sorted(p for p in directory.iterdir() if p.suffix in ACCEPTED_SUFFIXES and p.is_file())
    if not files:
        raise DataFileError(f"{directory}: no demonstration files (*.json or *.npz) found")
    episodes = [episode for file in files for episode in load_episodes(file)]
    common_feature_names(episodes, f"demonstrations in {directory}")
    return episodes


def _episode_to_json(episode: QuestioningEpisode) -> dict:
    turns = []
    for turn in episode.turns:
        record = {"chosen": turn.chosen, "phi": turn.phi.tolist()}
        if turn.kinds is not None:
            record["kinds"] = list(turn.kinds)
        if turn.labels is not None:
            record["labels"] = list(turn.labels)
        turns.append(record)
    return {"name": episode.name, "metadata": episode.metadata, "turns": turns}


def _check_header(format_name, version) -> int:
    if format_name != FORMAT_NAME:
        raise ValueError(f"not a demonstration file: 'format' is {format_name!r}, expected {FORMAT_NAME!r}")
    if isinstance(version, bool) or version not in (FORMAT_VERSION, *LEGACY_VERSIONS):
        raise ValueError(f"demonstration format version {version!r} is not supported; accepted: {FORMAT_VERSION} "
                         f"(and {', '.join(map(str, LEGACY_VERSIONS))}, converted on loading); {MAKE_NEW}")
    return int(version)


def _version_field(fields) -> str | None:
    """The name of the file's version field: format_version, or version 1's "version"; None if it has neither."""
    present = [key for key in (VERSION_KEY, LEGACY_VERSION_KEY) if key in fields]
    if len(present) > 1:
        raise ValueError(f"both {VERSION_KEY!r} and {LEGACY_VERSION_KEY!r} are given; a file has one "
                         f"({VERSION_KEY!r} since version {FORMAT_VERSION})")
    return present[0] if present else None


def _current(episodes: list[QuestioningEpisode], version: int) -> list[QuestioningEpisode]:
    """Episodes in the current format: old versions converted exactly, or refused saying how to make new ones."""
    if version == FORMAT_VERSION:
        return episodes
    try:
        return upgrade_episodes(episodes)
    except NotConvertible as error:
        raise ValueError(f"demonstration format version {version} scores no query at the current state and "
                         f"cannot be converted to version {FORMAT_VERSION} (eq. 7.1, the next state): {error}; "
                         f"{MAKE_NEW}") from None


def _episodes_from_json(path: Path) -> list[QuestioningEpisode]:
    try:
        document = json.loads(path.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as error:
        raise ValueError(f"{path}: not valid JSON ({error})") from None
    except RecursionError:
        raise ValueError(f"{path}: not valid JSON for a demonstration file (arrays or objects nested too deeply)") \
            from None
    if not isinstance(document, dict):
        raise ValueError("expected a JSON object with 'format', 'format_version', 'feature_names' and 'episodes'")
    version_key = _version_field(document)
    missing = [key for key in ("format", version_key or VERSION_KEY, "feature_names", "episodes")
               if key not in document]
    if missing:
        raise ValueError(f"missing field {missing[0]!r}; a demonstration file needs format, format_version, "
                         "feature_names and episodes")
    version = _check_header(document["format"], document[version_key])
    names = check_feature_names(document["feature_names"], "field 'feature_names'")
    raw_episodes = document["episodes"]
    if not isinstance(raw_episodes, list) or not raw_episodes:
        raise ValueError("field 'episodes' must be a non-empty list of episodes")
    episodes = []
    for e, raw in enumerate(raw_episodes):
        if not isinstance(raw, dict) or not isinstance(raw.get("turns"), list):
            raise ValueError(f"episode {e}: expected an object with a 'turns' list")
        unknown = sorted(set(raw) - {"name", "metadata", "turns"})
        if unknown:
            raise ValueError(f"episode {e}: unknown field {unknown[0]!r}; accepted: name, metadata, turns")
        turns = []
        for t, record in enumerate(raw["turns"]):
            if not isinstance(record, dict) or "phi" not in record or "chosen" not in record:
                raise ValueError(f"episode {e}, turn {t}: expected an object with 'phi' and 'chosen'")
            unknown = sorted(set(record) - {"phi", "chosen", "kinds", "labels"})
            if unknown:
                raise ValueError(f"episode {e}, turn {t}: unknown field {unknown[0]!r}; "
                                 "accepted: phi, chosen, kinds, labels")
            try:
                turns.append(DecisionTurn(record["phi"], record["chosen"], record.get("kinds"),
                                          record.get("labels")))
            except ValueError as error:
                raise ValueError(f"episode {e}, turn {t}: {error}") from None
        episodes.append(QuestioningEpisode(names, tuple(turns), raw.get("name", f"episode-{e}"),
                                           raw.get("metadata", {})))
    return _current(episodes, version)


def _episodes_to_arrays(names: tuple[str, ...], episodes: Sequence[QuestioningEpisode]) -> dict[str, np.ndarray]:
    turns = [turn for episode in episodes for turn in episode.turns]
    arrays = {
        "format": np.array(FORMAT_NAME), VERSION_KEY: np.array(FORMAT_VERSION),
        "feature_names": np.array(names),
        "phi": np.vstack([turn.phi for turn in turns]),
        "turn_offsets": np.cumsum([0] + [turn.n_actions for turn in turns]),
        "chosen": np.array([turn.chosen for turn in turns], dtype=np.int64),
        "episode_offsets": np.cumsum([0] + [len(episode.turns) for episode in episodes]),
        "episode_names": np.array([episode.name for episode in episodes]),
        "episode_metadata": np.array([json.dumps(episode.metadata) for episode in episodes]),
    }
    for attribute in ("kinds", "labels"):
        present = [getattr(turn, attribute) is not None for turn in turns]
        if any(present) and not all(present):
            raise ValueError(f"NPZ needs action {attribute} on every turn or on none; mixed turns can go to JSON")
        if all(present):
            arrays[attribute] = np.array([value for turn in turns for value in getattr(turn, attribute)])
    return arrays


def _episodes_from_npz(path: Path) -> list[QuestioningEpisode]:
    try:
        with np.load(path, allow_pickle=False) as data:
            arrays = {key: data[key] for key in data.files}
    except (OSError, ValueError, EOFError) as error:
        raise ValueError(f"{path}: not a readable NPZ archive without pickled objects ({error})") from None
    version_key = _version_field(arrays) or VERSION_KEY
    required = ("format", version_key, "feature_names", "phi", "turn_offsets", "chosen", "episode_offsets",
                "episode_names", "episode_metadata")
    missing = [key for key in required if key not in arrays]
    if missing:
        raise ValueError(f"missing array {missing[0]!r}; a demonstration NPZ needs {', '.join(required)}")
    raw_version = arrays[version_key]
    version = _check_header(str(arrays["format"]), int(raw_version) if raw_version.dtype.kind in "iu" else None)
    names = check_feature_names([str(n) for n in arrays["feature_names"].tolist()], "array 'feature_names'")
    phi, turn_offsets, chosen = arrays["phi"], arrays["turn_offsets"], arrays["chosen"]
    episode_offsets = arrays["episode_offsets"]
    n_turns = len(chosen)
    if (turn_offsets.ndim != 1 or len(turn_offsets) != n_turns + 1 or turn_offsets[0] != 0
            or np.any(np.diff(turn_offsets) < 1) or turn_offsets[-1] != len(phi)):
        raise ValueError("array 'turn_offsets' must rise from 0 to the number of Phi rows, one step per turn")
    if (episode_offsets.ndim != 1 or episode_offsets[0] != 0 or np.any(np.diff(episode_offsets) < 1)
            or episode_offsets[-1] != n_turns or len(arrays["episode_names"]) != len(episode_offsets) - 1
            or len(arrays["episode_metadata"]) != len(episode_offsets) - 1):
        raise ValueError("arrays 'episode_offsets', 'episode_names' and 'episode_metadata' do not describe the turns")
    extras = {}
    for attribute in ("kinds", "labels"):
        if attribute in arrays:
            if len(arrays[attribute]) != len(phi):
                raise ValueError(f"array {attribute!r} must have one entry per Phi row ({len(phi)})")
            extras[attribute] = [str(v) for v in arrays[attribute].tolist()]
    turns = []
    for t in range(n_turns):
        lo, hi = int(turn_offsets[t]), int(turn_offsets[t + 1])
        try:
            kinds, labels = (tuple(extras[a][lo:hi]) if a in extras else None for a in ("kinds", "labels"))
            turns.append(DecisionTurn(phi[lo:hi], chosen[t], kinds, labels))
        except ValueError as error:
            raise ValueError(f"turn {t}: {error}") from None
    episodes = []
    for e in range(len(episode_offsets) - 1):
        try:
            metadata = json.loads(str(arrays["episode_metadata"][e]))
        except json.JSONDecodeError:
            raise ValueError(f"episode {e}: metadata is not valid JSON") from None
        episodes.append(QuestioningEpisode(names, tuple(turns[episode_offsets[e]:episode_offsets[e + 1]]),
                                           str(arrays["episode_names"][e]), metadata))
    return _current(episodes, version)
