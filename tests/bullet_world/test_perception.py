"""Perception on synthetic images: no simulator, analytically ray-cast boxes (with texture if asked)."""

import numpy as np
import pytest

from bullet_world.perception import (
    PIXEL_X_OFFSET,
    PIXEL_Y_OFFSET,
    deproject,
    measure_object,
    measure_objects,
    smooth_depth,
)


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


def render_boxes(boxes, width=320, height=240, eye=(0.0, 0.0, 1.2), checker_m=None):
    """Ray-cast axis-aligned boxes (centre x, y, size l, w, h, colour, id) standing on z = 0, sampling
    pixels where the TinyRenderer does. ``checker_m`` paints box tops with a checkerboard of that pitch."""
    view, proj = look_at(eye, (0, 0, 0), (0, 1, 0)), perspective(60, width / height, 0.1, 3.0)
    inverse = np.linalg.inv(proj @ view)
    rows, cols = np.mgrid[0:height, 0:width]
    x_ndc = (2 * (cols + PIXEL_X_OFFSET) / width) - 1
    y_ndc = 1 - 2 * (rows + PIXEL_Y_OFFSET) / height
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
        if checker_m:
            dark = inside & ((np.floor(point[:, 0] / checker_m) + np.floor(point[:, 1] / checker_m)) % 2 == 0)
            rgb[dark] = np.asarray(colour) // 4
    t = (hit_z - eye[2]) / direction[:, 2]
    world = np.asarray(eye) + t[:, None] * direction
    clip = proj @ view @ np.vstack([world.T, np.ones(len(world))])
    depth = (clip[2] / clip[3] + 1) / 2
    shape = (height, width)
    return rgb.reshape(*shape, 3), depth.reshape(shape).astype(np.float32), seg.reshape(shape), view, proj


PIXEL_M = 2 * 1.2 * np.tan(np.radians(30)) / 240  # metres per pixel on the counter


def test_deproject_inverts_the_projection():
    rgb, depth, seg, view, proj = render_boxes([(0.1, -0.05, 0.2, 0.1, 0.05, (200, 30, 30), 7)])
    rows, cols = np.nonzero(seg == 7)
    points = deproject(depth, view, proj, rows, cols)
    assert np.allclose(points[:, 2], 0.05, atol=1e-3)
    assert points[:, 0].min() == pytest.approx(0.0, abs=PIXEL_M) and points[:, 0].max() == pytest.approx(0.2,
                                                                                                        abs=PIXEL_M)


@pytest.mark.parametrize("cx, cy, length, width, height", [(0.0, 0.0, 0.20, 0.08, 0.05),
                                                           (-0.25, 0.15, 0.12, 0.11, 0.12),
                                                           (0.3, -0.2, 0.07, 0.05, 0.2)])
def test_box_size_location_colour_and_volume(cx, cy, length, width, height):
    colour = (40, 160, 220)
    rgb, depth, seg, view, proj = render_boxes([(cx, cy, length, width, height, colour, 3)])
    measured = measure_objects(rgb, depth, seg, view, proj, [3])[3]
    assert measured.length == pytest.approx(length, abs=2 * PIXEL_M)
    assert measured.width == pytest.approx(width, abs=2 * PIXEL_M)
    assert measured.height == pytest.approx(height, abs=2e-3)
    assert measured.centroid[:2] == pytest.approx([cx, cy], abs=PIXEL_M)
    assert measured.centroid[2] == pytest.approx(height / 2, abs=2e-3)
    assert measured.mean_rgb == pytest.approx(np.array(colour) / 255, abs=1e-6)
    assert measured.volume == pytest.approx(length * width * height, rel=0.25)  # pixels of 5 mm here
    assert measured.top_drop == pytest.approx(0.0, abs=0.02)  # a flat top
    assert measured.hsv[0] == pytest.approx(0.56, abs=0.02)   # sky blue
    assert measured.variation == pytest.approx(0.0, abs=1e-6) and measured.keypoints == 0


def test_box_corners_follow_the_measured_box():
    rgb, depth, seg, view, proj = render_boxes([(0.05, 0.02, 0.16, 0.06, 0.05, (200, 200, 200), 1)])
    corners = measure_objects(rgb, depth, seg, view, proj, [1])[1].box_corners
    assert corners[:, 0].min() == pytest.approx(-0.03, abs=PIXEL_M)
    assert corners[:, 1].max() == pytest.approx(0.05, abs=PIXEL_M)


def test_texture_shows_as_keypoints_and_edges():
    plain = render_boxes([(0.0, 0.0, 0.24, 0.16, 0.05, (220, 200, 60), 1)])
    checked = render_boxes([(0.0, 0.0, 0.24, 0.16, 0.05, (220, 200, 60), 1)], checker_m=0.03)
    smooth = measure_objects(*plain, [1])[1]
    busy = measure_objects(*checked, [1])[1]
    assert smooth.keypoints == 0 and smooth.edge_density == 0.0
    assert busy.keypoints > 10 and busy.edge_density > 0.05
    assert busy.variation > 0.1 and busy.contrast > 0.3


def test_two_objects_are_measured_separately_and_missing_ones_are_none():
    boxes = [(-0.2, 0.0, 0.1, 0.1, 0.05, (255, 0, 0), 1), (0.2, 0.1, 0.15, 0.05, 0.1, (0, 255, 0), 2)]
    rgb, depth, seg, view, proj = render_boxes(boxes)
    result = measure_objects(rgb, depth, seg, view, proj, [1, 2, 99])
    assert result[99] is None
    assert result[1].mean_rgb[0] == pytest.approx(1.0) and result[2].mean_rgb[1] == pytest.approx(1.0)
    assert result[1].centroid[0] < 0 < result[2].centroid[0]


def test_one_pass_agrees_with_one_mask_per_object():
    boxes = [(-0.25, -0.1, 0.1, 0.08, 0.05, (255, 0, 0), 4), (0.0, 0.1, 0.15, 0.05, 0.1, (0, 255, 0), 9),
             (0.25, -0.05, 0.06, 0.06, 0.15, (0, 0, 255), 2)]
    rgb, depth, seg, view, proj = render_boxes(boxes)
    together = measure_objects(rgb, depth, seg, view, proj, [4, 9, 2])
    for body in (4, 9, 2):
        rows, cols = np.nonzero(seg == body)
        alone = measure_object(deproject(smooth_depth(depth, seg), view, proj, rows, cols), rgb[rows, cols],
                               body, 0.0)
        assert together[body].length == pytest.approx(alone.length, abs=1e-6)
        assert together[body].centroid == pytest.approx(alone.centroid, abs=1e-6)


def test_depth_smoothing_never_mixes_two_objects():
    boxes = [(-0.05, 0.0, 0.1, 0.1, 0.03, (255, 0, 0), 1), (0.05, 0.0, 0.1, 0.1, 0.12, (0, 255, 0), 2)]
    rgb, depth, seg, view, proj = render_boxes(boxes)
    rows, cols = np.nonzero(seg == 1)
    points = deproject(smooth_depth(depth, seg), view, proj, rows, cols)
    assert points[:, 2].max() == pytest.approx(0.03, abs=1e-3)


def test_mismatched_images_are_rejected():
    rgb, depth, seg, view, proj = render_boxes([(0, 0, 0.1, 0.1, 0.1, (1, 2, 3), 1)])
    with pytest.raises(ValueError, match="image shapes differ"):
        measure_objects(rgb[:-1], depth, seg, view, proj, [1])
