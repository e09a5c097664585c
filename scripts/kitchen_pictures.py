"""Regenerate the pictures of the three kitchens and of the teaching page in docs/ (docs/kitchen.md and
docs/web.md show them, the README the page's).

For each kitchen: the overhead camera's annotated picture of a seeded scene with the arm
(``docs/img/kitchens/kitchen-N-camera.png``, as `teachbot world show --png` draws it, at 3/4 size) and a view of
the room from the teacher's side rendered by PyBullet's TinyRenderer (``docs/img/kitchens/kitchen-N-room.png``).
Deterministic: the same seed gives the same pictures. Then, in headless Chromium (unless ``--no-page`` or there is
no Chromium), each kitchen's 3D view as the meshcat mirror shows it (``docs/img/kitchens/kitchen-N-3d.png``,
`teachbot view --screenshot`, at 3/4 size) and the teaching page mid-question (``docs/img/web-teach.png``, by
scripts/web_screenshot.py: a real ``teach --web`` session).

    .venv/bin/python scripts/kitchen_pictures.py [--seed 0] [--out docs/img/kitchens] [--no-page] [--json]

``--kitchen FILE`` (repeatable) draws those kitchens instead of the shipped three (generated ones, say: the
gallery of docs/kitchen.md#generated-kitchens), named by their file's stem; the teaching page is then left alone.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pybullet as p

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bullet_world.annotate import annotate, write_png  # noqa: E402
from bullet_world.datafiles import available  # noqa: E402
from bullet_world.viewpoint import Viewpoint  # noqa: E402
from bullet_world.world import World  # noqa: E402
from robot import Arm  # noqa: E402

ROOM_SIZE = (640, 400)


def room_view(world: World) -> np.ndarray:
    """The whole room seen from the teacher's side, a little above and behind them (RGB)."""
    viewpoint = Viewpoint.of_kitchen(world.kitchen)
    target = np.array([*viewpoint.centre, -0.1])
    eye = viewpoint.eye(target, distance=2.3, height=1.4)
    width, height = ROOM_SIZE
    view = p.computeViewMatrix(eye.tolist(), target.tolist(), [0, 0, 1])
    projection = p.computeProjectionMatrixFOV(50, width / height, 0.1, 10.0)
    light = world.lighting
    _, _, rgba, _, _ = p.getCameraImage(width, height, view, projection, renderer=p.ER_TINY_RENDERER,
                                        lightDirection=list(light.direction), lightColor=list(light.colour),
                                        lightAmbientCoeff=light.ambient, lightDiffuseCoeff=light.diffuse,
                                        lightSpecularCoeff=0.05, shadow=1, physicsClientId=world.client)
    return np.asarray(rgba, dtype=np.uint8).reshape(height, width, 4)[:, :, :3]


def _shown(path: Path) -> str:
    path = path.resolve()
    return str(path.relative_to(ROOT)) if path.is_relative_to(ROOT) else str(path)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "img" / "kitchens")
    parser.add_argument("--no-page", action="store_true", help="not the teaching page's picture")
    parser.add_argument("--kitchen", action="append", default=None, metavar="FILE",
                        help="a kitchen file to draw instead of the shipped three (repeatable)")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    kitchens = {Path(path).stem: path for path in args.kitchen} if args.kitchen else {
        name: name for name in available("kitchens")}
    args.out.mkdir(parents=True, exist_ok=True)
    written = []
    for name, kitchen in kitchens.items():
        with World(kitchen=kitchen, seed=args.seed) as world:
            Arm(world)
            scene = world.new_scene(np.random.default_rng(args.seed))
            camera = annotate(world.images, scene, world.kitchen, scale=2)
            camera = cv2.resize(camera, None, fx=0.75, fy=0.75, interpolation=cv2.INTER_AREA)
            for kind, picture in (("camera", camera), ("room", room_view(world))):
                path = args.out / f"{name}-{kind}.png"
                write_png(path, picture)
                written.append({"kitchen": name, "picture": kind, "path": _shown(path),
                                "bytes": path.stat().st_size})
    page = ROOT / "docs" / "img" / "web-teach.png"
    if not args.no_page:
        from bullet_world.viewer.snapshot import find_chromium

        if find_chromium() is None:
            print("no Chromium (apt-get install -y chromium): the page's picture is left as it is", file=sys.stderr)
        else:
            for name, kitchen in kitchens.items():
                path = args.out / f"{name}-3d.png"
                subprocess.run([str(Path(sys.executable).with_name("teachbot")), "view", "--kitchen", kitchen, "--seed",
                                str(args.seed), "--screenshot", str(path)], check=True, stdout=subprocess.DEVNULL)
                picture = cv2.imread(str(path))
                write_png(path, cv2.resize(picture, None, fx=0.75, fy=0.75, interpolation=cv2.INTER_AREA))
                written.append({"kitchen": name, "picture": "3d", "path": _shown(path),
                                "bytes": path.stat().st_size})
            if not args.kitchen:
                subprocess.run([sys.executable, str(ROOT / "scripts" / "web_screenshot.py"), str(page)], check=True)
                written.append({"kitchen": None, "picture": "page", "path": str(page.relative_to(ROOT)),
                                "bytes": page.stat().st_size})
    for entry in written:
        print(f"{entry['path']}: {entry['bytes'] / 1024:.0f} KB")
    if args.json:
        print(json.dumps({"pictures": written}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
