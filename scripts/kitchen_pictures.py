"""Regenerate the pictures of the three kitchens in docs/ (docs/kitchen.md shows them).

For each kitchen: the overhead camera's annotated picture of a seeded scene with the arm
(``docs/img/kitchens/kitchen-N-camera.png``, as `teachbot world show --png` draws it, at 3/4 size) and a view of
the room from the teacher's side rendered by PyBullet's TinyRenderer (``docs/img/kitchens/kitchen-N-room.png``).
Deterministic: the same seed gives the same pictures.

    .venv/bin/python scripts/kitchen_pictures.py [--seed 0] [--out docs/img/kitchens] [--json]
"""

from __future__ import annotations

import argparse
import json
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


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "img" / "kitchens")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    written = []
    for name in available("kitchens"):
        with World(kitchen=name, seed=args.seed) as world:
            Arm(world)
            scene = world.new_scene(np.random.default_rng(args.seed))
            camera = annotate(world.images, scene, world.kitchen, scale=2)
            camera = cv2.resize(camera, None, fx=0.75, fy=0.75, interpolation=cv2.INTER_AREA)
            for kind, picture in (("camera", camera), ("room", room_view(world))):
                path = args.out / f"{name}-{kind}.png"
                write_png(path, picture)
                written.append({"kitchen": name, "picture": kind, "path": str(path.relative_to(ROOT)),
                                "bytes": path.stat().st_size})
    for entry in written:
        print(f"{entry['path']}: {entry['bytes'] / 1024:.0f} KB")
    if args.json:
        print(json.dumps({"pictures": written}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
