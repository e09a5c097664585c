"""An annotated camera picture: object numbers, perceived bounding boxes, semantic locations."""

from __future__ import annotations

import cv2
import numpy as np

from bullet_world.camera import CameraImages
from bullet_world.kitchen import Kitchen
from bullet_world.perception import PIXEL_X_OFFSET, PIXEL_Y_OFFSET
from bullet_world.scene import Scene

BOX_COLOUR = (255, 255, 255)
LOCATION_COLOUR = (40, 220, 255)
TEXT_COLOUR = (255, 255, 255)


def project(images: CameraImages, points) -> np.ndarray:
    """Pixel (x, y) of world points (n, 3): the inverse of :func:`bullet_world.perception.deproject`."""
    points = np.atleast_2d(np.asarray(points, dtype=float))
    clip = images.projection_matrix @ images.view_matrix @ np.c_[points, np.ones(len(points))].T
    ndc = clip[:2] / clip[3]
    height, width = images.segmentation.shape
    cols = (ndc[0] + 1.0) / 2.0 * width - PIXEL_X_OFFSET
    rows = (1.0 - ndc[1]) / 2.0 * height - PIXEL_Y_OFFSET
    return np.column_stack([cols, rows])


def annotate(images: CameraImages, scene: Scene, kitchen: Kitchen, scale: int = 2) -> np.ndarray:
    """The camera picture (RGB, enlarged ``scale`` times) with every object's number and perceived box,
    and the outline and name of every semantic location."""
    picture = cv2.resize(images.rgb, None, fx=scale, fy=scale, interpolation=cv2.INTER_NEAREST)
    for location in kitchen.locations.values():
        cx, cy, _ = location.centre
        hx, hy = location.half_size
        corners = project(images, [[cx - hx, cy - hy, 0], [cx + hx, cy - hy, 0], [cx + hx, cy + hy, 0],
                                   [cx - hx, cy + hy, 0]]) * scale
        cv2.polylines(picture, [np.round(corners).astype(np.int32)], True, LOCATION_COLOUR, 1, cv2.LINE_AA)
        label = tuple(np.round(corners.min(axis=0) + [3, 12]).astype(int))
        cv2.putText(picture, location.name, label, cv2.FONT_HERSHEY_SIMPLEX, 0.4, LOCATION_COLOUR, 1, cv2.LINE_AA)
    base = project(images, [kitchen.robot_base])[0] * scale
    cv2.drawMarker(picture, tuple(np.round(base).astype(int)), LOCATION_COLOUR, cv2.MARKER_TILTED_CROSS, 14, 2)
    outlines = scene.outlines if scene.outlines is not None else np.zeros((0, 4, 2))
    for index in range(scene.n_objects):
        top = scene.positions[index, 2] + scene.tops[index] / 2
        if index < len(outlines):
            corners = project(images, np.c_[outlines[index], np.full(4, top)]) * scale
            cv2.polylines(picture, [np.round(corners).astype(np.int32)], True, BOX_COLOUR, 1, cv2.LINE_AA)
        centre = project(images, [[*scene.positions[index, :2], top]])[0] * scale
        text = str(index + 1)
        (w, h), _ = cv2.getTextSize(text, cv2.FONT_HERSHEY_SIMPLEX, 0.45, 1)
        origin = np.round(centre + [-w / 2, h / 2]).astype(int)
        cv2.rectangle(picture, tuple(origin + [-2, 3]), tuple(origin + [w + 2, -h - 3]), (0, 0, 0), -1)
        cv2.putText(picture, text, tuple(origin), cv2.FONT_HERSHEY_SIMPLEX, 0.45, TEXT_COLOUR, 1, cv2.LINE_AA)
    return picture


def write_png(path, picture_rgb: np.ndarray) -> None:
    """Write an RGB picture as PNG (one-line error naming the path when it fails)."""
    if not cv2.imwrite(str(path), cv2.cvtColor(picture_rgb, cv2.COLOR_RGB2BGR)):
        raise ValueError(f"could not write a PNG to '{path}' (does the folder exist and end the name in .png?)")
