"""Perception on synthetic images: no simulator, analytically rendered boxes."""

import numpy as np
import pytest

from bullet_world.perception import deproject, measure_objects


def look_at(eye, target, up):
    eye, target, up = (np.asarray(v, dtype=float) for v in (eye, target, up))
    forward = target - eye
    forward /= np.linalg.norm(forward)
    side = np.cross(forward, up)
    side /= np.linalg.norm(side)
    true_up = np.cross(side, forward)
    view = np.eye(4)
    view[0, :3], view[1, :3], view[2, :3] = side, true_up, -forward
    view[:3, 3] = -view[:3, :3] @ eye
    return view


def perspective(fov_degrees, aspect, near, far):
    f = 1.0 / np.tan(np.radians(fov_degrees) / 2)
    proj = np.zeros((4, 4))
    proj[0, 0], proj[1, 1] = f / aspect, f
    proj[2, 2], proj[2, 3] = (far + near) / (near - far), 2 * far * near / (near - far)
    proj[3, 2] = -1.0
    return proj


def render_boxes(boxes, width=320, height=240, eye=(0.0, 0.0, 1.2)):
    """Ray-cast axis-aligned boxes (centre x, y, size l, w, h, colour, id) standing on z = 0."""
    view, proj = look_at(eye, (0, 0, 0), (0, 1, 0)), perspective(60, width / height, 0.1, 3.0)
    inverse = np.linalg.inv(proj @ view)
    rows, cols = np.mgrid[0:height, 0:width]
    x_ndc = (2 * (cols + 0.5) / width) - 1
    y_ndc = 1 - 2 * (rows + 0.5) / height
    far_point = inverse @ np.stack([x_ndc.ravel(), y_ndc.ravel(), np.ones(x_ndc.size), np.ones(x_ndc.size)])
    direction = (far_point[:3] / far_point[3]).T - np.asarray(eye)
    seg = np.full(x_ndc.size, -1, dtype=np.int32)
    rgb = np.full((x_ndc.size, 3), 90, dtype=np.uint8)
    hit_z = np.zeros(x_ndc.size)
    for (cx, cy, length, wid, h, colour, body) in boxes:
        t = (h - eye[2]) / direction[:, 2]
        point = np.asarray(eye) + t[:, None] * direction
        inside = (np.abs(point[:, 0] - cx) <= length / 2) & (np.abs(point[:, 1] - cy) <= wid / 2)
        seg[inside], rgb[inside], hit_z[inside] = body, colour, h
    t = (hit_z - eye[2]) / direction[:, 2]
    world = np.asarray(eye) + t[:, None] * direction
    clip = proj @ view @ np.vstack([world.T, np.ones(len(world))])
    depth = (clip[2] / clip[3] + 1) / 2
    shape = (height, width)
    return rgb.reshape(*shape, 3), depth.reshape(shape).astype(np.float32), seg.reshape(shape), view, proj


def test_deproject_inverts_the_projection():
    rgb, depth, seg, view, proj = render_boxes([(0.1, -0.05, 0.2, 0.1, 0.05, (200, 30, 30), 7)])
    rows, cols = np.nonzero(seg == 7)
    points = deproject(depth, view, proj, rows, cols)
    assert np.allclose(points[:, 2], 0.05, atol=1e-3)


@pytest.mark.parametrize("cx, cy, length, width, height", [(0.0, 0.0, 0.20, 0.08, 0.05),
                                                           (-0.25, 0.15, 0.12, 0.11, 0.12),
                                                           (0.3, -0.2, 0.07, 0.05, 0.2)])
def test_box_size_location_and_colour(cx, cy, length, width, height):
    colour = (40, 160, 220)
    rgb, depth, seg, view, proj = render_boxes([(cx, cy, length, width, height, colour, 3)])
    measured = measure_objects(rgb, depth, seg, view, proj, [3])[3]
    pixel = 2 * 1.2 * np.tan(np.radians(30)) / 240  # metres per pixel on the counter
    assert measured.length == pytest.approx(length, abs=2 * pixel)
    assert measured.width == pytest.approx(width, abs=2 * pixel)
    assert measured.height == pytest.approx(height, abs=2e-3)
    assert measured.centroid[:2] == pytest.approx([cx, cy], abs=pixel)
    assert measured.centroid[2] == pytest.approx(height / 2, abs=2e-3)
    assert measured.mean_rgb == pytest.approx(np.array(colour) / 255, abs=1e-6)


def test_two_objects_are_measured_separately_and_missing_ones_are_none():
    boxes = [(-0.2, 0.0, 0.1, 0.1, 0.05, (255, 0, 0), 1), (0.2, 0.1, 0.15, 0.05, 0.1, (0, 255, 0), 2)]
    rgb, depth, seg, view, proj = render_boxes(boxes)
    result = measure_objects(rgb, depth, seg, view, proj, [1, 2, 99])
    assert result[99] is None
    assert result[1].mean_rgb[0] == pytest.approx(1.0) and result[2].mean_rgb[1] == pytest.approx(1.0)
    assert result[1].centroid[0] < 0 < result[2].centroid[0]


def test_mismatched_images_are_rejected():
    rgb, depth, seg, view, proj = render_boxes([(0, 0, 0.1, 0.1, 0.1, (1, 2, 3), 1)])
    with pytest.raises(ValueError, match="image shapes differ"):
        measure_objects(rgb[:-1], depth, seg, view, proj, [1])
