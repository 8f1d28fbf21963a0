"""Imports point one way (DESIGN.md): one module owns each heavy dependency."""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PACKAGES = ("homer_sim", "planners", "model", "scenarios")


def _imports(path: Path) -> set[str]:
    names: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.Import):
            names.update(alias.name.split(".")[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module.split(".")[0])
    return names


def _modules() -> dict[str, set[str]]:
    return {str(p.relative_to(ROOT)): _imports(p) for package in PACKAGES for p in (ROOT / package).rglob("*.py")}


def test_only_the_recording_module_imports_rerun() -> None:
    users = {path for path, names in _modules().items() if "rerun" in names}
    assert users <= {"homer_sim/recording.py"}
    assert "homer_sim/recording.py" in users


def test_only_the_ik_module_imports_mink() -> None:
    users = {path for path, names in _modules().items() if "mink" in names}
    assert users <= {"planners/ik.py"}


def test_model_and_graph_values_stay_free_of_simulators() -> None:
    for path, names in _modules().items():
        if path.startswith("model/") or path in ("homer_sim/graph.py", "homer_sim/layout.py", "homer_sim/catalog.py"):
            assert not names & {"mujoco", "mink", "rerun", "dm_control"}, path


def test_core_never_imports_planners_or_scenarios() -> None:
    for path, names in _modules().items():
        if path.startswith("homer_sim/") and path != "homer_sim/cli.py":
            assert not names & {"planners", "scenarios"}, path
        if path.startswith("planners/"):
            assert "scenarios" not in names, path
