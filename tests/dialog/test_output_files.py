"""Output files must be regular files: FIFOs, devices and folders are refused in one line without being opened,
and a path that can't even be looked up gets its own true message (issue 24, item 4; issue 23, case 1).

One rule for every command: its output paths are checked before the work starts, and missing folders above an
output are created when it is written.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from dialog.cli import main

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "dialog" / "data" / "studies" / "example.toml"

#: every command-line option that names an output file, as a command that writes it quickly
FILE_OUTPUTS = {
    "demo --transcript": lambda p: ["demo", "--turns", "1", "--transcript", p],
    "teach --transcript": lambda p: ["teach", "--teacher", "scripted", "--turns", "1", "--no-pictures",
                                     "--transcript", p],
    "view --export": lambda p: ["view", "--export", p, "--seconds", "0"],
    "learn-weights --out": lambda p: ["learn-weights", "--demos", "shipped", "--method", "per-turn",
                                      "--allow-degenerate", "--out", p],
    "train-questioner --out": lambda p: ["train-questioner", "--out", p, "--steps", "64", "--envs", "1"],
    "world show --png": lambda p: ["world", "show", "--png", p],
}
SUFFIX = {"demo --transcript": ".jsonl", "teach --transcript": ".jsonl", "view --export": ".html",
          "learn-weights --out": ".toml", "train-questioner --out": ".toml", "world show --png": ".png"}


def run_cli(args: list[str], cwd: Path) -> subprocess.CompletedProcess:
    """The command in its own process, so that a refusal that is missing shows as a timeout, not a hung test."""
    return subprocess.run([sys.executable, "-m", "dialog.cli", *args], cwd=cwd, capture_output=True, text=True,
                          timeout=60, env={**os.environ, "PYTHONPATH": str(ROOT)})


def one_line(result, *fragments: str) -> str:
    assert result.returncode == 2, (result.returncode, result.stdout[-500:], result.stderr[-2000:])
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in result.stderr, result.stderr
    for fragment in fragments:
        assert fragment in lines[0], (fragment, lines[0])
    return lines[0]


@pytest.mark.parametrize("option", sorted(FILE_OUTPUTS))
def test_a_fifo_as_an_output_file_is_refused_without_blocking(option, tmp_path):
    fifo = tmp_path / f"out{SUFFIX[option]}"
    os.mkfifo(fifo)
    one_line(run_cli(FILE_OUTPUTS[option](str(fifo)), tmp_path), str(fifo), "it is a FIFO (named pipe), not a "
                                                                            "regular file")


def test_a_fifo_as_the_viewer_export_is_one_warning_and_the_demo_goes_on(tmp_path):
    fifo = tmp_path / "episode.html"
    os.mkfifo(fifo)
    result = run_cli(["demo", "--turns", "1", "--viewer-export", str(fifo), "--transcript", "t.jsonl"], tmp_path)
    assert result.returncode == 0, result.stderr
    assert f"warning: {fifo}: cannot write the viewer export: it is a FIFO" in result.stderr
    assert (tmp_path / "t.jsonl").stat().st_size > 0


@pytest.mark.parametrize("device", ["/dev/null", "/dev/full"])
@pytest.mark.parametrize("option", ["demo --transcript", "teach --transcript", "view --export", "learn-weights --out"])
def test_a_device_as_an_output_file_is_refused(option, device, tmp_path, capsys):
    # through a link to the device: a teachbot that renamed a finished file into place would replace the link,
    # not the system's device (run as root, the bug this guards against replaced /dev/full itself)
    link = tmp_path / f"device{SUFFIX[option]}"
    link.symlink_to(device)
    assert main(FILE_OUTPUTS[option](str(link))) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"{link}: cannot write the " in err and "it is a character device" in err
    assert link.is_symlink() and Path(device).is_char_device()


def _long_name(tmp_path: Path, suffix: str) -> tuple[str, str]:
    return str(tmp_path / ("n" * 300 + suffix)), "a name in the path is 30"


def _long_path(tmp_path: Path, suffix: str) -> tuple[str, str]:
    return str(tmp_path / "/".join(["d" * 200] * 22) / f"x{suffix}"), "bytes long; this system allows at most"


def _loop(tmp_path: Path, suffix: str) -> tuple[str, str]:
    os.symlink(tmp_path / "b", tmp_path / "a")
    os.symlink(tmp_path / "a", tmp_path / "b")
    return str(tmp_path / "a" / f"x{suffix}"), "symbolic links in the path loop"


@pytest.mark.parametrize("make", [_long_name, _long_path, _loop], ids=["300-character name", "path over 4096",
                                                                      "symlink loop"])
@pytest.mark.parametrize("option", sorted(FILE_OUTPUTS))
def test_a_path_that_cannot_be_looked_up_gets_its_own_message(option, make, tmp_path, capsys):
    path, fragment = make(tmp_path, SUFFIX[option])
    assert main(FILE_OUTPUTS[option](path)) == 2
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and fragment in lines[0], err
    assert "does not exist" not in err and "no space left" not in err


@pytest.mark.parametrize("option", sorted(FILE_OUTPUTS))
def test_a_trailing_separator_names_a_folder_not_a_file(option, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as stopped:
        main(FILE_OUTPUTS[option]("newdir/"))
    assert stopped.value.code == 2
    assert "'newdir/' ends in '/', so it names a folder; give a file path" in capsys.readouterr().err
    assert not (tmp_path / "newdir").exists()


def test_a_proc_path_is_not_reported_as_a_full_disk(capsys):
    assert main(["demo", "--turns", "1", "--transcript", "/proc/teachbot-test.jsonl"]) == 2
    err = capsys.readouterr().err
    assert "a file system of the kernel's" in err and "no space left" not in err


# -- one rule: missing folders above an output are created (issue 23, case 1) ----------------------------------
FOLDER_CREATED = {
    "demo --transcript": FILE_OUTPUTS["demo --transcript"],
    "teach --transcript": FILE_OUTPUTS["teach --transcript"],
    "view --export": FILE_OUTPUTS["view --export"],
    "learn-weights --out": FILE_OUTPUTS["learn-weights --out"],
    "world show --png": FILE_OUTPUTS["world show --png"],
    "demo --viewer-export": lambda p: ["demo", "--turns", "1", "--viewer-export", p, "--transcript",
                                       str(Path(p).parent.parent / "t.jsonl")],
    "study report --out": lambda p: ["study", "report", str(EXAMPLE), "--folder", str(Path(p).parent / "records"),
                                     "--out", str(Path(p).parent)],
}
# train-questioner --out in a new folder: tests/dialog/test_rl_training.py trains into one


@pytest.mark.parametrize("option", sorted(FOLDER_CREATED))
def test_every_command_creates_the_missing_folders_of_its_output(option, tmp_path, capsys, monkeypatch):
    suffix = SUFFIX.get(option, ".html" if "export" in option else ".md")
    monkeypatch.chdir(tmp_path)  # missing folders are created inside the current folder
    path = Path("new-folder") / "below" / ("report.md" if option == "study report --out" else f"out{suffix}")
    assert main(FOLDER_CREATED[option](str(path))) == 0, capsys.readouterr().err
    assert path.is_file() and path.stat().st_size > 0


# -- outside the current folder a missing folder is refused, not created (issue 42, case 2) ---------------------
@pytest.mark.parametrize("option", ["demo --transcript", "view --export", "teach --transcript",
                                    "world show --png", "learn-weights --out"])
def test_a_file_in_a_missing_folder_outside_the_current_one_is_refused_and_nothing_is_created(option, tmp_path):
    here = tmp_path / "here"
    here.mkdir()
    path = tmp_path / "nonexistent" / "dir" / f"out{SUFFIX[option]}"
    line = one_line(run_cli(FILE_OUTPUTS[option](str(path)), here), f"the folder {path.parent} does not exist",
                    "missing folders are created only inside the current folder")
    assert line.startswith(f"teachbot {option.split()[0]}") and f": {option.split()[-1]}: {path}: the folder " in line
    assert not (tmp_path / "nonexistent").exists()


def test_a_demo_in_a_missing_folder_at_the_root_is_refused(tmp_path):
    top = Path("/") / f"teachbot-missing-{os.getpid()}"
    assert not top.exists()
    try:
        one_line(run_cli(["demo", "--turns", "1", "--transcript", str(top / "dir" / "t.jsonl")], tmp_path),
                 f"the folder {top / 'dir'} does not exist")
        assert not top.exists()
    finally:
        if top.exists():  # the bug: the folder was made at the file system's root
            shutil.rmtree(top)


def test_the_viewer_export_into_a_missing_folder_elsewhere_is_refused(tmp_path):
    here = tmp_path / "here"
    here.mkdir()
    page = tmp_path / "nonexistent" / "episode.html"
    one_line(run_cli(["demo", "--turns", "1", "--viewer-export", str(page), "--transcript", "t.jsonl"], here),
             f"--viewer-export: {page}: the folder {page.parent} does not exist")
    assert not page.parent.exists() and not (here / "t.jsonl").exists()


# -- default names are numbered, never overwritten (issue 42, case 2) ------------------------------------------
def test_every_demo_keeps_the_earlier_demos_transcript_and_page(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    pages = tmp_path / "pages"
    pages.mkdir()
    for _ in range(2):
        assert main(["demo", "--turns", "1", "--viewer-export", str(pages)]) == 0, capsys.readouterr().err
    err = capsys.readouterr().err
    first, second = Path("runs/demo-dt-task-seed0.jsonl"), Path("runs/demo-dt-task-seed0-2.jsonl")
    assert first.is_file() and second.is_file() and first.read_bytes() == second.read_bytes()
    assert (pages / "episode.html").is_file() and (pages / "episode-2.html").is_file()
    assert f"the page goes to {pages / 'episode-2.html'}" in err


def test_the_numbered_name_is_teachs_rule(tmp_path):
    from dialog.output_paths import numbered

    path = tmp_path / "teach-pack-lunchbox-mypkg.mod.Class-seed0.jsonl"
    assert numbered(path) == path
    path.write_text("x")
    assert numbered(path) == tmp_path / "teach-pack-lunchbox-mypkg.mod.Class-seed0-2.jsonl"
