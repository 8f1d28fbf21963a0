"""The scene graph value: an immutable in-tree over all nodes of the apartment.

This module imports neither mujoco nor rerun: the model package and the dataset code use it as a plain
value. Observing a graph from physics lives in `homer_sim.observe`.
"""

from __future__ import annotations

from collections.abc import Container, Iterator, Sequence
from dataclasses import dataclass

import numpy as np

from homer_sim.errors import HomerError, unknown_name

NONE, ON, INSIDE = 0, 1, 2
RELATION_NAMES = ("NONE", "ON", "INSIDE")
CATEGORIES = ("room", "furniture", "appliance", "prop", "decor", "object")
OUTSIDE = "outside"  # the root beyond the front door (HOMER's name): what the person takes along when they go out


class GraphError(HomerError):
    """A parent array that is not an in-tree."""


@dataclass(frozen=True, eq=False)
class SceneGraph:
    """Each non-room node's parent and relation (ON or INSIDE); rooms are the roots.

    nodes: node names, in a fixed order shared by every graph of one apartment.
    categories: one of CATEGORIES per node.
    parent: Shape (N,), int32, the parent's index, -1 for a root.
    relation: Shape (N,), int8, ON or INSIDE, NONE for a root.
    """

    nodes: tuple[str, ...]
    categories: tuple[str, ...]
    parent: np.ndarray
    relation: np.ndarray

    def __post_init__(self) -> None:
        parent = np.array(self.parent, dtype=np.int32)
        relation = np.array(self.relation, dtype=np.int8)
        parent.flags.writeable = False
        relation.flags.writeable = False
        object.__setattr__(self, "parent", parent)
        object.__setattr__(self, "relation", relation)
        validate_in_tree(self.nodes, self.categories, parent, relation)

    # --- lookup -----------------------------------------------------------------------------------------
    def index(self, name: str) -> int:
        try:
            return self._index_map()[name]
        except KeyError:
            raise unknown_name("node", name, self.nodes) from None

    def _index_map(self) -> dict[str, int]:
        cached = self.__dict__.get("_index_cache")
        if cached is None:
            cached = {name: i for i, name in enumerate(self.nodes)}
            object.__setattr__(self, "_index_cache", cached)
        return cached

    def parent_of(self, name: str) -> str | None:
        p = int(self.parent[self.index(name)])
        return None if p < 0 else self.nodes[p]

    def relation_of(self, name: str) -> str:
        return RELATION_NAMES[int(self.relation[self.index(name)])]

    def children_of(self, name: str) -> list[str]:
        i = self.index(name)
        return [self.nodes[c] for c in np.flatnonzero(self.parent == i)]

    def edges(self) -> Iterator[tuple[str, str, str]]:
        """(child, parent, relation) for every non-root node."""
        for child, p in enumerate(self.parent):
            if p >= 0:
                yield self.nodes[child], self.nodes[p], RELATION_NAMES[int(self.relation[child])]

    def anchor_of(self, name: str, movable: Container[str]) -> str:
        """The first node at or above `name` that is not in `movable` (the furniture, appliance or room an object
        is reached at, through whatever objects it lies on)."""
        while name in movable and self.parent_of(name):
            name = self.parent_of(name)
        return name

    def room_of(self, name: str) -> str:
        """The root above `name` (its room, or `outside`)."""
        i = self.index(name)
        while self.parent[i] >= 0:
            i = int(self.parent[i])
        return self.nodes[i]

    # --- change -----------------------------------------------------------------------------------------
    def with_parent(self, name: str, parent: str, relation: int) -> SceneGraph:
        """A copy in which `name` hangs below `parent` with `relation` (ON or INSIDE)."""
        parent_arr = self.parent.copy()
        relation_arr = self.relation.copy()
        i = self.index(name)
        parent_arr[i] = self.index(parent)
        relation_arr[i] = relation
        return SceneGraph(self.nodes, self.categories, parent_arr, relation_arr)

    def mismatches(self, other: SceneGraph) -> list[dict]:
        """Nodes whose parent or relation differ, as dicts naming both sides."""
        if self.nodes != other.nodes:
            raise GraphError("graphs over different node lists cannot be compared")
        differ = np.flatnonzero((self.parent != other.parent) | (self.relation != other.relation))
        return [
            {
                "node": self.nodes[i],
                "expected": [self.parent_of(self.nodes[i]), self.relation_of(self.nodes[i])],
                "observed": [other.parent_of(self.nodes[i]), other.relation_of(self.nodes[i])],
            }
            for i in differ
        ]

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, SceneGraph):
            return NotImplemented
        return (
            self.nodes == other.nodes
            and np.array_equal(self.parent, other.parent)
            and np.array_equal(self.relation, other.relation)
        )

    def __hash__(self) -> int:
        return hash((self.nodes, self.parent.tobytes(), self.relation.tobytes()))


def validate_in_tree(
    nodes: Sequence[str], categories: Sequence[str], parent: np.ndarray, relation: np.ndarray
) -> None:
    """Raise GraphError unless rooms are the only roots and every other node reaches a room."""
    n = len(nodes)
    if len(categories) != n or parent.shape != (n,) or relation.shape != (n,):
        raise GraphError(f"graph arrays disagree in length: {n} nodes, parent {parent.shape}")
    bad_category = [c for c in categories if c not in CATEGORIES]
    if bad_category:
        raise GraphError(f"unknown categories {sorted(set(bad_category))}; known: {', '.join(CATEGORIES)}")
    is_room = np.array([c == "room" for c in categories], dtype=bool)
    if np.any((parent < -1) | (parent >= n)):
        raise GraphError("parent index out of range")
    roots = parent < 0
    if np.any(roots != is_room):
        wrong = [nodes[i] for i in np.flatnonzero(roots != is_room)]
        raise GraphError(f"only rooms may be roots and every room is one; offending nodes: {wrong[:5]}")
    if np.any(relation[~roots] == NONE) or np.any(relation[roots] != NONE):
        raise GraphError("every non-root needs relation ON or INSIDE, roots none")
    # Pointer jumping: after k rounds each node points 2**k steps up; roots point to themselves.
    jump = np.where(roots, np.arange(n), parent)
    for _ in range(int(np.ceil(np.log2(n + 1))) + 1):
        jump = jump[jump]
    if not np.all(roots[jump]):
        cyclic = [nodes[i] for i in np.flatnonzero(~roots[jump])]
        raise GraphError(f"parent cycle through {cyclic[:5]}")
