"""Benchmark: answering in the browser page against answering at the terminal, the same session in the same run.

    python scripts/bench_web.py                   # 20 turns of dt-task, seed 0
    python scripts/bench_web.py --turns 30 --json # JSON last line
    python scripts/bench_web.py --no-3d           # the page without its 3D view
    python scripts/bench_web.py --click-at-once   # click before the 3D view has drawn the question

A real ``teachbot teach --web`` session is answered in headless Chromium by
clicks (a concept button, an object's number button, the feature checkboxes);
for every answer the time from the click to the next question being shown and
waiting in the page is measured (shown: its words and buttons painted), and, of
it, the time until the question's message reached the browser; with the 3D
view, also the time until the view has drawn it. The next click comes once the
view has drawn the question, as a participant reads before answering
(``--click-at-once``: as soon as it is shown, so that the click waits behind
the view's frame). The page's load time runs from opening the URL to the
first question ready to answer and, with the 3D view, drawn in it.
Then the same answers are typed into ``teachbot teach`` at a pseudo-terminal,
and the time from Enter to the next prompt is measured the same way. Both include the robot's own
work between the questions (the strategy's decision, the arm's pointing);
the difference is what the page costs. Goal: page p95 under 300 ms beside a DT
decision, i.e. the page adds less than 300 ms to the terminal's p95.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

from bullet_world.viewer.snapshot import CHROMIUM_FLAGS, find_chromium
from dialog.transcripts.jsonl import read_session

TEACHBOT = str(Path(sys.executable).with_name("teachbot"))
GOAL_MS = 300.0
QUESTION = re.compile(r"(Which features tell|Can you show me|What is the)")
# The page is ready: its first question waits for the answer and, with the 3D view, the view has drawn it with
# the arm's meshes and every object in it (and nothing newer waits to be drawn).
READY = """() => {
    const drawn = (name) => { const node = viewer.scene.getObjectByName(name); let mesh = false;
                              if (node) { node.traverse((o) => { mesh = mesh || Boolean(o.isMesh); }); } return mesh; };
    return Boolean(question && waiting && (!viewer || (drawn3d === question.id && !viewer.needs_render
        && Object.keys(objectNodes).length > 0 && [...Object.keys(objectNodes), "robot"].every(drawn))));
}"""
# The next question (not the one answered, ``id``) is on the screen: it waits for its answer and its words and
# buttons have been painted (app.js's ``painted``), or the session ended.
SHOWN = "(id) => ended || (question && waiting && question.id !== id && painted === question.id)"
# ... and the 3D view has drawn it too (nothing waits to be drawn).
DRAWN = "() => ended || !viewer || (drawn3d === question.id && !viewer.needs_render)"


def processes(roots: list[int]) -> dict[int, str]:
    """Every process under ``roots`` (Linux /proc), named by its part: the session (teachbot and its meshcat
    server), Chromium's GPU process (where WebGL is drawn), its page (renderer), the rest of the browser, or
    playwright's driver."""
    parents = {}
    for entry in Path("/proc").iterdir():
        try:
            parents[int(entry.name)] = int((entry / "stat").read_text().rsplit(")", 1)[1].split()[1])
        except (ValueError, OSError, IndexError):
            continue
    found, frontier = {}, list(roots)
    while frontier:
        pid = frontier.pop()
        try:
            line = Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode("utf-8", "replace")
        except OSError:
            continue
        kind = re.search(r"--type=([a-z-]+)", line)
        found[pid] = ("browser_gpu" if kind and kind.group(1) == "gpu-process" else
                      "browser_page" if kind and kind.group(1) == "renderer" else
                      "browser_other" if "chrom" in line else "driver" if "playwright" in line else "session")
        frontier += [child for child, parent in parents.items() if parent == pid and child not in found]
    return found


def cpu_seconds(named: dict[int, str]) -> dict[int, float]:
    tick = os.sysconf("SC_CLK_TCK")
    used = {}
    for pid in named:
        try:
            fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        used[pid] = (int(fields[11]) + int(fields[12])) / tick  # user and system time
    return used


def cpu_by_part(named: dict[int, str], before: dict[int, float], after: dict[int, float]) -> dict[str, float]:
    parts = dict.fromkeys(("session", "browser_gpu", "browser_page", "browser_other"), 0.0)
    for pid, seconds in after.items():
        if named[pid] in parts:  # not playwright's driver: it only clicks
            parts[named[pid]] += seconds - before.get(pid, 0.0)
    return {part: round(seconds, 2) for part, seconds in parts.items()}


def page_clock(page) -> float:
    """This process's ``time.perf_counter()`` at the page's ``performance.now()`` of 0, in seconds: from the
    quickest of a few round trips, to a millisecond or so, while the page is idle."""
    trips = []
    for _ in range(7):
        before = time.perf_counter()
        now_ms = page.evaluate("() => performance.now()")
        after = time.perf_counter()
        trips.append((after - before, (before + after) / 2 - now_ms / 1000))
    return min(trips)[1]


def web_session(args, folder: Path) -> dict:
    """Answer a --web session by clicks; the click-to-question times, the page's load time, and over the
    answered turns the CPU seconds of each part, the 3D frames drawn and the wall seconds."""
    from playwright.sync_api import sync_playwright

    command = [TEACHBOT, "teach", "--web", "--seed", str(args.seed), "--turns", str(args.turns), "--strategy",
               args.strategy, "--transcript", "runs/web.jsonl", *(["--no-3d"] if args.no_3d else [])]
    process = subprocess.Popen(command, cwd=folder, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    url = None
    for line in process.stdout:
        found = re.search(r"Open the page: (\S+)", line)
        if found:
            url = found.group(1)
            break
    threading.Thread(target=lambda: [None for _ in process.stdout], daemon=True).start()
    if url is None:
        raise SystemExit("teachbot teach --web printed no URL")
    times, arrivals, drawn, received = [], [], [], {}

    def watch(socket) -> None:  # when each "waiting" message reaches the browser (its network layer)
        def frame(payload) -> None:
            message = json.loads(payload) if isinstance(payload, str) else {}
            if message.get("type") == "waiting":
                received[message["question"]] = time.perf_counter()
        if "/ws?" in socket.url:
            socket.on("framereceived", frame)

    try:
        with sync_playwright() as driver:
            browser = driver.chromium.launch(executable_path=find_chromium(), args=list(CHROMIUM_FLAGS))
            page = browser.new_page(viewport={"width": 1400, "height": 1000})
            page.on("websocket", watch)
            started = time.perf_counter()
            page.goto(url)
            page.wait_for_function(READY, timeout=120_000, polling=5)
            load_ms = (time.perf_counter() - started) * 1000
            named = processes([process.pid, os.getpid()])
            named.pop(os.getpid(), None)  # this script's own driving is neither the session nor the page
            frames = "() => viewer ? viewer.renderer.info.render.frame : 0"
            clock = page_clock(page)  # the page says when it painted a question, in its own clock
            cpu_before, frames_before, turns_started = cpu_seconds(named), page.evaluate(frames), time.perf_counter()
            while True:
                question = page.evaluate("() => question")
                clicked = time.perf_counter()
                if question["expects"] == "label":
                    page.locator("#answers button").first.click()
                elif question["expects"] == "demo":
                    page.get_by_role("button", name="object 1", exact=True).click()
                else:
                    page.locator("#features input[data-number='1.1']").check()
                    clicked = time.perf_counter()
                    page.get_by_role("button", name="use these").click()
                page.wait_for_function(SHOWN, arg=question["id"], timeout=120_000, polling=5)
                shown = clock + page.evaluate("() => paintedAt") / 1000  # not when this poll noticed it
                if page.evaluate("() => ended"):
                    cpu = cpu_by_part(named, cpu_before, cpu_seconds(named))
                    frames_3d, wall_s = page.evaluate(frames) - frames_before, time.perf_counter() - turns_started
                    break
                times.append((shown - clicked) * 1000)
                arrivals.append((received.get(page.evaluate("() => question.id"), shown) - clicked) * 1000)
                if not (args.click_at_once or args.no_3d):  # a participant reads the question (and looks at the view)
                    page.wait_for_function(DRAWN, timeout=120_000, polling=5)
                    drawn.append((time.perf_counter() - clicked) * 1000)
            browser.close()
        process.wait(60)
    finally:
        if process.poll() is None:
            process.kill()
    return {"click_to_question_ms": times, "click_to_arrival_ms": arrivals, "click_to_drawn_ms": drawn,
            "page_load_ms": load_ms,
            "cpu_seconds": cpu, "frames_3d": frames_3d, "wall_s": round(wall_s, 1)}


def terminal_session(args, folder: Path, lines: list[str]) -> list[float]:
    """Type the same lines at a pseudo-terminal; the Enter-to-next-prompt times."""
    import pexpect

    env = dict(os.environ, TERM="dumb", NO_COLOR="1", COLUMNS="200")
    child = pexpect.spawn(TEACHBOT, ["teach", "--seed", str(args.seed), "--turns", str(args.turns), "--strategy",
                                     args.strategy, "--transcript", "runs/terminal.jsonl"], cwd=str(folder), env=env,
                          encoding="utf-8", timeout=120, dimensions=(50, 200))
    child.expect(QUESTION)
    child.expect("> ")
    times = []
    for line in lines:
        sent = time.perf_counter()
        child.sendline(line)
        if child.expect([QUESTION, pexpect.EOF]) == 1:
            break
        child.expect("> ")
        times.append((time.perf_counter() - sent) * 1000)
    child.expect(pexpect.EOF)
    return times


def summary(times: list[float]) -> dict:
    values = np.asarray(times, dtype=float)
    return {"n": int(values.size), "p50": round(float(np.percentile(values, 50)), 1),
            "p95": round(float(np.percentile(values, 95)), 1), "max": round(float(values.max()), 1)}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--turns", type=int, default=20)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--strategy", default="dt-task")
    parser.add_argument("--no-3d", action="store_true", help="the page without its 3D view (camera picture only)")
    parser.add_argument("--click-at-once", action="store_true",
                        help="click as soon as the question is shown, without waiting for the 3D view to draw it")
    parser.add_argument("--json", action="store_true", help="end with one JSON line")
    args = parser.parse_args(argv)
    if find_chromium() is None:
        raise SystemExit("no Chromium found: apt-get install -y chromium")
    with tempfile.TemporaryDirectory(prefix="teachbot-bench-web-") as tmp:
        folder = Path(tmp)
        web = web_session(args, folder)
        records = read_session(folder / "runs/web.jsonl")[1]
        lines = [line for record in records for line in record["answer"]["lines"]]
        terminal = terminal_session(args, folder, lines)
        _, typed = read_session(folder / "runs/terminal.jsonl")
    same = [r["action"] for r in records] == [r["action"] for r in typed]
    page, at_terminal = summary(web["click_to_question_ms"]), summary(terminal)
    arrival = summary(web["click_to_arrival_ms"])
    drawn_3d = summary(web["click_to_drawn_ms"]) if web["click_to_drawn_ms"] else None
    overhead = round(page["p95"] - at_terminal["p95"], 1)
    result = {"turns": args.turns, "seed": args.seed, "strategy": args.strategy, "3d_view": not args.no_3d,
              "click_at_once": args.click_at_once, "same_questions": same,
              "page_click_to_question_ms": page, "page_click_to_arrival_ms": arrival,
              "page_click_to_3d_drawn_ms": drawn_3d,
              "terminal_enter_to_question_ms": at_terminal,
              "page_load_ms": round(web["page_load_ms"], 1), "page_p95_overhead_ms": overhead,
              "goal_ms": GOAL_MS, "goal_met": page["p95"] < at_terminal["p95"] + GOAL_MS,
              "page_turns_wall_s": web["wall_s"], "page_turns_cpu_s": web["cpu_seconds"],
              "page_turns_3d_frames": web["frames_3d"], "load_average": [round(v, 2) for v in os.getloadavg()]}
    print(f"{args.turns} turns of {args.strategy}, seed {args.seed}, 3D view {'off' if args.no_3d else 'on'} "
          f"(the same questions at both: {same})")
    print(f"page:     click to next question  p50 {page['p50']:.0f} ms  p95 {page['p95']:.0f} ms  "
          f"max {page['max']:.0f} ms  (n={page['n']})")
    print(f"          of which until the question reached the browser  p50 {arrival['p50']:.0f} ms  "
          f"p95 {arrival['p95']:.0f} ms (the rest: the page showing it)")
    if drawn_3d is not None:
        print(f"          click until the 3D view has drawn it too  p50 {drawn_3d['p50']:.0f} ms  "
              f"p95 {drawn_3d['p95']:.0f} ms (then the next click)")
    print(f"terminal: Enter to next question  p50 {at_terminal['p50']:.0f} ms  p95 {at_terminal['p95']:.0f} ms  "
          f"max {at_terminal['max']:.0f} ms  (n={at_terminal['n']})")
    drawn = "" if args.no_3d else ", drawn in the 3D view"
    print(f"the page adds {overhead:.0f} ms at p95 (goal: under {GOAL_MS:.0f} ms); page load "
          f"{web['page_load_ms']:.0f} ms (to the first question ready{drawn})")
    cpu = web["cpu_seconds"]
    print(f"over the page's {web['wall_s']:.1f} s of turns: CPU s session {cpu['session']:.2f}, browser GPU process "
          f"{cpu['browser_gpu']:.2f}, page {cpu['browser_page']:.2f}, rest {cpu['browser_other']:.2f}; "
          f"3D frames drawn {web['frames_3d']}; load average {result['load_average'][0]:.2f}")
    if args.json:
        print(json.dumps(result))
    return 0


if __name__ == "__main__":
    sys.exit(main())
