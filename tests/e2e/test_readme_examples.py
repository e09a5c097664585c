"""The README's example commands run as written (in a scratch folder), each ending with exit 0.

Commands are taken from the README's code blocks (a line may start with the prompt ``$ ``) and inline code
spans, plus the commands in MOVED: examples the README once showed that now live in the doc that owns them
(issue 51), which must still show them. A few are not run, each for the reason given in SKIPPED, which must
name only commands the README or MOVED still shows.
"""

import os
import re
import shlex
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.e2e

ROOT = Path(__file__).resolve().parents[2]
README = ROOT / "README.md"
TEACHBOT = Path(sys.executable).with_name("teachbot")
TIMEOUT_S = 600

# Examples the README showed before it became a five-minute read (issue 51), each in the doc that now shows it.
MOVED = {
    "teachbot teach --resume runs/teach-pack-lunchbox-dt-task-seed0.jsonl": "docs/dialog.md",
    "teachbot teach --strategy all-cd --turns 40 --budget 30 --change-every 10 --realtime 20": "docs/dialog.md",
    "teachbot teach --teacher scripted --mislabel-rate 0.1 --dont-know-rate 0.05 --json": "docs/dialog.md",
    "teachbot study run dialog/data/studies/example.toml --participant P01 --web": "docs/web.md",
    "teachbot demo --web": "docs/web.md",
    "teachbot study run dialog/data/studies/example.toml --participant P01": "docs/studies.md",
    "teachbot study status dialog/data/studies/example.toml": "docs/studies.md",
    "teachbot study report dialog/data/studies/example.toml": "docs/studies.md",
    "teachbot demo --turns 10 --viewer-export episode.html": "docs/viewer.md",
    "teachbot regress --suite ch7 --strategies dt-task-env active-fs dt-iros dt-task --seeds 0 1 --ray local":
        "docs/experiments.md",
    "teachbot regress --suite recipes": "docs/recipes.md",
    "teachbot regress --suite smoke --check": "docs/kitchen.md",
}

SKIPPED = {
    "teachbot teach": "a person answers at the terminal (tests/e2e/test_teach_terminal.py drives it in a pty)",
    "teachbot teach --resume runs/teach-pack-lunchbox-dt-task-seed0.jsonl":
        "resumes a person's session: needs one recorded first and a person to answer",
    "teachbot teach --strategy all-cd --turns 40 --budget 30 --change-every 10 --realtime 20":
        "a person at the terminal, 20 s per turn for 40 turns",
    "teachbot expert": "a person picks the questions at the terminal",
    "teachbot teach --web": "a person answers in the page (tests/e2e/test_web_teach.py drives it in Chromium)",
    "teachbot study run dialog/data/studies/example.toml --participant P01 --web":
        "a participant in the page (tests/e2e/test_web_study.py drives it in Chromium)",
    "teachbot demo --web": "waits for a browser to open the page (tests/e2e/test_web_demo.py opens it in Chromium)",
    "teachbot study run dialog/data/studies/example.toml --participant P01": "a participant at the terminal",
    "teachbot view --task pack-lunchbox --seed 0": "serves the viewer until Ctrl-C, as the README says",
    "teachbot regress --suite recipes": "runs long (2,040 recipe trials)",
    "teachbot learn-weights --demos shipped --out w.toml --json":
        "runs long (trajectory IRL: 100 iterations of dialog rollouts, about 10 minutes on 2 cores)",
    "teachbot train-questioner --out questioner.toml":
        "runs long (20,000 steps of masked PPO, about 30 minutes on 2 cores; tests/dialog/test_rl_training.py "
        "trains for 256)",
    "teachbot regress --suite ch7 --strategies dt-task-env active-fs dt-iros dt-task --seeds 0 1 --ray local":
        "the chapter-7 suite is run by the lead only; long, and starts a Ray cluster",
}


def readme_commands(text: str) -> list[str]:
    """Every ``teachbot ...`` command in a page's code blocks and inline code spans (tables left out)."""
    commands = []
    for block in re.findall(r"^```[a-z]*\n(.*?)^```", text, flags=re.S | re.M):
        for line in block.splitlines():
            line = line.split("  #")[0].strip().removeprefix("$ ")
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
COMMANDS += [command for command in MOVED if command not in COMMANDS]


def test_the_readme_has_examples_and_every_skip_names_one_of_them():
    assert len(COMMANDS) >= 10
    assert set(SKIPPED) <= set(COMMANDS), sorted(set(SKIPPED) - set(COMMANDS))
    assert all(command.startswith("teachbot ") for command in COMMANDS)


def test_every_moved_example_is_still_shown_by_its_doc():
    for command, doc in MOVED.items():
        assert command in readme_commands((ROOT / doc).read_text(encoding="utf-8")), f"{doc} no longer shows {command}"


@pytest.mark.parametrize("command", [c for c in COMMANDS if c not in SKIPPED])
def test_a_readme_example_runs_as_written(command, tmp_path):
    argv = [str(TEACHBOT), *shlex.split(command)[1:]]
    for argument in argv[1:]:  # a file of the clone the example names (a study file, rl:POLICY) is copied, with
        name = argument.removeprefix("rl:")  # the files beside it that it names (a consent text, the policy's npz)
        source = README.parent / name
        if not name.startswith("-") and "/" in name and source.is_file():
            (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
            for part in (p for p in source.parent.iterdir() if p.is_file()):
                shutil.copy(part, (tmp_path / name).parent / part.name)
    returncode, stderr = run_in_own_group(argv, tmp_path)
    assert returncode == 0, f"{command} exited {returncode}:\n{stderr[-2000:]}"
    assert "Traceback" not in stderr


def run_in_own_group(argv: list[str], cwd: Path) -> tuple[int, str]:
    """Run ``argv`` in its own process group; past ``TIMEOUT_S`` the whole group is killed and the test fails,
    so worker processes (``teachbot regress`` starts one per core) do not outlive it."""
    process = subprocess.Popen(argv, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               stdin=subprocess.DEVNULL, start_new_session=True)
    try:
        _, stderr = process.communicate(timeout=TIMEOUT_S)
    except subprocess.TimeoutExpired:
        os.killpg(process.pid, signal.SIGKILL)
        process.communicate()
        pytest.fail(f"{shlex.join(argv[1:])} did not finish within {TIMEOUT_S} s (its process group was killed)")
    return process.returncode, stderr


def test_a_command_past_its_time_is_killed_with_every_process_it_started(tmp_path, monkeypatch):
    """The timeout kills the example's whole process group: a child it started (as regress starts workers)
    does not keep running after the test."""
    import time

    monkeypatch.setattr(sys.modules[__name__], "TIMEOUT_S", 2)
    pid_file = tmp_path / "child.pid"
    script = ("import subprocess, sys, time; "
              "child = subprocess.Popen([sys.executable, '-c', 'import time; time.sleep(120)']); "
              f"open({str(pid_file)!r}, 'w').write(str(child.pid)); child.wait()")
    with pytest.raises(pytest.fail.Exception, match="did not finish within 2 s"):
        run_in_own_group([sys.executable, "-c", script], tmp_path)
    child = int(pid_file.read_text())
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline:
        try:
            if "\nState:\tZ" in Path(f"/proc/{child}/status").read_text():
                break  # killed, waiting for init to reap it
        except FileNotFoundError:
            break  # killed and reaped
        time.sleep(0.1)
    else:
        pytest.fail(f"the example's child process {child} outlived the timeout")


def test_every_readme_regress_example_that_names_strategies_computes_its_suites_findings():
    """Issue 42, case 5: the Ray example named two strategies of ch7, so all four of its findings were skipped.
    The run itself is in SKIPPED; this checks, without running it, that its strategies are the findings' own."""
    from dialog.experiments.suite import load_suite
    from learning.strategies import STRATEGY_NAMES

    examples = [shlex.split(c) for c in COMMANDS if c.startswith("teachbot regress ") and " --strategies " in c]
    assert examples, "the README shows a regress example with --strategies"
    for words in examples:
        suite = load_suite(words[words.index("--suite") + 1], STRATEGY_NAMES)
        named = words[words.index("--strategies") + 1:]
        named = named[:next((i for i, w in enumerate(named) if w.startswith("--")), len(named))]
        skipped = [f.id for f in suite.findings if f.better not in named or not set(f.than) <= set(named)]
        assert suite.findings and not skipped, (shlex.join(words), skipped)
