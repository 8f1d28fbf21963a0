"""The executor: a person lives a sampled schedule in physics, and the scene graph is read every 10 minutes.

Actions act on the world through the avatar: walking is kinematic along grid paths, grasps weld an object to
a hand at its current relative pose and lift it with physics, placements release it at a sampled free spot
where it settles, doors and drawers are driven by force at their joints. The executor finds objects where
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
from homer_sim.home.floorplan import find_path
from homer_sim.home.spots import Spots
from homer_sim.observe import SceneGraphObserver
from homer_sim.person.avatar import Avatar, AvatarError
from homer_sim.person.handling import Handling
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


class Executor(Handling):
    """Runs timed script actions in a World that has an avatar."""

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
        self._object_of_body = {int(b): n for b, n in zip(world.object_body_ids, world.object_names, strict=True)}
        self.parts = {}
        for art in world.articulations.values():
            self.parts.setdefault(art.furniture, []).append(art)
        self.dynamic_obstacles: Callable[[], np.ndarray | None] | None = None
        self._paths: dict[tuple, list] = {}
        self.minute = float(DAY_START_MIN)
        self.rng = np.random.default_rng(0)
        self.log = DayLog()
        self._grabbed_from: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        self.grabbed_at: dict[str, float] = {}  # object -> routine minute the person last took it in hand

    # --- day --------------------------------------------------------------------------------------------
    def start_day(self, rng: np.random.Generator) -> None:
        self.world.reset_settled()
        self.avatar.reset()
        self.rng = rng
        self.minute = float(DAY_START_MIN)
        self.log = DayLog()
        self._grabbed_from = {}
        self.grabbed_at = {}
        self._graph = self.observer.observe_all()

    def carried_indices(self) -> list[int]:
        return [self.world.object_index(n) for n in self.avatar.carried()]

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
        previous = self._graph
        changed = np.flatnonzero((graph.parent != previous.parent) | (graph.relation != previous.relation))
        for i in changed:
            name = self.nodes[i]
            self.log.moves.append((round(self.minute, 2), name, previous.parent_of(name) or "",
                                   graph.parent_of(name) or "", RELATION_NAMES[int(graph.relation[i])]))
        self._graph = graph

    def tick(self, minute: int) -> None:
        """Take the snapshot of grid minute `minute`."""
        self.minute = float(minute)
        graph = self.observe()
        self.log.minutes.append(int(minute))
        self.log.parents.append(graph.parent.copy())
        self.log.relations.append(graph.relation.copy())
        if self.recording is not None:
            self.recording.log_scene_graph(graph, routine_minute=float(minute))

    # --- moving the person ------------------------------------------------------------------------------
    def anchor(self, node: str) -> str:
        """The furniture or room a node is reached at: an object's first non-movable ancestor."""
        graph = self._graph
        while node in self.movable:
            node = graph.parent_of(node)
        return node

    def go(self, node: str) -> None:
        """Walk to where `node` is used (an object: where it lies now)."""
        anchor = self.anchor(node)
        if anchor in self.rooms and node in self.movable:
            pos = self.world.object_pose(node)[0]
            x, y, _ = self.spots.free_floor_near((pos[0], pos[1]), anchor)
            yaw = math.atan2(pos[1] - y, pos[0] - x)
        else:
            x, y, yaw = self.spots.standing_for(anchor)
        self.walk_to(x, y, yaw)

    def walk_to(self, x: float, y: float, yaw: float) -> None:
        if math.hypot(x - self.avatar.x, y - self.avatar.y) > 0.05:
            key = (self.spots.plan.cell(self.avatar.x, self.avatar.y), self.spots.plan.cell(x, y))
            extra = self.dynamic_obstacles() if self.dynamic_obstacles else None
            path = self._paths.get(key) if extra is None else None
            if path is None:
                path = find_path(self.spots.blocked, self.spots.plan, (self.avatar.x, self.avatar.y), (x, y), extra)
                if path is None:
                    raise AvatarError(f"no path from {self.avatar.x:.2f}, {self.avatar.y:.2f} to {x:.2f}, {y:.2f}")
                if extra is None:
                    self._paths[key] = path
            if self.recording is not None:
                self.recording.log_path(path, routine_minute=self.minute)
        self.avatar.move_to(x, y, yaw)
        if self.recording is not None:
            self.recording.log_body_poses(self.world.data, force=True)

    # --- script actions ---------------------------------------------------------------------------------
    def open(self, furniture: str) -> None:
        """Open a door now; a chest of drawers opens the drawer needed when something is taken or put."""
        parts = self.parts.get(furniture, [])
        if parts and all(a.joint_type == "hinge" for a in parts):
            self.go(furniture)
            self.ensure_open(parts, [])

    def close(self, furniture: str) -> None:
        parts = [a for a in self.parts.get(furniture, []) if self.world.openness(a.name) > 0.02]
        if parts:
            self.go(furniture)
            self.close_parts(parts)

    def drop(self, name: str) -> None:
        room = self.world.layout.room_at(self.avatar.x, self.avatar.y)
        self.put(name, room, INSIDE)

    def do(self, action) -> None:
        """Carry out one script action (verbs as in homer_sim.person.scripts); time-only verbs move the person to
        what they act on."""
        verb, args = action.verb, action.args
        handlers = {
            "walk": lambda: self.go_unless_carried(args[0]),
            "grab": lambda: self.grab(args[0]),
            "open": lambda: self.open(args[0]),
            "close": lambda: self.close(args[0]),
            "putback": lambda: self.put(args[0], args[1], None),
            "putin": lambda: self.put(args[0], args[1], INSIDE),
            "putobjback": lambda: self.put_back_where_grabbed(args[0]),
            "puton": lambda: self.wear(args[0]),
            "putoff": lambda: self.take_off(args[0]),
            "drop": lambda: self.drop(args[0]),
        }
        if verb in handlers:
            handlers[verb]()
        elif args:
            self.go_unless_carried(args[-1])

    def go_unless_carried(self, node: str) -> None:
        if node not in self.avatar.carried():
            self.go(node)

    def _perform(self, activity: str, action) -> None:
        if self.recording is not None:
            self.recording.set_routine_time(self.minute)
        try:
            self.do(action)
        except HomerError as error:
            raise ActionError(activity, action, error) from error

    def run_activity(self, script, start: float, end: float) -> None:
        """Carry out one script over routine minutes [start, end], without snapshots."""
        for minute, action in timed_actions(script, start, end, self.rng):
            self.minute = minute
            self._perform(script.activity, action)

    def run_day(self, entries, scripts: Mapping, rng: np.random.Generator,
                after_tick: Callable[[int], float] | None = None, end_min: float | None = None) -> DayLog:
        """Live one day: `entries` are (activity, start_min, end_min) in time order, `scripts` maps each
        activity to the script this household uses. Snapshots every GRID_MIN routine minutes.

        after_tick: called after each snapshot with its grid minute (a robot acting, for instance); returns the
        routine minute its work ends, and actions due before then wait until then. end_min: stop after the
        snapshot at this minute (default: the whole day)."""
        day = DayRun(self, entries, scripts, rng, end_min)
        free_at = -math.inf
        while (minute := day.advance(free_at)) is not None:
            if after_tick is not None:
                free_at = after_tick(minute)
        return self.log


class DayRun:
    """One day lived tick by tick: `advance` carries out the actions due before the next grid minute and takes
    its snapshot, so a caller (the assisted-day task) can act between snapshots. `Executor.run_day` is this loop.
    """

    def __init__(self, executor: Executor, entries, scripts: Mapping, rng: np.random.Generator,
                 end_min: float | None = None) -> None:
        """Start the day (see `Executor.run_day` for the arguments); no action is carried out yet."""
        self.executor = executor
        executor.start_day(rng)
        events = []
        for activity, start, end in entries:
            events += [(t, activity, a) for t, a in timed_actions(scripts[activity], start, end, rng)]
            executor.log.schedule.append((activity, float(start), float(end)))
        last = max([DAY_END_MIN] + [end for _, _, end in entries])
        grid = range(DAY_START_MIN, int(math.ceil(last / GRID_MIN)) * GRID_MIN + 1, GRID_MIN)
        self.grid = [m for m in grid if end_min is None or m <= end_min]  # routine minutes of the snapshots
        self.ended_early = len(self.grid) < len(grid)  # end_min cut the day short
        self._pending = iter(events)
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
        while self._event is not None and self._event[0] < minute:
            start, activity, action = self._event
            executor.minute = max(start, free_at)
            if activity != self._current and executor.recording is not None:
                executor.recording.log_event(f"{activity} starts", routine_minute=start)
            self._current = activity
            executor._perform(activity, action)
            self._event = next(self._pending, None)
        executor.tick(minute)
        return minute

    @property
    def over(self) -> bool:
        """Whether every snapshot of the day has been taken."""
        return self._next >= len(self.grid)


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
