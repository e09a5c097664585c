"""The teacher's viewpoint: standing across the counter from the robot, facing it.

Every "left", "right", "front" and "back" the teacher reads or sees is this one:
the words of the questions, the numbered pictures (the robot at the top, the
teacher's left on the picture's left) and the viewer's default camera. Front is
the teacher's side of the counter, back is the robot's.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

AXES = np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]])


@dataclass(frozen=True)
class Viewpoint:
    """Where the teacher looks from: ``facing`` (unit, along a counter axis, towards the robot) and
    ``centre`` (the middle of the work area, from which sides are measured)."""

    facing: tuple[float, float] = (0.0, -1.0)
    centre: tuple[float, float] = (0.0, 0.0)

    @classmethod
    def of_kitchen(cls, kitchen) -> Viewpoint:
        """The teacher opposite the robot: facing against the robot's forward axis, snapped to the counter's axes."""
        forward = np.array([np.cos(kitchen.robot_yaw), np.sin(kitchen.robot_yaw)])
        facing = -AXES[int(np.argmax(AXES @ forward))]
        centre = kitchen.focus if kitchen.focus is not None else kitchen.counter_centre
        return cls((float(facing[0]), float(facing[1])), (float(centre[0]), float(centre[1])))

    @property
    def left(self) -> np.ndarray:
        """The teacher's left as a world direction (x, y): ``facing`` turned a quarter to the left."""
        return np.array([-self.facing[1], self.facing[0]])

    def sides(self, xy) -> np.ndarray:
        """Points (n, 2) as (metres to the teacher's right, metres towards the teacher) from ``centre``."""
        offset = np.atleast_2d(np.asarray(xy, dtype=float))[:, :2] - np.asarray(self.centre)
        return np.column_stack([offset @ -self.left, offset @ -np.asarray(self.facing)])

    def eye(self, target, distance: float = 1.0, height: float = 0.75) -> np.ndarray:
        """A camera eye on the teacher's side: ``distance`` back from ``target`` and ``height`` above it."""
        target = np.asarray(target, dtype=float)
        return target + np.array([*(-distance * np.asarray(self.facing)), height])


def picture_turn(direction_pixels: np.ndarray, left_pixels: np.ndarray) -> tuple[int, bool]:
    """Quarter turns (``np.rot90``'s k) and whether to mirror afterwards, so that a picture whose world
    ``facing`` direction points along ``direction_pixels`` (column, row) shows it upwards and the
    teacher's left (``left_pixels``) leftwards."""
    def turned(vector, k):
        column, row = vector
        for _ in range(k % 4):  # rot90: pixel (column, row) goes to (row, width - 1 - column)
            column, row = row, -column
        return np.array([column, row])

    k = max(range(4), key=lambda k: -turned(direction_pixels, k)[1])
    mirror = bool(turned(left_pixels, k)[0] > 0)
    return k, mirror


def turn_pixels(pixels, k: int, mirror: bool, width: int, height: int) -> np.ndarray:
    """Pixel (column, row) positions of a ``width`` x ``height`` picture after :func:`picture_turn`'s turn."""
    pixels = np.array(pixels, dtype=float).reshape(-1, 2)
    for _ in range(k % 4):
        pixels = np.column_stack([pixels[:, 1], width - 1 - pixels[:, 0]])
        width, height = height, width
    if mirror:
        pixels[:, 0] = width - 1 - pixels[:, 0]
    return pixels


def turn_image(image: np.ndarray, k: int, mirror: bool) -> np.ndarray:
    """The picture turned as :func:`picture_turn` says (a contiguous copy)."""
    turned = np.rot90(image, k)
    return np.ascontiguousarray(turned[:, ::-1] if mirror else turned)
