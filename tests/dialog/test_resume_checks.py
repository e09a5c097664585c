"""``teachbot teach --resume`` checks what it reads: the header, every turn record, the replay, the options beside it.

Each refusal is one line ``teachbot teach: FILE: line N: what is wrong (what was expected)``, exit 2, no traceback.
"""

import json

import pytest

from dialog.cli import main

pytestmark = pytest.mark.e2e
TURNS = 4


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    """The lines of a short scripted session (a feature query, then demonstration queries), parsed."""
    path = tmp_path_factory.mktemp("recorded") / "session.jsonl"
    assert main(["teach", "--teacher", "scripted", "--strategy", "all-cd", "--turns", str(TURNS), "--budget", "10",
                 "--change-every", "2", "--seed", "2", "--transcript", str(path), "--no-pictures"]) == 0
    return [json.loads(line) for line in path.read_text().splitlines()]


def resume(tmp_path, capsys, lines, *options):
    capsys.readouterr()
    path = tmp_path / "resumed.jsonl"
    path.write_text("".join(json.dumps(line) + "\n" for line in lines))
    code = main(["teach", "--resume", str(path), "--no-pictures", *options])
    out, err = capsys.readouterr()
    return code, out, err, path


def refused(tmp_path, capsys, lines, *options):
    """The one-line refusal; its text after ``teachbot teach: FILE: ``."""
    code, out, err, path = resume(tmp_path, capsys, lines, *options)
    assert code == 2, out + err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    prefix = f"teachbot teach: {path}: "
    assert err.startswith(prefix), err
    return err.strip()[len(prefix):]


def edited(recorded, header=None, drop=(), line=None, change=None):
    lines = json.loads(json.dumps(recorded))
    lines[0]["session"].update(header or {})
    for key in drop:
        del lines[0]["session"][key]
    if line is not None:
        lines[line - 1] = change(lines[line - 1])
    return lines


def test_the_recorded_session_asks_for_features_then_demonstrations(recorded):
    assert [line["action"]["kind"] for line in recorded[1:]] == ["feature"] + ["demo"] * (TURNS - 1)


@pytest.mark.parametrize("header, fragment", [
    ({"turns": "30"}, "'turns' is \"30\" (expected a whole number of at least 1)"),
    ({"turns": 0}, "'turns' is 0 (expected a whole number of at least 1)"),
    ({"seed": 0.5}, "'seed' is 0.5 (expected a whole number of 0 or more)"),
    ({"seed": -1}, "'seed' is -1"),
    ({"seed": True}, "'seed' is true"),
    ({"teacher": "scripted"}, "'teacher' is \"scripted\" (expected a table whose kind is one of terminal"),
    ({"teacher": {"kind": "robot"}}, "'teacher' is {\"kind\": \"robot\"}"),
    ({"teacher": {"kind": "scripted", "mislabel_rate": 2}}, "mislabel_rate between 0 and 1, not 2"),
    ({"teacher": {"kind": "scripted", "volume": 3}}, "unknown: volume"),
    ({"budget": float("nan")}, "'budget' is NaN (expected a finite number of cost units, 0 or more)"),
    ({"budget": "lots"}, "'budget' is \"lots\""),
    ({"change_every": 1.5}, "'change_every' is 1.5"),
    ({"realtime": 0}, "'realtime' is 0 (expected null or a positive number"),
    ({"kitchen": "kitchen-9"}, "'kitchen' is \"kitchen-9\" (expected one of kitchen-1, kitchen-2, kitchen-3)"),
    ({"task": 7}, "'task' is 7 (expected one of"),
    ({"strategy": "clairvoyant"}, "'strategy' is \"clairvoyant\" (expected one of"),
    ({"costs": {"label": -1}}, "'costs' is {\"label\": -1} (expected a cost of 0 or more for each of"),
    ({"fetch_from_pantry": "yes"}, "'fetch_from_pantry' is \"yes\" (expected true or false)"),
    ({"version": 2}, "'version' is 2"),
    ({"command": "expert"}, "'command' is \"expert\" (expected 'teach'"),
    ({"features": "86"}, "'features' is \"86\""),
])
def test_a_malformed_header_is_refused_at_line_1(recorded, tmp_path, capsys, header, fragment):
    message = refused(tmp_path, capsys, edited(recorded, header))
    assert message.startswith("line 1: the session header's ") and fragment in message


def test_a_header_without_its_budget_is_refused(recorded, tmp_path, capsys):
    assert refused(tmp_path, capsys, edited(recorded, drop=("budget",))) == "line 1: the session header lacks budget"


@pytest.mark.parametrize("line, change, fragment", [
    (2, lambda r: {"turn": 8}, "line 2: 'turn' is 8 (expected turn 1"),
    (2, lambda r: {"turn": 1}, "line 2: 'scene_id' is null (expected a whole number)"),
    (3, lambda r: {**r, "turn": "eight"}, "line 3: 'turn' is \"eight\" (expected turn 2"),
    (3, lambda r: {**r, "scene_id": "7"}, "line 3: 'scene_id' is \"7\""),
    (3, lambda r: {**r, "action": {"kind": "dance"}}, "line 3: 'action' is {\"kind\": \"dance\"}"),
    (3, lambda r: {**r, "action": {"kind": "label", "object": 0}}, "line 3: 'action.object' is 0"),
    (3, lambda r: {**r, "action": {"kind": "demo", "concept": "pasta"}}, "line 3: 'action.concept' is \"pasta\""),
    (3, lambda r: {**r, "action": {"kind": "label", "object": 1}, "answer": {"kind": "answer", "parsed": "pasta"}},
     "line 3: 'answer.parsed' is \"pasta\" (expected one of main dish, snack, fruit, beverage)"),
    (3, lambda r: {**r, "answer": {**r["answer"], "kind": "maybe"}}, "line 3: 'answer.kind' is \"maybe\""),
    (3, lambda r: {**r, "answer": {**r["answer"], "seconds": -1}}, "line 3: 'answer.seconds' is -1"),
    (3, lambda r: {**r, "answer": "fruit"}, "line 3: 'answer' is \"fruit\""),
    (2, lambda r: {**r, "answer": {**r["answer"], "parsed": ["no-such-feature"]}},
     "line 2: 'answer.parsed' is [\"no-such-feature\"] (expected names from this session's feature catalogue)"),
    (3, lambda r: {**r, "undid": [3]}, "line 3: 'undid' is [3] (expected a list of earlier turn numbers, 1 to 1)"),
    (3, lambda r: {**r, "time": float("inf")}, "line 3: 'time' is Infinity (expected a finite number)"),
    (3, lambda r: {**r, "model": {"examples": {"fruit": 1}}}, "line 3: 'model.examples' is {\"fruit\": 1}"),
    (3, lambda r: {**r, "fetched": "an apple"}, "line 3: 'fetched' is \"an apple\" (expected a table)"),
])
def test_a_malformed_turn_record_is_refused_with_its_line(recorded, tmp_path, capsys, line, change, fragment):
    assert refused(tmp_path, capsys, edited(recorded, line=line, change=change)).startswith(fragment)


def test_more_turns_than_the_header_allows_are_refused(recorded, tmp_path, capsys):
    message = refused(tmp_path, capsys, edited(recorded, {"turns": 2}))
    assert message.startswith("line 4: 'turn' is 3 (expected at most 2, the session's number of turns)")


@pytest.mark.parametrize("header", [{"seed": 1}, {"kitchen": "kitchen-2"}])
def test_a_session_recorded_with_another_seed_or_kitchen_is_refused_at_turn_1(recorded, tmp_path, capsys, header):
    message = refused(tmp_path, capsys, edited(recorded, header))
    assert message.startswith("line 2: turn 1 was recorded in another scene than the replay's (feature sum ")
    assert message.endswith("the transcript was made with another seed, task or kitchen")


def test_an_object_the_scene_does_not_have_is_refused(recorded, tmp_path, capsys):
    def point_at_96(record):
        return {**record, "action": {"kind": "label", "object": 96}, "answer": {**record["answer"], "parsed": "fruit"}}

    message = refused(tmp_path, capsys, edited(recorded, line=3, change=point_at_96))
    assert message.startswith("line 3: turn 2: 'action.object' is 96 (expected an object number from 1 to 12 of this "
                              "scene)")


def test_a_demonstrated_object_the_scene_does_not_have_is_refused(recorded, tmp_path, capsys):
    lines = edited(recorded, line=4, change=lambda r: {**r, "answer": {**r["answer"], "parsed": 96}})
    assert refused(tmp_path, capsys, lines).startswith("line 4: turn 3: 'answer.parsed' is 96 (expected an object "
                                                       "number from 1 to 12 of this scene)")


def test_example_counts_that_the_replay_does_not_give_are_refused(recorded, tmp_path, capsys):
    def inflate(record):
        record["model"]["examples"]["fruit"] += 3
        return record

    message = refused(tmp_path, capsys, edited(recorded, line=3, change=inflate))
    assert message.startswith("line 3: turn 2: replaying the transcript gives ")


def test_undoing_more_than_was_learned_is_refused(recorded, tmp_path, capsys):
    message = refused(tmp_path, capsys, edited(recorded, line=3, change=lambda r: {**r, "undid": [1, 1]}))
    assert message.startswith("line 3: turn 2: 'undid' is [1, 1] (expected the latest learned turns")


def test_a_changed_budget_left_is_refused(recorded, tmp_path, capsys):
    message = refused(tmp_path, capsys, edited(recorded, line=2, change=lambda r: {**r, "budget_left": 99}))
    assert message.startswith("line 2: turn 1: replaying the transcript leaves 8 of the budget, the transcript says 99")


def test_options_that_contradict_the_recorded_session_are_refused_by_name(recorded, tmp_path, capsys):
    message = refused(tmp_path, capsys, recorded[:3], "--seed", "5", "--task", "sort-groceries", "--turns", "3",
                      "--strategy", "passive", "--kitchen", "kitchen-2", "--budget", "7", "--teacher", "terminal")
    for fragment in ("--seed 5 differs from the recorded 2", "--task sort-groceries differs from the recorded "
                     "pack-lunchbox", "--turns 3 differs from the recorded 4", "--strategy passive differs from "
                     "the recorded all-cd", "--kitchen kitchen-2 differs from the recorded kitchen-1",
                     "--budget 7 differs from the recorded 10;"):
        assert fragment in message
    assert message.endswith("; leave them out, or start a new session without --resume")
    assert "--teacher" not in message  # given, but the default: it can't be told from not given
    assert message.startswith("a resumed session keeps its recorded settings")


def test_one_contradicting_number_reads_as_typed(recorded, tmp_path, capsys):
    """Issue 42, case 7: it read "--budget 10.0 (recorded: 40.0) differ"."""
    message = refused(tmp_path, capsys, recorded[:3], "--budget", "0.5")
    assert message == ("a resumed session keeps its recorded settings, but --budget 0.5 differs from the recorded "
                       "10; leave it out, or start a new session without --resume")


def test_options_that_agree_with_the_recorded_session_are_accepted(recorded, tmp_path, capsys):
    code, out, err, _ = resume(tmp_path, capsys, recorded, "--seed", "2", "--turns", str(TURNS),
                               "--teacher", "scripted", "--strategy", "all-cd")
    assert code == 0 and not err


def test_a_finished_session_says_so_and_prints_its_summary(recorded, tmp_path, capsys):
    code, out, err, path = resume(tmp_path, capsys, recorded, "--json")
    assert code == 0 and not err
    assert f"{path}: the session is already finished ({TURNS} of {TURNS} turns); nothing to resume" in out
    assert "Accuracy on pack-lunchbox held-out scenes" in out
    summary = json.loads(out.strip().splitlines()[-1])
    assert summary["completed"] == TURNS and summary["accuracy"] == recorded[-1]["accuracy"]
    assert path.read_text().count("\n") == TURNS + 1  # nothing was appended
