"""``teachbot view``: open one scene of the kitchen in meshcat and print the URL.

The scene is the first one ``teachbot demo`` would show for the same task,
kitchen and seed. ``--point N`` makes the arm point at object N the way a
label question does (highlight, question text); ``--export`` writes the
scene (and the pointing motion) as one static HTML page; ``--screenshot``
saves a PNG through headless Chromium. With either of them the command writes
its files and exits, unless ``--serve`` or ``--seconds`` asks it to keep serving.
"""

from __future__ import annotations

import argparse
import sys
import time

from dialog.commands._arguments import add_scene_options, positive_int, seconds
from dialog.output_paths import file_argument
from learning.errors import SettingsError


def register(commands) -> None:
    parser = commands.add_parser(
        "view", help="show one scene of the kitchen in meshcat (a browser) and print the URL",
        description="Mirror the first scene that 'teachbot demo' shows for the same task, kitchen and seed into "
                    "meshcat and print its URL; --point N lets the arm point at object N as a label question does. "
                    "--export and --screenshot write their file and exit unless --serve is given.")
    add_scene_options(parser)
    parser.add_argument("--point", type=positive_int, default=None, metavar="N",
                        help="let the arm point at object N and ask about it, as a label question does")
    parser.add_argument("--export", type=file_argument, default=None, metavar="HTML",
                        help="write the scene as one static HTML page (opens without a server)")
    parser.add_argument("--screenshot", type=file_argument, default=None, metavar="PNG",
                        help="save a picture of the page through headless Chromium (needs chromium and playwright)")
    parser.add_argument("--seconds", type=seconds, default=None,
                        help="keep serving this long, then exit (default: until Ctrl-C, or at once after "
                             "--export/--screenshot; 0: exit at once)")
    parser.add_argument("--serve", action="store_true",
                        help="keep serving until Ctrl-C after --export/--screenshot too")
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    from bullet_world.viewer.mirror import Viewer
    from dialog.commands.world import scene_table
    from dialog.environment import SimulatedKitchen
    from dialog.manager import episode_generators
    from dialog.output_paths import check_writable, writing
    from dialog.viewer import page_path, page_written

    export = None
    if args.export is not None:
        export = check_writable(page_path(args.export, "scene.html"), "scene page")
    if args.screenshot is not None:
        check_writable(args.screenshot, "screenshot")
    environment = SimulatedKitchen(task=args.task, kitchen=args.kitchen, seed=args.seed)
    try:
        scene = environment.next_scene(episode_generators(args.seed)["scenes"])
        if args.point is not None and args.point > scene.n_objects:
            raise SettingsError(f"--point {args.point}: the scene has objects 1 to {scene.n_objects}")
        viewer = Viewer(environment.world, record=args.export is not None)
        try:
            viewer.start_recording()
            viewer.on_scene(scene)
            if args.point is not None:
                action = {"kind": "label", "object": args.point}
                gesture = environment.point_at(scene, args.point - 1)
                viewer.on_question(action, f"What is this (object {args.point})?", scene)
                print(f"The arm points at object {args.point} (fingertip {gesture['horizontal_error_m'] * 100:.1f} cm "
                      f"from its centre, {gesture['sim_seconds']:.2f} s of simulated motion).")
            print(f"Scene {scene.scene_id} of {args.task} in {args.kitchen} (seed {args.seed}): "
                  f"{scene.n_objects} objects, numbered 1 to {scene.n_objects}.")
            for line in scene_table(scene, environment):
                print(f"  {line}")
            serving = _serving_seconds(args)
            if serving != 0:  # a URL only for a server that outlives this line (issue 51)
                print(f"Viewer: {viewer.url}")
            if export is not None:
                with writing(export, "scene page"):
                    written = viewer.export_html(export, title=f"teachbot {args.task} seed {args.seed}")
                print(page_written("Page", written))
            if args.screenshot is not None:
                from bullet_world.viewer.snapshot import screenshot

                shot = screenshot(viewer.url, args.screenshot, min_drawn=scene.n_objects + 2)
                print(f"Picture: {shot['path']} ({shot['drawn']} meshes and labels drawn)")
            _serve(serving)
        finally:
            viewer.close()
    finally:
        environment.close()
    return 0


def _serving_seconds(args: argparse.Namespace) -> float | None:
    """How long to serve: --seconds if given; else until Ctrl-C, except after writing a page or picture."""
    if args.seconds is not None:
        return args.seconds
    wrote_files = args.export is not None or args.screenshot is not None
    return 0.0 if wrote_files and not args.serve else None


def _serve(duration: float | None) -> None:
    if duration == 0:
        return
    print("Serving; press Ctrl-C to stop." if duration is None else f"Serving for {duration:g} s.", flush=True)
    try:
        time.sleep(duration) if duration is not None else _forever()
    except KeyboardInterrupt:
        print("", file=sys.stderr)


def _forever() -> None:
    while True:
        time.sleep(3600)
