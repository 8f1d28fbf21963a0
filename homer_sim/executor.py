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

import mujoco
import numpy as np

from homer_sim.avatar import Avatar, AvatarError, compose, relative_pose
from homer_sim.catalog import CATALOG
from homer_sim.errors import HomerError, PhysicsError
from homer_sim.floorplan import find_path
from homer_sim.graph import INSIDE, ON, RELATION_NAMES, SceneGraph
from homer_sim.observe import SceneGraphObserver
from homer_sim.spots import PlacementError, Spot, Spots
from homer_sim.world import World

log = logging.getLogger(__name__)

TICK_MIN = 10
DAY_START_MIN = 360
DAY_END_MIN = 1440
LIFT_M, LIFT_STEPS = 0.06, 30
SETTLE_S = 3.0
DRIVE_PROFILE = {"hinge": (12, 3), "slide": (25, 6)}  # increments, physics steps per increment
DRIVE_REST_STEPS = 10
OPEN_ENOUGH = 0.9


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


class Executor:
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
        self.parts = {}
        for art in world.articulations.values():
            self.parts.setdefault(art.furniture, []).append(art)
        self.dynamic_obstacles: Callable[[], np.ndarray | None] | None = None
        self._paths: dict[tuple, list] = {}
        self.minute = float(DAY_START_MIN)
        self.rng = np.random.default_rng(0)
        self.log = DayLog()
        self._grabbed_from: dict[str, tuple[np.ndarray, np.ndarray]] = {}

    # --- day --------------------------------------------------------------------------------------------
    def start_day(self, rng: np.random.Generator) -> None:
        self.world.reset_settled()
        self.avatar.reset()
        self.rng = rng
        self.minute = float(DAY_START_MIN)
        self.log = DayLog()
        self._grabbed_from = {}
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

    # --- physics helpers --------------------------------------------------------------------------------
    def step(self, n: int) -> None:
        self.world.step(n)
        if self.recording is not None:
            self.recording.log_body_poses(self.world.data)

    def settle(self) -> None:
        start = self.world.data.time
        while self.world.data.time - start < SETTLE_S:
            self.step(25)
            if np.all(self.world.objects_at_rest()):
                break
        self.check_inside()

    def check_inside(self) -> None:
        pos = self.world.object_positions()
        if np.isnan(pos).any() or (pos[:, 2] < -0.3).any():
            name = self.world.object_names[int(np.argmin(np.nan_to_num(pos[:, 2], nan=-9)))]
            raise PhysicsError(f"{name} fell out of the apartment (z = {pos[:, 2].min():.2f} m)")

    def drive(self, art, openness: float) -> None:
        """Move a door or drawer to `openness` along a minimum-jerk path, the hand on its handle.

        The joint is moved kinematically in small increments with physics steps in between, so whatever the
        part touches is pushed and a drawer carries its contents along by friction.
        """
        model, data = self.world.model, self.world.data
        lo, hi = art.range
        start, target = data.qpos[art.qpos_adr], lo + openness * (hi - lo)
        increments, steps = DRIVE_PROFILE[art.joint_type]
        dt = steps * model.opt.timestep
        handle = model.site(f"{art.name}/handle").id
        hand = self.avatar.free_hand()  # with both hands full the person pushes it with an elbow
        previous = start
        for i in range(1, increments + 1):
            s = i / increments
            q = start + (target - start) * (10 * s**3 - 15 * s**4 + 6 * s**5)
            data.qpos[art.qpos_adr] = q
            data.qvel[art.dof_adr] = (q - previous) / dt + 1e-9  # nonzero: the tree stays awake
            previous = q
            self.step(steps)
            if hand is not None:
                self.avatar.set_hand(hand, data.site_xpos[handle], follow=False)
        data.qpos[art.qpos_adr], data.qvel[art.dof_adr] = target, 0.0
        self.step(DRIVE_REST_STEPS)
        self.settle()  # what the part carried or pushed comes to rest
        if hand is not None:
            self.avatar.set_hand(hand, self.avatar.hand_home(hand), follow=False)

    # --- containers -------------------------------------------------------------------------------------
    def part_holding(self, furniture: str, point: np.ndarray | None) -> list:
        """The articulations of `furniture` that must be open to reach `point` (all hinge doors; the drawer
        whose interior contains the point)."""
        parts = self.parts.get(furniture, [])
        doors = [a for a in parts if a.joint_type == "hinge"]
        if doors or point is None:
            return doors
        model, data = self.world.model, self.world.data
        for art in parts:
            body = model.jnt_bodyid[art.joint_id]
            for site in range(model.nsite):
                if model.site_bodyid[site] == body and "/interior_" in model.site(site).name:
                    local = data.site_xmat[site].reshape(3, 3).T @ (point - data.site_xpos[site])
                    if np.all(np.abs(local) <= model.site_size[site] + 0.02):
                        return [art]
        return []

    def ensure_open(self, parts: list, opened: list) -> None:
        for art in parts:
            if self.world.openness(art.name) < OPEN_ENOUGH:
                self.drive(art, 1.0)
                opened.append(art)

    def close_parts(self, parts: list) -> None:
        for art in parts:
            if self.world.openness(art.name) > 0.02:
                self.drive(art, 0.0)

    # --- hands ------------------------------------------------------------------------------------------
    def grab(self, name: str) -> None:
        """Take `name` into a free hand (opening its container if closed), lifting it and what rests on it."""
        if name in self.avatar.carried():
            return
        hand = self.avatar.free_hand()
        if hand is None:
            raise AvatarError(f"cannot grab {name}: both hands hold {', '.join(self.avatar.held.values())}")
        self.go(name)
        container = self.anchor(name)
        opened: list = []
        if self._graph.relation_of(name) == "INSIDE" or container in self.parts:
            self.ensure_open(self.part_holding(container, self.world.object_pose(name)[0]), opened)
        pos, quat = self.world.object_pose(name)
        self._grabbed_from[name] = (pos.copy(), quat.copy(), container)
        riders = [c for c in self._graph.children_of(name) if c in self.movable and c not in self.avatar.carried()]
        hand_body = self.avatar.hands[hand]
        self.avatar.set_hand(hand, pos, follow=False)
        mujoco.mj_kinematics(self.world.model, self.world.data)
        for item in [name, *riders]:
            self.avatar.weld(item, hand_body)
            self.world.set_object_pose(item, *self.world.object_pose(item), forward=False)
        for k in range(LIFT_STEPS):
            self.avatar.set_hand(hand, pos + np.array([0.0, 0.0, LIFT_M * (k + 1) / LIFT_STEPS]), follow=False)
            self.step(1)
        for item in [name, *riders]:
            self.avatar.set_collisions(item, False)
        self.avatar.held[hand] = name
        self.avatar.riders[name] = riders
        self.avatar.set_hand(hand, self.avatar.hand_home(hand), follow=True)
        self.close_parts(opened)

    def release(self, name: str, spot: Spot) -> None:
        """Put a held object (and its riders) at `spot` and let it settle."""
        hand = self.avatar.hand_of(name)
        riders = self.avatar.riders.pop(name, [])
        pos, quat = self.world.object_pose(name)
        rel = {r: relative_pose(pos, quat, *self.world.object_pose(r)) for r in riders}
        target_quat = np.array([math.cos(spot.yaw / 2), 0.0, 0.0, math.sin(spot.yaw / 2)])
        for item in [name, *riders]:
            self.avatar.unweld(item)
            self.avatar.set_collisions(item, True)
        self.world.set_object_pose(name, spot.pos, target_quat, forward=False)
        for rider, (rp, rq) in rel.items():
            self.world.set_object_pose(rider, *compose(np.array(spot.pos), target_quat, rp, rq), forward=False)
        if hand is not None:
            self.avatar.held[hand] = None
            self.avatar.set_hand(hand, spot.pos, follow=False)
        self.world.set_object_pose(name, spot.pos, target_quat)
        self.settle()
        if hand is not None:
            self.avatar.set_hand(hand, self.avatar.hand_home(hand), follow=False)

    def ensure_held(self, name: str) -> None:
        if name in self.avatar.worn:
            self.take_off(name)
        elif self.avatar.hand_of(name) is None:
            self.grab(name)

    # --- placing ----------------------------------------------------------------------------------------
    def put(self, name: str, target: str, relation: int | None) -> None:
        """Put `name` ON/INSIDE `target` (relation None: as the target is built: inside a container)."""
        self.ensure_held(name)
        exclude = set(self.carried_indices())
        if target in self.rooms:
            if self.world.layout.room_at(self.avatar.x, self.avatar.y) != target:
                self.go(target)
            spot = self.spots.floor_spot(name, target, (self.avatar.x, self.avatar.y), self.rng, exclude)
            self.release(name, spot)
        elif target in self.movable:
            self.go(target)
            self.release(name, self._on_object(name, target))
        else:
            self.put_nearby(name, target, relation)
        self.observe()

    def _on_object(self, name: str, target: str) -> Spot:
        """A spot on (or in) object `target`, above whatever already lies there."""
        pos = self.world.object_pose(target)[0]
        x, y = pos[:2] + self.rng.uniform(-0.01, 0.01, size=2)
        z = self.spots.landing_z(name, (x, y), pos[2] + self._cls(target).size[2] / 2 + 0.3)
        return Spot((float(x), float(y), z), 0.0, target, None)

    def _put_on_furniture(self, name: str, target: str, relation: int | None, exclude: set[int]) -> None:
        places = self.spots.places_of(target, relation)
        if not places:
            raise PlacementError(f"{target} has no place to put {name}")
        start_level = next((o.level for o in self.world.layout.objects if o.name == name and o.parent == target), None)
        order = [places[i] for i in self.rng.permutation(len(places))]
        order.sort(key=lambda kp: kp[0] != start_level)
        self.go(target)
        for index, place in order:
            opened: list = []
            if place.relation == INSIDE or place.part is not None:
                needed = [a for a in self.parts.get(target, []) if a.joint_type == "hinge" or
                          a.name.endswith("/" + (place.part or ""))]
                self.ensure_open(needed, opened)
            spot = self.spots.free_spot(name, target, index, self.rng, exclude)
            if spot is not None:
                self.release(name, spot)
                self.close_parts(opened)
                return
            self.close_parts(opened)
        raise PlacementError(f"no free spot for {name} on {target}")

    def put_nearby(self, name: str, target: str, relation: int | None) -> None:
        """Put on `target`, or when it is full on the nearest furniture of the same room that has room (a
        person puts the magazine on the shelf when the counter is full)."""
        try:
            self._put_on_furniture(name, target, relation, set(self.carried_indices()))
            return
        except PlacementError:
            if relation == INSIDE:
                raise
        for other in self.spots.neighbours(target):
            try:
                self._put_on_furniture(name, other, ON, set(self.carried_indices()))
                log.debug("%s: %s full, put on %s", name, target, other)
                return
            except PlacementError:
                continue
        raise PlacementError(f"no free spot for {name} on {target} or any furniture near it")

    def put_back_where_grabbed(self, name: str) -> None:
        """Back to the spot it was taken from if that is still free, else anywhere on the same furniture."""
        self.ensure_held(name)
        if name not in self._grabbed_from:
            raise AvatarError(f"cannot put {name} back: it was not taken from anywhere today")
        pos, quat, anchor = self._grabbed_from[name]
        bottom = pos[2] - self._cls(name).size[2] / 2
        z = self.spots.landing_z(name, (pos[0], pos[1]), pos[2] + 0.3)
        if anchor in self.rooms or z - self._cls(name).size[2] / 2 > bottom + 0.01:
            self.put(name, anchor, None)
            return
        self.go(anchor)
        self.release(name, Spot((float(pos[0]), float(pos[1]), z), 2 * math.atan2(quat[3], quat[0]), anchor, None))
        self.observe()

    def wear(self, name: str) -> None:
        self.ensure_held(name)
        hand = self.avatar.hand_of(name)
        self.avatar.unweld(name)
        self.avatar.held[hand] = None
        slot = len(self.avatar.worn)
        c, s = math.cos(self.avatar.yaw), math.sin(self.avatar.yaw)
        spot = np.array([self.avatar.x - 0.05 * c, self.avatar.y - 0.05 * s, 1.1 + 0.05 * slot])
        self.world.set_object_pose(name, spot, self.world.object_pose(name)[1])
        self.avatar.weld(name, self.avatar.root)
        self.avatar.worn.append(name)

    def take_off(self, name: str) -> None:
        if self.avatar.hand_of(name) is not None:
            return
        if name not in self.avatar.worn:
            raise AvatarError(f"cannot take off {name}: it is not worn")
        hand = self.avatar.free_hand()
        if hand is None:
            raise AvatarError(f"cannot take off {name}: both hands are full")
        self.avatar.unweld(name)
        self.avatar.worn.remove(name)
        self.world.set_object_pose(name, self.avatar.hand_home(hand), self.world.object_pose(name)[1])
        self.avatar.weld(name, self.avatar.hands[hand])
        self.avatar.held[hand] = name

    def _cls(self, name: str):
        return CATALOG[self.world.layout.objects[self.world.object_index(name)].cls]


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
        """Carry out one script action (verbs as in homer_sim.scripts); time-only verbs move the person to
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
        try:
            self.do(action)
        except HomerError as error:
            raise ActionError(activity, action, error) from error

    def run_activity(self, script, start: float, end: float) -> None:
        """Carry out one script over routine minutes [start, end], without snapshots."""
        for minute, action in timed_actions(script, start, end, self.rng):
            self.minute = minute
            self._perform(script.activity, action)

    def run_day(self, entries, scripts: Mapping, rng: np.random.Generator) -> DayLog:
        """Live one day: `entries` are (activity, start_min, end_min) in time order, `scripts` maps each
        activity to the script this household uses. Snapshots every TICK_MIN routine minutes."""
        self.start_day(rng)
        events = []
        for activity, start, end in entries:
            events += [(t, activity, a) for t, a in timed_actions(scripts[activity], start, end, rng)]
            self.log.schedule.append((activity, float(start), float(end)))
        last = max([DAY_END_MIN] + [end for _, _, end in entries])
        grid = range(DAY_START_MIN, int(math.ceil(last / TICK_MIN)) * TICK_MIN + 1, TICK_MIN)
        pending = iter(events)
        event = next(pending, None)
        current = None
        for minute in grid:
            while event is not None and event[0] < minute:
                self.minute = event[0]
                if event[1] != current and self.recording is not None:
                    self.recording.log_event(f"{event[1]} starts", routine_minute=event[0])
                current = event[1]
                self._perform(event[1], event[2])
                event = next(pending, None)
            self.tick(minute)
        return self.log


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
