"""How a page session ends: quit, Ctrl-C and a full disk each keep ``--web`` in the "continue with" command, and
the page says what happened (issue 42, case 4). The command is the researcher's: it is printed at the terminal,
and the page says in plain words that the session is saved (issue 41, item 4)."""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import shutil
import signal
import subprocess

import pytest
import tornado.httpclient
import tornado.websocket

from dialog.commands._resume import UNRECORDED_TEACH_OPTIONS, continue_command
from dialog.web.session import web_continue_options
from tests.e2e.teach_helpers import PRINTED
from tests.e2e.web_helpers import WebCommand

pytestmark = pytest.mark.e2e
CAN_MOUNT = hasattr(os, "geteuid") and os.geteuid() == 0 and shutil.which("mount") is not None


def web_args(**given) -> argparse.Namespace:
    options = dict(web=True, host="127.0.0.1", port=0, allow_remote=False, origin=[], no_3d=False, pictures=False,
                   no_pictures=False, viewer=False, viewer_export=None, viewer_hold=False)
    return argparse.Namespace(**{**options, **given})


def test_the_continue_command_repeats_the_page_options_that_were_given():
    words = ["teach", "--resume", "runs/t.jsonl"]
    assert continue_command(words, web_args(), UNRECORDED_TEACH_OPTIONS + web_continue_options(web_args())) == \
        "teachbot teach --resume runs/t.jsonl --web"
    given = web_args(port=8765, origin=["https://a.example", "https://b.example"], no_3d=True)
    assert continue_command(words, given, web_continue_options(given)) == (
        "teachbot teach --resume runs/t.jsonl --web --port 8765 --origin https://a.example --origin "
        "https://b.example --no-3d")
    remote = web_args(host="0.0.0.0", allow_remote=True)
    assert continue_command(words, remote, web_continue_options(remote)).endswith(
        "--web --host 0.0.0.0 --allow-remote")
    assert web_continue_options(web_args(web=False)) == ()


class Page:
    """A page's websocket to a running session: answers the open question, collects what the server sends."""

    def __init__(self, url: str):
        base, token = url.split("?token=")
        self.socket_url, self.origin = f"{base.replace('http://', 'ws://')}ws?token={token}", base.rstrip("/")
        self.socket = None
        self.ended: str | None = None

    async def open(self) -> None:
        request = tornado.httpclient.HTTPRequest(self.socket_url, headers={"Origin": self.origin})
        self.socket = await tornado.websocket.websocket_connect(request)

    async def question(self) -> dict | None:
        """The next question once the robot waits for its answer; None once the session ended."""
        question, waiting = None, False
        while not (question and waiting):
            text = await self.socket.read_message()
            if text is None:
                return None
            message = json.loads(text)
            if message["type"] == "state":
                question, waiting = message["question"], message["waiting"]
            elif message["type"] == "question":
                question = message["question"]
            elif message["type"] == "waiting":
                waiting = question is not None and message["question"] == question["id"]
            elif message["type"] == "ended":
                self.ended = message["text"]
        return question

    def answer(self, question: dict, **message) -> None:
        self.socket.write_message(json.dumps({"question": question["id"], **message}))

    async def until_closed(self) -> None:
        while await self.question() is not None:
            pass


def run_page(coroutine, timeout_s: float = 240.0):
    return asyncio.run(asyncio.wait_for(coroutine, timeout_s))


def teach(cwd, transcript: str = "runs/t.jsonl", turns: int = 3) -> WebCommand:
    return WebCommand("teach", "--web", "--no-3d", "--seed", "0", "--turns", str(turns), "--transcript", transcript,
                      cwd=cwd)


def test_quit_in_the_page_keeps_web_in_the_continue_command_and_the_page_says_so(tmp_path):
    command = teach(tmp_path)
    page = Page(command.url)
    try:
        async def scenario():
            await page.open()
            first = await page.question()
            page.answer(first, type="concept", concept=first["concepts"][0])
            page.answer(await page.question(), type="command", command="quit")
            await page.until_closed()

        run_page(scenario())
        assert command.finish(90) == 0
    finally:
        command.stop()
    again = f"Continue it with: {PRINTED} teach --resume runs/t.jsonl --web --no-3d"
    assert any(again in line for line in command.out), "".join(command.out)
    assert page.ended is not None and "The session is saved after 1 of 3 turns" in page.ended
    assert "The robot now names" in page.ended and "teachbot" not in page.ended and "--resume" not in page.ended
    assert "pack-lunchbox" not in page.ended and ".jsonl" not in page.ended


def test_ctrl_c_at_the_terminal_keeps_web_and_the_page_says_it_was_interrupted(tmp_path):
    command = teach(tmp_path)
    page = Page(command.url)
    try:
        async def scenario():
            await page.open()
            assert await page.question() is not None
            command.process.send_signal(signal.SIGINT)
            await page.until_closed()

        run_page(scenario())
        assert command.finish(90) == 130
    finally:
        command.stop()
    again = f"continue it with: {PRINTED} teach --resume runs/t.jsonl --web --no-3d"
    assert any(again in line for line in command.out), "".join(command.out)
    assert page.ended is not None and page.ended.startswith("The session was interrupted.")
    assert "teachbot" not in page.ended and ".jsonl" not in page.ended
    assert "Traceback" not in "".join(command.err)


@pytest.mark.skipif(not CAN_MOUNT, reason="a real full disk needs root to mount a tmpfs")
def test_a_full_disk_keeps_web_and_the_page_says_what_stopped_the_session(tmp_path):
    disk = tmp_path / "disk"
    disk.mkdir()
    subprocess.run(["mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", str(disk)], check=True)
    try:
        command = teach(tmp_path, "disk/t.jsonl", turns=12)
        page = Page(command.url)
        try:
            async def scenario():
                await page.open()
                question = await page.question()
                with open(disk / "filler", "wb", buffering=0) as filler:  # the disk fills up mid-session
                    try:
                        while filler.write(b"\0" * 4096):
                            pass
                    except OSError:
                        pass
                while question is not None:  # until a write finds no room (the transcript's last page fills)
                    page.answer(question, type="command", command="don't know")
                    question = await page.question()

            run_page(scenario())
            assert command.finish(90) != 0
        finally:
            command.stop()
    finally:
        subprocess.run(["umount", "-l", str(disk)], check=False)
    err = "".join(command.err)
    assert "Traceback" not in err and "--web --no-3d" in err, err[-2000:]
    assert "ENOSPC" in err and "--resume disk/t.jsonl" in err
    assert page.ended is not None and page.ended.startswith("The session stopped: the computer could not save")
    assert "teachbot" not in page.ended and ".jsonl" not in page.ended
