"""Names that scripts use, mapped to the apartment's node names.

Lookup order: an exact node name; then `ALIASES` (HOMER/VirtualHome names of things that differ from ours,
mostly class names without our instance suffix); then `SCENERY` (things scripts name that never move and are
not nodes of ours: they map to the furniture or room they belong to, e.g. a faucet to its sink, a ceiling
light to its room). Names are matched in lower case, surrounding spaces ignored.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from functools import cache

from homer_sim.errors import UnknownNameError, unknown_name
from homer_sim.home.apartment import default_layout

ALIASES: dict[str, str] = {
    # Class names of furniture we have several of, or name after their room: the instance scripts mean.
    "kitchen_counter": "kitchen_counter_left",
    "table": "table_dining_room",
    "sink": "sink_dining_room",
    "bookshelf": "bookshelf_dining_room",
    "sofa": "sofa_home_office",
    "desk": "desk_home_office",
    "tvstand": "tvstand_home_office",
    "nightstand": "table_bedroom",
    "towel_rack": "bathroom_counter",
    # Other VirtualHome spellings of our nodes.
    "coffee_maker": "coffe_maker",
    "toothpaste": "tooth_paste",
}
"""Script names of nodes we have under another name."""

SCENERY: dict[str, str] = {
    "faucet": "sink_dining_room",
    "faucet_dining_room": "sink_dining_room",
    "faucet_bathroom": "sink_bathroom",
    "light_dining_room": "dining_room",
    "light_home_office": "home_office",
    "light_bedroom": "bedroom",
    "light_bathroom": "bathroom",
    "computer": "desk_home_office",
    "computer_home_office": "desk_home_office",
    "printer": "desk_home_office",
    "tv": "tvstand_home_office",
    "chair": "chair_home_office",
}
"""Things that never move and are no nodes of ours -> the furniture or room they belong to."""


class UnknownScriptNameError(UnknownNameError):
    """A script names something the apartment has no node, alias or scenery entry for (a KeyError)."""


class Resolver:
    """Maps a name written in a script to a node name: exact, then ALIASES, then SCENERY.

    Entries whose target is not among `node_names` are left out, so a resolver for another apartment only
    knows what it can map.
    """

    def __init__(self, node_names: Iterable[str], aliases: Mapping[str, str] = ALIASES,
                 scenery: Mapping[str, str] = SCENERY) -> None:
        self.nodes = frozenset(node_names)
        table = {name: name for name in self.nodes}
        for extra in (aliases, scenery):
            for name, target in extra.items():
                if target in self.nodes:
                    table.setdefault(name, target)
        self._table = table
        self.known: tuple[str, ...] = tuple(sorted(self.nodes)) + tuple(sorted(set(table) - self.nodes))
        """Every name this resolver maps: the node names first, then alias and scenery names."""

    def __call__(self, name: str) -> str:
        key = name.strip().lower()
        if key in self._table:
            return self._table[key]
        error = unknown_name("name", name, self.known)
        raise UnknownScriptNameError(str(error))

    def __contains__(self, name: str) -> bool:
        return name.strip().lower() in self._table


@cache
def default_resolver() -> Resolver:
    """The resolver of the default apartment (`homer_sim.home.apartment.default_layout`)."""

    return Resolver(default_layout().node_names())
