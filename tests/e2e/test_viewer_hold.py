"""``demo --viewer`` in a terminal keeps the viewer up after the summary until Enter; Ctrl-C ends it cleanly."""

import os
import subprocess
import sys
import urllib.request
from pathlib import Path

import pexpect
import pytest

pytestmark = pytest.mark.e2e

TEACHBOT = str(Path(sys.executable).with_name("teachbot"))
HOLD = r"The viewer stays at (\S+); press Enter to close it"


def spawn_demo(tmp_path):
    env = {key: value for key, value in os.environ.items() if key != "CI"}
    env.update(TERM="dumb", NO_COLOR="1")
    return pexpect.spawn(TEACHBOT, ["demo", "--viewer", "--turns", "2", "--transcript", "demo.jsonl"],
                         cwd=str(tmp_path), env=env, encoding="utf-8", timeout=120)


@pytest.mark.parametrize("ending", ["enter", "ctrl-c"])
def test_the_viewer_stays_until_enter_or_ctrl_c(tmp_path, ending):
    child = spawn_demo(tmp_path)
    child.expect_exact("Accuracy on pack-lunchbox")
    child.expect(HOLD)
    url = child.match.group(1)
    with urllib.request.urlopen(url, timeout=10) as page:  # still served after the summary
        assert page.status == 200
    assert child.isalive()
    if ending == "enter":
        child.sendline("")
    else:
        child.sendintr()
    child.expect(pexpect.EOF)
    child.close()
    assert child.exitstatus == 0 and "Traceback" not in child.before


def test_without_a_terminal_the_demo_does_not_hold(tmp_path):
    env = {key: value for key, value in os.environ.items() if key != "CI"}
    done = subprocess.run([TEACHBOT, "demo", "--viewer", "--turns", "1", "--transcript", "demo.jsonl"],
                          cwd=tmp_path, env=env, stdin=subprocess.DEVNULL, capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0 and "Viewer: http://127.0.0.1" in done.stderr
    assert "The viewer stays" not in done.stdout + done.stderr


def test_the_readme_view_export_writes_its_page_and_exits_even_in_a_terminal(tmp_path):
    child = pexpect.spawn(TEACHBOT, ["view", "--seed", "2", "--point", "5", "--export", "scene.html"],
                          cwd=str(tmp_path), encoding="utf-8", timeout=120, env=dict(os.environ, TERM="dumb"))
    child.expect(pexpect.EOF)
    child.close()
    assert child.exitstatus == 0 and "Page: " in child.before and "Serving" not in child.before
    assert (tmp_path / "scene.html").stat().st_size > 10_000
