"""An overhead RGB-D camera rendered with PyBullet's TinyRenderer (no display needed)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pybullet as p


@dataclass
class CameraImages:
    """One rendered frame plus the matrices needed to turn pixels into 3-D points."""

    rgb: np.ndarray          # (H, W, 3) uint8
    depth_buffer: np.ndarray  # (H, W) float32, OpenGL depth in [0, 1]
    segmentation: np.ndarray  # (H, W) int32, PyBullet body id per pixel (-1 background)
    view_matrix: np.ndarray   # (4, 4) world -> camera
    projection_matrix: np.ndarray  # (4, 4) camera -> clip


@dataclass
class Lighting:
    """TinyRenderer light: direction (towards the light), ambient and diffuse coefficients."""

    direction: tuple[float, float, float]
    ambient: float
    diffuse: float

    @classmethod
    def sample(cls, config: dict, rng: np.random.Generator) -> Lighting:
        """Draw a lighting condition around the kitchen's nominal one."""
        direction = np.asarray(config["direction"]) + rng.normal(0.0, config["direction_jitter"], 3)
        direction[2] = abs(direction[2]) + 0.3  # the light stays above the counter
        return cls(tuple(direction / np.linalg.norm(direction)), float(rng.uniform(*config["ambient"])),
                   float(rng.uniform(*config["diffuse"])))


class Camera:
    """Pinhole camera defined by eye, target, up and vertical field of view."""

    def __init__(self, eye, target, up, fov_degrees, width, height, near, far):
        self.width, self.height, self.near, self.far = int(width), int(height), float(near), float(far)
        self.eye = np.asarray(eye, dtype=float)
        self._view = p.computeViewMatrix(list(eye), list(target), list(up))
        self._projection = p.computeProjectionMatrixFOV(fov_degrees, width / height, near, far)

    @classmethod
    def from_config(cls, config: dict) -> Camera:
        return cls(**config)

    @property
    def view_matrix(self) -> np.ndarray:
        return np.asarray(self._view, dtype=float).reshape(4, 4, order="F")

    @property
    def projection_matrix(self) -> np.ndarray:
        return np.asarray(self._projection, dtype=float).reshape(4, 4, order="F")

    def render(self, client: int, lighting: Lighting) -> CameraImages:
        """Render colour, depth and segmentation with the TinyRenderer."""
        _, _, rgba, depth, seg = p.getCameraImage(
            self.width, self.height, self._view, self._projection,
            renderer=p.ER_TINY_RENDERER, lightDirection=list(lighting.direction),
            lightAmbientCoeff=lighting.ambient, lightDiffuseCoeff=lighting.diffuse,
            lightSpecularCoeff=0.05, shadow=0, physicsClientId=client,
        )
        rgba = np.asarray(rgba, dtype=np.uint8).reshape(self.height, self.width, 4)
        return CameraImages(
            rgb=np.ascontiguousarray(rgba[:, :, :3]),
            depth_buffer=np.asarray(depth, dtype=np.float32).reshape(self.height, self.width),
            segmentation=np.asarray(seg, dtype=np.int32).reshape(self.height, self.width),
            view_matrix=self.view_matrix,
            projection_matrix=self.projection_matrix,
        )
