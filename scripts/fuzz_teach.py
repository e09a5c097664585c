"""Drive real ``teachbot teach`` sessions in pseudo-terminals with hostile input, Ctrl-C/D/Z and kill -9.

    python scripts/fuzz_teach.py --inputs 300 --kills 3 --json

Fuzz sessions answer every question with hostile lines (see ``_fuzz_corpus``)
before a valid answer, and now and then press Ctrl-C (expects "Interrupted",
exit 130), Ctrl-D (end of input: saved, exit 0) or Ctrl-Z; each exit is
followed by ``--resume``. Kill sessions follow a per-turn plan, are killed with
SIGKILL at a random moment, resumed, and compared with an uninterrupted run of
the same plan. The last stdout line (with --json) holds the counts:
tracebacks (any in the output), hangs (no expected output for --timeout
seconds), lost_turns (acknowledged turns missing from the transcript), guessed
(hostile lines taken as anything but a refusal), resumes_identical.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import signal
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _fuzz_corpus import CTRL_C, CTRL_D, CTRL_Z, Question, hostile_line, typed, valid_answer  # noqa: E402
from _fuzz_terminal import (  # noqa: E402
    RESPONSES,
    SESSION_END,
    TEACHBOT,
    Hang,
    Process,
    comparable,
    first_difference,
    process_state,
    read_records,
)

ANSWERED = {"answer", "absent", "skip", "dont_know"}


@dataclass
class Totals:
    inputs: int = 0
    sessions: int = 0
    tracebacks: int = 0
    hangs: int = 0
    lost_turns: int = 0
    guessed: int = 0
    kills: int = 0
    resumes_identical: int = 0
    resumes: int = 0
    asked_back: int = 0
    valid_refused: int = 0
    controls: dict = field(default_factory=lambda: {"ctrl_c": 0, "ctrl_c_exit_130": 0, "ctrl_d": 0,
                                                    "ctrl_d_saved": 0, "ctrl_z": 0, "ctrl_z_stopped": 0,
                                                    "sigstop": 0})
    examples: list = field(default_factory=list)

    def example(self, kind: str, **details) -> None:
        if len(self.examples) < 12:
            self.examples.append({"what": kind, **details})


class Driver:
    """Runs sessions and keeps the totals."""

    def __init__(self, options, workdir: Path):
        self.options, self.workdir = options, workdir
        self.totals = Totals()
        self.rng = np.random.default_rng(options.seed)

    # -- one process -----------------------------------------------------------------------
    def spawn(self, args: list[str]) -> Process:
        self.current = Process(args, self.options.timeout, self.options.teachbot)
        return self.current

    def check_process(self, process: Process, path: Path, killed: bool, label: str) -> None:
        """After a process ended: tracebacks in its output, acknowledged turns missing on disk."""
        trace = process.tracebacks()
        if trace:
            self.totals.tracebacks += 1
            self.totals.example("traceback", session=label, tail=trace[-300:])
        expected = process.acked[:process.confirmed] if killed else process.acked
        on_disk = {record["turn"] for record in read_records(path)}
        lost = sorted(set(expected) - on_disk)
        if lost:
            self.totals.lost_turns += len(lost)
            self.totals.example("lost turns", session=label, turns=lost)

    def send_hostile(self, process: Process, question: Question, line: bytes, category: str,
                     label: str, valid: dict) -> bool:
        """Type one hostile line; False when it ended the question (a guess)."""
        self.totals.inputs += 1
        process.write(typed(line))
        response = process.respond()
        if response == "askback":
            self.totals.asked_back += 1
            process.write(b"no\n")
            response = process.respond()
        if response == "prompt":
            return True
        shown = line[:60].decode("utf-8", errors="backslashreplace")
        if response == "eof":  # the process died: its traceback is counted when it is checked
            return False
        if response in ("ack", "undo"):
            said = process.child.match.group(0).strip()
            self.totals.guessed += 1
            self.totals.example("guessed", session=label, question=question.kind, line=shown, category=category,
                                reply=said)
            if response == "undo":
                process.expect([RESPONSES["prompt"]])
                return True
            process.acked.append(question.turn)
            valid.setdefault(question.turn, set()).add(("hostile", line))
            return False
        self.totals.guessed += 1  # the line ended the session
        self.totals.example("guessed", session=label, question=question.kind, line=shown, category=category,
                            reply=response)
        return False

    def send_valid(self, process: Process, question: Question, answer: str, label: str, valid: dict) -> None:
        valid.setdefault(question.turn, set()).add(answer)
        process.write(answer.encode() + b"\n")
        response = process.respond()
        if response == "ack":
            process.acked.append(question.turn)
        elif response in ("prompt", "askback"):
            self.totals.valid_refused += 1
            self.totals.example("valid answer refused", session=label, question=question.kind, line=answer)
            process.write(b"skip\n")
            process.respond()

    def guessed_on_disk(self, path: Path, valid: dict, label: str) -> None:
        """Turns recorded as answered whose last line was not the valid answer typed (missed live)."""
        for record in read_records(path):
            answer = record.get("answer") or {}
            typed_lines = valid.get(record["turn"], set())
            if answer.get("kind") in ANSWERED and typed_lines and answer.get("raw") not in typed_lines \
                    and not any(isinstance(t, tuple) for t in typed_lines):
                self.totals.guessed += 1
                self.totals.example("guessed (transcript)", session=label, turn=record["turn"],
                                    raw=str(answer.get("raw"))[:60], kind=answer.get("kind"))

    # -- sessions --------------------------------------------------------------------------
    def fuzz_session(self, number: int) -> str:
        """Hostile lines at every question, one Ctrl-C or Ctrl-D exit and resume, Ctrl-Z now and then."""
        options, totals, rng = self.options, self.totals, self.rng
        seed, strategy = int(rng.integers(10_000)), str(rng.choice(options.strategies))
        label = f"fuzz-{number}"
        path = self.workdir / f"{label}.jsonl"
        exit_at = int(rng.integers(1, options.turns)) if rng.random() < options.exit_chance else -1
        exit_key = CTRL_C if rng.random() < 0.5 else CTRL_D
        process = self.spawn(self.new_args(seed, strategy, path))
        valid: dict = {}
        asked = 0
        try:
            while (question := process.next_question()) is not None:
                asked += 1
                if asked == exit_at and totals.inputs < options.inputs:
                    process = self.exit_and_resume(process, exit_key, path, label)
                    continue
                still_open = True
                for _ in range(int(rng.integers(0, 2 * options.per_turn + 1))):
                    if totals.inputs >= options.inputs:
                        break
                    if rng.random() < options.ctrl_z:
                        self.ctrl_z(process)
                        continue
                    category, line = hostile_line(question, rng)
                    still_open = self.send_hostile(process, question, line, category, label, valid)
                    if not still_open:
                        break
                if still_open:
                    self.send_valid(process, question, valid_answer(question, rng), label, valid)
            process.finish()
            self.check_process(process, path, killed=False, label=label)
        except Hang:
            self.hang(label)
        self.guessed_on_disk(path, valid, label)
        return f"{label} seed {seed} {strategy}: {len(read_records(path))} turns on disk"

    def exit_and_resume(self, process: Process, key: bytes, path: Path, label: str) -> Process:
        """Press Ctrl-C or Ctrl-D at a question, check the exit, resume the session."""
        self.totals.inputs += 1
        name = "ctrl_c" if key == CTRL_C else "ctrl_d"
        self.totals.controls[name] += 1
        process.write(key)
        said = process.expect([re.compile(r"Interrupted\.") if key == CTRL_C else SESSION_END])
        status = process.finish()
        if key == CTRL_C and said == 0 and status == 130:
            self.totals.controls["ctrl_c_exit_130"] += 1
        elif key == CTRL_D and said == 0 and status == 0:
            self.totals.controls["ctrl_d_saved"] += 1
        else:
            self.totals.example(f"{name} exit", session=label, status=status, said=said == 0)
        self.check_process(process, path, killed=False, label=label)
        return self.resume(path)

    def resume(self, path: Path) -> Process:
        self.totals.resumes += 1
        return self.spawn(["--resume", str(path), "--no-pictures"])

    def ctrl_z(self, process: Process) -> None:
        """Ctrl-Z at a question, then SIGCONT if it stopped; else SIGSTOP and SIGCONT (a shell's stop and fg).

        A session leader in its own pseudo-terminal is an orphaned process group, for which the kernel
        discards the terminal's stop signal; SIGSTOP still stops it. Either way the question stays open.
        """
        self.totals.inputs += 1
        self.totals.controls["ctrl_z"] += 1
        process.write(CTRL_Z)
        time.sleep(0.1)
        if process_state(process.child.pid) == "T":
            self.totals.controls["ctrl_z_stopped"] += 1
        else:
            os.kill(process.child.pid, signal.SIGSTOP)
            time.sleep(0.1)
            self.totals.controls["sigstop"] += process_state(process.child.pid) == "T"
        os.kill(process.child.pid, signal.SIGCONT)

    def hang(self, label: str) -> None:
        self.totals.hangs += 1
        self.totals.example("hang", session=label, tail=self.current.log.getvalue()[-300:])
        self.current.kill()

    def new_args(self, seed: int, strategy: str, path: Path) -> list[str]:
        options = self.options
        return ["--seed", str(seed), "--strategy", strategy, "--turns", str(options.turns), "--budget",
                str(options.budget), "--transcript", str(path), "--no-pictures"]

    def planned_session(self, label: str, seed: int, strategy: str, plan_seed: int,
                        kill_at: tuple[int, int, float] | None) -> tuple[Path, bool]:
        """A session whose lines depend only on (plan_seed, turn); killed once at ``kill_at`` if given.

        kill_at = (question number, lines typed before the kill, seconds to wait after typing them).
        Returns the transcript and whether the session ran to its end.
        """
        path = self.workdir / f"{label}.jsonl"
        process = self.spawn(self.new_args(seed, strategy, path))
        valid: dict = {}
        asked, killed = 0, False
        try:
            while (question := process.next_question()) is not None:
                asked += 1
                plan = np.random.default_rng([plan_seed, question.turn])
                lines = [hostile_line(question, plan) for _ in range(int(plan.integers(0, 3)))]
                answer = valid_answer(question, plan)
                kill_here = kill_at is not None and not killed and asked == kill_at[0]
                kill_position = min(kill_at[1], len(lines)) if kill_here and kill_at[1] >= 0 else None
                for position in range(len(lines) + 1):
                    if position == kill_position:
                        time.sleep(kill_at[2])
                        killed = self.kill_and_resume(path, label)
                        break
                    if position < len(lines):
                        if not self.send_hostile(process, question, lines[position][1], lines[position][0], label,
                                                 valid):
                            break
                    elif kill_here:  # typed the answer; kill while it is being learned and written
                        valid.setdefault(question.turn, set()).add(answer)
                        process.write(answer.encode() + b"\n")
                        time.sleep(kill_at[2])
                        killed = self.kill_and_resume(path, label)
                    else:
                        self.send_valid(process, question, answer, label, valid)
                process = self.current
            process.finish()
            self.check_process(process, path, killed=False, label=label)
        except Hang:
            self.hang(label)
            return path, False
        self.guessed_on_disk(path, valid, label)
        return path, True

    def kill_and_resume(self, path: Path, label: str) -> bool:
        """SIGKILL the current process, check what it left on disk, resume the session."""
        self.totals.kills += 1
        killed = self.current
        killed.kill()
        self.check_process(killed, path, killed=True, label=label)
        self.resume(path)
        return True

    def kill_session(self, number: int) -> str:
        """Kill -9 a planned session at a random moment, resume it, compare with an uninterrupted one."""
        rng = self.rng
        seed, strategy = int(rng.integers(10_000)), str(rng.choice(self.options.strategies))
        plan_seed = int(rng.integers(2**31))
        # at a question, after some of its lines; or (-1) just after its answer was typed, while it is learned
        position = -1 if rng.random() < 0.5 else int(rng.integers(0, 3))
        kill_at = (int(rng.integers(2, 7)), position, float(rng.uniform(0.0, 0.3)))
        reference, done = self.planned_session(f"kill-{number}-reference", seed, strategy, plan_seed, None)
        resumed, resumed_done = self.planned_session(f"kill-{number}", seed, strategy, plan_seed, kill_at)
        self.totals.sessions += 1
        same = done and resumed_done and comparable(read_records(reference)) == comparable(read_records(resumed))
        if same:
            self.totals.resumes_identical += 1
        else:
            self.totals.example("resume differs", session=f"kill-{number}",
                                difference=first_difference(read_records(reference), read_records(resumed)))
        return f"kill-{number} seed {seed} {strategy}: killed at question {kill_at[0]}, resumed identical: {same}"

    def run(self) -> dict:
        started = time.perf_counter()
        for number in range(self.options.kills):
            self.report(self.kill_session(number + 1))
        number = 0
        while self.totals.inputs < self.options.inputs:
            number += 1
            self.totals.sessions += 1
            self.report(self.fuzz_session(number))
        summary = {key: getattr(self.totals, key) for key in ("inputs", "sessions", "tracebacks", "hangs",
                                                              "lost_turns", "guessed", "kills",
                                                              "resumes_identical")}
        summary.update(resumes=self.totals.resumes, asked_back=self.totals.asked_back,
                       valid_refused=self.totals.valid_refused, controls=self.totals.controls,
                       seconds=round(time.perf_counter() - started, 1), examples=self.totals.examples)
        return summary

    def report(self, text: str) -> None:
        t = self.totals
        print(f"{text} | inputs {t.inputs} tracebacks {t.tracebacks} hangs {t.hangs} lost {t.lost_turns} "
              f"guessed {t.guessed} resumes identical {t.resumes_identical}/{t.kills}", file=sys.stderr, flush=True)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--inputs", type=int, default=300, help="hostile inputs to send in all (default 300)")
    parser.add_argument("--kills", type=int, default=3, help="sessions killed with SIGKILL and resumed (default 3)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--turns", type=int, default=12)
    parser.add_argument("--budget", type=float, default=20)
    parser.add_argument("--per-turn", type=float, default=3.0, help="mean hostile lines per question (default 3)")
    parser.add_argument("--ctrl-z", type=float, default=0.02, help="chance of Ctrl-Z instead of a hostile line")
    parser.add_argument("--exit-chance", type=float, default=0.5,
                        help="chance that a fuzz session is left with Ctrl-C or Ctrl-D and resumed (default 0.5)")
    parser.add_argument("--strategies", nargs="+", default=["dt-task", "all-cd", "active"])
    parser.add_argument("--timeout", type=float, default=45.0, help="seconds without expected output = a hang")
    parser.add_argument("--teachbot", default=TEACHBOT, help="the teachbot executable (default: beside python)")
    parser.add_argument("--keep", type=Path, default=None, help="keep the transcripts in this folder")
    parser.add_argument("--json", action="store_true", help="end with one JSON line of the counts")
    options = parser.parse_args(argv)
    if options.keep is not None:
        options.keep.mkdir(parents=True, exist_ok=True)
        summary = Driver(options, options.keep).run()
    else:
        with tempfile.TemporaryDirectory(prefix="fuzz-teach-") as folder:
            summary = Driver(options, Path(folder)).run()
    if options.json:
        print(json.dumps(summary, ensure_ascii=True))
    else:
        print("\n".join(f"{key}: {value}" for key, value in summary.items() if key != "examples"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
