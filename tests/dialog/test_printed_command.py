"""Commands printed for a person run as printed (issue 51 item 3): the program as it was started, quoted words."""

import os
import shlex
import stat
import sys
from pathlib import Path

from dialog import printed_command
from dialog.printed_command import command_line, program


def _script(folder: Path) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / "teachbot"
    path.write_text("#!/bin/sh\n")
    path.chmod(path.stat().st_mode | stat.S_IXUSR)
    return path


def test_teachbot_on_path_that_is_this_program_is_printed_by_name(tmp_path, monkeypatch):
    script = _script(tmp_path / "bin")
    monkeypatch.setenv("PATH", str(script.parent))
    assert program(str(script)) == ["teachbot"]


def test_a_program_not_on_path_is_printed_as_the_path_that_started_it(tmp_path, monkeypatch):
    script = _script(tmp_path / "venv" / "bin")
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("PATH", "/usr/bin:/bin")
    assert program("venv/bin/teachbot") == ["venv/bin/teachbot"]  # relative stays relative
    assert program(str(script)) == [str(script)]


def test_another_teachbot_first_on_path_does_not_stand_for_this_one(tmp_path, monkeypatch):
    other, mine = _script(tmp_path / "other"), _script(tmp_path / "mine")
    monkeypatch.setenv("PATH", f"{other.parent}{os.pathsep}{mine.parent}")
    assert program(str(mine)) == [str(mine)]


def test_a_teachbot_started_from_this_folder_by_bare_name_is_printed_with_dot_slash(tmp_path, monkeypatch):
    _script(tmp_path)
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("PATH", "/usr/bin:/bin")
    assert program("teachbot") == ["./teachbot"]


def test_run_as_a_library_or_a_test_the_installed_name_is_printed(monkeypatch):
    monkeypatch.setattr(sys, "argv", ["/somewhere/pytest", "-k", "x"])
    assert program() == ["teachbot"]
    assert command_line(["teach", "--resume", Path("my session.jsonl")]) == "teachbot teach --resume 'my session.jsonl'"


def test_every_word_is_quoted_for_the_shell(tmp_path, monkeypatch):
    folder = tmp_path / "my venv" / "bin"
    _script(folder)
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("PATH", "/usr/bin:/bin")
    monkeypatch.setattr(sys, "argv", ["my venv/bin/teachbot", "teach"])
    line = command_line(["study", "run", "it's.toml", "--participant", "P1"])
    assert line == "'my venv/bin/teachbot' study run 'it'\"'\"'s.toml' --participant P1"
    assert shlex.split(line) == ["my venv/bin/teachbot", "study", "run", "it's.toml", "--participant", "P1"]


def test_one_helper_prints_every_command():
    """No module builds a printed command on its own: each goes through dialog.printed_command."""
    root = Path(printed_command.__file__).resolve().parents[1]
    builders = [str(path.relative_to(root)) for folder in ("dialog", "learning", "bullet_world")
                for path in (root / folder).rglob("*.py")
                if path.name != "printed_command.py" and ('["teachbot", ' in path.read_text()
                                                           or "'teachbot', " in path.read_text())]
    assert builders == []
