"""Fuzz the teaching page's and the study page's messages against real ``--web`` sessions on 127.0.0.1.

    python scripts/fuzz_web.py --messages 2000 --json

The first session is a study run (``study run --web`` of the example study: its screens, questionnaires and
teach sessions); the next are ``teach --web`` sessions, until ``--messages`` hostile messages are sent. At every
open question or screen the fuzzer sends hostile messages (``_fuzz_web_messages``: malformed JSON, wrong types,
huge and non-finite numbers, deep nesting, lone surrogates and control characters in every text field, stale
and out-of-range ids, unknown fields, oversized), alone or in bursts, from two clients, now and then
reconnecting, then one valid answer (sometimes from both clients at once: one must be taken, one refused).
Counted: tracebacks (in the server's output), hangs (no refusal, question or end within --timeout, or a
process that does not exit), silent accepts (a hostile message without its one refusal, or a hostile line in
the transcript) and bytes lost (recorded bytes of a transcript or a study record that are gone later).
The same --seed gives the same messages. The last line (with --json) is one JSON object.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import tornado.httpclient
import tornado.websocket

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _fuzz_web_messages import Hostile, oversized  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
TEACHBOT = str(Path(sys.executable).with_name("teachbot"))
STUDY = ROOT / "dialog/data/studies/example.toml"
URL = re.compile(r"Open the page: (http://\S+)")
COUNTS = ("tracebacks", "hangs", "silent_accepts", "bytes_lost")


class Hang(Exception):
    pass


@dataclass
class Totals:
    messages: int = 0
    sessions: int = 0
    tracebacks: int = 0
    hangs: int = 0
    silent_accepts: int = 0
    bytes_lost: int = 0
    refusals: int = 0
    answers: int = 0
    double_answers: int = 0
    reconnects: int = 0
    closed_oversized: int = 0
    bursts: int = 0
    screens: int = 0
    categories: dict = field(default_factory=dict)
    examples: list = field(default_factory=list)

    def example(self, what: str, **details) -> None:
        if len(self.examples) < 12:
            self.examples.append({"what": what, **details})


class Client:
    """One page's websocket: what the server sends is read into the session's state as it comes."""

    def __init__(self, url: str):
        base, token = url.split("?token=")
        self.request = tornado.httpclient.HTTPRequest(f"{base.replace('http://', 'ws://')}ws?token={token}",
                                                      headers={"Origin": base.rstrip("/")})
        self.socket = None
        self.refusals = 0
        self.question: dict | None = None
        self.screen: dict | None = None
        self.waiting = False
        self.ended = False
        self.closed = True
        self.teacher_lines = 0
        self.changed = asyncio.Event()

    async def open(self) -> None:
        self.socket = await tornado.websocket.websocket_connect(self.request, max_message_size=1 << 24)
        self.closed = False
        asyncio.ensure_future(self._read(self.socket))

    async def _read(self, socket) -> None:
        while True:
            text = await socket.read_message()
            if socket is not self.socket:
                return
            if text is None:
                self.closed = True
                self.changed.set()
                return
            message = json.loads(text)
            kind = message.get("type")
            if kind == "state":
                self.question, self.waiting, self.ended = message["question"], message["waiting"], message["ended"]
                self.screen = message["screen"]
            elif kind == "question":
                self.question, self.waiting, self.screen = message["question"], False, None
            elif kind == "waiting":
                self.waiting = self.question is not None and message["question"] == self.question["id"]
            elif kind == "screen":
                self.screen, self.question = message["screen"], None
            elif kind == "refused":
                self.refusals += 1
            elif kind == "ended":
                self.ended, self.question, self.screen = True, None, None
            elif kind == "line" and message.get("who") == "teacher":
                self.teacher_lines += 1
            self.changed.set()

    async def until(self, condition, timeout_s: float) -> bool:
        end = time.monotonic() + timeout_s
        while not condition():
            left = end - time.monotonic()
            if left <= 0:
                return False
            self.changed.clear()
            try:
                await asyncio.wait_for(self.changed.wait(), min(left, 0.5))
            except asyncio.TimeoutError:
                pass
        return True

    def send(self, raw: str | bytes) -> None:
        try:
            self.socket.write_message(raw, binary=isinstance(raw, bytes))
        except (tornado.websocket.WebSocketClosedError, AttributeError):
            raise Hang("the server closed the page's socket") from None

    def close(self) -> None:
        socket, self.socket, self.closed = self.socket, None, True
        if socket is not None:
            socket.close()


class Session:
    """One ``teachbot ... --web`` process and the recorded files it must not lose."""

    def __init__(self, args: list[str], cwd: Path, records: Path, timeout_s: float):
        self.cwd, self.records = cwd, records
        env = dict(os.environ, NO_COLOR="1", COLUMNS="200")
        self.err_path = cwd / "stderr.txt"
        self.out_path = cwd / "stdout.txt"
        self.process = subprocess.Popen([TEACHBOT, *args], cwd=cwd, env=env, stdin=subprocess.DEVNULL,
                                        stdout=open(self.out_path, "w"), stderr=open(self.err_path, "w"),
                                        start_new_session=True)
        self.seen: dict[Path, bytes] = {}
        end = time.monotonic() + timeout_s
        while time.monotonic() < end:
            found = URL.search(self.out_path.read_text(errors="replace"))
            if found:
                self.url = found.group(1)
                return
            if self.process.poll() is not None:
                break
            time.sleep(0.1)
        raise Hang(f"no page URL from {' '.join(args[:3])}: {self.err_path.read_text(errors='replace')[-300:]}")

    def lost_bytes(self) -> int:
        """Recorded bytes gone since the last look (a file must only grow), and remember what is there now."""
        lost = 0
        for path in sorted(self.records.rglob("*")) if self.records.is_dir() else []:
            if not path.is_file() or path.name.endswith(".lock"):
                continue
            now = path.read_bytes()
            before = self.seen.get(path, b"")
            if not now.startswith(before):
                common = os.path.commonprefix([before, now])
                lost += len(before) - len(common)
            self.seen[path] = now
        return lost

    def finish(self, timeout_s: float) -> bool:
        try:
            self.process.wait(timeout_s)
            return True
        except subprocess.TimeoutExpired:
            os.killpg(self.process.pid, signal.SIGKILL)
            self.process.wait(10)
            return False

    def tracebacks(self) -> list[str]:
        text = self.err_path.read_text(errors="replace") + self.out_path.read_text(errors="replace")
        return [text[max(0, m.start() - 100): m.start() + 600] for m in re.finditer("Traceback", text)]


class Fuzzer:
    def __init__(self, options, workdir: Path):
        self.options, self.workdir = options, workdir
        self.rng = np.random.default_rng(options.seed)
        self.hostile = Hostile(self.rng)
        self.totals = Totals()
        self.started = time.monotonic()

    def out_of_budget(self) -> bool:
        return (self.totals.messages >= self.options.messages
                or time.monotonic() - self.started > self.options.max_seconds)

    # -- one message and its refusal -------------------------------------------------------------------
    async def refused(self, client: Client, sends: list[tuple[str, str | bytes]], label: str) -> None:
        """Send hostile messages (a burst when more than one); each must get one refusal on ``client``."""
        before, lines, shown = client.refusals, client.teacher_lines, _open_id(client)
        for category, raw in sends:
            self.totals.messages += 1
            self.totals.categories[category] = self.totals.categories.get(category, 0) + 1
            client.send(raw)
        want = before + len(sends)
        if await client.until(lambda: client.refusals >= want or client.closed, self.options.timeout):
            if client.closed:
                raise Hang(f"{label}: the socket closed after {sends[-1][0]} messages")
            self.totals.refusals += len(sends)
            return
        if client.teacher_lines > lines or client.ended or _open_id(client) != shown:
            self.totals.silent_accepts += want - client.refusals
            self.totals.example("silent accept", session=label, category=sends[-1][0], raw=_shown(sends[-1][1]))
            return
        raise Hang(f"{label}: {want - client.refusals} of {len(sends)} messages without a refusal "
                   f"({sends[-1][0]}: {_shown(sends[-1][1])})")

    # -- one session -----------------------------------------------------------------------------------
    async def drive(self, session: Session, label: str) -> set:
        """Answer the session's questions and screens, with hostile messages first, until it ends."""
        options, rng = self.options, self.rng
        first, second = Client(session.url), Client(session.url)
        await first.open()
        await second.open()
        valid_lines: set[str] = set()
        while True:
            ready = await first.until(lambda: first.ended or first.closed or first.screen is not None
                                      or (first.question is not None and first.waiting), options.timeout * 4)
            if not ready:
                raise Hang(f"{label}: no question, screen or end within {options.timeout * 4:g} s")
            if first.ended or first.closed:
                break
            self.totals.bytes_lost += session.lost_bytes()
            screen, question = first.screen, first.question
            if self.out_of_budget() and screen is None:
                first.send(json.dumps({"type": "command", "question": question["id"], "command": "quit"}))
                await first.until(lambda: first.ended or first.closed, options.timeout * 4)
                break
            ident = (screen or question)["id"]
            await second.until(lambda ident=ident: (second.screen or second.question or {}).get("id") == ident,
                               options.timeout)
            for _ in range(int(rng.poisson(options.per_stop)) if not self.out_of_budget() else 0):
                if self.out_of_budget():
                    break
                client = first if rng.random() < 0.7 else second
                roll = rng.random()
                if roll < 0.04:  # a reload: the page reconnects and gets the same state
                    client.close()
                    await client.open()
                    self.totals.reconnects += 1
                    continue
                if roll < 0.05 and question is not None:  # over the websocket limit: the socket closes
                    self.totals.messages += 1
                    client.send(oversized(question["id"]))
                    if not await client.until(lambda client=client: client.closed, options.timeout):
                        raise Hang(f"{label}: a message over the websocket limit did not close the socket")
                    self.totals.closed_oversized += 1
                    await client.open()
                    continue
                count = int(rng.integers(5, 25)) if roll < 0.12 else 1
                self.totals.bursts += count > 1
                sends = [self.hostile.for_screen(screen) if screen is not None else self.hostile.for_question(question)
                         for _ in range(count)]
                await self.refused(client, sends, label)
            await self.answer(first, second, screen, question, valid_lines, label)
        for client in (first, second):
            client.close()
        return valid_lines

    async def answer(self, first: Client, second: Client, screen, question, valid_lines: set, label: str) -> None:
        """The valid answer, from one client, or from both at once (one taken, the other refused)."""
        rng = self.rng
        if screen is not None:
            message = {"type": "screen", "screen": screen["id"], "answers": [
                str(int(rng.integers(item["low"], item["high"] + 1))) if item["kind"] == "likert" else "fine"
                for item in screen.get("items", [])]}
            if screen.get("choices"):  # the consent: the first button (agree), so that the study goes on
                message["choice"] = screen["choices"][0]
            self.totals.screens += 1
        elif question["expects"] == "label":
            concept = question["concepts"][int(rng.integers(len(question["concepts"])))]
            message, line = {"type": "concept", "question": question["id"], "concept": concept}, concept
        elif question["expects"] == "demo":
            number = int(rng.integers(1, question["objects"] + 1))
            message, line = {"type": "object", "question": question["id"], "object": number}, f"number {number}"
        else:
            message, line = {"type": "command", "question": question["id"], "command": "skip"}, "skip"
        if screen is None:
            valid_lines.add(line)
            self.totals.answers += 1
        both = screen is None and rng.random() < 0.15
        refusals = first.refusals + second.refusals
        first.send(json.dumps(message))
        if both:
            self.totals.double_answers += 1
            second.send(json.dumps(message))
        ident = (screen or question)["id"]

        def moved_on() -> bool:
            now = first.screen or first.question or {}
            return first.ended or first.closed or (now.get("id", ident) != ident and (
                first.screen is not None or first.waiting))
        if not await first.until(moved_on, self.options.timeout * 4):
            raise Hang(f"{label}: the valid answer {message} was not taken")
        if both and not await second.until(lambda: first.refusals + second.refusals > refusals, self.options.timeout):
            self.totals.silent_accepts += 1
            self.totals.example("both answers taken", session=label, message=message)

    def check_transcripts(self, records: Path, valid_lines: set, label: str) -> None:
        """Every answer line on disk is a valid answer the fuzzer sent: no hostile message reached a transcript."""
        for path in records.rglob("*.jsonl"):
            for line in path.read_text(encoding="utf-8", errors="replace").splitlines():
                record = json.loads(line) if line.strip() else {}
                for said in (record.get("answer") or {}).get("lines", []):
                    if said not in valid_lines:
                        self.totals.silent_accepts += 1
                        self.totals.example("hostile line recorded", session=label, file=path.name, line=said[:60])

    def run_session(self, number: int) -> str:
        options = self.options
        folder = self.workdir / f"session-{number}"
        folder.mkdir()
        seed = int(self.rng.integers(10_000))
        if number == 1 and not options.no_study:
            label = f"study-{number}"
            args = ["study", "run", str(STUDY), "--participant", "P01", "--folder", "records", "--web",
                    "--no-viewer", "--no-3d"]
        else:
            label = f"teach-{number}"
            args = ["teach", "--web", "--no-3d", "--no-pictures", "--seed", str(seed), "--turns", str(options.turns),
                    "--transcript", "records/t.jsonl"]
        self.totals.sessions += 1
        session = None
        valid_lines: set = set()
        try:
            session = Session(args, folder, folder / "records", options.timeout * 4)
            valid_lines = asyncio.run(self.drive(session, label)) or set()
            if not session.finish(options.timeout * 2):
                raise Hang(f"{label}: the process did not exit after the session ended")
        except Hang as hang:
            self.totals.hangs += 1
            self.totals.example("hang", session=label, detail=str(hang)[:300])
            if session is not None:
                session.finish(0.1)
        if session is not None:
            self.totals.bytes_lost += session.lost_bytes()
            for trace in session.tracebacks():
                self.totals.tracebacks += 1
                self.totals.example("traceback", session=label, tail=trace[-400:])
            self.check_transcripts(folder / "records", valid_lines, label)
        if not options.keep:
            shutil.rmtree(folder, ignore_errors=True)
        return f"{label} seed {seed}"

    def run(self) -> dict:
        number = 0
        while not self.out_of_budget():
            number += 1
            self.report(self.run_session(number))
        t = self.totals
        summary = {key: getattr(t, key) for key in ("messages", "sessions", *COUNTS)}
        summary.update(refusals=t.refusals, answers=t.answers, screens=t.screens, double_answers=t.double_answers,
                       reconnects=t.reconnects, closed_oversized=t.closed_oversized, bursts=t.bursts,
                       categories=dict(sorted(t.categories.items())),
                       seconds=round(time.monotonic() - self.started, 1), examples=t.examples)
        return summary

    def report(self, text: str) -> None:
        t = self.totals
        print(f"{text} | messages {t.messages} refusals {t.refusals} tracebacks {t.tracebacks} hangs {t.hangs} "
              f"silent accepts {t.silent_accepts} bytes lost {t.bytes_lost}", file=sys.stderr, flush=True)


def _open_id(client: Client):
    return (client.screen or client.question or {}).get("id")


def _shown(raw) -> str:
    text = raw.decode("utf-8", "backslashreplace") if isinstance(raw, bytes) else raw
    text = text.encode("utf-8", "backslashreplace").decode("utf-8")
    return text if len(text) <= 80 else f"{text[:80]}... ({len(text)} characters)"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--messages", type=int, default=2000, help="hostile messages to send in all (default 2000)")
    parser.add_argument("--per-stop", type=float, default=30.0,
                        help="mean hostile messages at each question or screen (default 30)")
    parser.add_argument("--turns", type=int, default=8, help="turns of each teach session (default 8)")
    parser.add_argument("--no-study", action="store_true", help="teach sessions only (no study run first)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--timeout", type=float, default=20.0, help="seconds without the expected reply = a hang")
    parser.add_argument("--max-seconds", type=float, default=600.0, help="stop sending after this many seconds")
    parser.add_argument("--keep", action="store_true", help="keep each session's folder (printed)")
    parser.add_argument("--json", action="store_true", help="end with one JSON line of the counts")
    options = parser.parse_args(argv)
    folder = Path(tempfile.mkdtemp(prefix="fuzz-web-"))
    try:
        summary = Fuzzer(options, folder).run()
    finally:
        if options.keep:
            print(f"sessions kept in {folder}", file=sys.stderr)
        else:
            shutil.rmtree(folder, ignore_errors=True)
    if options.json:
        print(json.dumps(summary, ensure_ascii=True))
    else:
        print("\n".join(f"{key}: {value}" for key, value in summary.items() if key != "examples"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
