"""Per-object measurements from rendered RGB-D and segmentation images.

A pure function of the images and the camera matrices (no simulator), so it can
be tested on synthetic images. Sizes and locations come from the depth image
turned into a point cloud, never from the simulator's poses.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np


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


def deproject(depth_buffer: np.ndarray, view_matrix: np.ndarray, projection_matrix: np.ndarray,
              rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
    """World coordinates (N, 3) of the pixels (rows, cols) from the OpenGL depth buffer."""
    height, width = depth_buffer.shape
    x_ndc = (2.0 * (cols + 0.5) / width) - 1.0
    y_ndc = 1.0 - (2.0 * (rows + 0.5) / height)
    z_ndc = 2.0 * depth_buffer[rows, cols].astype(float) - 1.0
    clip = np.stack([x_ndc, y_ndc, z_ndc, np.ones_like(x_ndc)])
    world = np.linalg.inv(projection_matrix @ view_matrix) @ clip
    return (world[:3] / world[3]).T


def measure_object(points: np.ndarray, colours: np.ndarray, body_id: int, counter_z: float) -> ObjectMeasurement:
    """Measure one object from its point cloud (N, 3) and pixel colours (N, 3) uint8."""
    footprint = points[:, :2].astype(np.float32)
    (cx, cy), (side_a, side_b), angle = cv2.minAreaRect(footprint)
    length, width = (side_a, side_b) if side_a >= side_b else (side_b, side_a)
    yaw = np.radians(angle) if side_a >= side_b else np.radians(angle + 90.0)
    top = float(np.percentile(points[:, 2], 99.0))
    height = max(top - counter_z, 0.0)
    hull = cv2.convexHull(footprint)
    return ObjectMeasurement(
        body_id=int(body_id),
        pixels=len(points),
        mean_rgb=colours.mean(axis=0) / 255.0,
        length=float(length),
        width=float(width),
        height=height,
        centroid=np.array([cx, cy, counter_z + height / 2.0]),
        yaw=float(np.mod(yaw, np.pi)),
        top_area=float(cv2.contourArea(hull)),
    )


def measure_objects(rgb: np.ndarray, depth_buffer: np.ndarray, segmentation: np.ndarray,
                    view_matrix: np.ndarray, projection_matrix: np.ndarray, body_ids, counter_z: float = 0.0,
                    min_pixels: int = 12) -> dict[int, ObjectMeasurement | None]:
    """Measure every requested body; a body seen by fewer than ``min_pixels`` pixels maps to None."""
    if rgb.shape[:2] != depth_buffer.shape or depth_buffer.shape != segmentation.shape:
        raise ValueError(f"image shapes differ: rgb {rgb.shape}, depth {depth_buffer.shape}, "
                         f"segmentation {segmentation.shape}")
    results: dict[int, ObjectMeasurement | None] = {}
    for body_id in body_ids:
        rows, cols = np.nonzero(segmentation == body_id)
        if len(rows) < min_pixels:
            results[int(body_id)] = None
            continue
        points = deproject(depth_buffer, view_matrix, projection_matrix, rows, cols)
        results[int(body_id)] = measure_object(points, rgb[rows, cols], body_id, counter_z)
    return results
