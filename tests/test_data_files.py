"""One validation layer for every data file kind (issue 13, case 6): each bad file is written to tmp_path and
loaded through the real loader; the error is one line naming the file and the field."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from bullet_world.catalogue import DATA_DIR, load_kitchen, load_object_kinds, load_task
from bullet_world.datafiles import DataFileError as WorldDataFileError
from bullet_world.datafiles import available
from bullet_world.features import load_feature_catalogue
from dialog.cli import main
from dialog.experiments.suite import SUITE_DIR, SuiteError, load_suite, suite_names
from dialog.expert.scripted import RULES_FILE, ExpertRules
from dialog.language.describe import COLOURS_FILE, colour_table
from dialog.language.vocabulary import VOCABULARY_FILE, VocabularyError, load_vocabulary
from learning.datafiles import check_keys, numbers, read_toml, value_range
from learning.decision.weights import PRESETS, preset_weights
from learning.decision.weights_file import load_weights
from learning.errors import DataFileError
from learning.recipes.format import builtin_recipe_names, load_builtin_recipe, load_recipe
from tests.datafile_edits import changed, refused

KITCHEN = (DATA_DIR / "kitchens" / "kitchen-1.toml").read_text()
TASK = (DATA_DIR / "tasks" / "pack-lunchbox.toml").read_text()
SMOKE = (SUITE_DIR / "smoke.toml").read_text()


def write(tmp_path: Path, text: str, name: str = "file.toml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


# -- the layer itself ------------------------------------------------------------------------------------------


def test_the_layer_refuses_missing_binary_and_non_utf8_files(tmp_path):
    with pytest.raises(FileNotFoundError, match="kitchen file .*nowhere.toml does not exist"):
        read_toml(tmp_path / "nowhere.toml", "kitchen")
    binary = tmp_path / "binary.toml"
    binary.write_bytes(b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR")
    with pytest.raises(DataFileError, match="binary.toml: is a binary file"):
        read_toml(binary, "suite")
    latin = tmp_path / "latin.toml"
    latin.write_bytes('name = "caf\xe9"\n'.encode("latin-1"))
    with pytest.raises(DataFileError, match="latin.toml: is not UTF-8 text"):
        read_toml(latin, "task")
    with pytest.raises(DataFileError, match="is not a file"):
        read_toml(tmp_path, "recipe")


def test_the_layer_names_the_field_and_what_is_accepted():
    with pytest.raises(DataFileError, match=r"f.toml: unknown field 'datsets'; accepted fields: name, datasets "
                                            r"\(did you mean 'datasets'\?\)"):
        check_keys({"datsets": 3}, "f.toml", optional=("name", "datasets"))
    with pytest.raises(DataFileError, match=r"unknown field 'x'; accepted fields: a, b$"):
        check_keys({"a": 1, "x": 1}, "f.toml", required=("a",), optional=("a", "b"))
    with pytest.raises(DataFileError, match="f.toml: missing field 'name'"):
        check_keys({}, "f.toml", required=("name",))
    with pytest.raises(DataFileError, match="item 2 of 'x' must be a finite number, got nan"):
        numbers({"x": [1.0, math.nan]}, "x", "f.toml")
    with pytest.raises(DataFileError, match=r"'r' must be \[low, high\] with low <= high, got \[2.0, 1.0\]"):
        value_range({"r": [2, 1]}, "r", "f.toml")
    with pytest.raises(DataFileError, match="'x' must be a list of 2 numbers"):
        numbers({"x": [1]}, "x", "f.toml", length=2)
    with pytest.raises(DataFileError, match="item 1 of 'x' must be a finite number, got True"):
        numbers({"x": [True, 1]}, "x", "f.toml", length=2)
    assert issubclass(WorldDataFileError, DataFileError) and issubclass(SuiteError, DataFileError)
    assert issubclass(VocabularyError, DataFileError)


# -- every shipped data file still loads ----------------------------------------------------------------------


def test_every_shipped_data_file_loads():
    for name in available("kitchens"):
        load_kitchen(name)
    for name in available("tasks"):
        load_task(name)
    for name in available("objects"):
        assert load_object_kinds(name)
    assert len(load_feature_catalogue(DATA_DIR / "features.toml")) > 80
    for name in builtin_recipe_names():
        load_builtin_recipe(name)
    for name in PRESETS:
        assert preset_weights(name).shape in ((7,), (11,))  # the thesis's seven, or with the expert's habits
    for name in suite_names():
        load_suite(name)
    assert load_vocabulary(VOCABULARY_FILE).synonyms
    assert colour_table(COLOURS_FILE)["hue"]
    assert ExpertRules.load(RULES_FILE).feature_query_by_turn >= 1


# -- kitchens ---------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("old, new, fragments", [
    ("fov_degrees = 24.4", "fov_degrees = nan", ("[camera]", "'fov_degrees' must be a finite number", "nan")),
    ("fov_degrees = 24.4", "fov_degrees = 180", ("[camera]", "'fov_degrees' must be > 0 and < 180")),
    ("max_reach = 0.78", "max_reach = inf", ("[object_region]", "'max_reach' must be a finite number")),
    ("x = [-0.74, 0.74]", "x = [0.74, -0.74]", ("[object_region]", "'x' must be [low, high] with low <= high")),
    ("ambient = [0.55, 0.75]", "ambient = [0.75, 0.55]", ("[lighting]", "'ambient' must be [low, high]")),
    ("ambient = [0.55, 0.75]", "ambient = [0.55, 1.75]", ("[lighting]", "item 2 of 'ambient' must be >= 0 and <= 1")),
    ("near = 1.2", "near = 3.0", ("[camera]", "'far' must be > 3")),
    ("min_gap = 0.010", "min_gap = 0.010\nfocus_sprad = 0.2", ("[object_region]", "unknown field 'focus_sprad'",
                                                               "did you mean 'focus_spread'")),
    ("width = 720", "width = 720.5", ("[camera]", "'width' must be a whole number")),
])
def test_a_bad_kitchen_names_the_file_and_field(tmp_path, old, new, fragments):
    refused(load_kitchen, write(tmp_path, changed(KITCHEN, old, new), "kitchen.toml"), *fragments)


# -- tasks, objects, features ----------------------------------------------------------------------------------


@pytest.mark.parametrize("old, new, fragments", [
    ("test_scenes = 6", "test_scenes = 0", ("'test_scenes' must be >= 1", "got 0")),
    ("test_scenes = 6", "test_scens = 6", ("unknown field 'test_scens'", "did you mean 'test_scenes'")),
    ("pools = 5", "pols = 5", ("[datasets]", "unknown field 'pols'", "did you mean 'pools'")),
    ("pool_size = 3200", "pool_size = -1", ("[datasets]", "'pool_size' must be >= 1")),
])
def test_a_bad_task_names_the_file_and_field(tmp_path, old, new, fragments):
    text = changed(TASK, 'objects = "pack-lunchbox"', f'objects = "{DATA_DIR / "objects" / "pack-lunchbox.toml"}"')
    refused(load_task, write(tmp_path, changed(text, old, new), "task.toml"), *fragments)


KIND = '[[kind]]\nname = "apple"\nconcept = "fruit"\nshape = "sphere"\nradius = [0.03, 0.04]\n' \
       'colours = [[1, 0, 0]]\ncolour_jitter = 0.05\nmass = [0.1, 0.2]\n'


@pytest.mark.parametrize("old, new, fragments", [
    ("radius = [0.03, 0.04]", "radius = [0.04, 0.03]", ("kind 1", "'radius' must be [low, high]")),
    ("radius = [0.03, 0.04]", "radius = [0.03, nan]", ("item 2 of 'radius' must be a finite number",)),
    ("mass = [0.1, 0.2]", "mas = [0.1, 0.2]", ("unknown field 'mas'", "did you mean 'mass'")),
    ("colour_jitter = 0.05", "colour_jitter = inf", ("'colour_jitter' must be a finite number",)),
])
def test_a_bad_object_file_names_the_kind_and_field(tmp_path, old, new, fragments):
    refused(load_object_kinds, write(tmp_path, changed(KIND, old, new), "objects.toml"), *fragments)


def test_a_bad_feature_catalogue_names_the_feature_and_field(tmp_path):
    good = '[[feature]]\nname = "colour.red"\ngroup = "object/appearance/colour"\ndescription = "how red"\n'
    refused(load_feature_catalogue, write(tmp_path, good + 'sorce = "robot"\n'), "feature 1",
            "unknown field 'sorce'", "did you mean 'source'")
    refused(load_feature_catalogue, write(tmp_path, good + 'source = "smell"\n'), "source 'smell' is not one of")


# -- recipes, weights, vocabulary, colour table, expert rules ------------------------------------------------


def test_recipe_weights_vocabulary_colours_and_rules_name_the_file_and_field(tmp_path):
    recipe = 'name = "tea"\n[[step]]\naction = "pick-place"\nobject = "cup"\nstart = "shelf"\nend = "counter"\n'
    refused(load_recipe, write(tmp_path, recipe.replace("start =", "strat ="), "recipe.toml"), "step 1",
            "unknown field 'strat'", "did you mean 'start'")
    refused(load_weights, write(tmp_path, "[weights]\na = nan\n", "weights.toml"), "weight 'a' must be a finite number")
    vocabulary = VOCABULARY_FILE.read_text() + "\n[synonims]\nfruit = [\"fruits\"]\n"
    refused(load_vocabulary, write(tmp_path, vocabulary, "vocabulary.toml"), "unknown field 'synonims'",
            "did you mean 'synonyms'")
    colours = changed(COLOURS_FILE.read_text(), "grey_saturation = 0.18", "grey_saturation = nan")
    refused(colour_table, write(tmp_path, colours, "colours.toml"), "'grey_saturation' must be a finite number")
    rules = changed(RULES_FILE.read_text(), "uncertain_margin = 0.5", "uncertain_margin = 1.5")
    refused(ExpertRules.load, write(tmp_path, rules, "rules.toml"), "[examples]", "'uncertain_margin' must be")


# -- suites, through `teachbot regress --suite FILE` ----------------------------------------------------------


def regress_refuses(tmp_path, capsys, path: Path, *fragments: str) -> str:
    code = main(["regress", "--suite", str(path), "--results", str(tmp_path / "out"), "--no-progress"])
    error = capsys.readouterr().err.strip()
    assert code == 2, error
    assert len(error.splitlines()) == 1 and error.startswith("teachbot regress: ") and str(path) in error, error
    for fragment in fragments:
        assert fragment in error, error
    assert not (tmp_path / "out").exists()
    return error


@pytest.mark.parametrize("old, new, fragments", [
    ("seeds = [0]", 'seeds = ["zero"]', ("item 1 of 'seeds' must be a whole number", "'zero'")),
    ("demo = 1", "dmeo = 1", ("[costs]", "unknown field 'dmeo'", "label, demo, feature, none",
                              "did you mean 'demo'")),
    ("label = 1", "label = nan", ("[costs]", "'label' must be a finite number")),
    ("checkpoints = [4, 8, 12, 16]", "checkpoints = [4, nan]", ("item 2 of 'checkpoints' must be a whole number",)),
    ("datasets = 3", "datasets = -1", ("'datasets' must be >= 1", "got -1")),
    ("datasets = 3", "datsets = 3", ("unknown field 'datsets'", "did you mean 'datasets'")),
    ("budget = 16", "budget = inf", ("condition 1", "'budget' must be a finite number")),
    ("turns = 20", "turns = 0", ("condition 1", "'turns' must be >= 1")),
    ('axis = "questions"', 'axis = "questions"\n[teacher]\nmislabel_rate = 1.5',
     ("[teacher]", "'mislabel_rate' must be >= 0 and <= 1")),
    ('axis = "questions"', 'axis = "questions"\n[dataset]\npool_sise = 10',
     ("[dataset]", "unknown field 'pool_sise'", "did you mean 'pool_size'")),
])
def test_a_bad_suite_gets_one_line_naming_file_and_field(tmp_path, capsys, old, new, fragments):
    regress_refuses(tmp_path, capsys, write(tmp_path, changed(SMOKE, old, new), "suite.toml"), *fragments)


def test_a_binary_or_non_utf8_suite_gets_one_line(tmp_path, capsys):
    binary = tmp_path / "binary.toml"
    binary.write_bytes(bytes(range(256)))
    regress_refuses(tmp_path, capsys, binary, "binary file")
    latin = tmp_path / "latin.toml"
    latin.write_bytes(SMOKE.replace("Quick", "Qu\xefck").encode("latin-1"))
    regress_refuses(tmp_path, capsys, latin, "not UTF-8")


def test_a_recipe_task_refuses_a_non_finite_scene_setting(tmp_path):
    from bullet_world.recipes.setup import load_recipe_setup

    text = changed((DATA_DIR / "tasks" / "serve-pasta.toml").read_text(), "region_margin = 0.015",
                   "region_margin = nan")
    refused(load_recipe_setup, write(tmp_path, text, "serve-pasta.toml"), "[recipe_scenes]",
            "'region_margin' must be a finite number")


@pytest.mark.parametrize("name", ["../../../../x", "/tmp/teachbot-suite", "smoke\n", ".hidden", "a/b", ""])
def test_a_suite_name_is_a_file_name_not_a_path(tmp_path, capsys, monkeypatch, name):
    """Issue 24, case 2: a suite's name names its results folder and baseline; a path is refused before any run."""
    monkeypatch.chdir(tmp_path)
    path = write(tmp_path, changed(SMOKE, 'name = "smoke"', f"name = {json.dumps(name)}"), "suite.toml")
    error = regress_refuses(tmp_path, capsys, path, "suite name", "is not accepted; a name is 1 to 64 letters")
    assert "\n" not in error
    assert sorted(p.name for p in tmp_path.iterdir()) == ["suite.toml"]  # no results folder anywhere


def test_a_suite_condition_name_is_a_file_name_too(tmp_path, capsys):
    regress_refuses(tmp_path, capsys, write(tmp_path, changed(SMOKE, 'name = "static"', 'name = "../static"'),
                                            "suite.toml"), "condition name '../static' is not accepted")


@pytest.mark.parametrize("nested", ["[" * 1000 + "]" * 1000, "{a = " * 400 + "1" + "}" * 400])
def test_deeply_nested_brackets_in_a_toml_file_are_one_line_not_a_recursion_error(tmp_path, nested):
    deep = tmp_path / "deep.toml"
    deep.write_text("x = " + nested + "\n")
    with pytest.raises(DataFileError, match="deep.toml: not valid TOML for teachbot: arrays or tables nested too "
                                            "deeply"):
        read_toml(deep, "suite")


def test_a_data_file_behind_a_link_loop_or_with_a_name_too_long_says_so_not_does_not_exist(tmp_path):
    """Issue 24, case 6: a symbolic link loop was "does not exist"; a 300-character name raised OSError."""
    (tmp_path / "a.toml").symlink_to(tmp_path / "b.toml")
    (tmp_path / "b.toml").symlink_to(tmp_path / "a.toml")
    with pytest.raises(DataFileError, match=r"study file .*a.toml: cannot be read: symbolic links in the path loop"):
        read_toml(tmp_path / "a.toml", "study")
    with pytest.raises(DataFileError, match="cannot be read: a name in the path is 305 bytes long; this file system "
                                            "allows at most 255"):
        read_toml(tmp_path / ("n" * 300 + ".toml"), "suite")
