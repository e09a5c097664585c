"""The fingerprint of short fixed episodes (dialog/experiments/fingerprint.py): every transcript and every series
byte-identical to the recording, so a speed-up may not move a decision or a number."""

from __future__ import annotations

from pathlib import Path

import pytest

from dialog.experiments.fingerprint import compare, fingerprint, fingerprint_episodes, recorded
from learning.errors import DataFileError


def test_every_fixed_episode_gives_the_recorded_transcript_and_series():
    assert compare(fingerprint(), recorded()) == []


def test_the_list_covers_every_suite_and_the_strategies_named_by_the_brief():
    labels = [episode.label for episode in fingerprint_episodes()]
    assert len(labels) == len(set(labels))
    groups = {label.split("/")[0] for label in labels}
    assert groups == {"smoke", "ch6-static", "ch6-dynamic", "ch7", "ch7-pack-lunchbox", "embodied"}
    strategies = {label.split("/")[1] for label in labels}
    assert {"dt-task", "dt-iros", "dt-task-env", "active", "random"} <= strategies
    assert set(recorded()) == set(labels)


def test_compare_names_each_moved_episode():
    then = {"a/x/d0": {"transcript": "1", "series": "2"}, "b/y/d0": {"transcript": "3", "series": "4"}}
    now = {"a/x/d0": {"transcript": "1", "series": "2"}, "b/y/d0": {"transcript": "5", "series": "4"},
           "c/z/d0": {"transcript": "6", "series": "7"}}
    assert compare(now, then) == ["c/z/d0: not recorded", "b/y/d0: transcript changed"]
    assert compare(then, then) == []


def test_a_bad_episode_list_or_recording_is_one_line(tmp_path: Path):
    bad = tmp_path / "list.toml"
    bad.write_text('[[group]]\nname = "x"\n')
    with pytest.raises(DataFileError) as caught:
        fingerprint_episodes(bad)
    assert "\n" not in str(caught.value) and "task" in str(caught.value)
    broken = tmp_path / "hashes.json"
    broken.write_text("{")
    with pytest.raises(DataFileError) as caught:
        recorded(broken)
    assert "\n" not in str(caught.value) and "--record" in str(caught.value)


def test_where_the_checkout_lies_is_not_part_of_a_fingerprint():
    """An RL policy's transcript records its file by absolute path; a fresh clone elsewhere must hash the same."""
    from dialog.experiments.fingerprint import ROOT, located_nowhere

    here = f'{{"policy": {{"file": "{ROOT}/learning/rl/policies/q.toml"}}}}'.encode()
    assert located_nowhere(here) == b'{"policy": {"file": "<repo>/learning/rl/policies/q.toml"}}'
