"""An overhead RGB-D camera rendered with PyBullet's TinyRenderer (no display needed), with sensor noise.

The TinyRenderer spends most of a frame shading the large counter top behind
the objects. A flat, evenly coloured plane under a directional light has one
shaded colour and a depth given by a ray-plane intersection, so the camera can
take it out of the render and paint it back analytically (same colour model,
same depth, same segmentation id): the objects and the arm are still really
rendered, and the frame costs a fraction of the time.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pybullet as p

DEPTH_NOISE_M_AT_1M = 0.0004   # depth noise standard deviation grows with the square of the distance
RGB_NOISE = 2.0                # colour noise standard deviation, in 0..255 units
SPECULAR = 0.05
HIDDEN_Z = -50.0               # where the backdrop body waits while a frame renders


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
    """TinyRenderer light: direction (towards the light), ambient and diffuse coefficients, colour."""

    direction: tuple[float, float, float]
    ambient: float
    diffuse: float
    colour: tuple[float, float, float] = (1.0, 1.0, 1.0)

    @classmethod
    def sample(cls, config: dict, rng: np.random.Generator) -> Lighting:
        """Draw a lighting condition around the kitchen's nominal one."""
        direction = np.asarray(config["direction"]) + rng.normal(0.0, config["direction_jitter"], 3)
        direction[2] = abs(direction[2]) + 0.3  # the light stays above the counter
        colour = np.asarray(config.get("colour", (1.0, 1.0, 1.0)))
        warmth = rng.normal(0.0, config.get("colour_jitter", 0.0))
        colour = np.clip(colour + warmth * np.array([1.0, 0.0, -1.0]), 0.0, 1.0)
        return cls(tuple(direction / np.linalg.norm(direction)), float(rng.uniform(*config["ambient"])),
                   float(rng.uniform(*config["diffuse"])), tuple(float(c) for c in colour))

    def plane_shade(self) -> float:
        """Brightness factor of a horizontal surface facing up under this light."""
        return self.ambient + self.diffuse * max(0.0, float(self.direction[2]))


@dataclass
class Backdrop:
    """A flat counter top painted analytically instead of rendered."""

    body: int
    centre: tuple[float, float]
    half_size: tuple[float, float]
    top_z: float
    colour: tuple[float, float, float]


class Camera:
    """Pinhole camera defined by eye, target, up and vertical field of view."""

    def __init__(self, eye, target, up, fov_degrees, width, height, near, far):
        self.width, self.height, self.near, self.far = int(width), int(height), float(near), float(far)
        self.eye = np.asarray(eye, dtype=float)
        self._view = p.computeViewMatrix(list(eye), list(target), list(up))
        self._projection = p.computeProjectionMatrixFOV(fov_degrees, width / height, near, far)
        self.backdrop: Backdrop | None = None
        self._plane: tuple[np.ndarray, np.ndarray, Backdrop] | None = None

    @classmethod
    def from_config(cls, config: dict) -> Camera:
        return cls(**config)

    @property
    def view_matrix(self) -> np.ndarray:
        return np.asarray(self._view, dtype=float).reshape(4, 4, order="F")

    @property
    def projection_matrix(self) -> np.ndarray:
        return np.asarray(self._projection, dtype=float).reshape(4, 4, order="F")

    def set_backdrop(self, backdrop: Backdrop | None) -> None:
        """Paint this flat body analytically instead of rendering it (see the module note)."""
        if backdrop != self.backdrop:
            self._plane = None
        self.backdrop = backdrop

    def _backdrop_plane(self) -> tuple[np.ndarray, np.ndarray]:
        """Which pixels see the backdrop's top, and the depth-buffer value there (computed once)."""
        if self._plane is None or self._plane[2] != self.backdrop:
            backdrop = self.backdrop
            rows, cols = np.mgrid[0:self.height, 0:self.width]
            x_ndc = 2.0 * (cols + 0.5) / self.width - 1.0
            y_ndc = 1.0 - 2.0 * (rows + 0.5) / self.height
            clip = np.stack([x_ndc.ravel(), y_ndc.ravel(), np.ones(x_ndc.size), np.ones(x_ndc.size)])
            far = np.linalg.inv(self.projection_matrix @ self.view_matrix) @ clip
            direction = (far[:3] / far[3]).T - self.eye
            t = (backdrop.top_z - self.eye[2]) / direction[:, 2]
            hit = self.eye + t[:, None] * direction
            on_top = (np.abs(hit[:, 0] - backdrop.centre[0]) <= backdrop.half_size[0]) & \
                     (np.abs(hit[:, 1] - backdrop.centre[1]) <= backdrop.half_size[1]) & (t > 0)
            projected = self.projection_matrix @ self.view_matrix @ np.c_[hit, np.ones(len(hit))].T
            depth = (((projected[2] / projected[3]) + 1.0) / 2.0).astype(np.float32)
            self._plane = (on_top.reshape(self.height, self.width), depth.reshape(self.height, self.width), backdrop)
        return self._plane[0], self._plane[1]

    def _paint_backdrop(self, rgb, depth, seg, lighting: Lighting) -> None:
        on_top, plane_depth = self._backdrop_plane()
        paint = on_top & (seg < 0)
        shade = np.asarray(self.backdrop.colour) * lighting.plane_shade() * np.asarray(lighting.colour)
        np.copyto(rgb, np.clip(shade * 255.0, 0, 255).astype(np.uint8), where=paint[..., None])
        np.copyto(depth, plane_depth, where=paint)
        np.copyto(seg, np.int32(self.backdrop.body), where=paint)

    def render(self, client: int, lighting: Lighting, rng: np.random.Generator | None = None) -> CameraImages:
        """Render colour, depth and segmentation with the TinyRenderer; add sensor noise when ``rng`` is given."""
        hidden = None
        if self.backdrop is not None:
            hidden = p.getBasePositionAndOrientation(self.backdrop.body, physicsClientId=client)
            p.resetBasePositionAndOrientation(self.backdrop.body, [0, 0, HIDDEN_Z], hidden[1],
                                              physicsClientId=client)
        try:
            _, _, rgba, depth, seg = p.getCameraImage(
                self.width, self.height, self._view, self._projection,
                renderer=p.ER_TINY_RENDERER, lightDirection=list(lighting.direction),
                lightColor=list(lighting.colour), lightAmbientCoeff=lighting.ambient,
                lightDiffuseCoeff=lighting.diffuse, lightSpecularCoeff=SPECULAR, shadow=0, physicsClientId=client,
            )
        finally:
            if hidden is not None:
                p.resetBasePositionAndOrientation(self.backdrop.body, hidden[0], hidden[1], physicsClientId=client)
        rgb = np.ascontiguousarray(np.asarray(rgba, dtype=np.uint8).reshape(self.height, self.width, 4)[:, :, :3])
        depth = np.array(depth, dtype=np.float32).reshape(self.height, self.width)
        seg = np.array(seg, dtype=np.int32).reshape(self.height, self.width)
        if self.backdrop is not None:
            self._paint_backdrop(rgb, depth, seg, lighting)
        if rng is not None:
            rgb, depth = self._add_noise(rgb, depth, seg, rng)
        return CameraImages(rgb=rgb, depth_buffer=depth, segmentation=seg, view_matrix=self.view_matrix,
                            projection_matrix=self.projection_matrix)

    def _add_noise(self, rgb: np.ndarray, depth: np.ndarray, seg: np.ndarray, rng: np.random.Generator):
        """Gaussian colour noise, and depth noise whose spread grows with distance squared (structured
        light), on every pixel that shows an object or the arm (the painted counter stays clean)."""
        backdrop = self.backdrop.body if self.backdrop is not None else -2
        foreground = np.flatnonzero((seg.ravel() >= 0) & (seg.ravel() != backdrop))
        flat_rgb = rgb.reshape(-1, 3)
        noise = rng.standard_normal((foreground.size, 3), dtype=np.float32) * RGB_NOISE
        flat_rgb[foreground] = np.clip(flat_rgb[foreground] + noise, 0, 255).astype(np.uint8)
        n, f = self.near, self.far
        flat_depth = depth.reshape(-1)
        z_ndc = 2.0 * flat_depth[foreground].astype(np.float64) - 1.0
        distance = 2.0 * n * f / (f + n - z_ndc * (f - n))
        distance += rng.standard_normal(distance.size) * DEPTH_NOISE_M_AT_1M * distance ** 2
        flat_depth[foreground] = ((f + n - 2.0 * n * f / distance) / (f - n) + 1.0) / 2.0
        return rgb, depth
