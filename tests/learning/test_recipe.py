"""Recipe format: built-in recipes (thesis Tables 4.1, 4.2) and clear errors."""

import pytest

from learning.recipes.format import (
    Recipe,
    RecipeStep,
    builtin_recipe_names,
    load_builtin_recipe,
    load_recipe,
    recipe_parameters,
)

VALID_RECIPE = """\
name = "make-tea"
description = "Kettle and cup to the table."

[[step]]
action = "pick-place"
object = "kettle"
start = "stove"
end = "table"

[[step]]
action = "pick-place"
object = "cup"
start = "shelf"
end = "table"
"""


def write(tmp_path, text, name="recipe.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_builtin_recipes_are_listed():
    assert {"serve-pasta", "serve-salad"} <= set(builtin_recipe_names())


def test_serve_pasta_matches_table_4_1():
    recipe = load_builtin_recipe("serve-pasta")
    assert recipe.name == "serve-pasta"
    assert recipe.description
    assert [(s.action, s.object, s.start, s.end) for s in recipe.steps] == [
        ("pick-place", "pasta-pot", "stove", "counter"),
        ("pick-place", "bowl", "cupboard", "counter"),
        ("pick-place", "pasta-sauce", "fridge", "counter"),
    ]
    parameters = recipe_parameters(recipe)
    assert parameters.objects == ("pasta-pot", "bowl", "pasta-sauce")
    assert parameters.locations == ("stove", "counter", "cupboard", "fridge")


def test_serve_salad_matches_table_4_2():
    recipe = load_builtin_recipe("serve-salad")
    assert recipe.steps == (
        RecipeStep("pick-place", "bowl", "cupboard", "counter"),
        RecipeStep("pick-place", "salad-dressing", "fridge", "counter"),
    )
    parameters = recipe_parameters(recipe)
    assert parameters.objects == ("bowl", "salad-dressing")
    assert set(parameters.locations) == {"cupboard", "fridge", "counter"}


def test_user_recipe_loads(tmp_path):
    recipe = load_recipe(write(tmp_path, VALID_RECIPE))
    assert recipe.name == "make-tea"
    assert str(recipe.steps[1]) == "pick-place <cup, shelf, table>"
    assert recipe_parameters(recipe).locations == ("stove", "table", "shelf")


def test_description_is_optional(tmp_path):
    text = VALID_RECIPE.replace('description = "Kettle and cup to the table."\n', "")
    assert load_recipe(write(tmp_path, text)).description == ""


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        (
            VALID_RECIPE.replace('action = "pick-place"\nobject = "cup"', 'action = "pour"\nobject = "cup"'),
            r"step 2: unknown action 'pour'; accepted actions: pick-place",
        ),
        (VALID_RECIPE.replace('start = "shelf"\n', ""), r"step 2: missing field 'start'"),
        (VALID_RECIPE.replace('name = "make-tea"\n', ""), r"missing field 'name'"),
        ('name = "empty"\nstep = []\n', r"field 'step' is empty"),
        ('name = "no-steps"\n', r"missing field 'step'"),
        (
            VALID_RECIPE.replace('object = "kettle"', "object = 3"),
            r"step 1: field 'object' must be a non-empty string, got int",
        ),
        (VALID_RECIPE.replace('name = "make-tea"', "name = true"), r"field 'name' must be a non-empty string"),
        (VALID_RECIPE.replace('end = "table"\n\n[[step]]', 'end = ""\n\n[[step]]'), r"step 1: field 'end' is ''"),
        ('name = "x"\nstep = "pick-place"\n', r"field 'step' must be an array of \[\[step\]\] tables"),
        (
            VALID_RECIPE.replace('object = "cup"', 'object = "cup"\ncolour = "red"'),
            r"step 2: unknown field 'colour'; accepted fields: action, object, start, end",
        ),
        (VALID_RECIPE.replace("name =", "nmae ="), r"unknown field 'nmae'; accepted fields: name, description, step"),
        (
            VALID_RECIPE.replace('object = "cup"', 'object = "stove"'),
            r"'stove' is used both as an object and as a location",
        ),
        (VALID_RECIPE.replace('name = "make-tea"', "name = make-tea"), r"not valid TOML"),
    ],
)
def test_broken_recipe_files_give_one_line_errors_naming_file_and_field(tmp_path, text, expected):
    path = write(tmp_path, text, "broken.toml")
    with pytest.raises(ValueError, match=expected) as caught:
        load_recipe(path)
    message = str(caught.value)
    assert "broken.toml" in message
    assert "\n" not in message


def test_missing_file_and_unknown_builtin_are_reported(tmp_path):
    with pytest.raises(FileNotFoundError, match="nowhere.toml"):
        load_recipe(tmp_path / "nowhere.toml")
    with pytest.raises(ValueError, match="unknown built-in recipe 'serve-soup'; accepted: .*serve-pasta"):
        load_builtin_recipe("serve-soup")


def test_recipe_dataclass_validates_directly():
    with pytest.raises(ValueError, match="at least one step"):
        Recipe("nothing", "", ())
    with pytest.raises(ValueError, match="unknown action 'throw'"):
        Recipe("bad", "", (RecipeStep("throw", "ball", "floor", "bin"),))
