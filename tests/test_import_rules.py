"""docs/architecture.md's import rules: learning stays pure; bullet_world never imports robot or dialog; robot never
dialog; the project (its four packages and scripts/) has no import circle, counting the imports made only for type
checkers; inside dialog/ imports run down the layers."""

import ast
from graphlib import CycleError, TopologicalSorter
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
RULES = {
    "learning": {"pybullet", "pybullet_data", "cv2", "meshcat", "bullet_world", "robot", "dialog"},
    "bullet_world": {"dialog", "robot"},
    "robot": {"dialog"},
}


def imported_top_levels(path: Path) -> set[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(alias.name.split(".")[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names.add(node.module.split(".")[0])
    return names


@pytest.mark.parametrize("package", sorted(RULES))
def test_package_imports_follow_the_design(package):
    files = sorted((ROOT / package).rglob("*.py"))
    assert files, f"no python files in {package}/"
    violations = {
        str(path.relative_to(ROOT)): sorted(imported_top_levels(path) & RULES[package]) for path in files
    }
    assert {k: v for k, v in violations.items() if v} == {}


def test_the_checker_catches_a_forbidden_import(tmp_path):
    sample = tmp_path / "bad.py"
    sample.write_text("import numpy\nfrom pybullet import connect\nimport cv2 as vision\n")
    assert imported_top_levels(sample) & RULES["learning"] == {"pybullet", "cv2"}


HOUSE = ("bullet_world", "robot", "learning", "dialog")
SCRIPTS = "scripts"  # not a package: a script imports its siblings by their bare names (scripts/ is on sys.path)
# dialog/'s layers, lowest first: a module imports only modules of its own layer or of a lower one
DIALOG_LAYERS = (
    ("dialog.clock", "dialog.threads", "dialog.interrupts", "dialog.output_paths", "dialog.printed_command"),
    ("dialog.language", "dialog.environment"),
    ("dialog.teachers",),
    ("dialog.transcripts",),
    ("dialog.embodied", "dialog.user_weights", "dialog.settings", "dialog.manager", "dialog.episode",
     "dialog.session", "dialog.viewer", "dialog.recipe_session",
     "dialog.commands._arguments"),  # the argument types the commands, the viewer options and the page share
    ("dialog.expert", "dialog.experiments", "dialog.rl", "dialog.study", "dialog.web"),
    ("dialog.commands",),
    ("dialog.cli",),
)


def house_modules() -> dict[str, Path]:
    modules = {}
    for package in HOUSE:
        for path in (ROOT / package).rglob("*.py"):
            parts = list(path.relative_to(ROOT).with_suffix("").parts)
            modules[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    return modules


def project_modules() -> dict[str, Path]:
    """The house's modules and the scripts (as ``scripts.NAME``)."""
    return house_modules() | {f"{SCRIPTS}.{path.stem}": path for path in sorted((ROOT / SCRIPTS).glob("*.py"))}


def imported_modules(name: str, path: Path, modules) -> set[str]:
    """The project modules ``name`` imports anywhere: in functions and under ``if TYPE_CHECKING`` too (a type
    named across modules ties them as much as a call does)."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found: set[str] = set()

    def resolve(target: str) -> None:
        if name.startswith(f"{SCRIPTS}.") and f"{SCRIPTS}.{target}" in modules:
            target = f"{SCRIPTS}.{target}"  # a script's sibling, imported by its bare name
        while target and target not in modules:
            target = target.rpartition(".")[0]
        if target and target != name:
            found.add(target)

    def visit(node: ast.AST) -> None:
        if isinstance(node, ast.Import):
            for alias in node.names:
                resolve(alias.name)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parent = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join([*parent, *([node.module] if node.module else [])])
            for alias in node.names:
                resolve(f"{base}.{alias.name}" if f"{base}.{alias.name}" in modules else base)
        for child in ast.iter_child_nodes(node):
            visit(child)

    visit(ast.parse(path.read_text(encoding="utf-8"), filename=str(path)))
    return found


def import_graph() -> dict[str, set[str]]:
    modules = project_modules()
    return {name: imported_modules(name, path, modules) for name, path in modules.items()}


def import_circle(graph: dict[str, set[str]]) -> list[str]:
    """One import circle of ``graph`` (its modules in import order, the first repeated at the end); [] if none."""
    try:
        tuple(TopologicalSorter(graph).static_order())
    except CycleError as error:
        return list(reversed(error.args[1]))  # graphlib lists a circle against the direction of the imports
    return []


def test_the_project_has_no_import_circle():
    circle = import_circle(import_graph())
    assert not circle, f"import circle: {' -> '.join(circle)}"


def test_a_circle_closed_only_for_type_checkers_counts(tmp_path):
    (tmp_path / "a.py").write_text("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from dialog.b import B\n")
    (tmp_path / "b.py").write_text("from dialog.a import A\n")
    modules = {"dialog": tmp_path / "a.py", "dialog.a": tmp_path / "a.py", "dialog.b": tmp_path / "b.py"}
    graph = {name: imported_modules(name, path, modules) for name, path in modules.items() if name != "dialog"}
    assert graph == {"dialog.a": {"dialog.b"}, "dialog.b": {"dialog.a"}}
    assert import_circle(graph) in (["dialog.a", "dialog.b", "dialog.a"], ["dialog.b", "dialog.a", "dialog.b"])


def test_scripts_importing_each_other_are_in_the_graph():
    graph = import_graph()
    assert "scripts._fuzz_corpus" in graph["scripts.fuzz_teach"]
    assert "dialog.experiments.suite" in graph["scripts.experiments"]


def dialog_layer(module: str) -> int | None:
    for layer, owners in enumerate(DIALOG_LAYERS):
        if any(module == owner or module.startswith(owner + ".") for owner in owners):
            return layer
    return None


def test_every_dialog_module_has_a_layer():
    assert [m for m in import_graph() if m.startswith("dialog.") and dialog_layer(m) is None] == []


def test_imports_inside_dialog_run_down_the_layers():
    graph = import_graph()
    upward = sorted(f"{module} -> {target}" for module, targets in graph.items() if module.startswith("dialog.")
                    for target in targets if target.startswith("dialog.") and target != "dialog"
                    and dialog_layer(target) > dialog_layer(module))
    assert upward == []


def test_the_graph_sees_imports_inside_functions(tmp_path):
    sample = tmp_path / "sample.py"
    sample.write_text("def late():\n    from dialog.cli import main\n")
    assert imported_modules("dialog.sample", sample, {"dialog.cli": sample, "dialog": sample}) == {"dialog.cli"}


def test_one_episode_builder_wires_the_manager():
    """Issue 25: ``dialog.episode.build_episode`` is the one place a DialogManager is made; every command, suite,
    the Gymnasium environment and the scripts call it."""
    makers = sorted(str(path.relative_to(ROOT)) for package in (*HOUSE, "scripts")
                    for path in (ROOT / package).rglob("*.py")
                    if "DialogManager(" in path.read_text(encoding="utf-8"))
    assert makers == ["dialog/episode.py"]


def test_the_default_strategy_is_written_once():
    from dialog.commands.teach import DEFAULT_STRATEGY as teach_default
    from dialog.settings import DEFAULTS
    from learning import TeachingLoop
    from learning.strategies import DEFAULT_STRATEGY

    assert DEFAULTS.strategy == teach_default == DEFAULT_STRATEGY == "dt-task"
    assert TeachingLoop(["a", "b"]).strategy.name == DEFAULT_STRATEGY


def test_the_decision_rule_does_not_import_the_fit():
    """learning/decision (the DT rule and its features and weights) is below learning/irl (fitting the weights):
    irl reads decision features, never the other way round."""
    upward = sorted(f"{module} -> {target}" for module, targets in import_graph().items()
                    if module.startswith("learning.decision")
                    for target in targets if target.startswith("learning.irl"))
    assert upward == []


def test_the_turn_rules_are_the_library_s():
    """One implementation of a turn's rules (learning/turn.py): the library loop, the dialog manager and the
    synthetic episodes import it, and no other module defines ``admissible``."""
    graph = import_graph()
    assert {"learning.loop", "dialog.manager", "learning.synthetic"} <= {m for m, t in graph.items()
                                                                          if "learning.turn" in t}
    defining = sorted(name for name, path in house_modules().items()
                      if "def admissible(" in path.read_text(encoding="utf-8"))
    assert defining == ["learning.turn"]
