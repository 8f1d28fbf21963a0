"""How the person handles things: grasping, carrying, putting down, opening and closing, in physics.

`Handling` is the part of the person that touches objects and articulations; `homer_sim.person.executor.Executor`
builds it and adds the day and script dispatch, `homer_sim.person.walking.Walker` the walking. Grasps weld an
object to a hand at its current relative pose and lift it with physics; a put-down brings it above a sampled free
spot, lowers it until it touches down and lets go; doors and drawers are driven through their joints by force
along minimum-jerk paths.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable

import mujoco
import numpy as np

from homer_sim.errors import PhysicsError
from homer_sim.graph import INSIDE, ON, SceneGraph
from homer_sim.home.placement import yaw_quat
from homer_sim.home.spots import PlacementError, Spot, Spots, keep_out_rect
from homer_sim.person.avatar import Avatar, AvatarError, compose, relative_pose
from homer_sim.person.state import DayState
from homer_sim.person.walking import Walker
from homer_sim.world import World

log = logging.getLogger(__name__)

LIFT_M, LIFT_STEPS = 0.06, 30
SETTLE_S = 3.0
DRIVE_PROFILE = {"hinge": (16, 5), "slide": (25, 6)}  # increments, physics steps per increment
DRIVE_REST_STEPS = 10
LOWER_M = 0.02  # m above its spot from which a put-down object is lowered onto it
LOWER_PRESS_M = 0.01  # m the hand goes on below the spot when the object has not touched down by then
LOWER_STEPS, LOWER_STEP_PHYSICS = 10, 5  # increments of the lowering, physics steps per increment
DRIVE_OMEGA = 40.0  # rad/s, the natural frequency of the spring that keeps a driven part on its path
DRIVE_TOLERANCE = 0.02  # of the joint's range: how near its target a driven part is let go
DRIVE_AT_REST = 0.05  # rad/s or m/s under which a driven part at its target is let go
DRIVE_STUCK = 0.1  # of the joint's range: a driven part further than this from its target is stuck
DRIVE_HOLD_STEPS = 250  # physics steps the force may hold a part after its path ends, to reach its target
OPEN_ENOUGH = 0.9


class DoorBlocked(AvatarError):
    """A door the person swings touches an object (`blocker`) and stops there."""

    def __init__(self, message: str, blocker: str) -> None:
        super().__init__(message)
        self.blocker = blocker


class Handling:
    """Grasping, placing and articulations by the `avatar` in `world`.

    Inputs, declared: the world, the avatar, the free spots (`spots`), the day so far (`day`: its random stream
    samples spots, its graph says what rests on what, its minute stamps grasps), the `walker` that takes the
    person where a node is used, `observe` (reads the scene graph after a put, recording what moved), the doors
    and drawers of each furniture (`parts`), the names of the movable objects and of the rooms, and an optional
    recording. State: where each object was taken from today and when (`grabbed_at`, routine minutes).
    """

    def __init__(self, world: World, avatar: Avatar, spots: Spots, day: DayState, walker: Walker,
                 observe: Callable[[], SceneGraph], parts: dict[str, list], movable: set[str], rooms: set[str],
                 recording=None) -> None:
        self.world = world
        self.avatar = avatar
        self.spots = spots
        self.day = day
        self.walker = walker
        self.observe = observe
        self.parts = parts
        self.movable = movable
        self.rooms = rooms
        self.recording = recording
        self._object_of_body = {int(b): n for b, n in zip(world.object_body_ids, world.object_names, strict=True)}
        self._grabbed_from: dict[str, tuple[np.ndarray, np.ndarray, str]] = {}
        self.grabbed_at: dict[str, float] = {}  # object -> routine minute the person last took it in hand

    def start_day(self) -> None:
        """Forget what was taken where on an earlier day."""
        self._grabbed_from = {}
        self.grabbed_at = {}

    def carried_indices(self) -> list[int]:
        """Object indices of what the person holds or wears."""
        return [self.world.object_index(n) for n in self.avatar.carried()]

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

    def drive(self, art, openness: float, retried: bool = False) -> None:
        """Move a door or drawer to `openness` by force, the hand on its handle.

        A force on the joint (`qfrc_applied`) makes the part follow a minimum-jerk path: the path's own inertial
        and damping force plus a critically damped spring to it, re-evaluated at every physics step; at the end
        the force holds the target until the part is there and at rest (at most DRIVE_HOLD_STEPS), then lets go.
        Whatever the part touches is pushed, and a drawer carries its contents along by friction; a door that
        touches an object stops and raises DoorBlocked; a part the force leaves far from its target (jammed, too
        stiff) raises AvatarError, unless the walker's `make_way` (the robot) cleared the part's swing and a second
        push (`retried`) gets it there: a robot standing in the washing machine door's swing jammed it.
        """
        model, data = self.world.model, self.world.data
        lo, hi = art.range
        start, target = float(data.qpos[art.qpos_adr]), lo + openness * (hi - lo)
        increments, steps = DRIVE_PROFILE[art.joint_type]
        duration = increments * steps * model.opt.timestep
        handle = model.site(f"{art.name}/handle").id
        hand = self.avatar.free_hand()  # with both hands full the person pushes it with an elbow
        inertia = float(model.dof_M0[art.dof_adr])  # the part's own (a door on a fixed hinge), armature included
        damping = float(model.dof_damping[art.dof_adr])
        stiffness, gain = inertia * DRIVE_OMEGA**2, 2.0 * inertia * DRIVE_OMEGA
        tolerance = DRIVE_TOLERANCE * (hi - lo)

        def push(t: float) -> None:
            s = min(t / duration, 1.0)
            q = start + (target - start) * (10 * s**3 - 15 * s**4 + 6 * s**5)
            v = (target - start) * (30 * s**2 - 60 * s**3 + 30 * s**4) / duration if s < 1.0 else 0.0
            a = (target - start) * (60 * s - 180 * s**2 + 120 * s**3) / duration**2 if s < 1.0 else 0.0
            data.qfrc_applied[art.dof_adr] = (inertia * a + damping * v + stiffness * (q - data.qpos[art.qpos_adr])
                                              + gain * (v - data.qvel[art.dof_adr]))

        try:
            t = 0.0
            for _ in range(increments):
                for _ in range(steps):
                    push(t)
                    self.step(1)
                    t += model.opt.timestep
                blocker = self._door_blocked(art) if art.joint_type == "hinge" else None
                if blocker is not None:
                    raise DoorBlocked(f"{art.name} is blocked by {blocker} at openness "
                                      f"{self.world.openness(art.name):.2f}", blocker)
                if hand is not None:
                    self.avatar.set_hand(hand, data.site_xpos[handle], follow=False)
            for _ in range(DRIVE_HOLD_STEPS):
                if abs(data.qpos[art.qpos_adr] - target) < tolerance and abs(data.qvel[art.dof_adr]) < DRIVE_AT_REST:
                    break
                push(t)
                self.step(1)
        finally:
            data.qfrc_applied[art.dof_adr] = 0.0
        if abs(data.qpos[art.qpos_adr] - target) > DRIVE_STUCK * (hi - lo):
            if not retried and self._make_way_for(art):  # the robot stood in its swing: once more
                self.drive(art, openness, retried=True)
                return
            raise AvatarError(f"{art.name} is stuck at openness {self.world.openness(art.name):.2f}: the person's "
                              f"push did not move it to {openness:.2f}")
        self.step(DRIVE_REST_STEPS)
        self.settle()  # what the part carried or pushed comes to rest
        if hand is not None:
            self.avatar.set_hand(hand, self.avatar.hand_home(hand), follow=False)

    def _others(self) -> np.ndarray | None:
        """The floor cells the walker's `dynamic_obstacles` block now (where a robot stands), None without any:
        nothing is set down there (a vacuum cleaner put down beside the robot fell against it)."""
        return self.walker.dynamic_obstacles() if self.walker.dynamic_obstacles else None

    def _make_way_for(self, art) -> bool:
        """Ask the walker's `make_way` to clear the floor in front of `art`'s furniture (`keep_out_rect`, points
        every 0.1 m); whether it moved."""
        rect = keep_out_rect(self.world.layout.furniture_by_name()[art.furniture])
        if self.walker.make_way is None or rect is None:
            return False
        xs, ys = np.meshgrid(np.arange(rect[0], rect[2] + 1e-9, 0.1), np.arange(rect[1], rect[3] + 1e-9, 0.1))
        return self.walker.make_way([(float(x), float(y)) for x, y in zip(xs.ravel(), ys.ravel(), strict=True)])

    def _door_blocked(self, art) -> str | None:
        """The object a swinging door touches, if any (a door never shoves things out of its way)."""
        model, data = self.world.model, self.world.data
        if data.ncon == 0:
            return None
        door = model.jnt_bodyid[art.joint_id]
        bodies = model.geom_bodyid[data.contact.geom]
        for a, b in bodies:
            other = b if a == door else a if b == door else None
            if other is not None and other in self._object_of_body:
                return self._object_of_body[other]
        return None

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
        """Open each part that is not open enough; an object in a door's way is set aside first (once)."""
        for art in parts:
            if self.world.openness(art.name) < OPEN_ENOUGH:
                try:
                    self.drive(art, 1.0)
                except DoorBlocked as blocked:
                    self._set_aside(blocked)
                    self.drive(art, 1.0)
                opened.append(art)

    def close_parts(self, parts: list) -> None:
        """Close each part; an object sticking out into a door's way is pushed back in first (once)."""
        for art in parts:
            if self.world.openness(art.name) > 0.02:
                try:
                    self.drive(art, 0.0)
                except DoorBlocked as blocked:
                    self._push_back(blocked.blocker, art.name.split("/")[0], blocked)
                    self.drive(art, 0.0)

    def _push_back(self, name: str, furniture: str, blocked: DoorBlocked) -> None:
        """Put `name` (in the way of a door of `furniture`) at a free spot inside it, as a person tidies a
        toppled glass back onto its shelf before closing the cupboard; re-raises `blocked` if there is none."""
        if name in self.avatar.carried():
            raise blocked
        exclude = set(self.carried_indices()) | {self.world.object_index(name)}
        for index, _ in self.spots.places_of(furniture, INSIDE):
            spot = self.spots.free_spot(name, furniture, index, self.day.rng, exclude)
            if spot is not None:
                log.debug("%s: pushed back into %s so the door closes", name, furniture)
                self.world.set_object_pose(name, spot.pos, yaw_quat(spot.yaw))
                self.settle()
                return
        raise blocked

    def _set_aside(self, blocked: DoorBlocked) -> None:
        """Move the object in the way of a door the person opens to a free floor spot nearby (it fell out, or
        someone left it there); re-raises `blocked` if the person holds it or there is no room."""
        name = blocked.blocker
        room = self.world.layout.room_at(self.avatar.x, self.avatar.y)
        if name in self.avatar.carried() or room is None:
            raise blocked
        exclude = set(self.carried_indices()) | {self.world.object_index(name)}
        try:
            spot = self.spots.floor_spot(name, room, (self.avatar.x, self.avatar.y), self.day.rng, exclude,
                                         self._others())
        except PlacementError:
            raise blocked from None
        log.debug("%s: set aside so a door opens", name)
        self.world.set_object_pose(name, spot.pos)
        self.settle()

    # --- hands ------------------------------------------------------------------------------------------
    def grab(self, name: str) -> None:
        """Take `name` into a free hand (opening its container if closed), lifting it and what rests on it."""
        if name in self.avatar.carried():
            return
        hand = self.avatar.free_hand()
        if hand is None:
            raise AvatarError(f"cannot grab {name}: both hands hold {', '.join(self.avatar.held.values())}")
        self.walker.go(name)
        container = self.walker.anchor(name)
        opened: list = []
        if self.day.graph.relation_of(name) == "INSIDE" or container in self.parts:
            self.ensure_open(self.part_holding(container, self.world.object_pose(name)[0]), opened)
        pos, quat = self.world.object_pose(name)
        self._grabbed_from[name] = (pos.copy(), quat.copy(), container)
        self.grabbed_at[name] = self.day.minute
        riders = [c for c in self.day.graph.children_of(name) if c in self.movable and c not in self.avatar.carried()]
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
        """Put a held object (and its riders) down at `spot`: the hand, turning it to the spot's yaw, brings it
        LOWER_M above the spot, lowers it with physics until it touches what it is put on (or reaches the spot),
        lets go, and the object settles. One in no hand (carried otherwise) is set onto the spot and settles."""
        hand = self.avatar.hand_of(name)
        riders = self.avatar.riders.pop(name, [])
        pos, quat = self.world.object_pose(name)
        rel = {r: relative_pose(pos, quat, *self.world.object_pose(r)) for r in riders}
        target_quat = np.array(yaw_quat(spot.yaw))
        above = np.array(spot.pos) + np.array([0.0, 0.0, LOWER_M if hand is not None else 0.0])
        for item in [name, *riders]:
            self.avatar.unweld(item)
        self.world.set_object_pose(name, above, target_quat, forward=False)
        for rider, (rp, rq) in rel.items():
            self.world.set_object_pose(rider, *compose(above, target_quat, rp, rq), forward=False)
        if hand is not None:
            self.avatar.held[hand] = None
            self.avatar.set_hand(hand, above, follow=False)
        mujoco.mj_kinematics(self.world.model, self.world.data)
        for item in [name, *riders]:
            if hand is not None:
                self.avatar.weld(item, self.avatar.hands[hand])
            self.avatar.set_collisions(item, True)
        self.world.set_object_pose(name, above, target_quat)  # at rest, kinematics updated
        if hand is not None:
            self._lower(name, hand, above, riders)
            for item in [name, *riders]:
                self.avatar.unweld(item)
        self.settle()
        if hand is not None:
            self.avatar.set_hand(hand, self.avatar.hand_home(hand), follow=False)

    def _lower(self, name: str, hand: str, above: np.ndarray, riders: list[str]) -> None:
        """Move `hand`, holding `name` (welded) from `above`, down LOWER_M (and LOWER_PRESS_M more) with physics,
        until `name` touches something other than itself, its riders and the hand."""
        model, data = self.world.model, self.world.data
        own = {self.world.object_body_ids[self.world.object_index(o)] for o in [name, *riders]} | {
            self.avatar.hands[hand], self.avatar.root}
        body = self.world.object_body_ids[self.world.object_index(name)]
        for k in range(1, LOWER_STEPS + 1):
            self.avatar.set_hand(hand, above - np.array([0.0, 0.0, (LOWER_M + LOWER_PRESS_M) * k / LOWER_STEPS]),
                                 follow=False)
            self.step(LOWER_STEP_PHYSICS)
            touching = [(a, b) for a, b in model.geom_bodyid[data.contact.geom[: data.ncon]] if body in (a, b)]
            if any((b if a == body else a) not in own for a, b in touching):
                return

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
                self.walker.go(target)
            spot = self.spots.floor_spot(name, target, (self.avatar.x, self.avatar.y), self.day.rng, exclude,
                                         self._others())
            self.release(name, spot)
        elif target in self.movable:
            self.walker.go(target)
            self.release(name, self._on_object(name, target))
        else:
            self.put_nearby(name, target, relation)
        self.observe()

    def _on_object(self, name: str, target: str) -> Spot:
        """A spot on (or in) object `target`, above whatever already lies there."""
        pos = self.world.object_pose(target)[0]
        x, y = pos[:2] + self.day.rng.uniform(-0.01, 0.01, size=2)
        z = self.spots.landing_in(name, target, (x, y), pos[2] + self._cls(target).size[2] / 2 + 0.3)
        return Spot((float(x), float(y), z), 0.0, target, None)

    def _put_on_furniture(self, name: str, target: str, relation: int | None, exclude: set[int]) -> None:
        places = self.spots.places_of(target, relation)
        if not places:
            raise PlacementError(f"{target} has no place to put {name}")
        start_level = next((o.level for o in self.world.layout.objects if o.name == name and o.parent == target), None)
        order = [places[i] for i in self.day.rng.permutation(len(places))]
        order.sort(key=lambda kp: kp[0] != start_level)
        self.walker.go(target)
        for index, place in order:
            opened: list = []
            if place.relation == INSIDE or place.part is not None:
                needed = [a for a in self.parts.get(target, []) if a.joint_type == "hinge" or
                          a.name.endswith("/" + (place.part or ""))]
                self.ensure_open(needed, opened)
            spot = self.spots.free_spot(name, target, index, self.day.rng, exclude, packed=True)
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
        self.walker.go(anchor)
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
        return self.world.object_class(name)
