"""The README's example commands run as written (in a scratch folder), each ending with exit 0.

Commands are taken from the README's code blocks and inline code spans; a few are not run, each for the
reason given in SKIPPED, which must name only commands the README still shows.
"""

import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.e2e

README = Path(__file__).resolve().parents[2] / "README.md"
TEACHBOT = Path(sys.executable).with_name("teachbot")
TIMEOUT_S = 600

SKIPPED = {
    "teachbot teach": "a person answers at the terminal (tests/e2e/test_teach_terminal.py drives it in a pty)",
    "teachbot teach --resume runs/teach-pack-lunchbox-dt-task-seed0.jsonl":
        "resumes a person's session: needs one recorded first and a person to answer",
    "teachbot teach --strategy all-cd --turns 40 --budget 30 --change-every 10 --realtime 20 --viewer":
        "a person at the terminal, 20 s per turn for 40 turns",
    "teachbot expert": "a person picks the questions at the terminal",
    "teachbot teach --web": "a person answers in the page (tests/e2e/test_web_teach.py drives it in Chromium)",
    "teachbot study run dialog/data/studies/example.toml --participant P01 --web":
        "a participant in the page (tests/e2e/test_web_study.py drives it in Chromium)",
    "teachbot demo --web": "waits for a browser to open the page (tests/e2e/test_web_demo.py opens it in Chromium)",
    "teachbot study run dialog/data/studies/example.toml --participant P01": "a participant at the terminal",
    "teachbot view --task pack-lunchbox --seed 0": "serves the viewer until Ctrl-C, as the README says",
    "teachbot regress --suite ch6-dynamic": "runs long (the chapter-6 suite, minutes on every core)",
    "teachbot regress --suite recipes": "runs long (2,040 recipe trials)",
    "teachbot regress --suite ch7-irl --data-seeds 0 1 --seeds 0 1 2 3 4":
        "runs long (1,200 episodes, about 11 minutes on 2 cores: the pre-registered chapter-7 evaluation, run once)",
    "teachbot learn-weights --demos shipped --out w.toml --json":
        "runs long (trajectory IRL: 100 iterations of dialog rollouts, about 10 minutes on 2 cores)",
    "teachbot train-questioner --out questioner.toml":
        "runs long (20,000 steps of masked PPO, about 30 minutes on 2 cores; tests/dialog/test_rl_training.py "
        "trains for 256)",
    "teachbot regress --suite ch7 --strategies active dt-task --seeds 0 1 --ray local":
        "the chapter-7 suite is run by the lead only; long, and starts a Ray cluster",
}


def readme_commands(text: str) -> list[str]:
    """Every ``teachbot ...`` command in the README's code blocks and inline code spans (tables left out)."""
    commands = []
    for block in re.findall(r"^```[a-z]*\n(.*?)^```", text, flags=re.S | re.M):
        for line in block.splitlines():
            line = line.split("  #")[0].strip()
            if line.startswith("teachbot "):
                commands.append(" ".join(line.split()))
    prose = re.sub(r"^```[a-z]*\n.*?^```", "", text, flags=re.S | re.M)
    prose = "\n".join(line for line in prose.splitlines() if not line.lstrip().startswith("|"))
    for span in re.findall(r"`((?:\.venv/bin/)?teachbot(?: [^`]*)?)`", prose):
        commands.append(" ".join(span.split()).removeprefix(".venv/bin/"))
    unique = []
    for command in commands:
        if command not in unique and command != "teachbot":
            unique.append(command)
    return unique


COMMANDS = readme_commands(README.read_text(encoding="utf-8"))


def test_the_readme_has_examples_and_every_skip_names_one_of_them():
    assert len(COMMANDS) >= 10
    assert set(SKIPPED) <= set(COMMANDS), sorted(set(SKIPPED) - set(COMMANDS))
    assert all(command.startswith("teachbot ") for command in COMMANDS)


@pytest.mark.parametrize("command", [c for c in COMMANDS if c not in SKIPPED])
def test_a_readme_example_runs_as_written(command, tmp_path):
    argv = [str(TEACHBOT), *shlex.split(command)[1:]]
    for argument in argv[1:]:  # a file of the clone the example names (a study file, rl:POLICY) is copied beside it
        name = argument.removeprefix("rl:")
        source = README.parent / name
        if not name.startswith("-") and "/" in name and source.is_file():
            (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
            for part in (source, source.with_suffix(".npz")) if argument.startswith("rl:") else (source,):
                shutil.copy(part, tmp_path / Path(name).with_suffix(part.suffix))
    result = subprocess.run(argv, cwd=tmp_path, capture_output=True, text=True, timeout=TIMEOUT_S,
                            stdin=subprocess.DEVNULL, check=False)
    assert result.returncode == 0, f"{command} exited {result.returncode}:\n{result.stderr[-2000:]}"
    assert "Traceback" not in result.stderr
