"""The robot decides from typed data, never from names: no string prefix or suffix tests anywhere in `planners/`,
and no comparison of a kind, a label, a family or a name with a string literal (object class names included)."""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
NAMED = {"kind", "label", "name", "cls", "family"}  # attributes and variables whose string value must not steer
ALWAYS = {"label"}  # never compared at all: a grasp's label is for messages only


def _named(node: ast.AST) -> str | None:
    """The name an expression reads: `x.kind` -> "kind", `name` -> "name", `str(x.kind)` -> "kind", else None."""
    if isinstance(node, ast.Attribute):
        return node.attr
    if isinstance(node, ast.Name):
        return node.id
    if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "str" and node.args:
        return _named(node.args[0])
    return None


def _literal_text(node: ast.AST) -> bool:
    """Whether `node` is a string literal, an f-string, or a tuple, list or set holding one."""
    if isinstance(node, ast.Constant) and isinstance(node.value, str) or isinstance(node, ast.JoinedStr):
        return True
    return isinstance(node, ast.Tuple | ast.List | ast.Set) and any(_literal_text(e) for e in node.elts)


def violations(source: str, filename: str = "<source>") -> list[str]:
    """Each place in `source` where a name string steers control flow (see the module doc)."""
    found = []
    for node in ast.walk(ast.parse(source, filename=filename)):
        where = f"{filename}:{getattr(node, 'lineno', 0)}"
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr in (
                "startswith", "endswith"):
            found.append(f"{where}: .{node.func.attr}()")
        if isinstance(node, ast.Compare):
            sides = [node.left, *node.comparators]
            names = {_named(side) for side in sides} - {None}
            if names & ALWAYS or (names & NAMED and any(_literal_text(side) for side in sides)):
                found.append(f"{where}: {ast.unparse(node)}")
    return found


def test_the_checker_catches_name_branching() -> None:
    bad = ['if g.kind.endswith("-narrow"): pass', 'x = "-squared" in g.kind', 'if name == "milk": pass',
           'if cls.family != "sphere": pass', 'ok = str(g.kind) in ("top", "top-turned")', 'if g.label == k: pass',
           'if kind == f"shelf-{pitch}": pass']
    assert [len(violations(s)) for s in bad] == [1] * len(bad)
    good = ['if g.kind.family is Family.TOP: pass', 'if g.kind.narrow: pass', 'text = f"{g.kind}: failed"',
            'if cls.family in ROUND_FAMILIES: pass', 'if a.joint_type == "slide": pass']
    assert [violations(s) for s in good] == [[]] * len(good)


def test_no_planner_decision_reads_a_name_string() -> None:
    found = [v for path in sorted((ROOT / "planners").rglob("*.py"))
             for v in violations(path.read_text(), str(path.relative_to(ROOT)))]
    assert found == []
