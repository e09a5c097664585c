"""The kitchens as rooms (issue 41): the room's data format is checked field by field, every location is
built as its fixture with its top exactly the location's area, furniture never changes what the camera
measures of an object, and location names on the camera picture never cover an object's number."""

from __future__ import annotations

import numpy as np
import pybullet as p
import pytest

from bullet_world.annotate import annotate, boxes_intersect, place_region_labels, text_box
from bullet_world.catalogue import DATA_DIR, load_kitchen
from bullet_world.datafiles import available
from bullet_world.perception import measure_objects
from bullet_world.room import FIXTURE_TOP_M
from bullet_world.world import World
from tests.datafile_edits import changed, refused

KITCHEN = (DATA_DIR / "kitchens" / "kitchen-1.toml").read_text()


@pytest.mark.parametrize("old, new, fragments", [
    ('fixture = "cooktop"', 'fixture = "oven"', ("[locations.stove]", "fixture 'oven' is not one of", "cooktop")),
    ('material = "black-glass"', 'material = "lava"', ("[locations.stove]", "unknown material 'lava'", "marble")),
    ('floor = "terracotta"', 'floor = "carpet"', ("[room]", "'floor'", "unknown material 'carpet'")),
    ("worktop_height = 0.90", "worktop_height = -1", ("[room]", "'worktop_height'")),
    ("worktop_height = 0.90", "worktop_hight = 0.90", ("[room]", "did you mean 'worktop_height'")),
    ("terracotta = [0.62, 0.36, 0.26]", "terracotta = [0.62, 0.36, 2.0]", ("[materials]", "'terracotta'")),
    ('name = "sink tap"\nshape = "cylinder"', 'name = "sink tap"\nshape = "cone"',
     ("[[furniture]] 8", "shape 'cone' is not one of", "box")),
    ("size = [0.03, 0.03, 0.24]", "size = [0.03, 0.05, 0.24]", ("[[furniture]] 8", "[diameter, diameter, height]")),
    ("centre = [-0.72, 0.47, 0.12]", "centre = [0.0, 0.1, 0.12]",
     ("[[furniture]] 8", "'sink tap'", "where objects may be placed")),
    ('fixture = "fridge"\nmaterial = "steel"\naccent = "dark-steel"\n', "",
     ("[locations.fridge]", "every location is built as a fixture")),
])
def test_a_bad_room_names_the_file_and_field(tmp_path, old, new, fragments):
    path = tmp_path / "kitchen.toml"
    path.write_text(changed(KITCHEN, old, new))
    refused(load_kitchen, path, *fragments)


def test_every_kitchen_is_a_room_whose_fixture_tops_are_the_locations():
    for name in available("kitchens"):
        kitchen = load_kitchen(name)
        assert kitchen.room is not None and set(kitchen.fixtures) == set(kitchen.locations)
        under, above = kitchen.room_pieces()
        assert any(piece.name == "back wall" for piece in above), name
        assert all(piece.top <= 0.0 for piece in under)
        for location_name, location in kitchen.locations.items():
            label = f"{location_name} {kitchen.fixtures[location_name].kind}"
            top = next(piece for piece in above if piece.name == label)
            assert top.top == pytest.approx(FIXTURE_TOP_M) and not top.collision
            assert np.allclose(top.centre[:2], location.centre[:2])
            assert np.allclose(np.asarray(top.size[:2]) / 2, location.half_size)
    colours = {load_kitchen(name).room.door_colour for name in available("kitchens")}
    assert len(colours) == 3   # the kitchens differ in materials


def _hide(world: World, bodies) -> None:
    for body in bodies:
        p.resetBasePositionAndOrientation(body, [0, 0, -80], [0, 0, 0, 1], physicsClientId=world.client)


@pytest.mark.parametrize("kitchen", ["kitchen-1", "kitchen-2", "kitchen-3"])
def test_furniture_changes_no_object_measurement(kitchen):
    """The camera's objects are measured the same with and without the room: furniture neither occludes nor
    shades them, and perception only ever looks at the objects' own segmentation ids."""
    with World(kitchen=kitchen, seed=3, sensor_noise=False) as world:
        scene = world.new_scene(np.random.default_rng(5))
        rendered = world.render()
        assert set(world.furniture) & set(np.unique(rendered.segmentation)), "the room is in the picture"
        _hide(world, [body for body in world.furniture if body not in world.camera.backdrop.hidden
                      and body != world.camera.backdrop.floor[0]])
        bare = world.render()
        bodies = list(world.object_bodies)
        args = (rendered.view_matrix, rendered.projection_matrix, bodies)
        with_room = measure_objects(rendered.rgb, rendered.depth_buffer, rendered.segmentation, *args)
        without = measure_objects(bare.rgb, bare.depth_buffer, bare.segmentation, *args)
        for body in bodies:
            assert with_room[body].pixels == without[body].pixels
            assert np.allclose(with_room[body].centroid, without[body].centroid)
            assert with_room[body].length == pytest.approx(without[body].length)
            assert with_room[body].keypoints == without[body].keypoints
        assert scene.n_objects == len(bodies)


@pytest.mark.parametrize("kitchen, seed", [("kitchen-1", 0), ("kitchen-2", 1), ("kitchen-3", 2), ("kitchen-1", 7)])
def test_object_numbers_never_cover_location_names(kitchen, seed):
    with World(kitchen=kitchen, seed=seed) as world:
        for scene_seed in range(3):
            scene = world.new_scene(np.random.default_rng(100 * seed + scene_seed))
            boxes: dict = {}
            annotate(world.images, scene, world.kitchen, boxes=boxes)
            names = list(boxes["regions"].values())
            for number in boxes["numbers"]:
                assert not any(boxes_intersect(number, name) for name in names)
            for i, a in enumerate(names):
                assert not any(boxes_intersect(a, b) for b in names[i + 1:])


def test_a_name_moves_off_a_number_in_its_corner():
    """A number sitting where the name would go (the old "cu3board") pushes the name elsewhere."""
    corners = np.array([[100.0, 100.0], [200.0, 100.0], [200.0, 160.0], [100.0, 160.0]])
    first = place_region_labels({"cupboard": corners}, 0.45, [], (400, 300))["cupboard"]
    number = text_box("3", (first[0] + 20, first[1]), 0.6, 2)
    moved = place_region_labels({"cupboard": corners}, 0.45, [number], (400, 300))["cupboard"]
    assert boxes_intersect(text_box("cupboard", first, 0.45), number)
    assert not boxes_intersect(text_box("cupboard", moved, 0.45), number)


@pytest.mark.parametrize("kitchen", ["kitchen-1", "kitchen-2", "kitchen-3"])
def test_the_arm_points_at_every_object_without_touching_the_room(kitchen, monkeypatch):
    """Every object of a scene is pointed at (the fingertip ends above it) and at no simulation step on the
    way does the arm touch a piece of the room."""
    import robot.arm
    from robot import Arm
    from robot.gestures import point_at

    touched: set[str] = set()
    with World(kitchen=kitchen, seed=4) as world:
        arm = Arm(world)
        step = robot.arm.p.stepSimulation

        def step_and_look(*args, **kwargs):
            step(*args, **kwargs)
            for contact in p.getContactPoints(bodyA=arm.body_id, physicsClientId=world.client):
                if contact[2] in world.furniture:
                    touched.add(world.furniture[contact[2]])

        monkeypatch.setattr(robot.arm.p, "stepSimulation", step_and_look)
        scene = world.new_scene(np.random.default_rng(11))
        for index in range(scene.n_objects):
            motion = point_at(arm, scene.positions[index], float(scene.tops[index]))
            assert motion.reached, motion.reason
        arm.rest()
    assert not touched
