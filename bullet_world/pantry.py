"""Showing the camera one extra object for a moment (an example fetched from the pantry).

The scene on the counter is not disturbed: a fetched object stands on a free
spot the camera sees (or, when there is none, in the place of one object that
is set aside for the moment), is observed, and is taken away again; whatever
was set aside goes back exactly where it stood. Poses of the scene objects can
be saved before the robot reaches over them and put back afterwards, so a
gesture never rearranges the scene a teacher is looking at.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pybullet as p

from bullet_world.bodies import outline
from bullet_world.catalogue import ObjectKind
from bullet_world.kitchen import Location
from bullet_world.meshes import true_size
from bullet_world.placement import Footprint, _clear, _rows_for, footprint_rows
from bullet_world.world import World

VIEW_MARGIN_PX = 6     # a fetched object's outline keeps this far inside the camera image
AWAY_Z = -5.0          # where an object set aside waits: below the counter, beyond the camera's far plane
MOVED_M = 1e-3         # an object that moved more than this during a gesture is put back


@dataclass(frozen=True)
class Spot:
    """Where a fetched object may stand: a centre, a yaw, and the scene object it replaces (None: none)."""

    xy: np.ndarray
    yaw: float
    replaces: int | None = None  # index into ``world.objects``


def in_view(world: World, xy: np.ndarray, radius: float, height: float) -> np.ndarray:
    """Which centres (n, 2) keep a footprint of ``radius`` (and ``height``) inside the camera image."""
    xy = np.atleast_2d(np.asarray(xy, dtype=float))
    camera = world.camera
    offsets = radius * np.array([[1, 1], [1, -1], [-1, 1], [-1, -1]], dtype=float)
    corners = (xy[:, None, :] + offsets[None]).reshape(-1, 2)
    points = np.vstack([np.column_stack([corners, np.full(len(corners), z)]) for z in (0.0, height)])
    clip = (camera.projection_matrix @ camera.view_matrix @ np.column_stack([points, np.ones(len(points))]).T).T
    ok = clip[:, 3] > 1e-9
    ndc = clip[:, :2] / np.where(ok, clip[:, 3], 1.0)[:, None]
    columns = (ndc[:, 0] + 1.0) * 0.5 * camera.width
    rows = (1.0 - ndc[:, 1]) * 0.5 * camera.height
    m = VIEW_MARGIN_PX
    inside = ok & (columns >= m) & (columns <= camera.width - m) & (rows >= m) & (rows <= camera.height - m)
    return inside.reshape(2, len(xy), 4).all(axis=(0, 2))


def _rows_of(world: World, indices) -> np.ndarray:
    objects = [world.objects[i] for i in indices]
    return footprint_rows([Footprint.from_tuple(outline(o.kind, o.draw)) for o in objects],
                          [o.xy for o in objects], [o.yaw for o in objects])


def free_spots(world: World, kind: ObjectKind, draw: dict, region: Location, rng: np.random.Generator,
               count: int = 64, spill_m: float = 0.0) -> list[Spot]:
    """Spots in ``region`` (grown by ``spill_m``) where the drawn object stands clear of every scene
    object, on the counter and in the camera's view; in the order drawn."""
    footprint = Footprint.from_tuple(outline(kind, draw))
    half = np.asarray(region.half_size, dtype=float) + spill_m
    low = np.asarray(region.centre[:2], dtype=float) - half
    xy = rng.uniform(low, low + 2 * half, (count, 2))
    yaw = rng.uniform(0.0, np.pi, count)
    keep = world.kitchen.counter_edge_distance(xy) >= footprint.radius
    keep &= in_view(world, xy, footprint.radius, _height(kind, draw))
    rows = _rows_for(footprint, xy, yaw)
    keep &= _clear(rows, _rows_of(world, range(len(world.objects))), world.kitchen.min_gap)
    return [Spot(xy[i].copy(), float(yaw[i])) for i in np.flatnonzero(keep)]


def _height(kind: ObjectKind, draw: dict) -> float:
    return float(true_size(kind.state(draw.get("state", 0)), draw["dimensions"])[2])


def replacement_spots(world: World, kind: ObjectKind, draw: dict, candidates) -> list[Spot]:
    """Spots of scene objects (indices ``candidates``, in order) whose place the drawn object can take:
    with that object set aside it stands clear of the others, on the counter and in view."""
    footprint = Footprint.from_tuple(outline(kind, draw))
    height = _height(kind, draw)
    spots = []
    for index in candidates:
        standing = world.objects[index]
        xy = standing.xy[None, :]
        if world.kitchen.counter_edge_distance(xy)[0] < footprint.radius or not in_view(world, xy, footprint.radius,
                                                                                         height)[0]:
            continue
        others = [i for i in range(len(world.objects)) if i != index]
        if _clear(_rows_for(footprint, xy, np.array([standing.yaw])), _rows_of(world, others),
                  world.kitchen.min_gap)[0]:
            spots.append(Spot(standing.xy.copy(), standing.yaw, index))
    return spots


def glimpse(world: World, kind: ObjectKind, draw: dict, spot: Spot) -> np.ndarray:
    """Stand the drawn object at ``spot``, observe the scene, take it away again; its feature row.

    Raises :class:`bullet_world.world.HiddenObjectError` when the camera cannot see it (or some scene object). The world
    is left as it was either way: same objects, same poses, same last scene and frame.
    """
    last_scene, last_images = world.scene, world.images
    aside = None
    if spot.replaces is not None:
        aside = world.objects.pop(spot.replaces)
        position, orientation = p.getBasePositionAndOrientation(aside.body, physicsClientId=world.client)
        p.resetBasePositionAndOrientation(aside.body, [position[0], position[1], AWAY_Z], orientation,
                                          physicsClientId=world.client)
    body = world.add_object(kind, spot.xy, spot.yaw, draw=draw)
    try:
        return world.observe().X[-1].copy()
    finally:
        world.remove_object(body)
        if aside is not None:
            p.resetBasePositionAndOrientation(aside.body, position, orientation, physicsClientId=world.client)
            world.objects.insert(spot.replaces, aside)
        world.scene, world.images = last_scene, last_images


def object_poses(world: World) -> list[tuple]:
    """The base pose of every scene object (to put back after the robot reached over them)."""
    return [p.getBasePositionAndOrientation(o.body, physicsClientId=world.client) for o in world.objects]


def restore_poses(world: World, poses: list[tuple]) -> int:
    """Put every scene object that moved back where ``poses`` says, at rest; how many had moved."""
    moved = 0
    for obj, (position, orientation) in zip(world.objects, poses):
        now = p.getBasePositionAndOrientation(obj.body, physicsClientId=world.client)[0]
        if np.linalg.norm(np.subtract(now, position)) > MOVED_M:
            moved += 1
        p.resetBasePositionAndOrientation(obj.body, position, orientation, physicsClientId=world.client)
        p.resetBaseVelocity(obj.body, [0, 0, 0], [0, 0, 0], physicsClientId=world.client)
    return moved

