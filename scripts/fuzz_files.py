"""Mutate every kind of file teachbot reads, and every path option, then run the command that reads each.

    python scripts/fuzz_files.py --cases 300 --json

Kinds: the study file, a suite, DT weights, a questioner policy (its TOML and its NPZ), a kitchen and a task file,
the kitchen generator's data file and a kitchen it generated,
a teach transcript (resumed, and given to a replay teacher with --replay, also as a link to /dev/zero or a
FIFO), a study session's transcript (torn or answer-less beside its questionnaire, headers edited), its
questionnaire answers (lone surrogates in text) and an abort note, IRL demonstrations, and hostile output
paths (FIFOs, devices, folders, names and paths too long, a loop of links, ``newdir/``, /proc). Each case
copies good files made once at the start (a simulated study participant, a scripted teach session, ...), applies
one mutation (``_fuzz_files_kinds``), and runs the reading command as a subprocess with a timeout. Counted:
tracebacks, hangs (the timeout), silent accepts (a mutation that breaks a stated rule taken without a refusal;
for study records, ``study status`` must mark the session damaged) and recorded bytes lost (the complete lines
of every recorded file must still be there afterwards, or in a ``*.superseded-N`` copy). The same --seed gives
the same cases. The last line (with --json) is one JSON object.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from collections import defaultdict
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _fuzz_files_kinds as kinds  # noqa: E402

ROOT = kinds.ROOT
TEACHBOT = str(Path(sys.executable).with_name("teachbot"))
COUNTS = ("tracebacks", "hangs", "silent_accepts", "bytes_lost")


@dataclass
class Kind:
    name: str
    folder: str  # the good files, copied for each case
    target: str  # the file mutated
    commands: list  # each a list of arguments, run in the case's folder; the first decides refused or not
    rules: list  # (description, apply): mutations that break a stated rule
    recorded: str = ""  # a glob of recorded files whose bytes must survive
    damaged: str = ""  # for study records: the status line that must name the damaged session
    byte_rules: bool = False  # every byte change breaks a rule (an NPZ's SHA-256 is recorded)
    or_refused: bool = False  # with ``damaged``: a one-line refusal (exit 2) counts too (a study file's own text)


def _study(*args):
    return ["study", args[0], "study.toml", "--folder", "d", *args[1:]]


def toml_rules(*skip: str, names: bool = False) -> list:
    """A field set to a value of another type, an unknown field, and (``names``) a name that is a path."""
    rules = [("a field of another type", kinds.wrong_type(skip=skip)), ("an unknown field", kinds.unknown_field)]
    if names:
        rules += [(f"name {shown}", kinds.set_toml(("name",), value)) for shown, value in
                  (("a path", "../../../../x"), ("absolute", "/tmp/teachbot-fuzz-x"), ("with a newline", "x\n"))]
    return rules


def make_kinds(conditions) -> list[Kind]:
    first, second = (f"d/P01/1-{conditions[0]}", f"d/P02/1-{conditions[1]}")
    status = _study("status")
    run1, run2 = (_study("run", "--participant", who, "--simulated") for who in ("P01", "P02"))
    demo = ["demo", "--turns", "2", "--transcript", "t.jsonl"]
    regress = ["regress", "--suite", "tiny.toml", "--results", "r", "--no-progress"]
    learn = ["learn-weights", "--demos", "d.json", "--method", "per-turn", "--allow-degenerate", "--out", "w.toml"]
    ids = [("ids with a newline", kinds.set_toml(("ids",), ["P01\n", "P02"]))]
    return [
        Kind("study", "study", "study.toml", [status], toml_rules(names=True) + ids),
        Kind("suite", "suite", "tiny.toml", [regress], toml_rules(names=True)),
        Kind("weights", "weights", "w.toml", [[*demo, "--weights", "w.toml"]], toml_rules("provenance")),
        Kind("policy", "policy", "q.toml", [[*demo, "--strategy", "rl:q.toml"]], kinds.POLICY_RULES),
        Kind("policy-npz", "policy", "q.npz", [[*demo, "--strategy", "rl:q.toml"]], [], byte_rules=True),
        Kind("kitchen", "world", "kitchen.toml", [["world", "show", "--kitchen", "kitchen.toml"]], toml_rules()),
        Kind("task", "world", "task.toml", [["world", "show", "--task", "task.toml"]], toml_rules()),
        # issue 52: the kitchen generator's data file, and a kitchen it wrote
        Kind("generator", "generator", "kitchens.toml",
             [["world", "generate", "--seed", "7", "--out", "out", "--distributions", "kitchens.toml"]], toml_rules()),
        Kind("generated-kitchen", "generated", "generated-7.toml",
             [["world", "show", "--kitchen", "generated-7.toml"]], toml_rules()),
        Kind("transcript", "teach", "t.jsonl", [["teach", "--resume", "t.jsonl", "--no-pictures"]],
             kinds.TRANSCRIPT_RULES, recorded="t.jsonl*"),
        Kind("replay", "teach", "t.jsonl", [["teach", "--teacher", "replay", "--replay", "t.jsonl", "--turns", "4",
                                             "--no-pictures", "--transcript", "replayed.jsonl"]], kinds.REPLAY_RULES),
        Kind("study-transcript", "study", f"{first}.jsonl", [status, run1], kinds.STUDY_TRANSCRIPT_RULES,
             recorded="d/**/*", damaged=f"damaged: P01 session 1 ({conditions[0]})"),
        Kind("questionnaire", "study", f"{first}-questionnaire.jsonl", [status, run1], kinds.QUESTIONNAIRE_RULES,
             recorded="d/**/*", damaged=f"damaged: P01 session 1 ({conditions[0]})"),
        Kind("study-note", "study", f"{second}-aborted.json", [status, run2], kinds.NOTE_RULES, recorded="d/**/*",
             damaged=f"damaged: P02 session 1 ({conditions[1]})"),
        Kind("consent-record", "study", "d/P01/consent.json", [status, run1], kinds.CONSENT_RULES,
             recorded="d/**/*", damaged=f"damaged: P01 session 1 ({conditions[0]})"),
        Kind("practice-transcript", "study", "d/P01/0-practice.jsonl", [status, run1], kinds.PRACTICE_RULES,
             recorded="d/**/*", damaged="damaged: P01 practice round"),
        # the consent text P01 agreed to, changed since: P01's record no longer matches it (or the study is refused)
        Kind("consent-text", "study", "example-consent.txt", [status, run1], [], recorded="d/**/*",
             damaged=f"damaged: P01 session 1 ({conditions[0]})", byte_rules=True, or_refused=True),
        Kind("demonstrations", "demos", "d.json", [learn], kinds.DEMO_RULES),
    ]


# -- output paths: every one of these must be refused in one line ------------------------------------------------
PATH_COMMANDS = {
    "demo --transcript": lambda p: ["demo", "--turns", "1", "--transcript", p],
    "teach --transcript": lambda p: ["teach", "--teacher", "scripted", "--turns", "1", "--no-pictures",
                                     "--transcript", p],
    "view --export": lambda p: ["view", "--export", p, "--seconds", "0"],
    "world show --png": lambda p: ["world", "show", "--png", p],
    "learn-weights --out": lambda p: ["learn-weights", "--demos", "shipped", "--method", "per-turn",
                                      "--allow-degenerate", "--out", p],
}
SUFFIXES = {"demo --transcript": ".jsonl", "teach --transcript": ".jsonl", "view --export": ".html",
            "world show --png": ".png", "learn-weights --out": ".toml"}


def hostile_path(kind: str, folder: Path, suffix: str) -> str:
    if kind == "fifo":
        os.mkfifo(folder / f"fifo{suffix}")
        return f"fifo{suffix}"
    if kind == "file as parent":
        (folder / "plain").write_text("x")
        return f"plain/x{suffix}"
    if kind in ("/dev/null", "/dev/full"):
        # a link to the device, never the device's own path: a teachbot that wrote its output beside the target
        # and renamed it into place would replace the link, not the system's /dev/full (as root it could)
        os.symlink(kind, folder / f"device{suffix}")
        return f"device{suffix}"
    if kind == "symlink loop":
        os.symlink("loop-b", folder / "loop-a")
        os.symlink("loop-a", folder / "loop-b")
        return f"loop-a/x{suffix}"
    return {"a folder": ".", "300-character name":
            "n" * 300 + suffix, "path over 4096": "/".join(["p" * 200] * 22) + f"/x{suffix}", "newdir/": "newdir/",
            "/proc": f"/proc/teachbot-fuzz{suffix}"}[kind]


FOLDER_ACCEPTED = ("view --export",)  # outputs that take an existing folder and write their file inside it
PATH_KINDS = ("fifo", "/dev/null", "/dev/full", "a folder", "300-character name", "path over 4096", "symlink loop",
              "newdir/", "/proc", "file as parent")


# -- running and judging ------------------------------------------------------------------------------------------
@dataclass
class Case:
    index: int
    kind: str
    mutation: str
    breaks_rule: bool
    results: list = field(default_factory=list)  # (args, returncode or None for a hang, output)
    lost: int = 0
    traceback: bool = False
    hang: bool = False
    silent: bool = False


def run_command(args: list[str], cwd: Path, timeout: float) -> tuple[int | None, str]:
    process = subprocess.Popen([TEACHBOT, *args], cwd=cwd, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                               stderr=subprocess.STDOUT, start_new_session=True)
    try:
        out, _ = process.communicate(timeout=timeout)
        return process.returncode, out.decode("utf-8", "replace")
    except subprocess.TimeoutExpired:
        os.killpg(process.pid, signal.SIGKILL)
        out, _ = process.communicate()
        return None, out.decode("utf-8", "replace")


def snapshot(folder: Path, pattern: str) -> dict:
    return {p.relative_to(folder): p.read_bytes() for p in folder.glob(pattern) if p.is_file()} if pattern else {}


def bytes_lost(folder: Path, before: dict) -> int:
    """Bytes of complete lines recorded before that are neither still at the start of their file nor kept whole
    in a ``*.superseded-N`` copy (or anywhere else under the same folder)."""
    kept = {hashlib.sha256(p.read_bytes()).digest() for p in folder.rglob("*") if p.is_file()}
    lost = 0
    for relative, old in before.items():
        complete = old[:old.rfind(b"\n") + 1]
        path = folder / relative
        now = path.read_bytes() if path.is_file() else b""
        if now.startswith(complete) or hashlib.sha256(old).digest() in kept:
            continue
        same = next((i for i, (a, b) in enumerate(zip(complete, now)) if a != b), min(len(complete), len(now)))
        lost += len(complete) - same
    return lost


def refused(case: Case, kind: Kind | None) -> bool:
    code, output = case.results[0][1], case.results[0][2]
    if kind is not None and kind.damaged:
        return any(line.startswith(kind.damaged) for line in output.splitlines()) or (kind.or_refused and code == 2)
    return code == 2


class Fuzzer:
    def __init__(self, options, workdir: Path):
        self.options, self.workdir = options, workdir
        self.base = workdir / "base"

    def setup(self) -> list[Kind]:
        """The good files every case starts from, made by teachbot itself."""
        base = self.base
        for name in ("study", "suite", "weights", "policy", "world", "teach", "demos", "generator", "generated"):
            (base / name).mkdir(parents=True)
        text = (ROOT / "dialog/data/studies/example.toml").read_text(encoding="utf-8")
        text = re.sub(r"^turns = \d+", "turns = 3", text, flags=re.M).replace("participants = 6 ", "participants = 2 ")
        (base / "study/study.toml").write_text(text, encoding="utf-8")
        shutil.copy(ROOT / "dialog/data/studies/example-consent.txt", base / "study")
        conditions = re.findall(r'^\[\[conditions\]\]\nname = "([^"]+)"', text, flags=re.M)
        self._must(_study("run", "--participant", "P01", "--simulated"), base / "study")
        self._must(_study("run", "--participant", "P02", "--abort", "fuzz: a note to damage"), base / "study")
        shutil.copy(ROOT / "scripts/fuzz_files_suite.toml", base / "suite/tiny.toml")
        shutil.copy(ROOT / "learning/decision/presets/dt-task.toml", base / "weights/w.toml")
        policy = ROOT / "learning/rl/policies/questioner-ch7-training.toml"
        (base / "policy/q.toml").write_text(policy.read_text().replace(
            'weights = "questioner-ch7-training.npz"', 'weights = "q.npz"'), encoding="utf-8")
        shutil.copy(policy.with_suffix(".npz"), base / "policy/q.npz")
        shutil.copy(ROOT / "bullet_world/data/kitchens/kitchen-1.toml", base / "world/kitchen.toml")
        shutil.copy(ROOT / "bullet_world/data/tasks/pack-lunchbox.toml", base / "world/task.toml")
        shutil.copy(ROOT / "bullet_world/data/generator/kitchens.toml", base / "generator/kitchens.toml")
        self._must(["world", "generate", "--seed", "7", "--out", "."], base / "generated")
        self._must(["teach", "--teacher", "scripted", "--turns", "4", "--no-pictures", "--transcript", "t.jsonl"],
                   base / "teach")
        shutil.copy(sorted((ROOT / "learning/irl/expert-demos").glob("*.json"))[0], base / "demos/d.json")
        return make_kinds(conditions)

    def _must(self, args, cwd) -> None:
        code, output = run_command(args, cwd, self.options.timeout * 3)
        if code != 0:
            raise SystemExit(f"fuzz_files: setting up with teachbot {' '.join(args)} failed ({code}):\n{output}")

    def plan(self, kind_list: list[Kind]) -> list[tuple]:
        """Every case, drawn from --seed before any runs: (index, kind name or "paths", its own generator)."""
        rng = np.random.default_rng(self.options.seed)
        names = [k.name for k in kind_list] + ["paths"]
        cases = []
        for index in range(self.options.cases):
            name = names[index % len(names)]  # every kind equally often, in turn
            case_rng = np.random.default_rng(rng.integers(1 << 63))
            cases.append((index, name, case_rng))
        return cases

    def prepare(self, spec, by_name: dict, folder: Path) -> Case:
        """Copy the kind's good files to ``folder`` and apply the case's mutation (the same for the same spec)."""
        index, name, rng = spec
        kind = by_name[name]
        shutil.copytree(self.base / kind.folder, folder, symlinks=True)
        target = folder / kind.target
        structured = bool(kind.rules) and rng.random() < 0.6
        if structured:
            description, apply = kind.rules[int(rng.integers(len(kind.rules)))]
        else:
            description, apply = kinds.BYTE_MUTATIONS[int(rng.integers(len(kinds.BYTE_MUTATIONS)))]
        original = target.read_bytes()
        apply(target, rng)
        breaks = structured or (kind.byte_rules and target.read_bytes() != original)
        return Case(index, name, description, breaks)

    def run_case(self, spec, by_name: dict) -> Case:
        index, name, rng = spec
        folder = self.workdir / f"case-{index:05d}"
        if name == "paths":
            return self._path_case(index, folder, rng)
        kind = by_name[name]
        case = self.prepare(spec, by_name, folder)
        before = snapshot(folder, kind.recorded)
        for args in kind.commands:
            code, output = run_command(args, folder, self.options.timeout)
            case.results.append((args, code, output))
            if code is None:
                break
        case.lost = bytes_lost(folder, before) if before else 0
        self._judge(case, kind)
        shutil.rmtree(folder, ignore_errors=True)
        return case

    def _path_case(self, index: int, folder: Path, rng) -> Case:
        folder.mkdir()
        option = sorted(PATH_COMMANDS)[int(rng.integers(len(PATH_COMMANDS)))]
        what = PATH_KINDS[int(rng.integers(len(PATH_KINDS)))]
        path = hostile_path(what, folder, SUFFIXES[option])
        # documented (docs/dialog.md): `view --export DIR` writes its page inside an existing folder
        documented = what == "a folder" and option in FOLDER_ACCEPTED
        case = Case(index, "paths", f"{option} {what}", not documented)
        code, output = run_command(PATH_COMMANDS[option](path), folder, self.options.timeout)
        case.results.append((PATH_COMMANDS[option](path)[:2], code, output))
        if what == "newdir/" and (folder / "newdir").is_file():
            case.results[0] = (case.results[0][0], 0, output)  # a file named newdir was written: accepted
        self._judge(case, None)
        shutil.rmtree(folder, ignore_errors=True)
        return case

    def _judge(self, case: Case, kind: Kind | None) -> None:
        case.traceback = any("Traceback (most recent call last)" in out for _, _, out in case.results)
        case.hang = any(code is None for _, code, _ in case.results)
        case.silent = case.breaks_rule and not case.hang and not case.traceback and not refused(case, kind)


def summarise(cases: list[Case], seconds: float) -> dict:
    per_kind: dict = defaultdict(lambda: {"cases": 0, **{name: 0 for name in COUNTS}})
    examples = []
    for case in cases:
        entry = per_kind[case.kind]
        entry["cases"] += 1
        found = {"tracebacks": int(case.traceback), "hangs": int(case.hang), "silent_accepts": int(case.silent),
                 "bytes_lost": case.lost}
        for name, value in found.items():
            entry[name] += value
        if any(found.values()) and len(examples) < 12:
            last = case.results[-1][2].strip().splitlines()[-1:] if case.results else []
            examples.append({"case": case.index, "kind": case.kind, "mutation": case.mutation,
                             "found": [n for n, v in found.items() if v], "command": case.results[-1][0],
                             "exit": case.results[-1][1], "last_line": (last[0] if last else "")[:300]})
    totals = {name: sum(entry[name] for entry in per_kind.values()) for name in COUNTS}
    return {"cases": len(cases), "commands": sum(len(c.results) for c in cases),
            "rule_breaking_cases": sum(c.breaks_rule for c in cases), **totals,
            "per_kind": {k: per_kind[k] for k in sorted(per_kind)}, "seconds": round(seconds, 1),
            "examples": examples}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cases", type=int, default=300, help="mutated files and paths to try (default 300)")
    parser.add_argument("--seed", type=int, default=0, help="the same seed gives the same cases (default 0)")
    parser.add_argument("--workers", type=int, default=2, help="cases run at once (default 2)")
    parser.add_argument("--timeout", type=float, default=60.0, help="seconds a command may take before it is a hang")
    parser.add_argument("--kinds", nargs="+", default=None, metavar="KIND",
                        help="run only the cases of these kinds (the same cases a full run of --cases has)")
    parser.add_argument("--json", action="store_true", help="end with one JSON line of the counts")
    options = parser.parse_args(argv)
    started = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="fuzz-files-") as folder:
        fuzzer = Fuzzer(options, Path(folder))
        kind_list = fuzzer.setup()
        by_name = {kind.name: kind for kind in kind_list}
        with ThreadPoolExecutor(max_workers=max(1, options.workers)) as pool:
            plan = [spec for spec in fuzzer.plan(kind_list) if options.kinds is None or spec[1] in options.kinds]
            cases = list(pool.map(lambda spec: fuzzer.run_case(spec, by_name), plan))
    summary = summarise(sorted(cases, key=lambda c: c.index), time.perf_counter() - started)
    if options.json:
        print(json.dumps(summary, ensure_ascii=True))
    else:
        print("\n".join(f"{key}: {value}" for key, value in summary.items() if key != "examples"))
        for example in summary["examples"]:
            print(f"  {example}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
