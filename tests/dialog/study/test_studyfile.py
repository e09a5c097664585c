"""Study files: the shipped example loads; a bad one is refused with one line naming the file, field and rule."""

from pathlib import Path

import pytest

from dialog.cli import main
from dialog.study.studyfile import check_participant_id, load_study
from learning.errors import DataFileError

EXAMPLE = Path(__file__).resolve().parents[3] / "dialog" / "data" / "studies" / "example.toml"

GOOD = """
name = "tiny"
seed = 1
participants = 2
[[conditions]]
name = "a"
strategy = "active"
turns = 3
[[conditions]]
name = "b"
strategy = "passive"
turns = 3
[[questionnaire]]
id = "ease"
kind = "likert"
text = "Easy?"
anchors = ["no", "yes"]
"""


def test_the_example_study_loads():
    study = load_study(EXAMPLE)
    assert study.name == "example" and len(study.conditions) == 3 and study.participants[0] == "P01"
    assert [item.kind for item in study.items] == ["likert", "likert", "text"]
    assert study.simulated_teacher["mislabel_rate"] == 0.1


def test_a_small_study_gets_defaults(tmp_path):
    path = tmp_path / "tiny.toml"
    path.write_text(GOOD)
    study = load_study(path)
    assert study.participants == ("P01", "P02") and study.ordering == "latin"
    assert study.items[0].points == 7 and study.folder == Path("runs/studies/tiny")


@pytest.mark.parametrize("change, message", [
    (("turns = 3\n[[conditions]]\nname = \"b\"", "turns = 3\nturnz = 4\n[[conditions]]\nname = \"b\""),
     "unknown field 'turnz'"),
    (('strategy = "passive"', 'strategy = "clever"'), "strategy 'clever' is not one of"),
    (("participants = 2", 'ids = ["P 1", "P2"]'), "participant id 'P 1' is not accepted"),
    (("participants = 2", 'ids = ["../x"]'), "participant id '../x' is not accepted"),
    (("participants = 2", 'participants = 2\nids = ["A1"]'), "either 'participants'"),
    (('anchors = ["no", "yes"]', 'anchors = ["no"]'), "'anchors' must name the two ends"),
    (('name = "b"', 'name = "a"'), "condition names must differ"),
    (('anchors = ["no", "yes"]', 'anchors = ["no", "yes"]\n[orders]\nP01 = ["a", "b"]\nP02 = ["b", "a"]'),
     "only read with order"),
    (("turns = 3\n[[conditions]]\nname = \"b\"", "turns = 0\n[[conditions]]\nname = \"b\""), "'turns' must be >= 1"),
])
def test_bad_study_files_are_refused_with_one_clear_line(tmp_path, change, message):
    old, new = change
    assert old in GOOD
    path = tmp_path / "bad.toml"
    path.write_text(GOOD.replace(old, new, 1))
    with pytest.raises(DataFileError, match=message) as caught:
        load_study(path)
    assert "\n" not in str(caught.value)


def test_given_orders_must_hold_every_condition_once(tmp_path):
    path = tmp_path / "given.toml"
    path.write_text('order = "given"\n' + GOOD + '[orders]\nP01 = ["a", "a"]\nP02 = ["a", "b"]\n')
    with pytest.raises(DataFileError, match="P01 must run every condition once"):
        load_study(path)
    path.write_text('order = "given"\n' + GOOD + '[orders]\nP01 = ["b", "a"]\nP02 = ["a", "b"]\n')
    assert load_study(path).given_orders == {"P01": ("b", "a"), "P02": ("a", "b")}


def test_the_command_line_prints_a_bad_study_as_one_line(tmp_path, capsys):
    path = tmp_path / "bad.toml"
    path.write_text(GOOD.replace('strategy = "active"', 'strategy = "clever"'))
    assert main(["study", "status", str(path)]) == 2
    error = capsys.readouterr().err.strip()
    assert error.startswith("teachbot study: ") and str(path) in error and "\n" not in error
    assert main(["study", "run", str(tmp_path / "none.toml"), "--participant", "P01"]) == 2
    assert "does not exist" in capsys.readouterr().err


@pytest.mark.parametrize("value", ["P01", "lab2-07", "a_b", "P.01", "x" * 64])
def test_good_participant_ids(value):
    assert check_participant_id(value) == value


@pytest.mark.parametrize("value", ["", "Jane Doe", "a/b", "..", ".P01", "x" * 65, "-P1", "P01\n", "P01\r", "/tmp",
                                   "P01/", "P\u00e9", "P\x00"])
def test_participant_ids_are_short_ids_not_names_or_paths(value):
    with pytest.raises(DataFileError, match="not accepted"):
        check_participant_id(value)
