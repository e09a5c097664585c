"""Annotated camera pictures as the teacher sees the counter: object numbers, boxes, semantic locations.

The overhead frame is turned so that the robot is at the top and the teacher's
left is the picture's left (see :mod:`bullet_world.viewpoint`); everything
written on it is drawn after the turn, so it reads upright, with a dark outline
that shows on any colour.
"""

from __future__ import annotations

import cv2
import numpy as np

from bullet_world.camera import CameraImages
from bullet_world.kitchen import Kitchen
from bullet_world.perception import PIXEL_X_OFFSET, PIXEL_Y_OFFSET
from bullet_world.scene import Scene
from bullet_world.viewpoint import Viewpoint, picture_turn, turn_image, turn_pixels
from learning.errors import OutputPathError

BOX_COLOUR = (255, 255, 255)
LOCATION_COLOUR = (40, 220, 255)
TEXT_COLOUR = (255, 255, 255)
OUTLINE_COLOUR = (0, 0, 0)
FONT = cv2.FONT_HERSHEY_SIMPLEX


def project(images: CameraImages, points) -> np.ndarray:
    """Pixel (x, y) of world points (n, 3): the inverse of :func:`bullet_world.perception.deproject`."""
    points = np.atleast_2d(np.asarray(points, dtype=float))
    clip = images.projection_matrix @ images.view_matrix @ np.c_[points, np.ones(len(points))].T
    ndc = clip[:2] / clip[3]
    height, width = images.segmentation.shape
    cols = (ndc[0] + 1.0) / 2.0 * width - PIXEL_X_OFFSET
    rows = (1.0 - ndc[1]) / 2.0 * height - PIXEL_Y_OFFSET
    return np.column_stack([cols, rows])


class TeacherPicture:
    """One camera frame turned to the teacher's view, and where world points land on it."""

    def __init__(self, images: CameraImages, viewpoint: Viewpoint, scale: int = 1):
        self.images, self.scale = images, int(scale)
        centre = np.array([*viewpoint.centre, 0.0])
        middle, ahead, left = project(images, [centre, centre + [*viewpoint.facing, 0.0],
                                               centre + [*viewpoint.left, 0.0]])
        self.k, self.mirror = picture_turn(ahead - middle, left - middle)
        rgb = images.rgb if scale == 1 else cv2.resize(images.rgb, None, fx=scale, fy=scale,
                                                       interpolation=cv2.INTER_NEAREST)
        self.size = rgb.shape[1], rgb.shape[0]
        self.rgb = turn_image(rgb, self.k, self.mirror)

    def pixels(self, points) -> np.ndarray:
        """Picture (column, row) of world points (n, 3)."""
        return turn_pixels(project(self.images, points) * self.scale, self.k, self.mirror, *self.size)


def outlined_text(picture: np.ndarray, text: str, centre, scale: float, colour, thickness: int = 1,
                  anchor: str = "centre") -> None:
    """Write ``text`` centred on (or, with ``anchor="corner"``, starting at) ``centre``, with a dark outline."""
    (width, height), _ = cv2.getTextSize(text, FONT, scale, thickness)
    x, y = (float(v) for v in centre)
    origin = (int(round(x - width / 2)), int(round(y + height / 2))) if anchor == "centre" else (int(x), int(y))
    radius = max(2, int(round(2.5 * scale)))  # the dark rim: the text stamped around itself (OpenCV 5's putText
    for dx in range(-radius, radius + 1):     # ignores stroke thickness, so a thicker dark copy would not do)
        for dy in range(-radius, radius + 1):
            if 0 < dx * dx + dy * dy <= radius * radius:
                cv2.putText(picture, text, (origin[0] + dx, origin[1] + dy), FONT, scale, OUTLINE_COLOUR, thickness,
                            cv2.LINE_AA)
    cv2.putText(picture, text, origin, FONT, scale, colour, thickness, cv2.LINE_AA)


def location_corners(location) -> np.ndarray:
    """The four corners (4, 3) of a location's region on the counter top."""
    cx, cy = location.centre[:2]
    hx, hy = location.half_size
    return np.array([[cx - hx, cy - hy, 0], [cx + hx, cy - hy, 0], [cx + hx, cy + hy, 0], [cx - hx, cy + hy, 0]])


def draw_locations(picture: np.ndarray, to_pixels, locations: dict, colour=LOCATION_COLOUR,
                   text_scale: float = 0.45) -> None:
    """Outline every semantic location's region and write its name (outlined) inside its top edge."""
    for location in locations.values():
        corners = to_pixels(location_corners(location))
        cv2.polylines(picture, [np.round(corners).astype(np.int32)], True, colour, 2, cv2.LINE_AA)
        (_, text_h), _ = cv2.getTextSize(location.name, FONT, text_scale, 1)
        top_left = corners.min(axis=0)
        outlined_text(picture, location.name, (top_left[0] + 4, top_left[1] + text_h + 5), text_scale, colour,
                      anchor="corner")


def annotate(images: CameraImages, scene: Scene, kitchen: Kitchen, scale: int = 2) -> np.ndarray:
    """The camera picture (RGB, enlarged ``scale`` times, turned to the teacher's view) with every object's
    number and perceived box, the outline and name of every semantic location, and the robot's base."""
    view = TeacherPicture(images, Viewpoint.of_kitchen(kitchen), scale)
    picture = view.rgb.copy()
    draw_locations(picture, view.pixels, kitchen.locations)
    base = view.pixels([kitchen.robot_base])[0]
    cv2.drawMarker(picture, tuple(np.round(base).astype(int)), LOCATION_COLOUR, cv2.MARKER_TILTED_CROSS, 14, 2)
    outlines = scene.outlines if scene.outlines is not None else np.zeros((0, 4, 2))
    for index in range(scene.n_objects):
        top = scene.positions[index, 2] + scene.tops[index] / 2
        if index < len(outlines):
            corners = view.pixels(np.c_[outlines[index], np.full(4, top)])
            cv2.polylines(picture, [np.round(corners).astype(np.int32)], True, BOX_COLOUR, 1, cv2.LINE_AA)
        centre = view.pixels([[*scene.positions[index, :2], top]])[0]
        outlined_text(picture, str(index + 1), centre, 0.3 * scale, TEXT_COLOUR, 2)
    return picture


def write_png(path, picture_rgb: np.ndarray) -> None:
    """Write an RGB picture as PNG (one-line error naming the path when it fails)."""
    if not cv2.imwrite(str(path), cv2.cvtColor(picture_rgb, cv2.COLOR_RGB2BGR)):
        raise OutputPathError(f"could not write a PNG to '{path}' (does the folder exist and end the name in .png?)")
