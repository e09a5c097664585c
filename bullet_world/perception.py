"""Per-object measurements from rendered RGB-D and segmentation images.

A pure function of the images and the camera matrices (no simulator), so it can
be tested on synthetic images. Sizes and locations come from the depth image
turned into a point cloud, never from the simulator's poses. All objects are
measured in one pass: the object pixels are gathered once, deprojected once and
split by body, and keypoints and edges are found once on the whole image.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np

VOLUME_CELL_M = 0.004      # grid cell for the volume under the visible surface
INTERIOR_PX = 3            # keypoints and edges count only this far inside an object's outline
TOP_PERCENTILE = 97.0      # the object's top: robust to a few noisy depth pixels
SMOOTHING_PX = 2           # depth is averaged over (2k+1)^2 pixels inside one object before deprojection
# Where the TinyRenderer samples pixel (row, col) in normalised device coordinates (measured: with a
# pixel-centre convention every location came out half a pixel off in x and y).
PIXEL_X_OFFSET, PIXEL_Y_OFFSET = 0.0, 1.0
_ORB = None


@dataclass
class ObjectMeasurement:
    """What the camera tells about one object (metres, radians, colours in 0..1)."""

    body_id: int
    pixels: int
    mean_rgb: np.ndarray   # (3,)
    length: float          # longer side of the rotated footprint box
    width: float           # shorter side
    height: float          # top of the object above the counter
    centroid: np.ndarray   # (3,) centre of the bounding box, world frame
    yaw: float             # orientation of the long side, in [0, pi)
    top_area: float        # footprint area of the point cloud's convex hull, m^2
    hsv: np.ndarray = field(default_factory=lambda: np.zeros(3))  # hue, saturation, value of the mean colour
    variation: float = 0.0     # standard deviation of brightness over the object
    contrast: float = 0.0      # 90th minus 10th percentile of brightness
    keypoints: int = 0         # ORB keypoints inside the object's outline
    edge_density: float = 0.0  # share of interior pixels on Canny edges
    volume: float = 0.0        # volume under the visible surface, m^3
    perimeter: float = 0.0     # of the footprint's convex hull, m
    top_drop: float = 0.0      # (top - median point height) / height

    @property
    def box_corners(self) -> np.ndarray:
        """(4, 2) corners of the rotated footprint box in world x, y."""
        c, s = np.cos(self.yaw), np.sin(self.yaw)
        u, v = np.array([c, s]) * self.length / 2, np.array([-s, c]) * self.width / 2
        centre = np.asarray(self.centroid[:2])
        return np.array([centre + u + v, centre - u + v, centre - u - v, centre + u - v])


def deproject(depth_buffer: np.ndarray, view_matrix: np.ndarray, projection_matrix: np.ndarray,
              rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
    """World coordinates (N, 3) of the pixels (rows, cols) from the OpenGL depth buffer."""
    height, width = depth_buffer.shape
    x_ndc = (2.0 * (cols + PIXEL_X_OFFSET) / width) - 1.0
    y_ndc = 1.0 - (2.0 * (rows + PIXEL_Y_OFFSET) / height)
    z_ndc = 2.0 * depth_buffer[rows, cols].astype(float) - 1.0
    inverse = np.linalg.inv(projection_matrix @ view_matrix)
    world = [inverse[i, 0] * x_ndc + inverse[i, 1] * y_ndc + inverse[i, 2] * z_ndc + inverse[i, 3] for i in range(4)]
    return np.column_stack([world[0] / world[3], world[1] / world[3], world[2] / world[3]])


def _orb():
    global _ORB
    if _ORB is None:
        _ORB = cv2.ORB_create(nfeatures=20000, scaleFactor=1.5, nlevels=2, edgeThreshold=7, patchSize=7,
                              fastThreshold=14)
    return _ORB


def _group_starts(counts: np.ndarray) -> np.ndarray:
    return np.r_[0, np.cumsum(counts)]


def _grouped_quantiles(values: np.ndarray, labels: np.ndarray, counts: np.ndarray, fractions) -> np.ndarray:
    """(groups, fractions) order statistics (nearest rank) of ``values`` grouped by sorted ``labels``."""
    ordered = values[np.lexsort((values, labels))]
    ranks = np.round(np.outer(np.maximum(counts - 1, 0), fractions)).astype(np.int64)
    return ordered[np.minimum(_group_starts(counts)[:-1, None] + ranks, max(len(ordered) - 1, 0))]


def _grouped_mean_top(points: np.ndarray, labels: np.ndarray, counts: np.ndarray, cells: np.ndarray,
                      counter_z: float) -> np.ndarray:
    """Per group: the average over a grid (cell size per group) of the highest visible point in each
    occupied cell, as height above the counter. Times the footprint area: the volume under the surface."""
    n = len(counts)
    present = np.flatnonzero(counts > 0)
    starts = _group_starts(counts)[present]
    origin = np.zeros((n, 2))
    origin[present, 0] = np.minimum.reduceat(points[:, 0], starts)
    origin[present, 1] = np.minimum.reduceat(points[:, 1], starts)
    grid = np.floor((points[:, :2] - origin[labels]) / cells[labels, None]).astype(np.int64)
    rows = np.zeros(n, dtype=np.int64)
    rows[present] = np.maximum.reduceat(grid[:, 1], starts) + 1
    local = grid[:, 0] * rows[labels] + grid[:, 1]
    sizes = np.zeros(n, dtype=np.int64)
    sizes[present] = np.maximum.reduceat(local, starts) + 1
    key = _group_starts(sizes)[:-1][labels] + local
    tops = np.zeros(int(sizes.sum()))
    np.maximum.at(tops, key, np.maximum(points[:, 2] - counter_z, 0.0))
    occupied = np.bincount(key, minlength=len(tops)) > 0
    owner = np.repeat(np.arange(n), sizes)[occupied]
    cells_seen = np.bincount(owner, minlength=n)
    total = np.bincount(owner, weights=tops[occupied], minlength=n)
    return np.divide(total, cells_seen, out=np.zeros(n), where=cells_seen > 0)


def _measure_groups(points, colours, gray, labels, counts, outline, pixel_m, counter_z,
                    body_ids) -> list[ObjectMeasurement | None]:
    """Measurements of every group of points (sorted by label); None for an empty group. Statistics are
    computed for all groups at once; only the footprint hull and box are per group."""
    n = len(counts)
    safe = np.maximum(counts, 1)
    mean_rgb = np.column_stack([np.bincount(labels, weights=colours[:, c], minlength=n) for c in range(3)])
    mean_rgb /= 255.0 * safe[:, None]
    brightness = np.asarray(gray, dtype=float) / 255.0
    mean_b = np.bincount(labels, weights=brightness, minlength=n) / safe
    squares = np.bincount(labels, weights=brightness ** 2, minlength=n) / safe
    variation = np.sqrt(np.maximum(squares - mean_b ** 2, 0.0))
    heights = _grouped_quantiles(points[:, 2], labels, counts, [0.5, TOP_PERCENTILE / 100.0])
    spread = _grouped_quantiles(brightness, labels, counts, [0.1, 0.9])
    mean_top = _grouped_mean_top(points, labels, counts, np.maximum(VOLUME_CELL_M, 1.5 * pixel_m), counter_z)
    hsv = cv2.cvtColor(mean_rgb.astype(np.float32).reshape(1, n, 3), cv2.COLOR_RGB2HSV).reshape(n, 3)
    starts = _group_starts(counts)
    results: list[ObjectMeasurement | None] = []
    for index in range(n):
        if counts[index] == 0:
            results.append(None)
            continue
        part = slice(starts[index], starts[index + 1])
        rim = points[part][outline[part]]
        hull = cv2.convexHull((rim if len(rim) >= 3 else points[part])[:, :2].astype(np.float32))
        (cx, cy), (side_a, side_b), angle = cv2.minAreaRect(hull)
        length, width = (side_a, side_b) if side_a >= side_b else (side_b, side_a)
        yaw = np.radians(angle) if side_a >= side_b else np.radians(angle + 90.0)
        median_z, top = heights[index]
        height = max(float(top) - counter_z, 0.0)
        area = float(cv2.contourArea(hull))
        results.append(ObjectMeasurement(
            body_id=int(body_ids[index]), pixels=int(counts[index]), mean_rgb=mean_rgb[index],
            length=float(length), width=float(width), height=height,
            centroid=np.array([cx, cy, counter_z + height / 2.0]), yaw=float(np.mod(yaw, np.pi)), top_area=area,
            hsv=np.array([hsv[index, 0] / 360.0, hsv[index, 1], hsv[index, 2]], dtype=float),
            variation=float(variation[index]), contrast=float(spread[index, 1] - spread[index, 0]),
            volume=area * float(mean_top[index]), perimeter=float(cv2.arcLength(hull, True)),
            top_drop=float((top - median_z) / height) if height > 0 else 0.0,
        ))
    return results


def measure_object(points: np.ndarray, colours: np.ndarray, body_id: int, counter_z: float,
                   gray: np.ndarray | None = None, outline: np.ndarray | None = None,
                   pixel_m: float = 0.0) -> ObjectMeasurement:
    """Measure one object from its point cloud (N, 3) and pixel colours (N, 3) uint8.

    ``outline`` (N,) marks the points of the object's silhouette pixels: their footprint hull is that of
    all points for objects seen from above, from far fewer points. ``pixel_m``, the size of one pixel on
    the object, sets the grid for the volume (cells of at least 1.5 pixels, so none is left empty).
    """
    count = len(points)
    gray = colours.mean(axis=1) if gray is None else gray
    outline = np.ones(count, dtype=bool) if outline is None else outline
    return _measure_groups(points, colours, gray, np.zeros(count, dtype=np.int64), np.array([count]), outline,
                           np.array([pixel_m]), counter_z, [body_id])[0]


def _neighbourhood_same(segmentation: np.ndarray, radius: int) -> np.ndarray:
    """Pixels whose whole (2r+1)^2 neighbourhood shows the same body."""
    seg = segmentation.astype(np.float32)
    kernel = np.ones((2 * radius + 1, 2 * radius + 1), np.uint8)
    return cv2.erode(seg, kernel) == cv2.dilate(seg, kernel)


def smooth_depth(depth_buffer: np.ndarray, segmentation: np.ndarray) -> np.ndarray:
    """Average the depth over a small window wherever the whole window shows one body (noise down by the
    window size; object edges keep their own pixels)."""
    size = 2 * SMOOTHING_PX + 1
    blurred = cv2.blur(depth_buffer.astype(np.float32), (size, size))
    return np.where(_neighbourhood_same(segmentation, SMOOTHING_PX), blurred, depth_buffer)


def _texture_counts(gray_image: np.ndarray, inside: np.ndarray, n: int):
    """ORB keypoints and Canny edge pixels per object, counted on object interiors (labels, -1 elsewhere)."""
    keypoints = np.zeros(n)
    found = _orb().detect(gray_image, None)
    if found:
        where = np.array([kp.pt for kp in found]).astype(int)
        hit = inside[np.clip(where[:, 1], 0, inside.shape[0] - 1), np.clip(where[:, 0], 0, inside.shape[1] - 1)]
        keypoints = np.bincount(hit[hit >= 0], minlength=n).astype(float)
    flat = inside.ravel()
    valid = flat >= 0
    edges = cv2.Canny(gray_image, 60, 150).ravel() > 0
    interior = np.bincount(flat[valid], minlength=n).astype(float)
    edge_pixels = np.bincount(flat[valid & edges], minlength=n).astype(float)
    return keypoints, np.divide(edge_pixels, interior, out=np.zeros(n), where=interior > 0)


def measure_objects(rgb: np.ndarray, depth_buffer: np.ndarray, segmentation: np.ndarray,
                    view_matrix: np.ndarray, projection_matrix: np.ndarray, body_ids, counter_z: float = 0.0,
                    min_pixels: int = 12, texture: bool = True) -> dict[int, ObjectMeasurement | None]:
    """Measure every requested body; a body seen by fewer than ``min_pixels`` pixels maps to None.

    One pass: object pixels are labelled through a lookup table, sorted by object once, deprojected
    once; ``texture`` adds keypoint counts (ORB) and edge density (Canny) on each object's interior.
    """
    if rgb.shape[:2] != depth_buffer.shape or depth_buffer.shape != segmentation.shape:
        raise ValueError(f"image shapes differ: rgb {rgb.shape}, depth {depth_buffer.shape}, "
                         f"segmentation {segmentation.shape}")
    body_ids = [int(b) for b in body_ids]
    results: dict[int, ObjectMeasurement | None] = {b: None for b in body_ids}
    if not body_ids:
        return results
    n = len(body_ids)
    seg = segmentation.astype(np.int64)
    top_id = max(int(seg.max()), max(body_ids)) + 2
    lookup = np.full(top_id, -1, dtype=np.int64)
    lookup[np.asarray(body_ids) + 1] = np.arange(n)
    label_image = lookup[np.clip(seg, -1, top_id - 2) + 1]
    flat_labels = label_image.ravel()
    pixels = np.flatnonzero(flat_labels >= 0)
    order = np.argsort(flat_labels[pixels], kind="stable")
    pixels = pixels[order]
    labels = flat_labels[pixels]
    counts = np.bincount(labels, minlength=n)
    starts = np.r_[0, np.cumsum(counts)]
    rows, cols = np.divmod(pixels, segmentation.shape[1])
    points = deproject(smooth_depth(depth_buffer, segmentation), view_matrix, projection_matrix, rows, cols)
    colours = rgb.reshape(-1, 3)[pixels]
    gray_image = cv2.cvtColor(np.ascontiguousarray(rgb), cv2.COLOR_RGB2GRAY)
    gray = gray_image.ravel()[pixels].astype(float)
    on_outline = ~_neighbourhood_same(segmentation, 1).ravel()[pixels]
    keypoints, edge_density = np.zeros(n), np.zeros(n)
    if texture:
        inside = np.where(_neighbourhood_same(segmentation, INTERIOR_PX), label_image, -1)
        keypoints, edge_density = _texture_counts(gray_image, inside, n)
    eye = np.linalg.inv(view_matrix)[:3, 3]
    pixel_angle = 2.0 / (projection_matrix[1, 1] * segmentation.shape[0])  # radians per pixel, vertically
    first = np.minimum(starts[:-1], max(len(points) - 1, 0))
    distance = np.linalg.norm(points[first] - eye, axis=1) if len(points) else np.zeros(n)
    measured = _measure_groups(points, colours, gray, labels, counts, on_outline, distance * pixel_angle, counter_z,
                               body_ids)
    for index, body in enumerate(body_ids):
        if counts[index] < min_pixels:
            continue
        measurement = measured[index]
        measurement.keypoints = int(keypoints[index])
        measurement.edge_density = float(edge_density[index])
        results[body] = measurement
    return results
