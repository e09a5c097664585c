"""Demonstration files of format version 1, read as version 2 (thesis eq. 7.1: no query at the next state).

Version 1 scored no query at the current state: its row was phi(s_t). Version 2 scores it at
s_{t+1}, like every query: the same learning features and budget consumption, one turn less of
remaining time and t_NQ = min(q + 1, W) / W after one more quiet turn. The old row holds q and t,
so the conversion is exact when the episode says the rest: the seven decision features in
FEATURE_NAMES order, the action kinds of every turn, and the metadata the dialog's expert mode
writes (turns, change_every, window_factor and costs, with no query free). Anything else is refused.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from learning.decision.features import FEATURE_NAMES, Clock, window_turns

REQUIRED_METADATA = ("turns", "change_every", "window_factor", "costs")
TIME, QUIET = FEATURE_NAMES.index("remaining_time"), FEATURE_NAMES.index("non_query_time")
TOLERANCE = 1e-9  # an old row's time and quiet fractions must be k / T and q / W to this precision


class NotConvertible(ValueError):
    """A version-1 episode whose no-query rows cannot be moved to the next state exactly."""


def upgrade_episodes(episodes: list) -> list:
    """Every version-1 episode with its no-query rows at the next state; NotConvertible if one cannot be."""
    return [_upgrade(episode) for episode in episodes]


def _upgrade(episode):
    where = f"episode {episode.name!r}"
    if episode.feature_names != FEATURE_NAMES:
        raise NotConvertible(f"{where} has features {list(episode.feature_names)}, not the seven decision features")
    metadata = episode.metadata
    missing = [key for key in REQUIRED_METADATA if key not in metadata]
    if missing:
        raise NotConvertible(f"{where} does not record {', '.join(missing)} in its metadata")
    try:
        turns, window = int(metadata["turns"]), window_turns(int(metadata["change_every"]),
                                                              float(metadata["window_factor"]))
        quiet_cost = float(dict(metadata["costs"]).get("none", 0.0))
    except (TypeError, ValueError):
        raise NotConvertible(f"{where}: metadata turns, change_every, window_factor or costs are not numbers") from None
    if turns < 1 or quiet_cost != 0.0:
        raise NotConvertible(f"{where} needs turns >= 1 and a free no query (costs.none = 0)")
    upgraded = []
    for t, turn in enumerate(episode.turns):
        index = turn.no_query_index
        if index is None:
            raise NotConvertible(f"{where}, turn {t} has no action kinds naming its no-query row")
        phi = np.array(turn.phi)
        phi[index] = _next_state_row(phi[index], turns, window, f"{where}, turn {t}")
        queries = np.delete(phi[:, TIME], index)
        if np.any(np.abs(queries - phi[index, TIME]) > TOLERANCE):
            raise NotConvertible(f"{where}, turn {t}: its queries' remaining time is not one turn on")
        upgraded.append(replace(turn, phi=phi))
    return replace(episode, turns=tuple(upgraded), metadata={**metadata, "converted_from_format_version": 1})


def _next_state_row(row: np.ndarray, turns: int, window: int, where: str) -> np.ndarray:
    """The no-query row one turn on: the same learning features and budget, the clock after a quiet turn."""
    finished = turns - int(round(row[TIME] * turns))
    quiet_run = int(round(row[QUIET] * window))
    now = Clock(0.0, 1.0, finished, turns, quiet_run, window)
    if abs(now.remaining_time() - row[TIME]) > TOLERANCE or abs(now.non_query_time() - row[QUIET]) > TOLERANCE:
        raise NotConvertible(f"{where}: its no-query row's remaining time and non-query time are not "
                             f"k / {turns} and q / {window}")
    after = now.after(0.0, asked=False)
    row = row.copy()
    row[TIME], row[QUIET] = after.remaining_time(), after.non_query_time()
    return row
