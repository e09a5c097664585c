"""Reading the PyBullet world into plain data for the viewer: what every body looks like and where it is.

Everything is read generically from PyBullet (``getVisualShapeData``, base and
link states), so any body in the client appears, whatever built it: the
counter, the Panda from its URDF meshes, the objects of every kind. A frame is
a dict from a node path to ``(looks, matrix)``: the parts drawn at that node
and the node's 4x4 world pose. Only the thread that steps the simulation may
call these functions (PyBullet releases the GIL inside its calls, so another
thread reading the same client races with the physics).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pybullet as p

IDENTITY = tuple(float(v) for v in np.eye(4).ravel())
SHAPES = {p.GEOM_SPHERE: "sphere", p.GEOM_BOX: "box", p.GEOM_CYLINDER: "cylinder", p.GEOM_MESH: "mesh",
          p.GEOM_PLANE: "plane", p.GEOM_CAPSULE: "capsule"}


@dataclass(frozen=True)
class Look:
    """One drawable part. ``size``: box full extents; sphere (radius,); cylinder and capsule
    (radius, length); mesh scale (sx, sy, sz); plane (length, width); text (height in metres,);
    ``local`` is the part's pose in its node (row-major 4x4)."""

    shape: str
    size: tuple[float, ...]
    rgba: tuple[float, float, float, float]
    file: str = ""
    texture: str = ""
    text: str = ""
    style: str = ""
    local: tuple[float, ...] = IDENTITY


Frame = dict  # node path -> (tuple[Look, ...], 4x4 np.ndarray)


def pose_matrix(position, quaternion) -> np.ndarray:
    """4x4 homogeneous matrix of a PyBullet pose (quaternion x, y, z, w)."""
    x, y, z, w = (float(v) for v in quaternion)
    matrix = np.eye(4)
    matrix[:3, :3] = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                      [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                      [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
    matrix[:3, 3] = [float(v) for v in position]
    return matrix


def same_pose(a: np.ndarray, b: np.ndarray, tolerance: float = 1e-5) -> bool:
    """Whether two 4x4 poses agree within ``tolerance`` (exactly equal ones are the common, cheap case)."""
    return a.tobytes() == b.tobytes() or float(np.abs(a - b).max()) <= tolerance


def pose_matrices(positions: np.ndarray, quaternions: np.ndarray) -> np.ndarray:
    """(n, 4, 4) matrices of n poses at once (quaternions x, y, z, w)."""
    x, y, z, w = quaternions.T
    matrices = np.zeros((len(positions), 4, 4))
    matrices[:, 0, 0], matrices[:, 0, 1], matrices[:, 0, 2] = 1 - 2 * (y * y + z * z), 2 * (x * y - z * w), \
        2 * (x * z + y * w)
    matrices[:, 1, 0], matrices[:, 1, 1], matrices[:, 1, 2] = 2 * (x * y + z * w), 1 - 2 * (x * x + z * z), \
        2 * (y * z - x * w)
    matrices[:, 2, 0], matrices[:, 2, 1], matrices[:, 2, 2] = 2 * (x * z - y * w), 2 * (y * z + x * w), \
        1 - 2 * (x * x + y * y)
    matrices[:, :3, 3] = positions
    matrices[:, 3, 3] = 1.0
    return matrices


def translation(x: float, y: float, z: float) -> np.ndarray:
    matrix = np.eye(4)
    matrix[:3, 3] = (x, y, z)
    return matrix


def _part(row, appearance: tuple[str, tuple | None]) -> Look | None:
    """One row of ``getVisualShapeData`` as a Look (None for shapes meshcat can't draw)."""
    geometry, dims, file = row[2], row[3], row[4].decode("utf-8", "replace")
    shape = SHAPES.get(geometry)
    rgba = tuple(round(float(c), 4) for c in row[7])
    texture, colour = appearance
    if colour is not None:
        rgba = (*(round(float(c), 4) for c in colour[:3]), rgba[3])
    local = tuple(float(v) for v in pose_matrix(row[5], row[6]).ravel())
    if shape == "box":
        size = tuple(float(d) for d in dims[:3])
    elif shape == "sphere":
        size = (float(dims[0]),)
    elif shape in ("cylinder", "capsule"):
        size = (float(dims[1]), float(dims[0]))
    elif shape == "mesh":
        if not file or not file.lower().endswith((".obj", ".dae", ".stl")):
            return None
        size = tuple(float(d) for d in dims[:3])
    elif shape == "plane":
        size = (4.0, 4.0)
    else:
        return None
    return Look(shape, size, rgba, file=file if shape == "mesh" else "", texture=texture or "", local=local)


def body_links(client: int, body: int, appearance: tuple[str, tuple | None] = ("", None)
               ) -> dict[int, tuple[Look, ...]]:
    """The drawable parts of one body, per link index (-1 is the base). ``appearance`` is a
    texture file and a colour override for the base, for looks PyBullet can't report."""
    links: dict[int, list[Look]] = {}
    for row in p.getVisualShapeData(body, physicsClientId=client):
        look = _part(row, appearance if row[1] == -1 else ("", None))
        if look is not None:
            links.setdefault(int(row[1]), []).append(look)
    return {link: tuple(looks) for link, looks in links.items()}


def world_appearance(world) -> Callable[[int], tuple[str, tuple | None]]:
    """Texture file and colour of each object body, where the world knows more than PyBullet reports.

    PyBullet reports a texture's id but not its file, and our objects carry their colour in the
    texture (the shape's rgba is only a tint). So the viewer asks the world's placed objects for a
    ``texture`` path (used when present) and otherwise takes the object's drawn colour.
    """
    def appearance(body: int) -> tuple[str, tuple | None]:
        for placed in getattr(world, "objects", ()) or ():
            if getattr(placed, "body", None) != body:
                continue
            texture = getattr(placed, "texture", "") or ""
            draw = getattr(placed, "draw", None)
            colour = draw.get("colour") if isinstance(draw, dict) and not texture else None
            return str(texture), None if colour is None else tuple(float(c) for c in colour)
        return "", None
    return appearance


class WorldReader:
    """Names every body's nodes once and reads their poses into frames (main thread only)."""

    def __init__(self, world, appearance: Callable[[int], tuple[str, tuple | None]] | None = None):
        self.world = world
        self.client = world.client
        self.appearance = appearance or world_appearance(world)
        self._known: dict[int, tuple] = {}      # body -> (signature, node name, links, inertial inverse)
        self._serial = 0
        self._layout: tuple = ()
        self._poses: dict[str, tuple] = {}       # node -> (raw PyBullet pose, its 4x4 matrix)
        self.object_nodes: list[str] = []        # node of object i (shown as number i + 1)

    def _name(self, body: int) -> str:
        robot = getattr(getattr(self.world, "robot", None), "body_id", None)
        if body == robot:
            return "robot"
        if body == getattr(self.world, "counter_body", None):
            return "kitchen/counter"
        self._serial += 1
        furniture = getattr(self.world, "furniture", {}).get(body)
        if furniture is not None:   # the room: floor, cabinets, fixtures, walls (bullet_world.room)
            return f"kitchen/{''.join(c if c.isalnum() else '-' for c in furniture)}-{self._serial}"
        if body in self.world.object_bodies:
            return f"objects/o{self._serial}"
        name = p.getBodyInfo(body, physicsClientId=self.client)[1].decode("utf-8", "replace") or "body"
        return f"things/{''.join(c if c.isalnum() else '-' for c in name)}-{self._serial}"

    def refresh(self) -> None:
        """Re-read which bodies exist and what they look like (names survive unchanged bodies)."""
        count = p.getNumBodies(physicsClientId=self.client)
        bodies = [p.getBodyUniqueId(i, physicsClientId=self.client) for i in range(count)]
        known = {}
        for body in bodies:
            appearance = self.appearance(body)
            rows = p.getVisualShapeData(body, physicsClientId=self.client)
            signature = (rows, appearance)
            previous = self._known.get(body)
            if previous is not None and previous[0] == signature:
                known[body] = previous
                continue
            position, orientation = p.getDynamicsInfo(body, -1, physicsClientId=self.client)[3:5]
            inertial = np.linalg.inv(pose_matrix(position, orientation))
            inertial = None if np.allclose(inertial, np.eye(4)) else inertial
            known[body] = (signature, self._name(body), body_links(self.client, body, appearance), inertial)
        self._known = known
        self._poses.clear()
        self.object_nodes = [known[b][1] for b in self.world.object_bodies if b in known]
        self._layout = (count, tuple(self.world.object_bodies))

    def _stale(self) -> bool:
        return self._layout != (p.getNumBodies(physicsClientId=self.client), tuple(self.world.object_bodies))

    def frame(self, refresh: bool = False) -> Frame:
        """Every node's looks and world pose now; re-reads the bodies if they changed (or when asked)."""
        if refresh or self._stale():
            self.refresh()
        nodes, positions, quaternions, corrections = [], [], [], []
        for body, (_, name, links, inertial) in self._known.items():
            if -1 in links:
                position, orientation = p.getBasePositionAndOrientation(body, physicsClientId=self.client)
                nodes.append((name if len(links) == 1 else f"{name}/link-1", links[-1]))
                positions.append(position)
                quaternions.append(orientation)
                corrections.append(inertial)
            moving = [link for link in links if link >= 0]
            if moving:
                states = p.getLinkStates(body, moving, computeForwardKinematics=True, physicsClientId=self.client)
                for link, state in zip(moving, states):
                    nodes.append((f"{name}/link{link}", links[link]))
                    positions.append(state[4])
                    quaternions.append(state[5])
                    corrections.append(None)
        poses = list(zip(positions, quaternions))
        changed = [i for i, (node, _) in enumerate(nodes) if self._poses.get(node, (None,))[0] != poses[i]]
        if changed:  # a node that did not move keeps its very matrix object (cheap to compare downstream)
            matrices = pose_matrices(np.asarray([positions[i] for i in changed], dtype=float).reshape(-1, 3),
                                     np.asarray([quaternions[i] for i in changed], dtype=float).reshape(-1, 4))
            for i, matrix in zip(changed, matrices):
                correction = corrections[i]
                self._poses[nodes[i][0]] = (poses[i], matrix if correction is None else matrix @ correction)
        return {node: (looks, self._poses[node][1]) for node, looks in nodes}

    def place(self, node: str) -> tuple | None:
        """Where the node's body was at the last frame, to the millimetre (None if it has no such node)."""
        pose = self._poses.get(node)
        return None if pose is None else tuple(round(v, 3) for v in pose[0][0])

    def object_boxes(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """World axis-aligned bounding box (low, high corner) of object i, in number order."""
        return [tuple(np.asarray(corner) for corner in p.getAABB(body, physicsClientId=self.client))
                for body in self.world.object_bodies]
