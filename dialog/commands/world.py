"""``teachbot world show`` (an annotated camera picture), ``teachbot world check`` (perception against the
simulator's ground truth), ``world data`` (a task's data sets) and ``world generate`` (kitchens drawn from a
seed)."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from dialog.commands._arguments import (
    add_kitchen_option,
    add_scene_options,
    add_task_option,
    kitchen_names,
    positive_int,
    seed,
    stage,
)
from dialog.commands._json import print_json
from dialog.output_paths import check_writable, file_argument, make_parent
from learning.errors import SettingsError


def register(commands) -> None:
    parser = commands.add_parser(
        "world", help="look at the simulated kitchen: a scene's objects, a perception check, the data sets",
        description="Look at the simulated kitchen without the robot learning: 'show' lists one scene's objects "
                    "(and draws it with --png), 'check' measures perception against the simulator, 'data' builds "
                    "or loads a task's data sets.")
    actions = parser.add_subparsers(dest="action", required=True, metavar="ACTION")

    show = actions.add_parser(
        "show", help="list one scene's objects as a table (and write an annotated picture with --png)",
        description="The first scene that 'teachbot demo' and 'teachbot view' show for the same task, kitchen and "
                    "seed, as a table: object number, kind and concept, colour, size, location. --png also writes "
                    "the annotated camera picture.")
    add_scene_options(show)
    show.add_argument("--objects", type=positive_int, default=None,
                      help="objects in the scene (default: the task's objects_per_scene)")
    show.add_argument("--stage", type=stage, default=None,
                      help="state stage for tasks whose objects change state (default: the first scene's, as "
                           "demo shows it)")
    show.add_argument("--png", type=file_argument, default=None, help="also write the annotated camera picture (.png)")
    show.set_defaults(handler=run_show)

    check = actions.add_parser(
        "check", help="measure perception against the simulator over many objects",
        description="Build scenes until at least --objects objects were seen and compare the perceived size and "
                    "location of each with the simulator's ground truth, per object kind.")
    check.add_argument("--objects", type=positive_int, default=500, help="objects to measure at least (default 500)")
    check.add_argument("--per-scene", type=positive_int, default=55, help="objects per scene (default 55)")
    add_task_option(check, "pack-lunchbox")
    add_kitchen_option(check, None, "all of them; repeat --kitchen for several", action="append")
    check.add_argument("--seed", type=seed, default=0, help="seed of the first scene (default 0)")
    check.add_argument("--no-robot", action="store_true", help="leave the arm out (its features too)")
    check.add_argument("--json", action="store_true", help="end with one JSON line of the results")
    check.set_defaults(handler=run_check)

    data = actions.add_parser(
        "data", help="build (or load from the cache) a task's data sets and summarise them",
        description="Render a task's training pools and test pool in the simulator (or load them from the cache) "
                    "and print their sizes; the regression suites use the same data sets.")
    add_task_option(data, "pack-lunchbox")
    add_kitchen_option(data, "kitchen-1")
    data.add_argument("--seed", type=seed, default=0, help="seed of the data sets (default 0)")
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

    generate = actions.add_parser(
        "generate", help="write kitchen files drawn from a seed (galley, L-shape, island, U layouts)",
        description="Draw kitchens from the generator's distributions (a data file: layout families, fixtures, "
                    "materials, lighting, noise, each kitchen's household of dishes) and write them as kitchen "
                    "files, one per seed from --seed on. The same seed and distributions give the same bytes; "
                    "every kitchen is checked like the shipped ones before it is written. Use a written file "
                    "wherever a kitchen is asked for: --kitchen FOLDER/generated-N.toml.")
    generate.add_argument("--seed", type=seed, required=True, help="seed of the first kitchen")
    generate.add_argument("--count", type=positive_int, default=1, help="kitchens to write (default 1)")
    generate.add_argument("--out", type=Path, required=True, help="folder to write the kitchen files into")
    generate.add_argument("--distributions", type=Path, default=None, metavar="FILE",
                          help="the generator's data file (default bullet_world/data/generator/kitchens.toml)")
    generate.add_argument("--json", action="store_true", help="end with one JSON line of the written files")
    generate.set_defaults(handler=run_generate)


def run_show(args: argparse.Namespace) -> int:
    from dialog.environment import SimulatedKitchen
    from dialog.manager import episode_generators

    if args.png is not None and args.png.suffix.lower() != ".png":
        raise SettingsError(f"--png must name a .png file, got '{args.png}'")
    if args.png is not None:
        check_writable(args.png, "scene picture")  # before the scene is built
    environment = SimulatedKitchen(task=args.task, kitchen=args.kitchen, seed=args.seed, objects_per_scene=args.objects)
    try:
        rng = episode_generators(args.seed)["scenes"]  # the stream demo and view draw their first scene from
        if args.stage is None:
            scene = environment.next_scene(rng)
        else:
            scene = environment.world.new_scene(rng, stage=args.stage)
        print(f"Scene {scene.scene_id} of {args.task} in {args.kitchen} (seed {args.seed}): {scene.n_objects} "
              f"objects, {len(scene.feature_names)} features each; places as the teacher across the counter sees them")
        for line in scene_table(scene, environment):
            print(f"  {line}")
        if args.png is not None:
            from bullet_world.annotate import annotate, write_png

            make_parent(args.png, "scene picture")
            write_png(args.png, annotate(environment.world.images, scene, environment.world.kitchen))
            print(f"Picture: {args.png}")
    finally:
        environment.close()
    return 0


def scene_table(scene, environment) -> list[str]:
    """One line per object: number, kind (and state), concept, perceived colour and size, place and x, y."""
    from dialog.language.describe import SceneDescriber

    described = SceneDescriber(scene, environment.locations, environment.viewpoint)
    width = max([len("object"), *(len(_kind(scene, i)) for i in range(scene.n_objects))])
    concept_width = max([len("concept"), *map(len, scene.truth.concepts)])
    lines = [f"{'no.':>3}  {'object':<{width}}  {'concept':<{concept_width}}  {'colour':<11} {'size (cm)':<12} "
             "x, y (m)      place"]
    for index in range(scene.n_objects):
        size = "x".join(f"{v * 100:.0f}" for v in described.sizes[index]) if described.sizes is not None else "?"
        x, y = scene.positions[index][:2]
        lines.append(f"{index + 1:>3}  {_kind(scene, index):<{width}}  {scene.truth.concepts[index]:<{concept_width}}  "
                     f"{described.colour_names[index] or '?':<11} {size:<12} {x:+.2f}, {y:+.2f}  "
                     f"{described.places[index] or '?'}")
    return lines


def _kind(scene, index: int) -> str:
    kind = scene.truth.kinds[index]
    states = scene.truth.states
    return kind if not states or states[index] == "as-is" else f"{kind} ({states[index]})"


def run_check(args: argparse.Namespace) -> int:
    from bullet_world.check import perception_check

    kitchens = tuple(args.kitchen) if args.kitchen else tuple(kitchen_names())

    def progress(message: str) -> None:
        print(message, file=sys.stderr, flush=True)

    robot_factory = None
    if not args.no_robot:
        from robot import Arm

        robot_factory = Arm
    result = perception_check(kitchens, args.task, args.objects, args.per_scene, args.seed, progress=progress,
                              robot_factory=robot_factory)
    size, location = result["size_err_mm"], result["loc_err_mm"]
    used = kitchens[:min(result["scenes"], len(kitchens))]  # the scenes go round the kitchens in turn
    unused = f"; {', '.join(kitchens[len(used):])} not needed" if len(used) < len(kitchens) else ""
    scenes = f"{result['scenes']} scene{'' if result['scenes'] == 1 else 's'}"
    print(f"{result['objects']} objects in {scenes} ({', '.join(used)}{unused}): "
          f"size error median {size['median']} mm (p95 {size['p95']}), location error median "
          f"{location['median']} mm (p95 {location['p95']}); {result['features']} features; "
          f"{result['ms_per_scene']} ms per scene ({result['cpu_ms_per_scene']} ms CPU)")
    for kind, row in result["per_kind"].items():
        print(f"  {kind:<22} {row['objects']:>4} objects  size {row['size_err_mm']:>5} mm  "
              f"location {row['loc_err_mm']:>5} mm")
    if args.json:
        keys = ("objects", "size_err_mm", "loc_err_mm", "features", "ms_per_scene")
        print_json({key: result[key] for key in keys} | {"cpu_ms_per_scene": result["cpu_ms_per_scene"]})
    return 0


def source_in_words(meta: dict, seconds: float, rendered: bool) -> str:
    """"built in 41.3 s", or "loaded from the cache in 1.7 s (built in 41.3 s)" when nothing was rendered."""
    if not rendered:
        return f"loaded from the cache in {seconds:.1f} s (built in {meta.get('build_seconds')} s)"
    return f"built in {seconds:.1f} s"


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
    rendering: list[str] = []  # load_datasets reports progress only while it renders

    def progress(message: str) -> None:
        rendering.append(message)
        print(message, file=sys.stderr, flush=True)

    started = time.perf_counter()
    datasets = load_datasets(args.task, args.kitchen, args.seed, plan, robot_factory=robot_factory, cache=args.cache,
                             rebuild=args.rebuild, progress=progress)
    meta = datasets.metadata
    sizes = [len(pool) for pool in datasets.train]
    print(f"{args.task} in {args.kitchen} (seed {args.seed}): {len(sizes)} training pools of {sizes[0]}, "
          f"a test pool of {len(datasets.test)}, {len(datasets.feature_names)} features; "
          f"{source_in_words(meta, time.perf_counter() - started, bool(rendering))}; {meta.get('file')}")
    if args.json:
        print_json({"task": args.task, "kitchen": args.kitchen, "seed": args.seed, "train": sizes,
                          "test": len(datasets.test), "features": len(datasets.feature_names),
                          "file": meta.get("file"), "generator": meta.get("generator")})
    return 0


def run_generate(args: argparse.Namespace) -> int:
    from bullet_world.generation import DEFAULT_DISTRIBUTIONS, generate_kitchens
    from bullet_world.kitchen import load_kitchen

    if args.out.exists() and not args.out.is_dir():
        raise SettingsError(f"--out must be a folder, got the file '{args.out}'")
    written = generate_kitchens(args.seed, args.count, args.out, args.distributions)
    rows = []
    for path in written:
        kitchen = load_kitchen(path)
        rows.append({"path": str(path), "name": kitchen.name, "seed": kitchen.generated["seed"],
                     "family": kitchen.generated["family"]})
        print(f"{path}: {kitchen.generated['family']}, {kitchen.counter_size[0]:.2f} x {kitchen.counter_size[1]:.2f} m "
              f"worktop")
    if args.json:
        print_json({"kitchens": rows, "distributions": str(args.distributions or DEFAULT_DISTRIBUTIONS)})
    return 0
