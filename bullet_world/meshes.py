"""Generated unit meshes (OBJ with texture coordinates) for every shape family.

Each mesh fills the unit cube [-0.5, 0.5]^3, so an object's mesh scale is its
true bounding-box size (length, width, height). Texture coordinates follow one
atlas: u in [0, 0.5) is the outside (skin, label, metal), u in [0.5, 1] the
inside (fruit flesh, the contents of a pot or bowl). Files are written once
into the cache and reused by every world: PyBullet keeps one copy per file.
"""

from __future__ import annotations

import hashlib
import json
from functools import lru_cache
from pathlib import Path

import numpy as np

from bullet_world.datafiles import cache_dir, write_atomically

MESH_VERSION = 4
SEGMENTS = 20            # around a surface of revolution
SLICE_STEP = 0.9         # slices: centre spacing as a fraction of the fruit radius
SLICE_RISE = 0.5         # slices: each slice rests this fraction of its thickness above the previous one


class MeshBuilder:
    """Accumulates vertices, texture coordinates, normals and triangles."""

    def __init__(self):
        self.vertices, self.uvs, self.normals, self.faces = [], [], [], []

    def add(self, vertices, uvs, normals, faces) -> None:
        offset = len(self.vertices)
        self.vertices.extend(np.asarray(vertices, dtype=float).tolist())
        self.uvs.extend(np.asarray(uvs, dtype=float).tolist())
        normals = np.asarray(normals, dtype=float)
        normals = normals / np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-9)
        self.normals.extend(normals.tolist())
        self.faces.extend((np.asarray(faces, dtype=int) + offset).tolist())

    def quad(self, corners, uv_corners, normal) -> None:
        self.add(corners, uv_corners, [normal] * 4, [[0, 1, 2], [0, 2, 3]])

    def disc(self, radius, z, up: bool, u_centre: float, rings=None, centre_xy=(0.0, 0.0)) -> None:
        """A flat disc (radius may vary per angle through ``rings``) facing up or down."""
        angles = np.linspace(0, 2 * np.pi, SEGMENTS, endpoint=False)
        cx, cy = centre_xy
        ring = np.column_stack([cx + radius * np.cos(angles), cy + radius * np.sin(angles), np.full(SEGMENTS, z)])
        points = np.vstack([[cx, cy, z], ring])
        uv = np.column_stack([u_centre + 0.2 * np.r_[0, np.cos(angles)], 0.5 + 0.45 * np.r_[0, np.sin(angles)]])
        faces = [[0, 1 + i, 1 + (i + 1) % SEGMENTS] if up else [0, 1 + (i + 1) % SEGMENTS, 1 + i]
                 for i in range(SEGMENTS)]
        self.add(points, uv, [[0, 0, 1 if up else -1]] * len(points), faces)

    def revolve(self, radii, heights, outward: bool, u_range=(0.0, 0.5), centre_xy=(0.0, 0.0)) -> None:
        """The surface swept by the profile (radii, heights) around the z axis."""
        radii, heights = np.asarray(radii, float), np.asarray(heights, float)
        angles = np.linspace(0, 2 * np.pi, SEGMENTS + 1)
        slope = np.gradient(radii, heights) if len(radii) > 1 else np.zeros_like(radii)
        vertices, uvs, normals = [], [], []
        for r, z, dr in zip(radii, heights, slope):
            for j, a in enumerate(angles):
                vertices.append([centre_xy[0] + r * np.cos(a), centre_xy[1] + r * np.sin(a), z])
                span = (heights[-1] - heights[0]) or 1.0
                uvs.append([u_range[0] + (u_range[1] - u_range[0]) * j / SEGMENTS, (z - heights[0]) / span])
                sign = 1.0 if outward else -1.0
                normals.append([sign * np.cos(a), sign * np.sin(a), -sign * dr])
        faces = []
        ring = SEGMENTS + 1
        for i in range(len(radii) - 1):
            for j in range(SEGMENTS):
                a, b = i * ring + j, (i + 1) * ring + j
                faces += [[a, a + 1, b], [a + 1, b + 1, b]] if outward else [[a, b, a + 1], [a + 1, b, b + 1]]
        self.add(vertices, uvs, normals, faces)

    def obj_text(self) -> str:
        points = np.asarray(self.vertices)
        low, high = points.min(axis=0), points.max(axis=0)
        unit = (points - (low + high) / 2) / np.maximum(high - low, 1e-9)  # fill [-0.5, 0.5]^3
        lines = [f"v {x:.5f} {y:.5f} {z:.5f}" for x, y, z in unit]
        lines += [f"vt {u:.5f} {v:.5f}" for u, v in self.uvs]
        lines += [f"vn {x:.5f} {y:.5f} {z:.5f}" for x, y, z in self.normals]
        lines += ["f " + " ".join(f"{i + 1}/{i + 1}/{i + 1}" for i in face) for face in self.faces]
        return "\n".join(lines) + "\n"


def _box(mesh: MeshBuilder) -> None:
    h = 0.5
    faces = {  # normal: four corners counter-clockwise seen from outside
        (0, 0, 1): [(-h, -h, h), (h, -h, h), (h, h, h), (-h, h, h)],
        (0, 0, -1): [(-h, h, -h), (h, h, -h), (h, -h, -h), (-h, -h, -h)],
        (0, -1, 0): [(-h, -h, -h), (h, -h, -h), (h, -h, h), (-h, -h, h)],
        (0, 1, 0): [(h, h, -h), (-h, h, -h), (-h, h, h), (h, h, h)],
        (1, 0, 0): [(h, -h, -h), (h, h, -h), (h, h, h), (h, -h, h)],
        (-1, 0, 0): [(-h, h, -h), (-h, -h, -h), (-h, -h, h), (-h, h, h)],
    }
    for normal, corners in faces.items():
        mesh.quad(corners, [(0, 0), (0.5, 0), (0.5, 1), (0, 1)], normal)


def _lathe(mesh: MeshBuilder, profile, open_top: bool, fill: float) -> None:
    profile = np.asarray(profile, dtype=float)
    radii, heights = profile[:, 0] / profile[:, 0].max(), profile[:, 1]
    mesh.revolve(radii, heights, outward=True)
    if radii[0] > 0:
        mesh.disc(radii[0], heights[0], up=False, u_centre=0.25)
    if not open_top:
        if radii[-1] > 0:
            mesh.disc(radii[-1], heights[-1], up=True, u_centre=0.25)
        return
    wall, floor = 0.06, 0.08
    inner = np.maximum(radii - wall, 0.02)
    keep = heights > floor
    inner_heights = np.r_[floor, heights[keep]]
    inner_radii = np.r_[np.interp(floor, heights, inner), inner[keep]]
    mesh.revolve(inner_radii, inner_heights, outward=False)
    # rim: an annulus between the inner and outer top edges
    angles = np.linspace(0, 2 * np.pi, SEGMENTS + 1)
    top = heights[-1]
    ring = np.vstack([np.column_stack([r * np.cos(angles), r * np.sin(angles), np.full(angles.size, top)])
                      for r in (radii[-1], inner_radii[-1])])
    uv = np.column_stack([0.5 * np.r_[angles, angles] / (2 * np.pi), np.r_[np.ones(angles.size),
                                                                          np.full(angles.size, 0.95)]])
    n = angles.size
    mesh.add(ring, uv, [[0, 0, 1]] * len(ring), [f for j in range(SEGMENTS)
                                                    for f in ([j, j + 1, n + j], [j + 1, n + j + 1, n + j])])
    if fill > floor:
        mesh.disc(float(np.interp(fill, inner_heights, inner_radii)), fill, up=True, u_centre=0.75)
    else:
        mesh.disc(float(inner_radii[0]), floor, up=True, u_centre=0.25)


def _bag(mesh: MeshBuilder, steps: int = 10) -> None:
    xs, ys = np.linspace(-0.5, 0.5, steps + 1), np.linspace(-0.5, 0.5, steps + 1)
    gx, gy = np.meshgrid(xs, ys, indexing="ij")
    puff = (1 - (2 * gx) ** 8) * (1 - (2 * gy) ** 4)
    top = np.column_stack([gx.ravel(), gy.ravel(), (-0.5 + puff).ravel()])
    grad_x, grad_y = np.gradient(puff, xs, ys)
    normals = np.column_stack([-grad_x.ravel(), -grad_y.ravel(), np.ones(top.shape[0])])
    uv = np.column_stack([0.5 * (gx.ravel() + 0.5), gy.ravel() + 0.5])
    faces = []
    for i in range(steps):
        for j in range(steps):
            a, b = i * (steps + 1) + j, (i + 1) * (steps + 1) + j
            faces += [[a, b, a + 1], [a + 1, b, b + 1]]
    mesh.add(top, uv, normals, faces)
    h = 0.5
    mesh.quad([(-h, h, -h), (h, h, -h), (h, -h, -h), (-h, -h, -h)], [(0, 1), (0.5, 1), (0.5, 0), (0, 0)], (0, 0, -1))


def _slices(mesh: MeshBuilder, count: int) -> None:
    """Fruit rounds shingled in a row: each one a thin disc resting partly on the previous one."""
    radius, thickness = 1.0, 1.0
    for i in range(count):
        x = (i - (count - 1) / 2) * SLICE_STEP * radius
        z0 = i * SLICE_RISE * thickness
        mesh.revolve([radius, radius], [z0, z0 + thickness], outward=True, centre_xy=(x, 0.0))
        mesh.disc(radius * 0.93, z0 + thickness, up=True, u_centre=0.75, centre_xy=(x, 0.0))
        mesh.disc(radius, z0, up=False, u_centre=0.75, centre_xy=(x, 0.0))


def _cylinder(mesh: MeshBuilder) -> None:
    mesh.revolve([1.0, 1.0], [0.0, 1.0], outward=True)
    mesh.disc(1.0, 1.0, up=True, u_centre=0.25)
    mesh.disc(1.0, 0.0, up=False, u_centre=0.25)


def mesh_parameters(look) -> dict:
    """The parameters that decide a state's unit mesh (sizes excluded: they are the mesh scale)."""
    params = {"shape": look.shape}
    if look.shape == "lathe":
        params.update(profile=[list(p) for p in look.profile], open=look.open_top, fill=look.fill)
    if look.shape == "slices":
        params["count"] = look.count
    return params


def build_mesh(params: dict) -> MeshBuilder:
    mesh = MeshBuilder()
    shape = params["shape"]
    if shape == "box":
        _box(mesh)
    elif shape == "cylinder":
        _cylinder(mesh)
    elif shape == "sphere":
        theta = np.linspace(0.0, np.pi, 11)
        mesh.revolve(np.sin(theta) + 1e-6, -np.cos(theta), outward=True)
    elif shape == "lathe":
        _lathe(mesh, params["profile"], params["open"], params["fill"])
    elif shape == "bag":
        _bag(mesh)
    elif shape == "slices":
        _slices(mesh, params["count"])
    else:
        raise ValueError(f"no mesh for shape '{shape}'")
    return mesh


@lru_cache(maxsize=256)
def _mesh_file(key: str, cache: str) -> str:
    params = json.loads(key)
    digest = hashlib.sha1(f"{MESH_VERSION}:{key}".encode()).hexdigest()[:16]
    path = Path(cache) / "assets" / f"mesh-{params['shape']}-{digest}.obj"
    if not path.exists():
        write_atomically(path, build_mesh(params).obj_text().encode())
    return str(path)


def mesh_file(look, cache: str | Path | None = None) -> str:
    """Path of the unit OBJ mesh for a kind state (written to the cache on first use)."""
    return _mesh_file(json.dumps(mesh_parameters(look), sort_keys=True), str(cache_dir(cache)))


def true_size(look, dims: dict[str, float]) -> tuple[float, float, float]:
    """Bounding-box length, width and height (metres) of an object drawn with ``dims``."""
    shape = look.shape
    if shape in ("box", "bag"):
        return dims["length"], dims["width"], dims["height"]
    if shape == "sphere":
        return (2 * dims["radius"],) * 3
    if shape == "slices":
        r, t, n = dims["radius"], dims["height"], look.count
        return 2 * r + (n - 1) * SLICE_STEP * r, 2 * r, t * (1 + SLICE_RISE * (n - 1))
    return 2 * dims["radius"], 2 * dims["radius"], dims["height"]


def footprint(look, dims: dict[str, float]) -> tuple[str, float, float]:
    """("rect", length, width) or ("circle", radius, radius): the object's outline on the counter."""
    length, width, _ = true_size(look, dims)
    if look.shape in ("box", "bag", "slices"):
        return "rect", length, width
    return "circle", length / 2, length / 2
