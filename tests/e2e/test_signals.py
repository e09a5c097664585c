"""Signals on real ``teachbot`` processes: Ctrl-C at any moment, SIGTERM/SIGHUP/SIGKILL and the viewer's server.

Ctrl-C is sent the way a terminal sends it, to the whole process group, so child processes (the
meshcat server) get it too. The viewer's server must go with ``teachbot view`` however it ends.
"""

import os
import re
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tests.e2e.teach_helpers import PRINTED

pytestmark = pytest.mark.e2e

TEACHBOT = str(Path(sys.executable).with_name("teachbot"))
SERVER_SCRIPT = "server_process.py"


def start(*args, cwd: Path) -> subprocess.Popen:
    env = dict(os.environ, PYTHONUNBUFFERED="1", NO_COLOR="1")
    return subprocess.Popen([TEACHBOT, *map(str, args)], cwd=cwd, env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL, text=True, start_new_session=True)


def read_until(process: subprocess.Popen, pattern: str, timeout_s: float = 120.0) -> list[str]:
    """Lines of the process's output up to and including the first that matches ``pattern``."""
    lines, deadline = [], time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        line = process.stdout.readline()
        if not line:
            raise AssertionError(f"the process ended before '{pattern}':\n{''.join(lines)}")
        lines.append(line)
        if re.search(pattern, line):
            return lines
    raise AssertionError(f"no '{pattern}' within {timeout_s:g} s:\n{''.join(lines)}")


def finish(process: subprocess.Popen, earlier: list[str] = ()) -> tuple[int, str]:
    rest, _ = process.communicate(timeout=90)
    return process.returncode, "".join(earlier) + rest


def wait_for_teachbot_handlers(process: subprocess.Popen, timeout_s: float = 30.0) -> None:
    """Wait until the process catches SIGTERM and SIGHUP: ``teachbot``'s own code is running.

    Before that, Python itself is starting (site-packages, the editable install's finder), where no
    program's code can catch Ctrl-C yet; docs/dialog.md names this window.
    """
    wanted = (1 << (signal.SIGTERM - 1)) | (1 << (signal.SIGHUP - 1))
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline and process.poll() is None:
        try:
            status = Path(f"/proc/{process.pid}/status").read_text()
        except OSError:
            break
        caught = int(re.search(r"^SigCgt:\s*([0-9a-f]+)", status, re.M).group(1), 16)
        if caught & wanted == wanted:
            return
        time.sleep(0.002)
    raise AssertionError("teachbot never installed its signal handlers")


def assert_interrupted_cleanly(code: int, output: str) -> None:
    assert code == 130, output
    assert "Traceback" not in output and "Exception ignored" not in output, output
    assert output.count("Interrupted") == 1, output


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
@pytest.mark.parametrize("delay_s", [0.0, 0.1, 0.5, 1.0, 3.0])
def test_ctrl_c_at_any_moment_of_teach_and_demo(tmp_path, delay_s):
    commands = {
        "teach": ["teach", "--teacher", "scripted", "--turns", "200", "--transcript", tmp_path / "teach.jsonl"],
        # 200 turns, as teach: the 30-turn default can end (2.2 s on an idle machine) before the latest signal
        "demo": ["demo", "--viewer", "--turns", "200", "--transcript", tmp_path / "demo.jsonl"],
    }
    for name, args in commands.items():
        process = start(*args, cwd=tmp_path)
        wait_for_teachbot_handlers(process)
        time.sleep(delay_s)
        os.killpg(process.pid, signal.SIGINT)
        code, output = finish(process)
        assert_interrupted_cleanly(code, output)
        assert not viewer_servers_of(process.pid), f"{name}: a viewer server outlived the command"


def test_ctrl_c_in_the_teaching_loop_prints_the_resume_hint_once(tmp_path):
    transcript = tmp_path / "loop.jsonl"
    process = start("teach", "--teacher", "scripted", "--turns", "200", "--transcript", transcript, cwd=tmp_path)
    earlier = read_until(process, r"^Turn +2\b")
    os.killpg(process.pid, signal.SIGINT)
    code, output = finish(process, earlier)
    assert_interrupted_cleanly(code, output)
    assert f"{PRINTED} teach --resume {transcript}" in output
    assert transcript.read_text().count("\n") >= 2  # the header and the turns so far, each a whole line


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGHUP])
def test_sigterm_and_sighup_end_teach_cleanly(tmp_path, signum):
    transcript = tmp_path / "stopped.jsonl"
    process = start("teach", "--teacher", "scripted", "--turns", "200", "--transcript", transcript, cwd=tmp_path)
    earlier = read_until(process, r"^Turn +2\b")
    process.send_signal(signum)
    code, output = finish(process, earlier)
    assert code == 128 + signum, output
    assert "Traceback" not in output and f"stopped by {signal.Signals(signum).name}" in output, output
    assert transcript.read_text().endswith("\n")


# -- the viewer's server ---------------------------------------------------------------------------------------
def parent_of(pid: int) -> int | None:
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except (OSError, IndexError):
        return None
    return None if fields[0] == "Z" else int(fields[1])  # a zombie has ended


def alive(pid: int) -> bool:
    return parent_of(pid) is not None


def viewer_servers_of(parent: int) -> list[int]:
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit() and parent_of(int(entry.name)) == parent:
            try:
                command = (entry / "cmdline").read_bytes().decode("utf-8", "replace")
            except OSError:
                continue
            if SERVER_SCRIPT in command:
                found.append(int(entry.name))
    return found


def accepts(port: int) -> bool:
    try:
        with socket.create_connection(("127.0.0.1", port), timeout=1.0):
            return True
    except OSError:
        return False


def wait_until(condition, timeout_s: float) -> bool:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if condition():
            return True
        time.sleep(0.05)
    return condition()


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGHUP, signal.SIGKILL])
def test_the_viewer_server_goes_with_teachbot_view(tmp_path, signum):
    process = start("view", "--seconds", "60", cwd=tmp_path)
    earlier = read_until(process, r"^Serving")
    port = int(re.search(r"Viewer: http://127\.0\.0\.1:(\d+)/", "".join(earlier)).group(1))
    servers = viewer_servers_of(process.pid)
    assert len(servers) == 1 and accepts(port)
    process.send_signal(signum)
    code, output = finish(process, earlier)
    assert wait_until(lambda: not alive(servers[0]), 5.0), f"the server outlived its parent ({signum.name})"
    assert wait_until(lambda: not accepts(port), 5.0)
    if signum != signal.SIGKILL:
        assert code == 128 + signum and "Traceback" not in output, output


def test_view_export_writes_the_page_and_exits(tmp_path):
    page = tmp_path / "scene.html"
    process = start("view", "--export", page, cwd=tmp_path)
    code, output = finish(process)
    assert code == 0, output
    assert page.stat().st_size > 10_000 and "Serving" not in output


def test_the_viewer_server_ignores_ctrl_c_and_exits_when_its_input_pipe_closes():
    from bullet_world.viewer.server import SERVER_SCRIPT as script

    server = subprocess.Popen([sys.executable, str(script), "--parent", str(os.getpid())], stdin=subprocess.PIPE,
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        assert server.stdout.readline().startswith(b"zmq_url=")
        server.send_signal(signal.SIGINT)
        time.sleep(0.3)
        assert server.poll() is None  # Ctrl-C is the parent's to handle
        server.stdin.close()
        assert server.wait(timeout=5) == 0
        assert b"Traceback" not in server.stderr.read()
    finally:
        if server.poll() is None:
            server.kill()
        server.wait()
