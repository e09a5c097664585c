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


def text_box(text: str, origin, scale: float, thickness: int = 1) -> np.ndarray:
    """(x0, y0, x1, y1) that :func:`outlined_text` covers when ``text`` starts at corner ``origin`` (with its rim)."""
    (width, height), baseline = cv2.getTextSize(text, FONT, scale, thickness)
    rim = max(2, int(round(2.5 * scale))) + 1
    x, y = float(origin[0]), float(origin[1])
    return np.array([x - rim, y - height - rim, x + width + rim, y + baseline + rim])


def centred_origin(text: str, centre, scale: float, thickness: int = 1) -> tuple[float, float]:
    """The corner origin at which ``text`` is centred on ``centre`` (as :func:`outlined_text` centres it)."""
    (width, height), _ = cv2.getTextSize(text, FONT, scale, thickness)
    return float(round(centre[0] - width / 2)), float(round(centre[1] + height / 2))


def boxes_intersect(a, b) -> bool:
    return bool(a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3])


def place_region_labels(regions: dict, scale: float, taken: list, picture_size) -> dict[str, tuple[float, float]]:
    """Where to write each region's name (corner origin) so that it covers none of the ``taken`` boxes (the
    object numbers) nor another region's name: inside the region's top left corner when that is free, else
    the first free spot among the other corners, just outside, and then further and further away."""
    width, height = picture_size
    taken = list(taken)
    origins = {}
    for name, corners in regions.items():
        corners = np.asarray(corners, dtype=float)
        (text_w, text_h), _ = cv2.getTextSize(name, FONT, scale, 1)
        (x0, y0), (x1, y1) = corners.min(axis=0), corners.max(axis=0)
        candidates = [(x0 + 4, y0 + text_h + 5), (x1 - text_w - 4, y0 + text_h + 5), (x0 + 4, y1 - 6),
                      (x1 - text_w - 4, y1 - 6), (x0, y0 - 6), (x0, y1 + text_h + 6)]
        for step in range(1, 40):   # then a widening ring of spots around the region's top left corner
            d = 6 * step
            candidates += [(x0 + 4 + dx, y0 + text_h + 5 + dy) for dx, dy in
                           ((0, -d), (0, d), (-d, 0), (d, 0), (-d, -d), (d, -d), (-d, d), (d, d))]
        chosen = None
        for origin in candidates:
            box = text_box(name, origin, scale)
            if box[0] < 0 or box[1] < 0 or box[2] > width or box[3] > height:
                continue
            if not any(boxes_intersect(box, other) for other in taken):
                chosen = origin
                break
        origins[name] = chosen if chosen is not None else candidates[0]
        taken.append(text_box(name, origins[name], scale))
    return origins


def location_corners(location) -> np.ndarray:
    """The four corners (4, 3) of a location's region on the counter top."""
    cx, cy = location.centre[:2]
    hx, hy = location.half_size
    return np.array([[cx - hx, cy - hy, 0], [cx + hx, cy - hy, 0], [cx + hx, cy + hy, 0], [cx - hx, cy + hy, 0]])


def draw_regions(picture: np.ndarray, regions: dict, colour, text_scale: float, taken: list) -> dict:
    """Outline every region (name: corner pixels (4, 2)) and write its name where it covers none of the
    ``taken`` boxes (see :func:`place_region_labels`). Returns each name's text box."""
    origins = place_region_labels(regions, text_scale, taken, (picture.shape[1], picture.shape[0]))
    for name, corners in regions.items():
        cv2.polylines(picture, [np.round(np.asarray(corners)).astype(np.int32)], True, colour, 2, cv2.LINE_AA)
        outlined_text(picture, name, origins[name], text_scale, colour, anchor="corner")
    return {name: text_box(name, origin, text_scale) for name, origin in origins.items()}


def draw_numbers(picture: np.ndarray, numbers: list[tuple[str, tuple]], scale: float, colour) -> list:
    """Write each (text, centre) number, outlined; returns their text boxes."""
    boxes = []
    for text, centre in numbers:
        outlined_text(picture, text, centre, scale, colour, 2)
        boxes.append(text_box(text, centred_origin(text, centre, scale, 2), scale, 2))
    return boxes


def annotate(images: CameraImages, scene: Scene, kitchen: Kitchen, scale: int = 2,
             boxes: dict | None = None) -> np.ndarray:
    """The camera picture (RGB, enlarged ``scale`` times, turned to the teacher's view) with every object's
    number and perceived box, the outline and name of every semantic location (placed where no number
    is), and the robot's base. ``boxes``, when given, receives the numbers' and names' text boxes."""
    view = TeacherPicture(images, Viewpoint.of_kitchen(kitchen), scale)
    picture = view.rgb.copy()
    base = view.pixels([kitchen.robot_base])[0]
    cv2.drawMarker(picture, tuple(np.round(base).astype(int)), LOCATION_COLOUR, cv2.MARKER_TILTED_CROSS, 14, 2)
    outlines = scene.outlines if scene.outlines is not None else np.zeros((0, 4, 2))
    for index in range(scene.n_objects):
        top = scene.positions[index, 2] + scene.tops[index] / 2
        if index < len(outlines):
            corners = view.pixels(np.c_[outlines[index], np.full(4, top)])
            cv2.polylines(picture, [np.round(corners).astype(np.int32)], True, BOX_COLOUR, 1, cv2.LINE_AA)
    numbers = [(str(index + 1), tuple(view.pixels([[*scene.positions[index, :2],
                                                     scene.positions[index, 2] + scene.tops[index] / 2]])[0]))
               for index in range(scene.n_objects)]
    number_boxes = [text_box(text, centred_origin(text, centre, 0.3 * scale, 2), 0.3 * scale, 2)
                    for text, centre in numbers]
    regions = {name: view.pixels(location_corners(location)) for name, location in kitchen.locations.items()}
    region_boxes = draw_regions(picture, regions, LOCATION_COLOUR, 0.45, number_boxes)
    draw_numbers(picture, numbers, 0.3 * scale, TEXT_COLOUR)
    if boxes is not None:
        boxes.update(numbers=number_boxes, regions=region_boxes)
    return picture


def write_png(path, picture_rgb: np.ndarray) -> None:
    """Write an RGB picture as PNG (one-line error naming the path when it fails)."""
    if not cv2.imwrite(str(path), cv2.cvtColor(picture_rgb, cv2.COLOR_RGB2BGR)):
        raise OutputPathError(f"could not write a PNG to '{path}' (does the folder exist and end the name in .png?)")
