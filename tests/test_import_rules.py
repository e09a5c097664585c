"""DESIGN.md's import rules: learning stays pure; bullet_world never imports robot or dialog; robot never dialog."""

import ast
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
