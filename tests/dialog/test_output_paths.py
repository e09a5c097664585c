"""Every path teachbot writes: checked up front, and every write error one line naming the path and the cause.

A full disk and a read-only folder are real where we can mount a tmpfs (root);
elsewhere those cases are skipped and the same code path is driven by a patched write.
"""

from __future__ import annotations

import errno
import os
import shutil
import subprocess

import pytest

from dialog.cli import main
from dialog.output_paths import check_writable, writing
from dialog.transcripts.jsonl import TranscriptWriter, read_session
from learning.errors import OutputPathError

CAN_MOUNT = hasattr(os, "geteuid") and os.geteuid() == 0 and shutil.which("mount") is not None
needs_mount = pytest.mark.skipif(not CAN_MOUNT, reason="a real full disk / read-only folder needs root to mount "
                                                       "a tmpfs; the patched-write tests cover the same path")


@pytest.fixture
def mount(tmp_path):
    """``mount(size, read_only)`` gives a fresh tmpfs folder; every one is unmounted afterwards."""
    mounted = []

    def make(size: str = "64k", read_only: bool = False, name: str = "disk"):
        point = tmp_path / name
        point.mkdir()
        subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(point)], check=True)
        mounted.append(point)
        if read_only:
            subprocess.run(["mount", "-o", "remount,ro", str(point)], check=True)
        return point

    yield make
    for point in reversed(mounted):
        subprocess.run(["umount", "-l", str(point)], check=False)


def fill(folder, leave_pages: int = 0):
    """Fill a tmpfs until it is full, then give ``leave_pages`` 4 KiB pages back; returns the filler file."""
    filler = folder / "filler"
    with open(filler, "wb", buffering=0) as handle:
        try:
            while handle.write(b"\0" * 4096):
                pass
        except OSError as error:
            assert error.errno == errno.ENOSPC
    if leave_pages:
        os.truncate(filler, max(0, filler.stat().st_size // 4096 - leave_pages) * 4096)
    return filler


def one_error_line(capsys, command: str, *fragments: str) -> str:
    err = capsys.readouterr().err
    assert "Traceback" not in err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"teachbot {command}: "), err
    for fragment in fragments:
        assert fragment in lines[0], (fragment, lines[0])
    return lines[0]


# -- check_writable and writing ---------------------------------------------------------------------------------
def test_a_folder_where_a_file_belongs_and_a_file_as_parent_are_refused_and_nothing_is_created(tmp_path):
    with pytest.raises(OutputPathError, match=r"cannot write the transcript: it is a folder"):
        check_writable(tmp_path, "transcript")
    (tmp_path / "plain").write_text("x")
    with pytest.raises(OutputPathError) as error:
        check_writable(tmp_path / "plain" / "deeper" / "t.jsonl", "transcript")
    assert f"{tmp_path / 'plain'} is a file, not a folder" in str(error.value)
    with pytest.raises(OutputPathError, match="it is a file; give a folder"):
        check_writable(tmp_path / "plain", "results", folder=True)
    target = tmp_path / "new" / "sub" / "t.jsonl"
    assert check_writable(target, "transcript") == target and not (tmp_path / "new").exists()


@needs_mount
def test_a_read_only_folder_and_a_full_disk_are_refused_up_front(mount):
    read_only = mount(read_only=True, name="ro")
    with pytest.raises(OutputPathError, match=r"ro/a/t.jsonl: cannot write the transcript: .*\(EROFS\)"):
        check_writable(read_only / "a" / "t.jsonl", "transcript")
    full = mount(name="full")
    fill(full)
    with pytest.raises(OutputPathError, match=r"full/t.jsonl: cannot write the transcript: no space left on device "
                                              r"\(ENOSPC\)"):
        check_writable(full / "t.jsonl", "transcript")


def test_writing_names_the_path_and_the_cause_and_leaves_other_errors_alone(tmp_path):
    report = tmp_path / "report.md"
    with pytest.raises(OutputPathError, match=rf"^{report}: cannot write the results: no space left on device"):
        with writing(tmp_path, "results", inside=True):
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(report))
    with pytest.raises(OutputPathError, match=rf"^{tmp_path}: cannot write the results: read-only file system"):
        with writing(tmp_path, "results", inside=True):
            raise OSError(errno.EROFS, os.strerror(errno.EROFS))  # a write naming no file: the folder is named
    with pytest.raises(PermissionError):  # a file outside the results folder: not ours to explain
        with writing(tmp_path / "results", "results", inside=True):
            raise PermissionError(errno.EACCES, "denied", "/etc/elsewhere")
    with pytest.raises(FileNotFoundError):  # not a write error: keeps its own handling
        with writing(tmp_path / "x.toml", "weights file"):
            raise FileNotFoundError(errno.ENOENT, "missing", "x.toml")


# -- the transcript writer ------------------------------------------------------------------------------------
def test_a_failed_write_is_cut_back_so_the_transcript_stays_valid(tmp_path, monkeypatch):
    path = tmp_path / "t.jsonl"
    writer = TranscriptWriter(path)
    writer.write_header({"task": "pack-lunchbox"})
    writer.write({"turn": 1})
    real_write = os.write

    def half_then_full(fd, data):  # the disk fills up half way through the line
        if fd == writer.lock.fd and len(data) > 10:
            return real_write(fd, bytes(data[: len(data) // 2]))
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(os, "write", half_then_full)
    with pytest.raises(OutputPathError, match=r"t.jsonl: cannot write the transcript: no space left on device "
                                              r"\(ENOSPC\)"):
        writer.write({"turn": 2, "answer": "x" * 100})
    monkeypatch.undo()
    writer.close()
    writer.close()  # closing twice, or after a failed write, raises nothing
    header, records = read_session(path)  # strict: no half line
    assert header["task"] == "pack-lunchbox" and records == [{"turn": 1}]


@needs_mount
def test_a_real_full_disk_keeps_every_completed_line(mount):
    disk = mount(size="16k")
    path = disk / "t.jsonl"
    written = 0
    with TranscriptWriter(path) as writer:
        writer.write_header({"task": "pack-lunchbox"})
        with pytest.raises(OutputPathError, match=r"cannot write the transcript: no space left on device"):
            for turn in range(1, 1000):
                writer.write({"turn": turn, "padding": "p" * 700})
                written = turn
    assert 5 < written < 1000 and [r["turn"] for r in read_session(path)[1]] == list(range(1, written + 1))


# -- every command, through the real command line --------------------------------------------------------------
def _bad_path(kind: str, tmp_path, mount, name: str):
    if kind == "folder":
        folder = tmp_path / "a-folder"
        folder.mkdir()
        return folder, "it is a folder"
    if kind == "file-parent":
        (tmp_path / "plain").write_text("x")
        return tmp_path / "plain" / name, "is a file, not a folder"
    if not CAN_MOUNT:
        pytest.skip("needs root to mount a tmpfs")
    if kind == "read-only":
        return mount(read_only=True, name="ro") / name, "(EROFS)"
    disk = mount(name="full")
    fill(disk)
    return disk / name, "no space left on device (ENOSPC)"


COMMANDS = {
    "demo": lambda p: ["demo", "--turns", "2", "--transcript", p],
    "teach": lambda p: ["teach", "--teacher", "scripted", "--turns", "2", "--transcript", p],
    "regress": lambda p: ["regress", "--suite", "smoke", "--results", p, "--no-progress"],
    "learn-weights": lambda p: ["learn-weights", "--demos", "shipped", "--out", p],
    "view": lambda p: ["view", "--export", p, "--seconds", "0"],
}
NAMES = {"demo": "d.jsonl", "teach": "t.jsonl", "regress": "results", "learn-weights": "w.toml", "view": "v.html"}


@pytest.mark.parametrize("kind", ["folder", "file-parent", "read-only", "full"])
@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_every_command_refuses_an_unwritable_output_in_one_line(command, kind, tmp_path, mount, capsys):
    if command == "regress" and kind == "folder":
        pytest.skip("a results folder is meant to be a folder")
    if command == "view" and kind == "folder":
        pytest.skip("view --export FOLDER writes FOLDER/scene.html")
    if command == "learn-weights" and kind == "folder":
        folder = tmp_path / "w.toml"
        folder.mkdir()
        path, cause = folder, "it is a folder"
    else:
        path, cause = _bad_path(kind, tmp_path, mount, NAMES[command])
    if command == "regress" and kind == "file-parent":
        path = path.parent  # the results folder itself is a file
        cause = "it is a file"
    assert main(COMMANDS[command](str(path))) == 2
    one_error_line(capsys, command, str(path), cause)


def test_teach_resume_of_a_folder_is_one_line(tmp_path, capsys):
    assert main(["teach", "--resume", str(tmp_path)]) == 2
    one_error_line(capsys, "teach", str(tmp_path), "it is a folder")


@needs_mount
def test_a_full_disk_mid_session_keeps_the_completed_turns_and_resume_goes_on_once_there_is_room(mount, capsys):
    disk = mount(size="64k")
    filler = fill(disk, leave_pages=1)  # room for the header and a few turns, not for ten
    path = disk / "t.jsonl"
    assert main(["teach", "--teacher", "scripted", "--turns", "10", "--transcript", str(path)]) == 2
    line = one_error_line(capsys, "teach", f"{path}: cannot write the transcript: no space left on device (ENOSPC)",
                          f"teachbot teach --resume {path}")
    assert "completed turns are saved" in line
    header, records = read_session(path)  # strict: every line whole
    assert header is not None and 1 <= len(records) < 10
    assert [r["turn"] for r in records] == list(range(1, len(records) + 1))
    filler.unlink()
    assert main(["teach", "--resume", str(path)]) == 0
    assert f"resuming after turn {len(records)}" in capsys.readouterr().out
    assert [r["turn"] for r in read_session(path)[1]] == list(range(1, 11))


@needs_mount
@pytest.mark.parametrize("kind", ["read-only", "full"])
def test_scene_pictures_that_cannot_be_written_are_one_warning_and_the_session_completes(kind, tmp_path, mount,
                                                                                        capsys):
    disk = mount(size="64k", read_only=kind == "read-only")
    if kind == "full":
        fill(disk, leave_pages=1)  # passes the check up front; the first picture (tens of KB) does not fit
    path = tmp_path / "t.jsonl"
    assert main(["teach", "--teacher", "scripted", "--turns", "6", "--transcript", str(path),
                 "--pictures", str(disk / "pictures")]) == 0
    captured = capsys.readouterr()
    warnings = [line for line in captured.err.splitlines() if line.startswith("warning:")]
    assert len(warnings) == 1 and str(disk / "pictures") in warnings[0] and "going on without scene pictures" in \
        warnings[0] and "Traceback" not in captured.err
    assert [r["turn"] for r in read_session(path)[1]] == list(range(1, 7))
    assert not any("picture" in r for r in read_session(path)[1])


@pytest.mark.e2e
def test_demo_viewer_export_to_a_folder_writes_episode_html_and_says_so(tmp_path, capsys):
    folder = tmp_path / "pages"
    folder.mkdir()
    assert main(["demo", "--turns", "3", "--change-every", "2", "--transcript", str(tmp_path / "d.jsonl"),
                 "--viewer-export", str(folder)]) == 0
    err = capsys.readouterr().err
    assert (folder / "episode.html").is_file() and (folder / "episode.html").stat().st_size > 100_000
    assert f"the page goes to {folder / 'episode.html'}" in err and "Episode page:" in err


@needs_mount
def test_demo_viewer_export_that_cannot_be_written_is_a_warning(tmp_path, mount, capsys):
    page = mount(read_only=True, name="ro") / "episode.html"
    assert main(["demo", "--turns", "2", "--transcript", str(tmp_path / "d.jsonl"),
                 "--viewer-export", str(page)]) == 0
    err = capsys.readouterr().err
    assert f"warning: {page}: cannot write the viewer export" in err and "(EROFS)" in err
    assert len(read_session(tmp_path / "d.jsonl")[1]) == 2


def test_a_viewer_export_that_fails_on_close_is_one_warning_naming_the_page(tmp_path, capsys):
    from dialog.viewer import stop_viewer

    class FullDiskViewer:
        export_path = tmp_path / "episode.html"

        def close(self):
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    assert stop_viewer(FullDiskViewer()) is None
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"warning: {tmp_path / 'episode.html'}: cannot write the viewer export: no space left on device "
                   "(ENOSPC); the session itself is saved"]
