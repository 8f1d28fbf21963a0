"""Names that scripts use, mapped to the apartment's node names: the alias table `aliases.json`.

Lookup order, names matched in lower case with surrounding spaces ignored:

1. `instances` ("name (id)" -> node or null): one VirtualHome instance of the HOMER+ apartment, used when a script
   writes the id (`<kitchen_counter> (119)`, as the HOMER+ day scripts do). The authors' apartment has several
   pieces of one class where ours has fewer or names them by room; the id tells which one is meant (the ids
   are numbered room by room, and the authors' graphs give each piece's room and what stands on it). Two ids
   may map onto one node when we have one piece for two of theirs: their kitchen counters 122 (the coffee
   maker's) and 123 (the stove's, with the cutting board and bread) are both our left counter, which holds
   those; 119 (the sink's, where their scripts put most things) is our right one. Going by what the counters
   stand beside instead (our left one is beside our sink, the right one beside our stove) puts 119 and 122 on
   our left counter, which is then too full for what the authors set down there (replay-check on household A:
   92.1% agreement over what we have, against 92.8%). null marks an instance we have no counterpart for (none
   at present): it is unknown even though its class name alone would resolve.
2. the exact node name;
3. `aliases` (name -> node): HOMER/VirtualHome names of things we have under another name, mostly class names
   without our instance suffix (`table` -> `table_dining_room`) and other spellings of one thing
   (`water_glass` -> `drinking_glass`, `phone` -> `cellphone`);
4. `scenery` (name -> node): things scripts name that never move and are not nodes of ours, mapped to the
   furniture or room they belong to (a faucet to its sink, a light to its room), so the person goes there.

A name none of these maps is unknown: a script naming it fails with an error naming the file, line and the
closest known names. Things that have no counterpart stay unknown rather than being mapped onto something
merely similar (a sauce pan is not our cooking pot).
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Mapping
from functools import cache
from pathlib import Path

from homer_sim.errors import UnknownNameError, unknown_name
from homer_sim.home.apartment import default_layout

TABLE_PATH = Path(__file__).resolve().parent / "aliases.json"
_TABLE = json.loads(TABLE_PATH.read_text())

ALIASES: dict[str, str] = _TABLE["aliases"]
"""Script names of nodes we have under another name."""

SCENERY: dict[str, str] = _TABLE["scenery"]
"""Things that never move and are no nodes of ours -> the furniture or room they belong to."""

INSTANCES: dict[str, str | None] = _TABLE["instances"]
"""HOMER+ apartment instances, "name (id)" -> node, or None for an instance we have no counterpart for."""


def instance_key(name: str, instance: int | None) -> str | None:
    """The `INSTANCES` key of `name` with VirtualHome id `instance` (None without an id)."""
    return None if instance is None else f"{name.strip().lower()} ({instance})"


class UnknownScriptNameError(UnknownNameError):
    """A script names something the apartment has no node, alias or scenery entry for (a KeyError)."""


class Resolver:
    """Maps a name written in a script (and its VirtualHome id, if written) to a node name: instances, exact,
    ALIASES, then SCENERY.

    Entries whose target is not among `node_names` are left out, so a resolver for another apartment only
    knows what it can map; an instance mapped to None stays unknown.
    """

    def __init__(self, node_names: Iterable[str], aliases: Mapping[str, str] = ALIASES,
                 scenery: Mapping[str, str] = SCENERY, instances: Mapping[str, str | None] = INSTANCES) -> None:
        self.nodes = frozenset(node_names)
        table = {name: name for name in self.nodes}
        for extra in (aliases, scenery):
            for name, target in extra.items():
                if target in self.nodes:
                    table.setdefault(name, target)
        self._table = table
        self._instances = {key: target for key, target in instances.items() if target is None or target in self.nodes}
        self.known: tuple[str, ...] = tuple(sorted(self.nodes)) + tuple(sorted(set(table) - self.nodes))
        """Every name this resolver maps: the node names first, then alias and scenery names."""

    def __call__(self, name: str, instance: int | None = None) -> str:
        key = instance_key(name, instance)
        if key in self._instances:
            if self._instances[key] is None:
                raise UnknownScriptNameError(f"unknown name {name!r}: instance {instance} of the HOMER+ apartment "
                                             "has no counterpart here (see aliases.json)")
            return self._instances[key]
        if name.strip().lower() in self._table:
            return self._table[name.strip().lower()]
        error = unknown_name("name", name, self.known)
        raise UnknownScriptNameError(str(error))

    def knows(self, name: str, instance: int | None = None) -> bool:
        """Whether `name` (with VirtualHome id `instance`) resolves."""
        key = instance_key(name, instance)
        if key in self._instances:
            return self._instances[key] is not None
        return name.strip().lower() in self._table

    def __contains__(self, name: str) -> bool:
        return self.knows(name)


@cache
def default_resolver() -> Resolver:
    """The resolver of the default apartment (`homer_sim.home.apartment.default_layout`)."""

    return Resolver(default_layout().node_names())
