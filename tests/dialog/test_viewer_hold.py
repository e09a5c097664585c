"""``--viewer-hold``: a live viewer stays up at the end until Enter (a terminal) or for SECONDS; never under CI."""

import argparse
import io

import pytest

from dialog.viewer import add_viewer_option, hold_viewer


class FakeViewer:
    url = "http://127.0.0.1:7000/static/"


class Keyboard(io.StringIO):
    """A terminal's stdin: ``isatty`` says yes; ``interrupt`` makes reading raise Ctrl-C."""

    def __init__(self, text="\n", interrupt=False):
        super().__init__(text)
        self.interrupt, self.reads = interrupt, 0

    def isatty(self):
        return True

    def readline(self, *args):
        self.reads += 1
        if self.interrupt:
            raise KeyboardInterrupt
        return super().readline(*args)


def options(*argv):
    parser = argparse.ArgumentParser()
    add_viewer_option(parser)
    return parser.parse_args(["--viewer", *argv])


@pytest.fixture(autouse=True)
def no_ci(monkeypatch):
    monkeypatch.delenv("CI", raising=False)


def test_a_terminal_holds_until_enter():
    keyboard, out = Keyboard(), io.StringIO()
    hold_viewer(options(), FakeViewer(), keyboard, out)
    assert keyboard.reads == 1
    assert out.getvalue() == f"The viewer stays at {FakeViewer.url}; press Enter to close it\n"


def test_ctrl_c_ends_the_hold_cleanly():
    keyboard, out = Keyboard(interrupt=True), io.StringIO()
    hold_viewer(options(), FakeViewer(), keyboard, out)  # no KeyboardInterrupt escapes
    assert keyboard.reads == 1 and "press Enter" in out.getvalue()


@pytest.mark.parametrize("case", ["pipe", "ci", "zero", "no viewer", "headless"])
def test_no_hold_without_a_terminal_under_ci_with_zero_or_without_a_live_viewer(case, monkeypatch):
    stdin = io.StringIO("\n") if case == "pipe" else Keyboard()
    if case == "ci":
        monkeypatch.setenv("CI", "true")
    args = options("--viewer-hold", "0") if case == "zero" else options()
    viewer = None if case == "no viewer" else FakeViewer()
    if case == "headless":
        viewer.url = None
    out = io.StringIO()
    assert hold_viewer(args, viewer, stdin, out) == 0.0
    assert out.getvalue() == "" and stdin.read() == "\n"  # nothing said, nothing read


def test_hold_seconds_waits_that_long_even_without_a_terminal():
    out = io.StringIO()
    held = hold_viewer(options("--viewer-hold", "0.2"), FakeViewer(), io.StringIO(), out)
    assert 0.2 <= held < 2 and "for 0.2 s (Ctrl-C closes it)" in out.getvalue()


def test_a_bad_hold_is_refused_by_the_parser(capsys):
    with pytest.raises(SystemExit):
        options("--viewer-hold", "-1")
    assert "expected zero or more seconds" in capsys.readouterr().err
