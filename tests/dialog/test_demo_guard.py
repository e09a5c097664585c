"""`teachbot demo` never overwrites a recorded teaching session or a file that is not a transcript."""

import json

from dialog.cli import main


def _run_demo(path, capsys):
    code = main(["demo", "--turns", "1", "--transcript", str(path)])
    return code, capsys.readouterr().err


def test_a_teach_session_is_not_overwritten(tmp_path, capsys):
    path = tmp_path / "person.jsonl"
    header = {"session": {"format": "teachbot-transcript", "version": 1, "command": "teach", "seed": 0}}
    content = json.dumps(header) + "\n" + json.dumps({"turn": 1, "scene_id": 0}) + "\n"
    path.write_text(content)
    code, err = _run_demo(path, capsys)
    assert code == 2
    assert "recorded 'teach' session" in err and str(path) in err and "Traceback" not in err
    assert path.read_text() == content


def test_a_file_that_is_not_a_transcript_is_not_overwritten(tmp_path, capsys):
    path = tmp_path / "notes.jsonl"
    path.write_text("my own notes\n")
    code, err = _run_demo(path, capsys)
    assert code == 2 and "other than a teachbot transcript" in err
    assert path.read_text() == "my own notes\n"


def test_a_demo_rewrites_its_own_transcript(tmp_path, capsys):
    path = tmp_path / "demo.jsonl"
    assert _run_demo(path, capsys)[0] == 0
    first = path.read_text()
    assert json.loads(first.splitlines()[0])["session"]["command"] == "demo"
    assert _run_demo(path, capsys)[0] == 0
    assert path.read_text() == first
