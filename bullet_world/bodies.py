"""Turning a drawn object (kind, state, size, colour, mass) into a PyBullet body.

The look is a generated unit mesh scaled to the object's size, a generated
texture for its kind state and base colour, and a tint for its own colour. The
collision shape is the matching primitive (box, cylinder, sphere). Mesh files
and textures are shared by every object that uses them, and collision shapes
are reused for equal sizes (to the millimetre), so building a scene creates as
little as PyBullet allows: it never frees a shape once made.
"""

from __future__ import annotations

import zlib
from dataclasses import dataclass

import numpy as np
import pybullet as p

from bullet_world.catalogue import KindState, ObjectKind
from bullet_world.datafiles import cache_dir
from bullet_world.meshes import footprint, mesh_file, true_size
from bullet_world.textures import texture_file

ROLLING_FRICTION = 0.002   # keeps round fruit from rolling away when the arm shakes the counter


@dataclass
class PlacedObject:
    """One object in the world: what it is, how it was drawn, and where it stands."""

    body: int
    kind: ObjectKind
    draw: dict
    xy: np.ndarray
    yaw: float
    texture: str = ""   # the generated texture PNG the body is drawn with (the viewer shows it too)

    @property
    def look(self) -> KindState:
        return self.kind.state(self.draw.get("state", 0))

    @property
    def size(self) -> tuple[float, float, float]:
        return true_size(self.look, self.draw["dimensions"])

    @property
    def state_name(self) -> str:
        return self.look.name


def colour_index(look: KindState, draw: dict) -> int:
    """The base colour a draw tints: recorded in the draw, or the nearest one."""
    if "colour_index" in draw:
        return int(draw["colour_index"]) % len(look.colours)
    distances = np.linalg.norm(np.asarray(look.colours) - np.asarray(draw["colour"]), axis=1)
    return int(np.argmin(distances))


class BodyBuilder:
    """Creates object bodies in one client, sharing textures and collision shapes between them."""

    def __init__(self, client: int, cache=None):
        self.client, self.cache = client, str(cache_dir(cache))
        self._textures: dict[str, int] = {}
        self._collisions: dict[tuple, int] = {}
        self._looks: dict[tuple, tuple[str, int, str]] = {}

    def _texture(self, kind: ObjectKind, look: KindState, index: int) -> tuple[int, str]:
        """The loaded texture's id and its PNG file."""
        seed = zlib.crc32(f"{kind.name}/{look.name}".encode())
        path = texture_file(look.texture, look.colours[index], look.inner_colour, seed, self.cache)
        if path not in self._textures:
            self._textures[path] = p.loadTexture(path, physicsClientId=self.client)
        return self._textures[path], str(path)

    def _collision(self, look: KindState, size: tuple[float, float, float]) -> int:
        shape = {"box": "box", "bag": "box", "slices": "box", "sphere": "sphere"}.get(look.shape, "cylinder")
        key = (shape, *(round(s * 1000) for s in size))
        if key not in self._collisions:
            length, width, height = (max(k, 1) / 1000 for k in key[1:])
            if shape == "box":
                made = p.createCollisionShape(p.GEOM_BOX, halfExtents=[length / 2, width / 2, height / 2],
                                              physicsClientId=self.client)
            elif shape == "sphere":
                made = p.createCollisionShape(p.GEOM_SPHERE, radius=length / 2, physicsClientId=self.client)
            else:
                made = p.createCollisionShape(p.GEOM_CYLINDER, radius=length / 2, height=height,
                                              physicsClientId=self.client)
            self._collisions[key] = made
        return self._collisions[key]

    def spawn(self, kind: ObjectKind, draw: dict, xy, yaw: float) -> PlacedObject:
        """Build the body standing on the counter (z = 0) at ``xy`` turned by ``yaw``."""
        look = kind.state(draw.get("state", 0))
        size = true_size(look, draw["dimensions"])
        index = colour_index(look, draw)
        base = np.maximum(np.asarray(look.colours[index]), 1e-3)
        tint = np.clip(np.asarray(draw["colour"], dtype=float) / base, 0.0, 1.0)
        key = (kind.name, look.name, index)
        if key not in self._looks:  # the mesh file and texture of this kind state and base colour
            self._looks[key] = (mesh_file(look, self.cache), *self._texture(kind, look, index))
        mesh, texture, texture_path = self._looks[key]
        visual = p.createVisualShape(p.GEOM_MESH, fileName=mesh, meshScale=list(size),
                                     rgbaColor=[*tint.tolist(), 1.0], physicsClientId=self.client)
        position = [float(xy[0]), float(xy[1]), size[2] / 2]
        body = p.createMultiBody(float(draw["mass"]), self._collision(look, size), visual, position,
                                 p.getQuaternionFromEuler([0, 0, float(yaw)]), physicsClientId=self.client)
        p.changeVisualShape(body, -1, textureUniqueId=texture, physicsClientId=self.client)
        if look.shape not in ("box", "bag", "slices"):
            p.changeDynamics(body, -1, rollingFriction=ROLLING_FRICTION, spinningFriction=ROLLING_FRICTION,
                             physicsClientId=self.client)
        return PlacedObject(body, kind, draw, np.asarray(xy, dtype=float)[:2].copy(), float(yaw), texture_path)


def outline(kind: ObjectKind, draw: dict) -> tuple[str, float, float]:
    """The footprint of a drawn object (see :func:`bullet_world.meshes.footprint`)."""
    return footprint(kind.state(draw.get("state", 0)), draw["dimensions"])
