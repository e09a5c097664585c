"""A command teachbot prints for a person runs as printed, from the folder it was printed in (issue 51 item 3)."""

import os
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.e2e

TEACHBOT = Path(sys.executable).with_name("teachbot")


@pytest.mark.skipif(not TEACHBOT.exists(), reason="needs the installed teachbot program beside python")
def test_the_printed_resume_command_runs_as_printed_without_the_venv_on_path(tmp_path):
    """A real session started as .venv/bin/teachbot (PATH without the venv) prints a resume command; a shell in
    the same folder runs it as printed and it finishes the session."""
    venv = TEACHBOT.parent
    path = os.pathsep.join(p for p in os.environ.get("PATH", "").split(os.pathsep)
                           if p and Path(p).resolve() != venv.resolve())
    env = dict(os.environ, PATH=path or "/usr/bin:/bin", TERM="dumb", NO_COLOR="1")
    started = os.path.relpath(TEACHBOT, tmp_path)  # as a person types it: relative to the folder they are in
    first = subprocess.run([started, "teach", "--turns", "2", "--transcript", "my session.jsonl", "--no-pictures"],
                           cwd=tmp_path, env=env, input="quit\n",
                           capture_output=True, text=True, timeout=120, check=False)
    assert first.returncode == 0, first.stderr
    printed = [line for line in (first.stdout + first.stderr).splitlines() if "ontinue it with: " in line]
    assert printed, first.stdout + first.stderr
    command = printed[-1].split("ontinue it with: ", 1)[1]
    assert command.startswith(shlex.quote(started) + " teach --resume 'my session.jsonl'")
    again = subprocess.run(["/bin/sh", "-c", command], cwd=tmp_path, env=env, capture_output=True, text=True,
                           timeout=120, check=False, stdin=subprocess.DEVNULL)
    assert again.returncode == 0, again.stderr
    assert "command not found" not in again.stderr
