"""Imports point one way: the floors below, one owner per heavy dependency, no circles, no private imports."""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PACKAGES = ("homer_sim", "planners", "model", "scenarios")

FLOORS: tuple[tuple[str, ...], ...] = (
    ("homer_sim.errors", "homer_sim.transforms", "homer_sim.graph", "homer_sim.days", "homer_sim.clock",
     "homer_sim.robot_spec", "homer_sim"),
    ("homer_sim.home",),
    ("homer_sim.world", "homer_sim.observe", "homer_sim.recording", "homer_sim.check"),
    ("homer_sim.person",),
    ("homer_sim.data",),
    ("planners", "model"),
    ("scenarios",),
)
"""Each module imports only from its own floor or the floors below it (earlier in this tuple)."""

SIDE_BY_SIDE = ("planners", "model")
"""Packages on one floor that never import each other: the robot and the predictors meet only in scenarios."""


def _module_name(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _sources() -> dict[str, Path]:
    return {_module_name(p): p for package in PACKAGES for p in sorted((ROOT / package).rglob("*.py"))}


def _imported(path: Path) -> list[tuple[str, tuple[str, ...]]]:
    """(module, imported names) of every absolute import in `path`, at any depth (function-level too)."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.Import):
            found += [(alias.name, ()) for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            found.append((node.module, tuple(alias.name for alias in node.names)))
    return found


def _floor(module: str) -> int:
    """The floor of the longest unit that is `module` or a package holding it."""
    units = [(len(unit), index) for index, floor in enumerate(FLOORS) for unit in floor
             if module == unit or module.startswith(unit + ".")]
    assert units, f"{module} is on no floor: add it to FLOORS"
    return max(units)[1]


def _edges() -> dict[str, set[str]]:
    """Module -> the project modules it imports (a `from package import module` names the module)."""
    sources = _sources()
    edges: dict[str, set[str]] = {}
    for name, path in sources.items():
        targets = set()
        for module, names in _imported(path):
            if module.split(".")[0] not in PACKAGES:
                continue
            submodules = {f"{module}.{n}" for n in names} & sources.keys()
            targets |= submodules or {module}
        edges[name] = targets - {name}
    return edges


def test_only_the_recording_module_imports_rerun() -> None:
    users = {name for name, path in _sources().items() if any(m.split(".")[0] == "rerun" for m, _ in _imported(path))}
    assert users == {"homer_sim.recording"}


def test_only_the_ik_module_imports_mink() -> None:
    users = {name for name, path in _sources().items() if any(m.split(".")[0] == "mink" for m, _ in _imported(path))}
    assert len(users) == 1 and next(iter(users)).endswith(".ik"), users


def test_model_and_graph_values_stay_free_of_simulators() -> None:
    values = ("homer_sim.graph", "homer_sim.home.layout", "homer_sim.home.catalog", "homer_sim.data.dataset")
    for name, path in _sources().items():
        if name.startswith("model") or name in values:
            heavy = {m.split(".")[0] for m, _ in _imported(path)} & {"mujoco", "mink", "rerun", "dm_control"}
            assert not heavy, name


def test_every_import_points_down_the_floors() -> None:
    upward = [(name, target) for name, targets in _edges().items() for target in targets
              if _floor(target) > _floor(name)]
    assert upward == []


def test_the_robot_and_the_predictors_never_import_each_other() -> None:
    crossing = [(name, target) for name, targets in _edges().items() for target in targets
                if {name.split(".")[0], target.split(".")[0]} == set(SIDE_BY_SIDE)]
    assert crossing == []


def test_there_is_no_import_circle() -> None:
    edges = _edges()
    state: dict[str, int] = {}  # 1: on the current path, 2: done

    def visit(node: str, path: list[str]) -> list[str] | None:
        state[node] = 1
        for target in sorted(edges.get(node, ())):
            if state.get(target) == 1:
                return [*path, node, target]
            if target not in state and (circle := visit(target, [*path, node])):
                return circle
        state[node] = 2
        return None

    for start in sorted(edges):
        if start not in state:
            assert visit(start, []) is None


def test_no_module_imports_another_modules_private_names() -> None:
    private = [(name, module, n) for name, path in _sources().items() for module, names in _imported(path)
               if module.split(".")[0] in PACKAGES and module != name for n in names
               if n.startswith("_") and not n.startswith("__")]
    assert private == []
