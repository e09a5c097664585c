"""``teachbot world show`` (an annotated camera picture) and ``teachbot world check`` (perception
against the simulator's ground truth)."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from dialog.commands._arguments import positive_int
from learning.errors import SettingsError

KITCHENS = ("kitchen-1", "kitchen-2", "kitchen-3")


def register(commands) -> None:
    parser = commands.add_parser("world", help="look at the simulated kitchen: a picture, or a perception check")
    actions = parser.add_subparsers(dest="action", required=True, metavar="ACTION")

    show = actions.add_parser("show", help="write an annotated camera picture of one scene")
    show.add_argument("--kitchen", default="kitchen-1", help="kitchen data file name (default kitchen-1)")
    show.add_argument("--task", default="pack-lunchbox", help="task data file name (default pack-lunchbox)")
    show.add_argument("--seed", type=int, default=0, help="seed of the scene (default 0)")
    show.add_argument("--objects", type=positive_int, default=None,
                      help="objects in the scene (default: the task's objects_per_scene)")
    show.add_argument("--stage", type=int, default=None,
                      help="state stage for tasks whose objects change state (default: random states)")
    show.add_argument("--png", type=Path, required=True, help="where to write the picture (.png)")
    show.add_argument("--robot", action="store_true", help="add the arm (its features join the list)")
    show.set_defaults(handler=run_show)

    check = actions.add_parser("check", help="measure perception against the simulator over many objects")
    check.add_argument("--objects", type=positive_int, default=500, help="objects to measure at least (default 500)")
    check.add_argument("--per-scene", type=positive_int, default=55, help="objects per scene (default 55)")
    check.add_argument("--task", default="pack-lunchbox", help="task data file name (default pack-lunchbox)")
    check.add_argument("--kitchen", action="append", choices=KITCHENS, default=None,
                       help="kitchen(s) to use, repeatable (default: all three)")
    check.add_argument("--seed", type=int, default=0, help="seed of the first scene (default 0)")
    check.add_argument("--no-robot", action="store_true", help="leave the arm out (its features too)")
    check.add_argument("--json", action="store_true", help="end with one JSON line of the results")
    check.set_defaults(handler=run_check)

    data = actions.add_parser("data", help="build (or load from the cache) a task's data sets and summarise them")
    data.add_argument("--task", default="pack-lunchbox", help="task data file name (default pack-lunchbox)")
    data.add_argument("--kitchen", default="kitchen-1", choices=KITCHENS, help="kitchen (default kitchen-1)")
    data.add_argument("--seed", type=int, default=0, help="seed of the data sets (default 0)")
    data.add_argument("--cache", type=Path, default=None,
                      help="cache folder (default $TEACHBOT_CACHE or ~/.cache/teachbot)")
    data.add_argument("--no-robot", action="store_true", help="leave the arm out (its features too)")
    data.add_argument("--rebuild", action="store_true", help="render the data sets again even if cached")
    data.add_argument("--pool-size", type=positive_int, default=None,
                      help="objects per training pool (default: the task's [datasets] plan)")
    data.add_argument("--test-size", type=positive_int, default=None,
                      help="objects in the test pool (default: the task's [datasets] plan)")
    data.add_argument("--json", action="store_true", help="end with one JSON line")
    data.set_defaults(handler=run_data)


def run_show(args: argparse.Namespace) -> int:
    from bullet_world import World
    from bullet_world.annotate import annotate, write_png

    if args.png.suffix.lower() != ".png":
        raise SettingsError(f"--png must name a .png file, got '{args.png}'")
    with World(task=args.task, kitchen=args.kitchen, seed=args.seed, objects_per_scene=args.objects) as world:
        if args.robot:
            from robot import Arm

            Arm(world)
        scene = world.new_scene(np.random.default_rng(args.seed), stage=args.stage)
        write_png(args.png, annotate(world.images, scene, world.kitchen))
        print(f"{args.png}: {scene.n_objects} objects in {args.kitchen} ({args.task}, seed {args.seed}), "
              f"{len(scene.feature_names)} features each")
        for index, (kind, state) in enumerate(zip(scene.truth.kinds, scene.truth.states)):
            shown = kind if state == "as-is" else f"{kind} ({state})"
            print(f"  {index + 1:>2}. {shown:<28} {scene.truth.concepts[index]}")
    return 0


def run_check(args: argparse.Namespace) -> int:
    from bullet_world.check import perception_check

    kitchens = tuple(args.kitchen) if args.kitchen else KITCHENS

    def progress(message: str) -> None:
        print(message, file=sys.stderr, flush=True)

    robot_factory = None
    if not args.no_robot:
        from robot import Arm

        robot_factory = Arm
    result = perception_check(kitchens, args.task, args.objects, args.per_scene, args.seed, progress=progress,
                              robot_factory=robot_factory)
    size, location = result["size_err_mm"], result["loc_err_mm"]
    print(f"{result['objects']} objects in {result['scenes']} scenes ({', '.join(kitchens)}): "
          f"size error median {size['median']} mm (p95 {size['p95']}), location error median "
          f"{location['median']} mm (p95 {location['p95']}); {result['features']} features; "
          f"{result['ms_per_scene']} ms per scene ({result['cpu_ms_per_scene']} ms CPU)")
    for kind, row in result["per_kind"].items():
        print(f"  {kind:<22} {row['objects']:>4} objects  size {row['size_err_mm']:>5} mm  "
              f"location {row['loc_err_mm']:>5} mm")
    if args.json:
        keys = ("objects", "size_err_mm", "loc_err_mm", "features", "ms_per_scene")
        print(json.dumps({key: result[key] for key in keys} | {"cpu_ms_per_scene": result["cpu_ms_per_scene"]}))
    return 0


def run_data(args: argparse.Namespace) -> int:
    from dataclasses import replace

    from bullet_world.catalogue import load_task
    from bullet_world.datasets import load_datasets

    plan = load_task(args.task).datasets
    plan = replace(plan, pool_size=args.pool_size or plan.pool_size, test_size=args.test_size or plan.test_size)
    robot_factory = None
    if not args.no_robot:
        from robot import Arm

        robot_factory = Arm
    datasets = load_datasets(args.task, args.kitchen, args.seed, plan, robot_factory=robot_factory, cache=args.cache,
                             rebuild=args.rebuild, progress=lambda m: print(m, file=sys.stderr, flush=True))
    meta = datasets.metadata
    sizes = [len(pool) for pool in datasets.train]
    print(f"{args.task} in {args.kitchen} (seed {args.seed}): {len(sizes)} training pools of {sizes[0]}, "
          f"a test pool of {len(datasets.test)}, {len(datasets.feature_names)} features; "
          f"built in {meta.get('build_seconds')} s; {meta.get('file')}")
    if args.json:
        print(json.dumps({"task": args.task, "kitchen": args.kitchen, "seed": args.seed, "train": sizes,
                          "test": len(datasets.test), "features": len(datasets.feature_names),
                          "file": meta.get("file"), "generator": meta.get("generator")}))
    return 0
