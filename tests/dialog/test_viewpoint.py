"""One viewpoint, the teacher's: words, scene pictures and turns agree; expert columns explained; ties unguessed."""

import io

import cv2
import numpy as np
import pytest

from bullet_world.annotate import TeacherPicture, outlined_text
from bullet_world.kitchen import load_kitchen
from bullet_world.scene import Scene, SceneTruth
from bullet_world.viewpoint import Viewpoint, picture_turn, turn_image, turn_pixels
from dialog.expert.terminal import COLUMN_MEANINGS, SHORT_NAMES, guess_text, help_text
from dialog.language.describe import OLD_WORLD_VIEWPOINT, SceneDescriber, area_phrase
from dialog.transcripts.records import question_difference
from learning.actions import LabelQuery


def test_the_teacher_stands_across_the_counter_facing_the_robot():
    one, three = Viewpoint.of_kitchen(load_kitchen("kitchen-1")), Viewpoint.of_kitchen(load_kitchen("kitchen-3"))
    assert one.facing == (0.0, -1.0) and list(one.left) == [1.0, 0.0]  # robot at the front edge (-y) facing +y
    assert three.facing == (0.0, 1.0) and list(three.left) == [-1.0, 0.0]  # robot at the back wall facing -y
    robot = np.asarray(load_kitchen("kitchen-1").robot_base[:2])
    assert one.sides(robot)[0, 1] < 0  # the robot is at the back, away from the teacher


def test_words_are_the_teachers_left_right_front_and_back():
    view = Viewpoint.of_kitchen(load_kitchen("kitchen-1"))  # the robot's left (-x) is the teacher's right
    assert area_phrase((0.4, 0.05), view) == "on the left"
    assert area_phrase((-0.4, 0.05), view) == "on the right"
    assert area_phrase((0.0, 0.35), view) == "at the front"  # the teacher's side of the counter
    assert area_phrase((0.3, -0.3), view) == "at the back left"  # beside the robot, on the teacher's left
    assert area_phrase((0.0, 0.05), view) == "in the middle"


@pytest.mark.parametrize("k_and_mirror", [(k, m) for k in range(4) for m in (False, True)])
def test_turned_pixels_follow_the_turned_image(k_and_mirror):
    k, mirror = k_and_mirror
    image = np.zeros((30, 50), dtype=np.uint8)
    image[7, 41] = 255  # row 7, column 41
    turned = turn_image(image, k, mirror)
    column, row = turn_pixels([[41, 7]], k, mirror, 50, 30)[0]
    assert turned[int(row), int(column)] == 255


def test_the_picture_turn_puts_the_robot_up_and_the_teachers_left_left():
    # an overhead camera with +y up and +x right; the teacher faces -y (the robot at the image's bottom now)
    k, mirror = picture_turn(np.array([0.0, 10.0]), np.array([10.0, 0.0]))
    assert (k % 4, mirror) == (2, False)
    assert picture_turn(np.array([0.0, -10.0]), np.array([-10.0, 0.0])) == (0, False)


def test_numbers_keep_a_dark_outline_on_white():
    picture = np.full((60, 120, 3), 255, dtype=np.uint8)
    outlined_text(picture, "12", (60, 30), 0.8, (255, 255, 255), 2)
    dark = picture.sum(axis=2) < 150
    assert dark.sum() > 150  # the white digits on white stay readable: a rim of dark around them
    rows, columns = np.nonzero(dark)
    assert 40 < columns.mean() < 80 and 15 < rows.mean() < 45


@pytest.fixture(scope="module")
def kitchen():
    from dialog.environment import SimulatedKitchen

    environment = SimulatedKitchen(task="pack-lunchbox", kitchen="kitchen-1", seed=3, pictures=True)
    yield environment
    environment.close()


def test_an_object_called_on_the_left_is_in_the_left_half_of_the_scene_picture(kitchen, tmp_path):
    scene = kitchen.next_scene(np.random.default_rng(3))
    describer = SceneDescriber(scene, kitchen.locations, kitchen.viewpoint)
    lefts = [i for i in range(scene.n_objects) if describer.describe(i).endswith("left")]
    rights = [i for i in range(scene.n_objects) if describer.describe(i).endswith("right")]
    assert lefts and rights
    path = kitchen.scene_picture(scene, tmp_path / "scene.png")
    picture = cv2.imread(str(path))
    width = picture.shape[1]
    view = TeacherPicture(kitchen.world.images, kitchen.viewpoint)
    segmentation = turn_image(kitchen.world.images.segmentation, view.k, view.mirror)
    pixels = kitchen._scene_image[2]
    for index in lefts + rights:
        column, row = (int(round(v)) for v in pixels[index])
        assert (column < width / 2) == (index in lefts), describer.describe(index)
        window = segmentation[max(row - 2, 0):row + 3, max(column - 2, 0):column + 3]
        assert kitchen.world.object_bodies[index] in window  # the turned picture shows the object at its number
    base = view.pixels([kitchen.world.kitchen.robot_base])[0]
    assert base[1] < picture.shape[0] * 0.25  # the robot at the top, away from the teacher
    stove = view.pixels([kitchen.locations["stove"].centre])[0]
    region = np.all(np.abs(picture.astype(int) - (255, 220, 40)) < 30, axis=2)  # REGION_BGR outlines
    assert region[:, : width // 2].sum() > 100 and stove[0] < width / 2  # kitchen-1's stove: the teacher's left


def scene_with(positions):
    n = len(positions)
    names = ("size.length", "size.width", "size.height")
    truth = SceneTruth(("x",) * n, ("x",) * n, tuple(range(n)), np.zeros((n, 3)), np.zeros((n, 3)))
    return Scene(1, np.full((n, 3), 0.08), names, np.array(positions, dtype=float), np.zeros(n),
                 np.tile([0.8, 0.1, 0.1], (n, 1)), truth)


def test_a_transcript_with_the_old_side_words_still_resumes():
    scene = scene_with([(-0.3, -0.2, 0), (0.3, 0.3, 0), (0.0, 0.0, 0)])
    now = SceneDescriber(scene, {}, Viewpoint.of_kitchen(load_kitchen("kitchen-1")))
    old = SceneDescriber(scene, {}, OLD_WORLD_VIEWPOINT)
    assert now.describe(0).endswith("at the back right") and old.describe(0).endswith("at the front left")
    from dialog.language.questions import question_text

    action = LabelQuery(0)
    recorded = question_text(action, description=old.describe(0))
    assert question_difference(recorded, action, now, ("fruit",)) == ""
    assert "is not the replay's" in question_difference("What is this thing, number 1?", action, now, ("fruit",))


def test_expert_help_explains_every_column_and_ties_make_no_guess():
    text = help_text()
    assert tuple(COLUMN_MEANINGS)[4:] == SHORT_NAMES  # the table's feature columns, in FEATURE_NAMES order
    for name in (*SHORT_NAMES, "cost", "robot's guess"):
        assert name in COLUMN_MEANINGS and f"  {name}" in text
    assert "classifier discriminability" in text and "prediction margin" in text
    assert guess_text(np.full(4, 0.25), ("fruit", "snack", "main dish", "beverage")) == "no guess yet"
    assert guess_text(np.array([0.1, 0.6, 0.3]), ("fruit", "snack", "main dish")) == "snack 0.60"


def test_the_expert_table_has_its_key_and_help_prints_the_columns(tmp_path):
    from dialog.expert.terminal import PersonChooser
    from tests.dialog.test_expert import scripted_episode

    shown = io.StringIO()
    scripted_episode(tmp_path, 6, PersonChooser(io.StringIO("help\nnone\n"), shown), turns=2)
    text = shown.getvalue()
    assert "ACD discriminability" in text and "'help' explains each" in text  # the table's key under the table
    assert "instance variation: how much" in text  # help, in words
