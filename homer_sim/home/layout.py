"""The declarative layout of an apartment: rooms, walls with doorways, furniture, objects and their start parents.

A layout is plain data (frozen dataclasses, no mujoco). `homer_sim.home.build` compiles it to MuJoCo,
`homer_sim.home.validate` checks it, and `declared_graph` turns its start places into the scene graph the
physics must reproduce after settling. The default apartment lives in `homer_sim.home.apartment`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from homer_sim.graph import INSIDE, ON, SceneGraph

FACING_YAW = {"E": 0.0, "N": math.pi / 2, "W": math.pi, "S": -math.pi / 2}


@dataclass(frozen=True)
class Room:
    """A room (or `outside`), an axis-aligned rectangle of floor at z = 0.

    rect: (x_min, y_min, x_max, y_max) in m, world frame.
    """

    name: str
    rect: tuple[float, float, float, float]

    def contains(self, x: float, y: float) -> bool:
        x0, y0, x1, y1 = self.rect
        return x0 <= x <= x1 and y0 <= y <= y1


@dataclass(frozen=True)
class Wall:
    """An axis-aligned wall from `start` to `end` (m), with doorway gaps.

    doorways: (from, to) distances along the wall from `start`, in m; each is a gap in the wall.
    """

    start: tuple[float, float]
    end: tuple[float, float]
    doorways: tuple[tuple[float, float], ...] = ()
    name: str = ""

    @property
    def length(self) -> float:
        return float(math.dist(self.start, self.end))


@dataclass(frozen=True)
class Furniture:
    """A fixed piece of furniture, an appliance or a decor item.

    kind: the geometry family (see `homer_sim.home.furniture.KINDS`).
    pos: (x, y) centre of the footprint, m, world frame; the base stands on the floor (z = 0) unless
        `on` names the furniture it stands on.
    facing: direction the front faces, one of "E", "N", "W", "S".
    size: (width, depth, height) in m; width runs along the front, depth from back to front.
    category: furniture, appliance or decor.
    params: kind-specific settings, e.g. {"shelves": (0.45, 0.85), "hinge": "left", "drawers": 3}.
    """

    name: str
    cls: str
    kind: str
    room: str
    pos: tuple[float, float]
    facing: str
    size: tuple[float, float, float]
    category: str = "furniture"
    on: str | None = None
    params: dict = field(default_factory=dict, hash=False, compare=False)

    @property
    def yaw(self) -> float:
        return FACING_YAW[self.facing]


@dataclass(frozen=True)
class ObjectDecl:
    """A movable object and its start place.

    relation: ON or INSIDE of `parent`. `level` picks which of the parent's places (shelf, drawer) holds it
    (None: the first with room); `at` fixes (x, y) in m for objects on a room's floor.
    """

    name: str
    cls: str
    parent: str
    relation: int
    level: int | None = None
    at: tuple[float, float] | None = None


@dataclass(frozen=True)
class Layout:
    rooms: tuple[Room, ...]
    walls: tuple[Wall, ...]
    furniture: tuple[Furniture, ...]
    objects: tuple[ObjectDecl, ...]
    wall_height: float = 2.4
    wall_thickness: float = 0.1

    def room_names(self) -> tuple[str, ...]:
        return tuple(r.name for r in self.rooms)

    def node_names(self) -> tuple[str, ...]:
        """Every node in the fixed order graphs use: rooms, furniture, then objects."""
        return self.room_names() + tuple(f.name for f in self.furniture) + tuple(o.name for o in self.objects)

    def furniture_by_name(self) -> dict[str, Furniture]:
        return {f.name: f for f in self.furniture}

    def room_at(self, x: float, y: float) -> str | None:
        for room in self.rooms:
            if room.contains(x, y):
                return room.name
        return None


def node_categories(layout: Layout, object_category: dict[str, str]) -> tuple[str, ...]:
    """Categories aligned with `layout.node_names()`; object_category maps object class -> object/prop."""
    return (
        ("room",) * len(layout.rooms)
        + tuple(f.category for f in layout.furniture)
        + tuple(object_category[o.cls] for o in layout.objects)
    )


def declared_graph(layout: Layout, object_category: dict[str, str]) -> SceneGraph:
    """The start scene graph the layout declares (what settled physics must show)."""
    names = layout.node_names()
    index = {n: i for i, n in enumerate(names)}
    parent = np.full(len(names), -1, dtype=np.int32)
    relation = np.zeros(len(names), dtype=np.int8)
    for f in layout.furniture:
        i = index[f.name]
        parent[i], relation[i] = (index[f.on], ON) if f.on else (index[f.room], INSIDE)
    for o in layout.objects:
        parent[index[o.name]] = index[o.parent]
        relation[index[o.name]] = o.relation
    return SceneGraph(names, node_categories(layout, object_category), parent, relation)
