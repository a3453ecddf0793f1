"""The packages' layering: ``perception`` is a pure estimation and vision library (no simulator,
env, agents or training code, and no torch until the CNN is used), only ``spl_env/sim/`` talks to
PyBullet, and ``spl_env`` never depends on the agents or the training code.

Perception's modules are imported in a fresh interpreter, so that modules this test session has
already imported cannot hide a dependency; the source scans also catch imports inside functions.
"""

from __future__ import annotations

import ast
import json
import pkgutil
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

import perception

ROOT = Path(__file__).resolve().parents[1]
# Top-level modules that nothing under perception may import, directly or through another module.
NOT_IN_PERCEPTION = (
    "pybullet",
    "pybullet_data",
    "gymnasium",
    "spl_env",
    "stable_baselines3",
    "agents",
    "training",
)
PYBULLET_HOME = ROOT / "spl_env" / "sim"  # the only package that may import pybullet
# Source trees scanned for pybullet imports (tests may drive PyBullet themselves).
SOURCE_TREES = ("spl_env", "perception", "agents", "training", "benchmarks", "examples")

# Imports the given modules in order; prints {forbidden top-level module: the first of them whose
# import brought it in} as JSON.
IMPORT_IN_ORDER = """
import importlib, json, sys
found = {{}}
for name in {names!r}:
    importlib.import_module(name)
    for module in list(sys.modules):
        if module.split(".")[0] in {forbidden!r}:
            found.setdefault(module.split(".")[0], name)
print(json.dumps(found))
"""


def perception_modules() -> list[str]:
    """``perception`` and every module and package under it (walk_packages imports the packages
    to list them, which perception's purity makes harmless here; an import error fails)."""

    def fail(name: str) -> None:
        raise ImportError(f"cannot import {name} to list its modules")

    walk = pkgutil.walk_packages(perception.__path__, "perception.", onerror=fail)
    return ["perception", *(module.name for module in walk)]


def run_python(code: str) -> str:
    """Stdout of ``code`` run by a fresh interpreter in the repository root (fails on error)."""
    result = subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=300
    )
    assert result.returncode == 0, result.stderr
    return result.stdout


def test_perception_imports_no_simulator_env_agents_or_training() -> None:
    names = perception_modules()
    assert {"perception.pipeline", "perception.vision.cnn_detector"} <= set(names)
    code = IMPORT_IN_ORDER.format(names=names, forbidden=NOT_IN_PERCEPTION)
    found = json.loads(run_python(code))
    assert found == {}, f"forbidden module: the perception module whose import brought it: {found}"


@pytest.mark.parametrize("module", ["perception", "perception.pipeline", "perception.types"])
def test_perception_core_does_not_import_torch(module: str) -> None:
    code = f"import sys, {module}; print(sorted(m for m in sys.modules if m.startswith('torch')))"
    assert run_python(code).strip() == "[]"


def imported_roots(path: Path) -> Iterator[tuple[int, str]]:
    """(line, top-level module) of every absolute import in the file, at any depth (also the
    lazy ones inside functions)."""
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), filename=str(path))):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield node.lineno, alias.name.split(".")[0]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module is not None:
            yield node.lineno, node.module.split(".")[0]


def sources(*trees: str) -> list[Path]:
    """The .py files under the given top-level folders of the repository."""
    files = [path for tree in trees for path in sorted((ROOT / tree).rglob("*.py"))]
    assert files, f"no sources under {trees}"
    return files


def test_only_spl_env_sim_imports_pybullet() -> None:
    offenders = [
        f"{path.relative_to(ROOT)}:{line} imports {root}"
        for path in sources(*SOURCE_TREES)
        if not path.is_relative_to(PYBULLET_HOME)
        for line, root in imported_roots(path)
        if root.startswith("pybullet")
    ]
    assert offenders == []


@pytest.mark.parametrize(
    ("tree", "forbidden"),
    [
        ("spl_env", ("agents", "stable_baselines3", "training")),
        ("perception", NOT_IN_PERCEPTION),
    ],
)
def test_no_upward_imports_anywhere_in_the_source(tree: str, forbidden: tuple[str, ...]) -> None:
    offenders = [
        f"{path.relative_to(ROOT)}:{line} imports {root}"
        for path in sources(tree)
        for line, root in imported_roots(path)
        if root in forbidden
    ]
    assert offenders == []
