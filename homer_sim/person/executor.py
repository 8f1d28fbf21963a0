"""The executor: a person lives a sampled schedule in physics, and the scene graph is read every 10 minutes.

Actions act on the world through the avatar: walking is kinematic along grid paths, grasps weld an object to
a hand at its current relative pose and lift it with physics, placements lower it onto a sampled free spot
and let go, doors and drawers are driven by force at their joints. The executor finds objects where
the observed scene graph says they are and opens a container only when it is closed and in the way.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np

from homer_sim.clock import DAY_END_MIN, DAY_START_MIN, GRID_MIN
from homer_sim.errors import HomerError
from homer_sim.graph import INSIDE, RELATION_NAMES, SceneGraph
from homer_sim.home.spots import Spots
from homer_sim.observe import SceneGraphObserver
from homer_sim.person.avatar import Avatar
from homer_sim.person.handling import Handling
from homer_sim.person.state import DayState
from homer_sim.person.walking import Walker
from homer_sim.world import World

log = logging.getLogger(__name__)


class ActionError(HomerError):
    """An action of an activity's script could not be carried out; names the activity, line and reason."""

    def __init__(self, activity: str, action, cause: Exception) -> None:
        self.activity, self.line, self.reason = activity, getattr(action, "line", 0), str(cause)
        super().__init__(f"{activity}, line {self.line} ({getattr(action, 'text', action)}): {cause}")


@dataclass
class DayLog:
    """What one executed day produced, on the routine grid and as events."""

    minutes: list[int] = field(default_factory=list)
    parents: list[np.ndarray] = field(default_factory=list)
    relations: list[np.ndarray] = field(default_factory=list)
    moves: list[tuple[float, str, str, str, str]] = field(default_factory=list)
    schedule: list[tuple[str, float, float]] = field(default_factory=list)
    switches: list[tuple[float, str, str]] = field(default_factory=list)
    """(routine minute, node, "ON" or "OFF") for every switchon/switchoff the person did."""


class Executor:
    """Runs timed script actions in a World that has an avatar.

    Builds the parts that act for the person and hands each what it uses: a `Walker` (walking) and a
    `Handling` (grasps, placements, doors and drawers), both sharing the day's `DayState` (minute, random stream,
    last observed graph), which the executor advances; it observes the scene graph and keeps the day's log.
    """

    def __init__(self, world: World, observer: Callable[[World], SceneGraphObserver] = SceneGraphObserver,
                 recording=None) -> None:
        self.world = world
        self.avatar = Avatar(world)
        self.spots = Spots(world)
        self.observer = observer(world)
        self.recording = recording
        self.nodes = world.layout.node_names()
        self.movable = set(world.object_names)
        self.rooms = set(world.layout.room_names())
        self.parts: dict[str, list] = {}
        for art in world.articulations.values():
            self.parts.setdefault(art.furniture, []).append(art)
        self.day = DayState(float(DAY_START_MIN), np.random.default_rng(0))
        self.log = DayLog()
        self.switched_on: set[str] = set()  # the appliances (nodes) the person has switched on and not off
        self.walker = Walker(world, self.avatar, self.spots, self.day, self.movable, self.rooms, recording)
        self.hands = Handling(world, self.avatar, self.spots, self.day, self.walker, self.observe, self.parts,
                              self.movable, self.rooms, recording)

    @property
    def minute(self) -> float:
        """The routine minute the person's day has reached."""
        return self.day.minute

    @minute.setter
    def minute(self, value: float) -> None:
        self.day.minute = value

    @property
    def rng(self) -> np.random.Generator:
        """The day's random stream."""
        return self.day.rng

    @property
    def grabbed_at(self) -> dict[str, float]:
        """Object -> the routine minute the person last took it in hand today."""
        return self.hands.grabbed_at

    @property
    def dynamic_obstacles(self) -> Callable[[], np.ndarray | None] | None:
        """Extra blocked grid cells for each walk (see `Walker`), or None."""
        return self.walker.dynamic_obstacles

    @dynamic_obstacles.setter
    def dynamic_obstacles(self, cells: Callable[[], np.ndarray | None] | None) -> None:
        self.walker.dynamic_obstacles = cells

    # --- day --------------------------------------------------------------------------------------------
    def start_day(self, rng: np.random.Generator) -> None:
        self.world.reset_settled()
        self.avatar.reset()
        self.day.rng = rng
        self.day.minute = float(DAY_START_MIN)
        self.log = DayLog()
        self.switched_on = set()
        self.hands.start_day()
        self.day.graph = self.observer.observe_all()

    def carried_indices(self) -> list[int]:
        return self.hands.carried_indices()

    def person_outside(self) -> bool:
        return self.world.layout.room_at(self.avatar.x, self.avatar.y) == "outside"

    def observe(self) -> SceneGraph:
        """The scene graph now: physics for what rests, last settled parents for what is carried at home,
        `outside` for what the person carries or wears while out."""
        graph = self.observer.update(skip=self.carried_indices())
        if self.person_outside():
            for name in self.avatar.carried():
                graph = graph.with_parent(name, "outside", INSIDE)
        self._record_moves(graph)
        return graph

    def _record_moves(self, graph: SceneGraph) -> None:
        previous = self.day.graph
        changed = np.flatnonzero((graph.parent != previous.parent) | (graph.relation != previous.relation))
        for i in changed:
            name = self.nodes[i]
            self.log.moves.append((round(self.minute, 2), name, previous.parent_of(name) or "",
                                   graph.parent_of(name) or "", RELATION_NAMES[int(graph.relation[i])]))
        self.day.graph = graph

    def tick(self, minute: int) -> None:
        """Take the snapshot of grid minute `minute`."""
        self.minute = float(minute)
        graph = self.observe()
        self.log.minutes.append(int(minute))
        self.log.parents.append(graph.parent.copy())
        self.log.relations.append(graph.relation.copy())
        if self.recording is not None:
            self.recording.log_scene_graph(graph, routine_minute=float(minute))

    # --- what the person does (see `Walker` and `Handling`) -----------------------------------------------
    def go(self, node: str) -> None:
        """Walk to where `node` is used (see `Walker.go`)."""
        self.walker.go(node)

    def grab(self, name: str) -> None:
        """Take `name` into a free hand (see `Handling.grab`)."""
        self.hands.grab(name)

    def put(self, name: str, target: str, relation: int | None) -> None:
        """Put `name` ON/INSIDE `target` (see `Handling.put`)."""
        self.hands.put(name, target, relation)

    def wear(self, name: str) -> None:
        """Put on `name` (see `Handling.wear`)."""
        self.hands.wear(name)

    # --- script actions ---------------------------------------------------------------------------------
    def open(self, furniture: str) -> None:
        """Open a door now; a chest of drawers opens the drawer needed when something is taken or put."""
        parts = self.parts.get(furniture, [])
        if parts and all(a.joint_type == "hinge" for a in parts):
            self.walker.go(furniture)
            self.hands.ensure_open(parts, [])

    def close(self, furniture: str) -> None:
        parts = [a for a in self.parts.get(furniture, []) if self.world.openness(a.name) > 0.02]
        if parts:
            self.walker.go(furniture)
            self.hands.close_parts(parts)

    def switch(self, node: str, on: bool) -> None:
        """Switch the appliance `node` on or off where it stands: its state goes to `switched_on` and the log."""
        self.go_unless_carried(node)
        (self.switched_on.add if on else self.switched_on.discard)(node)
        self.log.switches.append((round(self.minute, 2), node, "ON" if on else "OFF"))

    def drop(self, name: str) -> None:
        room = self.world.layout.room_at(self.avatar.x, self.avatar.y)
        self.hands.put(name, room, INSIDE)

    def do(self, action) -> None:
        """Carry out one script action (verbs as in homer_sim.person.scripts); time-only verbs move the person to
        what they act on."""
        verb, args = action.verb, action.args
        handlers = {
            "walk": lambda: self.go_unless_carried(args[0]),
            "grab": lambda: self.hands.grab(args[0]),
            "open": lambda: self.open(args[0]),
            "close": lambda: self.close(args[0]),
            "putback": lambda: self.hands.put(args[0], args[1], None),
            "putin": lambda: self.hands.put(args[0], args[1], INSIDE),
            "putobjback": lambda: self.hands.put_back_where_grabbed(args[0]),
            "puton": lambda: self.hands.wear(args[0]),
            "putoff": lambda: self.hands.take_off(args[0]),
            "drop": lambda: self.drop(args[0]),
            "switchon": lambda: self.switch(args[0], True),
            "switchoff": lambda: self.switch(args[0], False),
        }
        if verb in handlers:
            handlers[verb]()
        elif args:
            self.go_unless_carried(args[-1])

    def go_unless_carried(self, node: str) -> None:
        if node not in self.avatar.carried():
            self.walker.go(node)

    def _perform(self, activity: str, action) -> None:
        if self.recording is not None:
            self.recording.set_routine_time(self.minute)
        try:
            self.do(action)
        except HomerError as error:
            raise ActionError(activity, action, error) from error

    def run_activity(self, script, start: float, end: float) -> None:
        """Carry out one script over routine minutes [start, end], without snapshots."""
        for minute, action in timed_actions(script, start, end, self.day.rng):
            self.minute = minute
            self._perform(script.activity, action)

    def run_day(self, entries, scripts: Mapping, rng: np.random.Generator,
                after_tick: Callable[[int], float] | None = None, end_min: float | None = None) -> DayLog:
        """Live one day: `entries` are (activity, start_min, end_min) in time order, `scripts` maps each
        activity to the script this household uses. Snapshots every GRID_MIN routine minutes.

        after_tick: called after each snapshot with its grid minute (a robot acting, for instance); returns the
        routine minute its work ends, and actions due before then wait until then. end_min: stop after the
        snapshot at this minute (default: the whole day)."""
        events, last = self.begin_day(entries, scripts, rng)
        return self.live(events, last, after_tick, end_min)

    def begin_day(self, entries, scripts: Mapping, rng: np.random.Generator) -> tuple[list, float]:
        """Start the day of `entries` (see `run_day`); returns its timed events, (routine minute, activity,
        action) in time order, and the last minute its snapshots reach (before rounding up to the grid)."""
        self.start_day(rng)
        events = []
        for activity, start, end in entries:
            events += [(t, activity, a) for t, a in timed_actions(scripts[activity], start, end, rng)]
            self.log.schedule.append((activity, float(start), float(end)))
        return events, max([DAY_END_MIN] + [end for _, _, end in entries])

    def live(self, events, last: float, after_tick: Callable[[int], float] | None = None,
             end_min: float | None = None, after_action: Callable[[int], None] | None = None,
             on_error: Callable[[int, ActionError], None] | None = None) -> DayLog:
        """Carry out `events`, (routine minute, activity, action) in time order, on a day already started, with a
        snapshot every GRID_MIN minutes up to `last` (rounded up to the grid). after_tick and end_min as in
        `run_day`; after_action: called with each event's index once it is done; on_error: called with an
        event's index and its ActionError when it fails, and the day goes on (without it the error ends the day)."""
        day = DayRun(self, events, last, end_min, after_action, on_error)
        free_at = -math.inf
        while (minute := day.advance(free_at)) is not None:
            if after_tick is not None:
                free_at = after_tick(minute)
        return self.log


class DayRun:
    """A started day lived tick by tick: `advance` carries out the actions due before the next grid minute and
    takes its snapshot, so a caller (the assisted-day task) can act between snapshots. `Executor.live` is this
    loop."""

    def __init__(self, executor: Executor, events, last: float, end_min: float | None = None,
                 after_action: Callable[[int], None] | None = None,
                 on_error: Callable[[int, ActionError], None] | None = None) -> None:
        """events, last, end_min, after_action and on_error as in `Executor.live`; no action is carried out yet."""
        self.executor = executor
        grid = range(DAY_START_MIN, int(math.ceil(last / GRID_MIN)) * GRID_MIN + 1, GRID_MIN)
        self.grid = [m for m in grid if end_min is None or m <= end_min]  # routine minutes of the snapshots
        self.ended_early = len(self.grid) < len(grid)  # end_min cut the day short
        self.after_action, self.on_error = after_action, on_error
        self._pending = iter(enumerate(events))
        self._event = next(self._pending, None)
        self._current: str | None = None
        self._next = 0

    def advance(self, free_at: float = -math.inf) -> int | None:
        """Carry out the actions due before the next grid minute (none starts before routine minute `free_at`)
        and take that minute's snapshot; returns the minute, or None when the day is over."""
        if self._next >= len(self.grid):
            return None
        minute = self.grid[self._next]
        self._next += 1
        executor = self.executor
        while self._event is not None and self._event[1][0] < minute:
            index, (start, activity, action) = self._event
            executor.minute = max(start, free_at)
            if activity != self._current and executor.recording is not None:
                executor.recording.log_event(f"{activity} starts", routine_minute=start)
            self._current = activity
            try:
                executor._perform(activity, action)
            except ActionError as error:
                if self.on_error is None:
                    raise
                self.on_error(index, error)
            if self.after_action is not None:
                self.after_action(index)
            self._event = next(self._pending, None)
        executor.tick(minute)
        return minute


def timed_actions(script, start: float, end: float, rng: np.random.Generator) -> list[tuple[float, object]]:
    """(routine minute, action) for each action of `script` spread over [start, end]: block durations are
    drawn in their ranges and scaled to the activity's length, actions spread at random inside each block."""
    blocks = [b for b in script.blocks]
    if not blocks:
        return []
    durations = np.array([rng.uniform(b.min_min, b.max_min) for b in blocks])
    total = durations.sum()
    durations = durations * ((end - start) / total) if total > 0 else np.full(len(blocks), (end - start) / len(blocks))
    timed, t = [], float(start)
    for block, duration in zip(blocks, durations, strict=True):
        offsets = np.sort(rng.uniform(0.0, duration, len(block.actions)))
        timed += [(t + float(o), action) for o, action in zip(offsets, block.actions, strict=True)]
        t += float(duration)
    return timed
