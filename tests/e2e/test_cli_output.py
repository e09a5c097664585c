"""What a command prints first: its own words, never the simulator's banner."""

import subprocess
import sys
from pathlib import Path

import pytest

TEACHBOT = Path(sys.executable).with_name("teachbot")


def _run(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([str(TEACHBOT), *args], capture_output=True, text=True, timeout=120, check=False)


@pytest.mark.parametrize("command", ["demo", "teach", "view", "world", "regress", "recipe", "expert",
                                     "learn-weights"])
def test_help_starts_with_the_usage_line(command):
    result = _run(command, "--help")
    assert result.returncode == 0
    assert result.stdout.startswith("usage: teachbot"), result.stdout[:200]
    assert "pybullet build time" not in result.stdout + result.stderr


def test_importing_the_packages_prints_nothing():
    code = "import bullet_world, robot, dialog.environment"
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=False)
    assert result.returncode == 0, result.stderr
    assert result.stdout == "" and result.stderr == ""


def test_version_names_the_installed_package():
    from importlib import metadata
    result = _run("--version")
    assert result.returncode == 0 and result.stdout == f"teachbot {metadata.version('teachbot')}\n"
