"""Speed of teachbot/Questioning-v0 and of the trained questioner's decisions, each against a reference in the same run.

1. Environment steps per second on cached data (the chapter-7 training
   condition: prepare-lunch, 12 objects a scene, budget 15, 30 turns), with
   the what-if observation (every slot's E[phi(s') | a]) and without it,
   against the turns per second of the plain dialog loop that ``teachbot
   regress`` runs. Both play the very same episodes (the same seeds, DT-task
   choosing every action), so ``env / loop`` is the price of the Gymnasium
   wrapper and its observation alone.
2. Decision time: the RL questioner's ``choose`` (observation + forward pass)
   against DT-task's ``choose`` (what-if engine + eq. 7.1), on the very same
   learning states with at least one affordable query, taken from the
   environment's episodes (a masked random agent plays them); the scene's
   p(y|x) is computed before the clock starts and the what-if cache is
   cleared before each.

BLAS runs on one thread. Speeds are CPU time of this process (other programs on the shared machine do not
inflate it), each measured ``--pairs`` times back to back in rotating order; the ratios env / loop are taken
within each repetition and their median reported, with their range. Decision times are CPU-time medians too;
the load average is reported.

    python scripts/bench_gym.py --json        # last line: one JSON object
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

SHIPPED = Path(__file__).resolve().parents[1] / "learning" / "rl" / "policies" / "questioner-ch7-training.toml"


def _parse(argv):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=6, help="episodes per measurement (default 6)")
    parser.add_argument("--policy", type=Path, default=SHIPPED, help="questioner policy (default: the shipped one)")
    parser.add_argument("--pairs", type=int, default=5,
                        help="repeated (loop, environment) measurements; the ratios are their medians (default 5)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--json", action="store_true", help="end with one JSON line")
    args = parser.parse_args(argv)
    for name in ("episodes", "pairs"):
        if getattr(args, name) < 1:
            parser.error(f"--{name} must be at least 1, got {getattr(args, name)}")
    return args


def repeated_pairs(pairs: int, episodes: int, seed: int) -> dict:
    """Loop turns/s and environment steps/s (with and without the what-if observation), measured ``pairs`` times
    back to back, the order rotating each time; the ratios env / loop are taken within each repetition, and
    the medians over repetitions are reported (one repetition's ratio swings with what else the machine runs)."""
    measures = {"loop": lambda: loop_turns_per_second(episodes, seed),
                "whatif": lambda: env_steps_per_second(True, episodes, seed),
                "no_whatif": lambda: env_steps_per_second(False, episodes, seed)}
    names = list(measures)
    rates: dict[str, list[float]] = {name: [] for name in names}
    for repetition in range(pairs):
        for name in names[repetition % 3:] + names[: repetition % 3]:
            rates[name].append(measures[name]())
    whatif_ratios = [w / loop for w, loop in zip(rates["whatif"], rates["loop"])]
    no_whatif_ratios = [w / loop for w, loop in zip(rates["no_whatif"], rates["loop"])]
    return {"pairs": pairs, "loop_turns_per_s": round(float(np.median(rates["loop"])), 2),
            "env_steps_per_s_whatif": round(float(np.median(rates["whatif"])), 2),
            "env_steps_per_s_no_whatif": round(float(np.median(rates["no_whatif"])), 2),
            "env_whatif_over_loop": round(float(np.median(whatif_ratios)), 3),
            "env_no_whatif_over_loop": round(float(np.median(no_whatif_ratios)), 3),
            "env_whatif_over_loop_range": [round(min(whatif_ratios), 3), round(max(whatif_ratios), 3)]}


def env_steps_per_second(whatif: bool, episodes: int, seed: int) -> float:
    """The environment playing the very episodes of ``loop_turns_per_second``: same seeds, DT-task's choices."""
    from dialog.rl.gym_env import QuestioningEnv
    from learning.strategies import make_strategy

    env, agent = QuestioningEnv(whatif=whatif), make_strategy("dt-task")
    rng = np.random.default_rng(seed)

    def play(episode: int) -> int:
        env.reset(seed=episode * 1000 + episode % env.settings.datasets)  # regress's episode seed of seed `episode`
        done, steps = False, 0
        while not done:
            action = agent.choose(env.manager.state, rng).action
            _, _, done, _, _ = env.step(env.layout.slot_of(action))
            steps += 1
        return steps

    play(seed + episodes)  # a warm-up episode, not timed (imports, caches)
    started = time.process_time()
    steps = sum(play(episode) for episode in range(seed, seed + episodes))
    return steps / (time.process_time() - started)


def loop_turns_per_second(episodes: int, seed: int) -> float:
    """The reference: ``regress``'s episodes (dialog.experiments.episodes.run_episode), DT-task choosing."""
    import tempfile
    from dataclasses import replace

    from dialog.experiments.episodes import run_episode
    from dialog.experiments.irl_rollouts import training_condition

    condition = training_condition()
    with tempfile.TemporaryDirectory() as scratch:
        def play(episode: int) -> int:
            spec = replace(condition.spec(episode), strategy="dt-task",
                           transcript=str(Path(scratch) / f"e{episode}.jsonl"))
            return len(run_episode(spec)["series"]["turn"])

        play(seed + episodes)  # a warm-up episode, not timed
        started = time.process_time()
        turns = sum(play(episode) for episode in range(seed, seed + episodes))
        return turns / (time.process_time() - started)


def decision_times(policy_path: Path, episodes: int, seed: int) -> dict:
    from dialog.rl.gym_env import QuestioningEnv
    from learning.rl.observation import ObservationLayout
    from learning.rl.policy_file import QuestionerPolicy, load_policy
    from learning.strategies import make_strategy
    from learning.strategies.rl_questioner import RLQuestionerStrategy

    env = QuestioningEnv()
    if policy_path.is_file():
        policy, source = load_policy(policy_path), str(policy_path)
    else:  # the time does not depend on the weights: a policy of the trained one's shape
        layout: ObservationLayout = env.layout
        rng = np.random.default_rng(seed)
        sizes = [layout.size, 64, 64, layout.n_actions]
        policy = QuestionerPolicy(layout, tuple(rng.normal(0, 0.1, (sizes[k + 1], sizes[k])) for k in range(3)),
                                  tuple(np.zeros(sizes[k + 1]) for k in range(3)))
        source = "random weights of the trained policy's shape (no policy file)"
    rl, dt = RLQuestionerStrategy(policy), make_strategy("dt-task")
    rng = np.random.default_rng(seed)
    times: dict[str, list[float]] = {"rl": [], "dt-task": []}
    for episode in range(episodes):
        _, info = env.reset(seed=10_000 + seed + episode)
        done = False
        while not done:
            state = env.manager.state
            if info["action_mask"].sum() < 2:  # only no query is left: nothing to decide
                _, _, done, _, info = env.step(0)
                continue
            state.probabilities()  # p(y|x) of the scene is part of the state (as in bench_decision.py)
            for name, strategy in (("rl", rl), ("dt-task", dt)):
                state.cache.clear()  # each starts cold: no what-if result memoised by the other
                started = time.process_time()
                strategy.choose(state, rng)
                times[name].append(time.process_time() - started)
            _, _, done, _, info = env.step(int(rng.choice(np.flatnonzero(info["action_mask"]))))
    rl_ms, dt_ms = (1000 * float(np.median(times[k])) for k in ("rl", "dt-task"))
    return {"policy": source, "decisions": len(times["rl"]), "rl_ms": round(rl_ms, 3), "dt_task_ms": round(dt_ms, 3),
            "rl_over_dt_task": round(rl_ms / dt_ms, 3)}


def main(argv=None) -> int:
    args = _parse(sys.argv[1:] if argv is None else argv)
    # threadpoolctl limits the libraries loaded when the limit starts: load every BLAS first (the environment's
    # imports bring scipy's), else its steps ran on two BLAS threads while regress's episodes, which set the
    # limit per episode, ran on one (cho_solve 5x slower in the environment on this machine)
    import dialog.experiments.episodes  # noqa: F401
    import dialog.rl.gym_env  # noqa: F401
    from dialog.threads import one_blas_thread

    load_before = os.getloadavg()[0]
    with one_blas_thread():
        speeds = repeated_pairs(args.pairs, args.episodes, args.seed)
        decisions = decision_times(args.policy, args.episodes, args.seed)
    result = {"episodes": args.episodes, **speeds, **decisions,
              "load_average": [round(load_before, 2), round(os.getloadavg()[0], 2)]}
    low, high = speeds["env_whatif_over_loop_range"]
    print(f"CPU time, medians of {args.pairs} repetitions of each measurement:")
    print(f"dialog loop (regress, DT-task choosing): {speeds['loop_turns_per_s']:.1f} turns/s")
    print(f"Questioning-v0, the same episodes and choices, with the what-if observation: "
          f"{speeds['env_steps_per_s_whatif']:.1f} steps/s ({speeds['env_whatif_over_loop']:.2f} x the loop; "
          f"{low:.2f}-{high:.2f} over the repetitions)")
    print(f"Questioning-v0 without it: {speeds['env_steps_per_s_no_whatif']:.1f} steps/s "
          f"({speeds['env_no_whatif_over_loop']:.2f} x the loop)")
    print(f"decision time over {decisions['decisions']} states: RL questioner {decisions['rl_ms']:.2f} ms, DT-task "
          f"{decisions['dt_task_ms']:.2f} ms (ratio {decisions['rl_over_dt_task']:.2f}); policy {decisions['policy']}")
    print(f"load average {result['load_average'][0]} -> {result['load_average'][1]}")
    if args.json:
        print(json.dumps(result))
    return 0


if __name__ == "__main__":
    sys.exit(main())
