"""Demonstration parsing (eq. 4.1, 4.2), grounding and object choice (§4.2.3, §4.2.4)."""

import numpy as np
import pytest

from learning.recipes.format import RecipeStep, load_builtin_recipe
from learning.recipes.grounding import (
    MATCH,
    NO_LIKELY_MATCH,
    NO_OBJECT_IN_START_REGION,
    ActionObservation,
    RecipeGrounding,
    Snapshot,
    parse_action,
)

# A synthetic kitchen: region centres relative to the robot (metres) and the
# appearance (r, g, b, length, width, height) of each object kind.
REGIONS = {
    "stove": np.array([0.5, 0.4, 0.9]),
    "cupboard": np.array([0.5, -0.5, 1.2]),
    "fridge": np.array([0.9, -0.1, 1.0]),
    "counter": np.array([0.3, 0.0, 0.8]),
    "far-shelf": np.array([0.1, 0.6, 1.1]),
}
APPEARANCE = {
    "pasta-pot": np.array([0.6, 0.6, 0.6, 0.25, 0.25, 0.15]),
    "bowl": np.array([0.8, 0.1, 0.1, 0.18, 0.18, 0.08]),
    "pasta-sauce": np.array([0.1, 0.5, 0.1, 0.07, 0.07, 0.20]),
    "blue-cup": np.array([0.1, 0.1, 0.8, 0.08, 0.08, 0.10]),
}
# Objects of the scene: kind and home region. The red-bowl look-alike lives on
# a far shelf; the blue cup is a distractor inside the cupboard.
OBJECTS = [
    ("pasta-pot", "stove"),
    ("bowl", "cupboard"),
    ("pasta-sauce", "fridge"),
    ("bowl", "far-shelf"),
    ("blue-cup", "cupboard"),
]
TARGET_INDEX = {"pasta-pot": 0, "bowl": 1, "pasta-sauce": 2}
SENSOR_NOISE = np.array([0.02, 0.02, 0.02, 0.005, 0.005, 0.005])
LOCATION_NOISE = 0.005


def observe(rng, appearance, locations):
    """A noisy snapshot of the true state."""
    return Snapshot(
        appearance + rng.normal(0, SENSOR_NOISE, appearance.shape),
        locations + rng.normal(0, LOCATION_NOISE, locations.shape),
    )


def placed_in(rng, region, spread=0.06):
    """Somewhere on the region: demonstrations vary placement by +-6 cm in x and y."""
    return REGIONS[region] + np.append(rng.uniform(-spread, spread, 2), 0.0)


def initial_state(rng, spread=0.06):
    appearance = np.array([APPEARANCE[kind] for kind, _ in OBJECTS])
    locations = np.array([placed_in(rng, region, spread) for _, region in OBJECTS])
    return appearance, locations


def execution_scene(seed):
    """A new scene at execution time, objects well inside their regions."""
    return initial_state(np.random.default_rng(seed), spread=0.03)


def demonstrate(recipe, rng):
    """One demonstration: before/after snapshots of every step of the recipe."""
    appearance, locations = initial_state(rng)
    observations = []
    for step in recipe.steps:
        before = observe(rng, appearance, locations)
        locations = locations.copy()
        locations[TARGET_INDEX[step.object]] = placed_in(rng, step.end)
        observations.append(ActionObservation(before, observe(rng, appearance, locations)))
    return observations


@pytest.fixture(scope="module")
def pasta():
    return load_builtin_recipe("serve-pasta")


@pytest.fixture(scope="module")
def grounding(pasta):
    rng = np.random.default_rng(7)
    learner = RecipeGrounding(rng=np.random.default_rng(0))
    learner.learn(pasta, [demonstrate(pasta, rng) for _ in range(6)])
    return learner


@pytest.mark.parametrize("seed", range(10))
def test_moved_object_is_found_among_noisy_distractors(seed):
    rng = np.random.default_rng(seed)
    n_objects = 8
    appearance = rng.uniform(0, 1, (n_objects, 6))
    locations = rng.uniform(-0.6, 0.6, (n_objects, 3))
    moved = int(rng.integers(n_objects))
    after_locations = locations.copy()
    after_locations[moved] += rng.choice([-1, 1], 3) * rng.uniform(0.1, 0.3, 3)
    before = Snapshot(
        appearance + rng.normal(0, 0.02, appearance.shape), locations + rng.normal(0, 0.01, (n_objects, 3))
    )
    after = Snapshot(
        appearance + rng.normal(0, 0.02, appearance.shape), after_locations + rng.normal(0, 0.01, (n_objects, 3))
    )
    action = parse_action(before, after)
    assert action.moved_index == moved
    np.testing.assert_array_equal(action.start_location, before.locations[moved])
    np.testing.assert_array_equal(action.end_location, after.locations[moved])
    np.testing.assert_array_equal(action.appearance_before, before.features[moved])
    np.testing.assert_array_equal(action.appearance_after, after.features[moved])
    assert action.change == pytest.approx(np.linalg.norm(after.locations[moved] - before.locations[moved]))


def test_lighting_change_is_ignored_by_default_and_counted_when_weighted():
    appearance = np.array([[0.2, 0.2, 0.2, 0.1, 0.1, 0.1], [0.8, 0.1, 0.1, 0.2, 0.2, 0.1]])
    locations = np.array([[0.0, 0.0, 0.8], [0.3, 0.3, 0.8]])
    brighter = appearance.copy()
    brighter[0, :3] += 0.5  # object 0 looks brighter but stays put
    moved = locations.copy()
    moved[1, 0] += 0.05  # object 1 moves 5 cm
    before, after = Snapshot(appearance, locations), Snapshot(brighter, moved)
    assert parse_action(before, after).moved_index == 1
    assert parse_action(before, after, appearance_weight=1.0).moved_index == 0


def test_bad_snapshots_are_rejected_with_the_reason():
    one = Snapshot(np.zeros((2, 6)), np.zeros((2, 3)))
    with pytest.raises(ValueError, match="no object changed"):
        parse_action(one, one)
    with pytest.raises(ValueError, match="before has 2 objects but after has 3"):
        parse_action(one, Snapshot(np.zeros((3, 6)), np.ones((3, 3))))
    with pytest.raises(ValueError, match=r"locations must be an \(n_objects x 3\) array"):
        Snapshot(np.zeros((2, 6)), np.zeros((2, 2)))
    with pytest.raises(ValueError, match="2 feature rows but 3 location rows"):
        Snapshot(np.zeros((2, 6)), np.zeros((3, 3)))


def test_learning_builds_one_model_per_recipe_parameter(grounding):
    assert set(grounding.object_models) == {"pasta-pot", "bowl", "pasta-sauce"}
    assert set(grounding.location_models) == {"stove", "cupboard", "fridge", "counter"}
    assert grounding.object_models["bowl"].samples_.shape == (12, 6)  # pre and post, 6 demos
    assert grounding.location_models["counter"].samples_.shape == (18, 3)  # 3 steps end there
    assert grounding.location_models["stove"].n_demonstrations_ == 6
    moved = [[action.moved_index for action in demo] for demo in grounding.demonstrated_actions]
    assert moved == [[0, 1, 2]] * 6


def test_location_and_object_models_sit_where_the_demonstrations_were(grounding):
    for name in ("stove", "cupboard", "fridge"):
        model = grounding.location_models[name]
        assert model.n_components_ == 1
        assert np.linalg.norm(model.means_[0] - REGIONS[name]) < 0.05
    np.testing.assert_allclose(grounding.object_models["bowl"].means_[0], APPEARANCE["bowl"], atol=0.03)


def test_choose_object_finds_the_right_object_in_the_start_region(grounding, pasta):
    appearance, locations = execution_scene(99)
    for step in pasta.steps:
        choice = grounding.choose_object(step, appearance, locations)
        assert choice.status == MATCH and choice.found
        assert choice.index == TARGET_INDEX[step.object]
        assert choice.index in choice.candidates
    bowl_choice = grounding.choose_object(pasta.steps[1], appearance, locations)
    assert set(bowl_choice.candidates) == {1, 4}  # the bowl and the blue cup are in the cupboard
    assert bowl_choice.object_distances[3] < 3.0  # the look-alike looks right but is elsewhere


def test_look_alike_outside_the_start_region_gives_no_match(grounding, pasta):
    appearance, locations = execution_scene(5)
    locations[1] = REGIONS["counter"]  # the real bowl was already served
    choice = grounding.choose_object(pasta.steps[1], appearance, locations)
    assert choice.status == NO_LIKELY_MATCH and not choice.found
    assert choice.index is None
    assert choice.candidates == (4,)
    assert "looks like 'bowl'" in choice.reason
    locations[4] = REGIONS["far-shelf"]  # and now the cupboard is empty
    empty = grounding.choose_object(pasta.steps[1], appearance, locations)
    assert empty.status == NO_OBJECT_IN_START_REGION
    assert empty.index is None and empty.candidates == ()
    assert "'cupboard'" in empty.reason


def test_end_location_target_is_the_counter(grounding, pasta):
    target = grounding.end_location_target(pasta.steps[0])
    assert target.shape == (3,)
    assert np.linalg.norm(target - REGIONS["counter"]) < 0.05


def test_learning_is_deterministic_and_incremental(pasta):
    demos = [demonstrate(pasta, np.random.default_rng(seed)) for seed in range(4)]
    all_at_once = RecipeGrounding(rng=np.random.default_rng(3))
    all_at_once.learn(pasta, demos)
    one_by_one = RecipeGrounding(rng=np.random.default_rng(3))
    one_by_one.learn(pasta, demos[:1])
    assert one_by_one.location_models["stove"].bic_per_k_.keys() == {1}
    one_by_one.learn(pasta, demos[1:])
    for name, model in all_at_once.location_models.items():
        np.testing.assert_allclose(model.samples_, one_by_one.location_models[name].samples_)
        assert model.n_demonstrations_ == one_by_one.location_models[name].n_demonstrations_ == 4
    again = RecipeGrounding(rng=np.random.default_rng(3))
    again.learn(pasta, demos)
    np.testing.assert_array_equal(again.object_models["bowl"].means_, all_at_once.object_models["bowl"].means_)


def test_single_demonstration_grounding_works(pasta):
    learner = RecipeGrounding(rng=np.random.default_rng(0))
    learner.learn(pasta, [demonstrate(pasta, np.random.default_rng(11))])
    appearance, locations = execution_scene(11)
    choice = learner.choose_object(pasta.steps[0], appearance, locations)
    assert learner.location_models["stove"].n_components_ == 1
    assert choice.location_distances.shape == (len(OBJECTS),)
    assert choice.location_distances[3] > 3.0  # the far shelf is never the stove


def test_bad_demonstrations_and_unknown_steps_are_reported(grounding, pasta):
    demo = demonstrate(pasta, np.random.default_rng(1))
    learner = RecipeGrounding()
    with pytest.raises(ValueError, match="demonstration 1 has 2 actions but recipe 'serve-pasta' has 3 steps"):
        learner.learn(pasta, [demo[:2]])
    still = ActionObservation(demo[0].before, demo[0].before)
    with pytest.raises(ValueError, match="demonstration 2, step 1: no object changed"):
        learner.learn(pasta, [demo, [still, *demo[1:]]])
    assert learner.object_models == {}  # nothing learned from a rejected batch
    with pytest.raises(ValueError, match="no object model for 'kettle'; learned objects: bowl, pasta-pot, pasta-sauce"):
        grounding.choose_object(
            RecipeStep("pick-place", "kettle", "stove", "counter"), np.zeros((1, 6)), np.zeros((1, 3))
        )
    with pytest.raises(ValueError, match="scene_features has 4 features"):
        grounding.choose_object(pasta.steps[0], np.zeros((1, 4)), np.zeros((1, 3)))
