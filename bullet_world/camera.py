"""An overhead RGB-D camera rendered with PyBullet's TinyRenderer (no display needed), with sensor noise.

The TinyRenderer spends most of a frame shading the large counter top behind
the objects. A flat, evenly coloured plane under a directional light has one
shaded colour and a depth given by a ray-plane intersection, so the camera can
take it out of the render and paint it back analytically (same colour model,
same depth, same segmentation id): the objects and the arm are still really
rendered, and the frame costs a fraction of the time. The same goes for what
lies under the worktop (base cabinets, fixture fronts: hidden from above by the
worktop) and for the floor around it, painted flat in its colour beyond the
depth sensor's range. Furniture on and above the worktop is rendered; like the
painted planes it carries no sensor noise (``scenery``), so the noise drawn on
the objects and the arm does not depend on the room.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pybullet as p

DEPTH_NOISE_M_AT_1M = 0.0004   # depth noise standard deviation grows with the square of the distance
RGB_NOISE = 2.0                # colour noise standard deviation, in 0..255 units
SPECULAR = 0.05
UNDER_TOP_DEPTH = 2e-4         # depth-buffer margin (about 0.5 mm at the counter) for "under the worktop"
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
    hidden: tuple[int, ...] = ()        # more bodies under the worktop, taken out of the render with it
    floor: tuple[int, tuple[float, float, float]] | None = None  # (body, colour) painted where nothing else is
    scenery: tuple[int, ...] = ()       # rendered furniture: no sensor noise on its pixels
    decals: tuple[Decal, ...] = ()      # flat pieces lying on the top, painted with it (in this order)


@dataclass(frozen=True)
class Decal:
    """A flat piece lying on the backdrop's top (a fixture's top, a burner ring, a sink): a box's footprint
    (``half`` its half sizes) or a cylinder's disc (``half[0]`` its radius), painted in its own colour."""

    body: int
    shape: str
    centre: tuple[float, float]
    half: tuple[float, float]
    colour: tuple[float, float, float]

    def covers(self, xy: np.ndarray) -> np.ndarray:
        offset = xy - np.asarray(self.centre)
        if self.shape == "cylinder":
            return np.hypot(offset[:, 0], offset[:, 1]) <= self.half[0]
        return (np.abs(offset[:, 0]) <= self.half[0]) & (np.abs(offset[:, 1]) <= self.half[1])


class Camera:
    """Pinhole camera defined by eye, target, up and vertical field of view."""

    def __init__(self, eye, target, up, fov_degrees, width, height, near, far):
        self.width, self.height, self.near, self.far = int(width), int(height), float(near), float(far)
        self.eye = np.asarray(eye, dtype=float)
        self._view = p.computeViewMatrix(list(eye), list(target), list(up))
        self._projection = p.computeProjectionMatrixFOV(fov_degrees, width / height, near, far)
        self.backdrop: Backdrop | None = None
        self._plane: tuple[np.ndarray, np.ndarray, Backdrop, np.ndarray, np.ndarray] | None = None
        self._painted: tuple[tuple[float, ...], np.ndarray] | None = None

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

    def _backdrop_plane(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Which pixels see the backdrop's top, the depth-buffer value there, and the colour (H, W, 3) and
        body id (H, W) painted on every pixel: the top's or a decal's on the top, the floor's elsewhere (-1 and
        no colour without a floor). Computed once per backdrop."""
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
            floor_body, floor_colour = backdrop.floor if backdrop.floor is not None else (-1, (0.0, 0.0, 0.0))
            colours = np.tile(np.asarray(floor_colour, dtype=np.float32), (len(hit), 1))
            bodies = np.full(len(hit), floor_body, dtype=np.int32)
            colours[on_top], bodies[on_top] = backdrop.colour, backdrop.body
            for decal in backdrop.decals:
                covered = on_top & decal.covers(hit[:, :2])
                colours[covered], bodies[covered] = decal.colour, decal.body
            shape = (self.height, self.width)
            self._plane = (on_top.reshape(shape), depth.reshape(shape), backdrop, colours.reshape(*shape, 3),
                           bodies.reshape(shape))
            self._painted = None
        return self._plane[0], self._plane[1], self._plane[3], self._plane[4]

    def _paint_backdrop(self, rgb, depth, seg, lighting: Lighting) -> None:
        """Paint the top (and its decals) where nothing was rendered above it, and the floor (beyond the far
        plane: colour only, depth stays 1) where nothing was rendered at all."""
        on_top, plane_depth, colours, bodies = self._backdrop_plane()
        factor = lighting.plane_shade() * np.asarray(lighting.colour, dtype=np.float32)
        key = tuple(float(v) for v in factor)
        if self._painted is None or self._painted[0] != key:   # one shading per lighting condition
            self._painted = (key, np.clip(colours * factor * 255.0, 0, 255).astype(np.uint8))
        under = on_top & ((seg < 0) | (depth > plane_depth + UNDER_TOP_DEPTH))  # what is under the top is hidden
        paint = under | ((seg < 0) & (bodies >= 0))
        np.copyto(rgb, self._painted[1], where=paint[..., None])
        np.copyto(seg, bodies, where=paint)
        np.copyto(depth, plane_depth, where=under)

    def render(self, client: int, lighting: Lighting, rng: np.random.Generator | None = None) -> CameraImages:
        """Render colour, depth and segmentation with the TinyRenderer; add sensor noise when ``rng`` is given."""
        hidden = {}
        if self.backdrop is not None:
            floor = () if self.backdrop.floor is None else (self.backdrop.floor[0],)
            decals = tuple(decal.body for decal in self.backdrop.decals)
            for body in (self.backdrop.body, *self.backdrop.hidden, *floor, *decals):
                hidden[body] = p.getBasePositionAndOrientation(body, physicsClientId=client)
                p.resetBasePositionAndOrientation(body, [0, 0, HIDDEN_Z], hidden[body][1], physicsClientId=client)
        try:
            _, _, rgba, depth, seg = p.getCameraImage(
                self.width, self.height, self._view, self._projection,
                renderer=p.ER_TINY_RENDERER, lightDirection=list(lighting.direction),
                lightColor=list(lighting.colour), lightAmbientCoeff=lighting.ambient,
                lightDiffuseCoeff=lighting.diffuse, lightSpecularCoeff=SPECULAR, shadow=0, physicsClientId=client,
            )
        finally:
            for body, pose in hidden.items():
                p.resetBasePositionAndOrientation(body, pose[0], pose[1], physicsClientId=client)
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
        light), on every pixel that shows an object or the arm (the painted counter and the room stay clean)."""
        clean = [] if self.backdrop is None else [self.backdrop.body, *self.backdrop.scenery,
                                                  *(decal.body for decal in self.backdrop.decals)]
        if self.backdrop is not None and self.backdrop.floor is not None:
            clean.append(self.backdrop.floor[0])
        flat_seg = seg.ravel()
        noisy = np.ones(max(int(flat_seg.max()), *clean, 0) + 2, dtype=bool)
        noisy[0] = False                     # background (-1)
        noisy[np.asarray(clean, dtype=np.int64) + 1] = False
        foreground = np.flatnonzero(noisy[flat_seg + 1])
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
