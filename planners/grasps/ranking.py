"""The order in which grasp candidates are tried, in one place: each table below lists groups of candidates,
best first; a candidate goes to the first group that takes it, and within a group candidates keep the order
their generator made them in (low before high, wide before narrow, plus before minus).

Inside furniture (`SHELF_ORDER`), the order depends on how the object stands (`ShelfCase`): one turned more than
FACE_FIRST_TURN off the front is taken square to its own face first (pads closing square to the front on a box
turned further turn it between them, and it keeps turning in the hand); a ball is taken front to back right after
level (held across, pitched, it meets the pads past their tips and creeps out). From above (`ABOVE_ORDER`), grasps
whose open fingers land on something (a neighbour, a drawer's wall) go after those that land clear, off-centre
copies after both, and grasps squared to a drawer's walls last; in a drawer, off-centre copies that slide the object
along the drawer's runners go after all of those (see `rank_from_above`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from enum import Enum
from typing import NamedTuple

import numpy as np

from homer_sim.home.catalog import ObjectClass
from planners.grasps.candidate import Family, Grasp, GraspKind

FACE_FIRST_TURN = math.radians(4.0)  # rad an object stands turned off the furniture's front beyond which grasps
# square to its face go first
ALONG_EARLY_FAMILIES = ("sphere",)  # shapes taken front to back right after level, before pitched
DRAG_TURN = math.radians(45.0)  # rad: an off-centre grasp's finger travel closer than this to a drawer's slide
# direction pushes the object along the runners


class Group(NamedTuple):
    """A group of candidates: what it holds, and the test that takes a kind into it."""

    what: str
    takes: Callable[[GraspKind], bool]


LEVEL = Group("level side grasps square to the front, low then high",
              lambda k: k.family is Family.SIDE and not (k.faced or k.halfway or k.slant))
PITCHED = Group("grasps pitched down into the compartment, across the object (aside where a neighbour is in the way)",
                lambda k: k.family is Family.SHELF and not (k.faced or k.along or k.roll))
FACED = Group("level, then pitched grasps square to the face of an object standing turned",
              lambda k: k.faced and not (k.along or k.roll))
HALFWAY = Group("level grasps halfway between the front and a turned object's face", lambda k: k.halfway)
SLANTED = Group("level grasps of a round object slanted off the front, past a side wall", lambda k: k.slant != 0)
ALONG = Group("pitched grasps closing front to back", lambda k: k.along and not k.faced)
ALONG_FACED = Group("the same in the turned object's own vertical plane", lambda k: k.along and k.faced)
POT_HANDLE = Group("a pot's side handle, level then pitched", lambda k: k.family is Family.POT_HANDLE)
TILTED_RIM = Group("pinches of a wide container's front rim, steepest first", lambda k: k.family is Family.RIM)
ROLLED = Group("straight-down grasps closing front to back, leaning aside under a low shelf",
               lambda k: k.roll != 0 and not k.faced)
ROLLED_FACED = Group("the same, square to a turned object's face", lambda k: k.roll != 0 and k.faced)


class ShelfCase(Enum):
    """How an object stands inside furniture, as far as the order of its grasps goes."""

    SQUARE = "square"  # square to the front, or turned at most FACE_FIRST_TURN
    TURNED = "turned"  # turned further
    BALL = "ball"  # a shape in ALONG_EARLY_FAMILIES


SHELF_ORDER: dict[ShelfCase, tuple[Group, ...]] = {
    ShelfCase.SQUARE: (LEVEL, PITCHED, FACED, SLANTED, ALONG, ALONG_FACED, POT_HANDLE, TILTED_RIM, ROLLED,
                       ROLLED_FACED),
    ShelfCase.TURNED: (FACED, HALFWAY, LEVEL, PITCHED, SLANTED, ALONG_FACED, ALONG, POT_HANDLE, TILTED_RIM,
                       ROLLED_FACED, ROLLED),
    ShelfCase.BALL: (LEVEL, ALONG, PITCHED, FACED, SLANTED, ALONG_FACED, POT_HANDLE, TILTED_RIM, ROLLED,
                     ROLLED_FACED),
}
"""The order of the grasps of an object inside furniture, by how it stands (see `shelf_case`)."""


class AboveCase(NamedTuple):
    """What the order of a grasp from above depends on besides its kind."""

    kind: GraspKind
    clear: bool  # the open fingers land on nothing but the object (for an off-centre copy: those of its original)


ABOVE_ORDER: tuple[tuple[str, Callable[[AboveCase], bool]], ...] = (
    ("centred grasps whose open fingers land clear (raised copies after the rest)",
     lambda c: not c.kind.squared and not c.kind.offset and c.clear),
    ("centred grasps whose open fingers land on something", lambda c: not c.kind.squared and not c.kind.offset),
    ("off-centre copies of the first", lambda c: not c.kind.squared and c.clear),
    ("off-centre copies of the second", lambda c: not c.kind.squared),
    ("the same four for grasps squared to a drawer's walls: centred, clear", lambda c: not c.kind.offset and c.clear),
    ("centred, on something", lambda c: not c.kind.offset),
    ("off-centre copies, clear", lambda c: c.clear),
    ("off-centre copies, on something", lambda c: True),
)
"""The order of grasps from above (top grasps, grip features, rims), best first."""


def shelf_case(cls: ObjectClass, turn_cos: float) -> ShelfCase:
    """How an object of `cls` stands whose nearest face turns `turn_cos` (the cosine of its angle) off the
    furniture's front."""
    if cls.family in ALONG_EARLY_FAMILIES:
        return ShelfCase.BALL
    return ShelfCase.TURNED if turn_cos < math.cos(FACE_FIRST_TURN) else ShelfCase.SQUARE


def rank_in_shelf(grasps: Sequence[Grasp], case: ShelfCase) -> list[Grasp]:
    """`grasps` of an object inside furniture in the order SHELF_ORDER gives for `case` (stable within a group)."""
    groups = SHELF_ORDER[case]
    return sorted(grasps, key=lambda g: _first(g.kind, [group.takes for group in groups]))


def rank_from_above(grasps: Sequence[tuple[Grasp, bool]], slide: np.ndarray | None = None) -> list[Grasp]:
    """The grasps of (grasp, whether its open fingers land clear; for an off-centre copy, its original's) pairs
    in the order ABOVE_ORDER gives (stable within a group). In a drawer sliding along `slide` (a horizontal
    direction, shape (2,) or (3,)), off-centre copies whose finger travel lies within DRAG_TURN of it go after
    every other grasp: closing, the near finger slides the object along the runners, and its friction on the
    drawer's bottom drags the drawer, and what else is in it, along (a charger's grasp moved a cd 2.2 cm so)."""
    tests = [test for _, test in ABOVE_ORDER]

    def drags(grasp: Grasp) -> bool:
        if slide is None or not grasp.kind.offset:
            return False
        return abs(float(grasp.rotation[:2, 1] @ slide[:2])) > math.cos(DRAG_TURN) * float(np.linalg.norm(slide[:2]))

    ranked = sorted(grasps, key=lambda pair: (drags(pair[0]), _first(AboveCase(pair[0].kind, pair[1]), tests)))
    return [grasp for grasp, _ in ranked]


def _first(item, tests: list[Callable]) -> int:
    """The index of the first of `tests` that `item` passes; a candidate no group takes is a bug."""
    for index, test in enumerate(tests):
        if test(item):
            return index
    raise AssertionError(f"no group takes {item}")
