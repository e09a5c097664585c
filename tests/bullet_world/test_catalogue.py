"""Data files: every task and kitchen loads; a broken file is reported with its field and what is accepted."""

import pytest

from bullet_world.catalogue import DataFileError, load_object_kinds, load_task
from bullet_world.datafiles import available
from bullet_world.kitchen import load_kitchen
from tests.datafile_edits import changed

GOOD_KIND = 'name = "x"\nconcept = "fruit"\nshape = "sphere"\nradius = [0.03, 0.04]\n' \
            'colours = [[1, 0, 0]]\ncolour_jitter = 0.0\nmass = [0.1, 0.2]\n'


def kinds_file(tmp_path, text: str):
    path = tmp_path / "objects.toml"
    path.write_text(text)
    return path


@pytest.mark.parametrize("task", ["pack-lunchbox", "prepare-lunch", "sort-groceries"])
def test_every_task_covers_its_concepts_in_every_kitchen(task):
    loaded = load_task(task)
    assert loaded.relevant_features and loaded.datasets.pools == 5
    for kitchen in available("kitchens"):
        kinds = loaded.kinds_in(kitchen)
        assert {k.concept for k in kinds} == set(loaded.concepts)


def test_concepts_share_shapes_so_no_single_feature_separates_them():
    task = load_task("pack-lunchbox")
    shapes = {}
    for kind in task.kinds:
        shapes.setdefault(kind.shape, set()).add(kind.concept)
    assert len(shapes["box"]) >= 2 and len(shapes["cylinder"]) >= 2 and len(shapes["lathe"]) >= 3


def test_prepare_lunch_kinds_have_states_in_order():
    task = load_task("prepare-lunch")
    assert task.has_states and task.place_at_locations
    pasta = next(k for k in task.kinds if k.name == "spaghetti")
    assert pasta.state_names == ("boxed", "in-pot", "in-bowl")
    assert [s.location for s in pasta.states] == ["pantry", "stove", "counter"]
    assert pasta.states[1].open_top and pasta.states[1].fill > 0
    assert next(k for k in task.kinds if k.name == "apple").state_names == ("whole", "sliced")
    assert next(k for k in task.kinds if k.name == "chip-bag").state_names == ("as-is",)


@pytest.mark.parametrize("text, message", [
    ('[[kind]]\nname = "x"\nconcept = "fruit"\nshape = "cube"\n', "shape 'cube' is not one of box, cylinder"),
    ('[[kind]]\n' + GOOD_KIND.replace("radius = [0.03, 0.04]", "radius = [0.05]"),
     "'radius' must be a list of 2 numbers"),
    ('[[kind]]\n' + GOOD_KIND.replace("colours = [[1, 0, 0]]", "colours = [[2, 0, 0]]"), "channels in 0..1"),
    ('[[kind]]\n' + GOOD_KIND + 'texture = "tartan"\n', "texture 'tartan' is not one of plain"),
    ('[[kind]]\n' + GOOD_KIND + 'location = "garage"\n', "location 'garage' is not one of stove"),
    ('[[kind]]\n' + GOOD_KIND.replace('shape = "sphere"\nradius = [0.03, 0.04]',
                                      'shape = "lathe"\nradius = [0.03, 0.04]\nheight = [0.1, 0.2]\n'
                                      'profile = [[1, 0.5], [1, 0.2]]'), "'profile' points must rise"),
    ('[[kind]]\n' + GOOD_KIND + '[[kind]]\n' + GOOD_KIND, "kind names must be unique"),
    ("this is = = not toml", "not valid TOML"),
])
def test_broken_object_files_name_the_field(tmp_path, text, message):
    with pytest.raises(DataFileError, match=message):
        load_object_kinds(kinds_file(tmp_path, text))


def test_a_state_inherits_what_it_does_not_repeat(tmp_path):
    text = '[[kind]]\n' + GOOD_KIND + '[[kind.state]]\nname = "whole"\n[[kind.state]]\nname = "halved"\n' \
                                      'radius = [0.01, 0.02]\n'
    kind = load_object_kinds(kinds_file(tmp_path, text))[0]
    assert kind.state_names == ("whole", "halved")
    assert kind.states[1].colours == kind.states[0].colours and kind.states[1].dimensions["radius"] == (0.01, 0.02)


def test_broken_task_files_name_the_field(tmp_path):
    base = load_task("pack-lunchbox").path
    text = open(base).read()
    path = tmp_path / "task.toml"
    path.write_text(text.replace('placement = "anywhere"', 'placement = "everywhere"'))
    with pytest.raises(DataFileError, match="placement 'everywhere' is not one of anywhere, locations"):
        load_task(path)
    path.write_text(text.replace('"object/weight"]', '"object/smell"]'))
    with pytest.raises(DataFileError, match="'object/smell' names no feature"):
        load_task(path)


def test_kitchen_locations_must_be_within_reach(tmp_path):
    from bullet_world.datafiles import DATA_DIR

    text = (DATA_DIR / "kitchens" / "kitchen-1.toml").read_text()
    path = tmp_path / "kitchen.toml"
    stove = "[locations.stove]\ncentre = "
    path.write_text(changed(text, stove + "[0.51, -0.24, 0.0]", stove + "[1.5, 0.4, 0.0]"))  # asserts it edits
    with pytest.raises(DataFileError, match="locations must be within 0.8 m"):
        load_kitchen(path)
    path.write_text(changed(text, "[locations.pantry]", "[locations.larder]"))
    with pytest.raises(DataFileError, match="missing pantry"):
        load_kitchen(path)
