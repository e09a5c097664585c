"""The viewer draws heavy untextured meshes (the Panda's links) simplified, their shape kept to a millimetre or two."""

import glob
import os

import numpy as np
import pybullet_data
from scipy.spatial import cKDTree

from bullet_world.viewer import meshes
from bullet_world.viewer.meshes import MeshArrays, parse_obj, read_obj, simplified

HAND = os.path.join(pybullet_data.getDataPath(), "franka_panda", "meshes", "visual", "hand.obj")


def surface_points(mesh: MeshArrays, per_triangle: int = 30) -> np.ndarray:
    """Points spread over every triangle of ``mesh`` (a fixed generator: the same points every run)."""
    corners = mesh.positions[mesh.faces].astype(float)
    u = np.random.default_rng(0).random((len(corners), per_triangle, 2))
    outside = u.sum(-1) > 1
    u[outside] = 1 - u[outside]
    a, b, c = corners[:, None, 0], corners[:, None, 1], corners[:, None, 2]
    return (a + u[..., :1] * (b - a) + u[..., 1:] * (c - a)).reshape(-1, 3)


def test_a_heavy_link_keeps_its_shape_with_fewer_triangles():
    full = parse_obj(HAND)
    small = simplified(full, 3000)
    assert len(full.faces) > 7000 and len(small.faces) <= 3000
    np.testing.assert_allclose(np.ptp(small.positions, 0), np.ptp(full.positions, 0), atol=0.002)
    distance, _ = cKDTree(surface_points(small)).query(full.positions)  # each original corner to the new surface
    assert np.percentile(distance, 95) < 0.002
    assert small.faces.max() < len(small.positions) and small.faces.dtype == np.uint32


def test_small_or_textured_meshes_are_left_as_they_are():
    full = parse_obj(HAND)
    assert simplified(full, len(full.faces)) is full
    textured = MeshArrays(full.positions, np.zeros((len(full.positions), 2), np.float32), full.faces)
    assert simplified(textured, 100) is textured


def test_the_viewer_reads_every_panda_link_within_its_triangle_budget():
    files = sorted(glob.glob(os.path.join(os.path.dirname(HAND), "*.obj")))
    full = sum(len(parse_obj(f).faces) for f in files)
    drawn = sum(len(read_obj(f, False, meshes.VIEWER_TRIANGLES).faces) for f in files)
    assert full > 90_000 and drawn <= meshes.VIEWER_TRIANGLES * len(files) and drawn < full / 3
    assert read_obj(HAND, False, None).faces.shape == parse_obj(HAND).faces.shape  # None: the full mesh
