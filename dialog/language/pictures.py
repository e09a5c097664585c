"""Numbered scene pictures: the camera image, turned to the teacher's view, with each object's number drawn at
its perceived position and the kitchen's locations outlined and named."""

from __future__ import annotations

from contextlib import suppress
from pathlib import Path

import cv2
import numpy as np

from bullet_world.annotate import centred_origin, draw_regions, outlined_text, text_box
from dialog.output_paths import writing
from learning.errors import OutputPathError

RING_BGR = (0, 215, 255)     # the object the robot asks about
LABEL_BGR = (255, 255, 255)
REGION_BGR = (255, 220, 40)  # the kitchen's locations (stove, fridge, pantry, cupboard)
OUTLINE_BGR = (0, 0, 0)


def project_points(points, view_matrix, projection_matrix, width: int, height: int) -> np.ndarray:
    """Pixel (column, row) of world points through OpenGL-style 4x4 view and projection matrices."""
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    homogeneous = np.hstack([points, np.ones((len(points), 1))])
    clip = (np.asarray(projection_matrix) @ np.asarray(view_matrix) @ homogeneous.T).T
    ndc = clip[:, :3] / clip[:, 3:4]
    columns = (ndc[:, 0] + 1.0) * 0.5 * width
    rows = (1.0 - ndc[:, 1]) * 0.5 * height
    return np.column_stack([columns, rows])


def annotate_scene(rgb: np.ndarray, pixels, numbers, highlight: int | None = None,
                   regions: dict | None = None, boxes: dict | None = None) -> np.ndarray:
    """A BGR copy of ``rgb`` with ``numbers[i]`` written (outlined, readable on any colour) at ``pixels[i]``;
    ``highlight`` (an index) is ringed; ``regions`` (name: corner pixels (4, 2)) are outlined and named where
    no number is. ``boxes``, when given, receives the numbers' and the names' text boxes."""
    image = cv2.cvtColor(np.ascontiguousarray(rgb, dtype=np.uint8), cv2.COLOR_RGB2BGR)
    height, width = image.shape[:2]
    scale = max(0.45, width / 900.0)
    placed = []
    for index, ((column, row), number) in enumerate(zip(np.asarray(pixels, dtype=float), numbers)):
        if np.isfinite(column) and np.isfinite(row):
            centre = (int(round(np.clip(column, 0, width - 1))), int(round(np.clip(row, 0, height - 1))))
            placed.append((index, str(number), centre))
    number_boxes = [text_box(text, centred_origin(text, centre, scale, 2), scale, 2) for _, text, centre in placed]
    region_boxes = draw_regions(image, regions or {}, REGION_BGR, 0.6 * scale, number_boxes)
    if boxes is not None:
        boxes.update(numbers=number_boxes, regions=region_boxes)
    for index, number, centre in placed:
        if index == highlight:
            radius = int(22 * scale / 0.7)
            cv2.circle(image, centre, radius, OUTLINE_BGR, 7, cv2.LINE_AA)
            cv2.circle(image, centre, radius, RING_BGR, 3, cv2.LINE_AA)
        outlined_text(image, str(number), centre, scale, RING_BGR if index == highlight else LABEL_BGR, 2)
    return image


def save_picture(path: str | Path, bgr: np.ndarray) -> Path:
    """Write a BGR image as PNG; the folder is created. A write that fails raises ``OutputPathError``."""
    path = Path(path)
    encoded, png = cv2.imencode(".png", bgr, [cv2.IMWRITE_PNG_COMPRESSION, 3])
    if not encoded:
        raise OutputPathError(f"{path}: OpenCV could not encode the scene picture {path} as PNG")
    with writing(path, "scene picture"):
        path.parent.mkdir(parents=True, exist_ok=True)
        try:
            path.write_bytes(png.tobytes())
        except OSError:
            with suppress(OSError):
                path.unlink(missing_ok=True)  # no half-written picture left behind
            raise
    return path
