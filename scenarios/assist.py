"""The robot's turn in the assisted day: relocations asked for at a 10-minute snapshot, carried out in physics.

`Helper.act` orders the relocations into skill calls (`scenarios.psi.plan_steps`: a container is opened before
it is used and closed after), runs them with the robot's skills and drives the robot back to its parking pose,
out of the person's way. The physics seconds it spends pass on the routine clock: the person's next actions wait
until the robot is done (they take turns). The robot does not drive into the person (`Navigator.others`); a
relocation that only the person stood in the way of, the robot not holding its object, waits and is tried again at
the next snapshot the robot acts at. Every other relocation ends done (the object observed on its destination)
or not, with the skill's reason; one whose object a later step of the same turn moved more than COLLATERAL_M is not
done after all; objects the robot displaced more than COLLATERAL_M that no relocation named are kept as collateral.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from homer_sim.errors import PhysicsError
from homer_sim.graph import ON, SceneGraph
from homer_sim.home.validate import blocked_when_open
from homer_sim.person.executor import DayLog, Executor
from homer_sim.world import World
from planners.motion.control import FREE_MOTION
from planners.motion.navigation import IN_THE_WAY, NavigationError
from planners.robot import DEFAULT_POSE, ROBOT_CLEARANCE_M
from planners.skills import Robot, SkillResult
from planners.skills.parts import CLOSED_OK, parts_to_open, parts_to_place
from scenarios.causes import SKILL_ERROR
from scenarios.psi import PlanStep, Relocation, anchor_of, plan_steps

log = logging.getLogger(__name__)

FALLBACK_PLACES = 3  # places tried to put an object down after a failed place
COLLATERAL_M = 0.02  # an object the robot moved farther than this (m) without being asked is collateral
PERSON_RADIUS_M = 0.25  # m around the person's position the robot's base keeps out of


@dataclass(frozen=True)
class StepOutcome:
    """One robot skill call: at routine `minute`, `step` done or not (with the skill's reason), taking
    `physics_s` seconds."""

    minute: float
    step: PlanStep
    success: bool
    reason: str
    physics_s: float


@dataclass(frozen=True)
class RelocationOutcome:
    """A relocation the robot attempted at query minute `minute`: done (the object observed on its destination
    afterwards) or why not; `ended_on` is the object's observed parent after the attempt."""

    minute: int
    relocation: Relocation
    done: bool
    reason: str
    ended_on: str


@dataclass
class AssistLog:
    """What the robot did over an assisted run, and the person's day as it went."""

    steps: list[StepOutcome] = field(default_factory=list)
    relocations: list[RelocationOutcome] = field(default_factory=list)
    collateral: list[tuple[int, str, float]] = field(default_factory=list)  # (query minute, object, moved m)
    robot_minutes: float = 0.0
    day: DayLog | None = None
    error: str = ""  # why the person could not go on, if they could not (the run stops there)


def containers_of(world: World) -> dict[str, tuple[str, ...]]:
    """Furniture with doors or drawers -> its articulation names."""
    found: dict[str, list[str]] = {}
    for art in world.articulations.values():
        found.setdefault(art.furniture, []).append(art.name)
    return {k: tuple(v) for k, v in found.items()}


class Helper:
    """The robot in an apartment with the person: `act` carries out relocations at a snapshot."""

    def __init__(self, world: World, executor: Executor, rng: np.random.Generator, recording=None) -> None:
        self.world = world
        self.executor = executor
        self.recording = recording
        self.robot = Robot(world, rng)
        self.containers = containers_of(world)
        self.blocked = blocked_when_open(world.layout)  # container -> furniture its open doors stand in front of
        self.log = AssistLog()
        self.waiting: list[Relocation] = []  # relocations the person stood in the way of, for the next snapshot
        self._placed_at: dict[str, np.ndarray] = {}  # where this turn's done relocations left their objects (m)
        executor.dynamic_obstacles = self.robot_cells
        executor.walker.make_way = self.make_way
        self.robot.navigator.others = self.person_rects

    def act(self, relocations: Sequence[Relocation], graph: SceneGraph, movable: np.ndarray, minute: int) -> float:
        """Carry out `relocations` (in this order) at grid minute `minute`, where `graph` was observed (movable:
        Shape (N,) bool over its nodes), after those that waited for the person to get out of the way (still on
        their source and not asked for again), then park; returns the routine minute the robot is done (`minute`
        when there is nothing to do). A waiting relocation whose object the person moved meanwhile is not done.
        """
        asked, still = {r.obj for r in relocations}, []
        for r in (r for r in self.waiting if r.obj not in asked):
            if graph.parent_of(r.obj) == r.source:
                still.append(r)
            else:
                self.refuse(r, minute, f"{IN_THE_WAY} (the person) until {r.obj} was moved")
        relocations, self.waiting = [*still, *relocations], []
        if not relocations:
            return float(minute)
        steps = plan_steps(graph, movable, relocations, self._parts_needed(relocations, graph, movable),
                           self.open_containers(), self.blocked)
        before = self.world.object_positions()
        started, first = float(self.world.data.time), len(self.log.relocations)
        self._carry_out(steps, relocations, minute, started)
        self._park()
        self._collateral(before, {r.obj for r in relocations}, minute)
        self._knocked_off(first)
        spent = (float(self.world.data.time) - started) / 60.0
        self.log.robot_minutes += spent
        self.event(f"robot done after {spent:.1f} min", minute + spent)
        return minute + spent

    def end_day(self, minute: float) -> None:
        """The day is over: relocations still waiting for the person to get out of the way are not done."""
        for r in self.waiting:
            self.refuse(r, int(minute), f"{IN_THE_WAY} (the person) until the day ended")
        self.waiting = []

    def refuse(self, relocation: Relocation, minute: int, reason: str) -> None:
        """Record `relocation` as not done for `reason`, without acting (the robot cannot attempt it now)."""
        self.log.relocations.append(RelocationOutcome(minute, relocation, False, reason, relocation.source))

    def open_containers(self) -> set[str]:
        """Containers with a door or drawer open more than a tenth."""
        return {f for f, parts in self.containers.items() if any(self.world.openness(p) > 0.1 for p in parts)}

    def _parts_needed(self, relocations: Sequence[Relocation], graph: SceneGraph, movable: np.ndarray
                      ) -> dict[str, list[str]]:
        """The containers `relocations` open, each with the parts they need open (the relocation suite's rules):
        of the furniture an object is taken from, every door or the drawer it lies in (`parts_to_open`); of a
        destination, what its places lie behind (`parts_to_place`). A dresser is placed on its top: its three
        drawers, all opened for that, moved the jackets in them 3-7 cm and one stuck half open."""
        needed: dict[str, set[str]] = {}
        for r in relocations:
            source = anchor_of(graph, movable, r.source)
            taken = parts_to_open(self.world, graph, list(self.containers.get(source, ())), r.obj)
            put = parts_to_place(self.world, self.robot.spots, list(self.containers.get(r.destination, ())),
                                 r.destination)
            for furniture, parts in ((source, taken), (r.destination, put)):
                needed.setdefault(furniture, set()).update(parts)
        return {f: [p for p in self.containers[f] if p in parts] for f, parts in needed.items() if parts}

    # --- acting ---------------------------------------------------------------------------------------------
    def _carry_out(self, steps: Sequence[PlanStep], relocations: Sequence[Relocation], minute: int,
                   started: float) -> None:
        """Run the steps; a failed open skips what needs that container (but its parts that the robot moved are
        closed again: a dresser's drawers, opened to 0.82 and 0.66, were left so, and the clothes in them counted
        as displaced), a failed pick or set-down skips the rest of its relocation."""
        failed_containers: dict[str, str] = {}
        picked: dict[str, SkillResult] = {}
        by_obj = {r.obj: r for r in relocations}
        for step in steps:
            if self.robot.held is not None and step.action not in ("place", "set_down"):
                self.event(f"robot stops the plan: it still holds {self.robot.held}", minute, "ERROR")
                break
            now = minute + (float(self.world.data.time) - started) / 60.0
            if self.recording is not None:
                self.recording.set_routine_time(now)
            try:
                result = self._run(step, failed_containers, picked, by_obj, minute)
            except PhysicsError:
                raise
            except Exception as error:  # a bug in a skill fails this step's relocation, not the whole day
                log.exception("robot %s %s", step.action, step.target)
                result = SkillResult(False, f"{SKILL_ERROR} in {step.action}: {type(error).__name__} {error}")
                if step.obj and self.robot.held == step.obj:
                    try:
                        self._put_down(step.obj, by_obj[step.obj].source)
                    except Exception:  # the put-down meets the bug too: the hand keeps it and the plan stops
                        log.exception("robot put-down of %s", step.obj)
            if result is None:
                continue
            self.log.steps.append(StepOutcome(now, step, result.success, result.reason,
                                              float(self.world.data.time) - started))
            self.event(f"robot {step.action} {step.target}: " + ("ok" if result.success else result.reason), now,
                        "INFO" if result.success else "WARN")
            if step.action == "open" and not result.success:
                failed_containers[step.node] = result.reason
            elif step.action in ("pick", "set_down"):
                picked[step.obj] = result
                if not result.success:
                    self._finish(by_obj[step.obj], minute, False, result.reason)
            elif step.action == "place":
                self._finish(by_obj[step.obj], minute, result.success, result.reason)

    def _run(self, step: PlanStep, failed_containers: dict[str, str], picked: dict[str, SkillResult],
             by_obj: dict[str, Relocation], minute: int) -> SkillResult | None:
        """One skill call, or None when the step is skipped because an earlier one failed."""
        if step.action == "open":
            return self.robot.open_articulation(step.target)
        if step.action == "close":  # also where an open failed part way: what rides in it is left as found
            if step.node in failed_containers and self.world.openness(step.target) <= CLOSED_OK:
                return None
            result = self.robot.close_articulation(step.target)
            if not result.success:  # one more try: a door left open blocks the person
                self.event(f"robot close {step.target} failed ({result.reason}); trying again", self.executor.minute,
                            "WARN")
                result = self.robot.close_articulation(step.target)
            return result
        if step.action == "pick" and step.node == "":  # again, where the robot set it down
            if not picked.get(step.obj, SkillResult(False)).success:
                return None
            destination = by_obj[step.obj].destination
            if destination in failed_containers:
                reason = f"{destination} did not open ({failed_containers[destination]})"
                picked[step.obj] = SkillResult(False, reason)
                self._finish(by_obj[step.obj], minute, False, reason)
                return None
            node = self.robot.observer.update().anchor_of(step.obj, self.world.object_names)  # what it lies on
            return self.robot.pick(step.obj, node, into=by_obj[step.obj].destination)
        if step.action == "pick":
            blocked = [c for c in (step.node, by_obj[step.obj].destination) if c in failed_containers]
            if blocked:
                reason = f"{blocked[0]} did not open ({failed_containers[blocked[0]]})"
                picked[step.obj] = SkillResult(False, reason)
                self._finish(by_obj[step.obj], minute, False, reason)
                return None
            return self.robot.pick(step.obj, step.node, into=by_obj[step.obj].destination)
        if not picked.get(step.obj, SkillResult(False)).success:
            return None
        if step.action == "set_down":
            result = self.robot.set_down({*self.containers, *(f for fs in self.blocked.values() for f in fs)})
            if not result.success and self.robot.held == step.obj:
                self._put_down(step.obj, by_obj[step.obj].source)
            return result
        result = self.robot.place(step.target)
        if not result.success and self.robot.held == step.obj:  # do not keep it in the hand: put it down
            self._put_down(step.obj, by_obj[step.obj].source)
        return result

    def _put_down(self, obj: str, source: str) -> None:
        """After a failed place: put the held object back where it came from, else on the nearest furniture
        with a top (at most FALLBACK_PLACES tries), else on the floor of the room the robot is in: a robot left
        holding it stops its plans and cannot make way for the person (`make_way`)."""
        x, y = self.robot.controller.q()[:2]
        tops = sorted((np.hypot(f.pos[0] - x, f.pos[1] - y), f.name) for f in self.world.layout.furniture
                      if f.name not in self.containers and self.robot.spots.places_of(f.name, ON))
        room = self.world.layout.room_at(x, y)
        for node in [*[source, *(name for _, name in tops)][:FALLBACK_PLACES], *([room] if room else [])]:
            if (node in self.robot.navigator.furniture or node == room) and self.robot.place(node).success:
                self.event(f"robot put {obj} down on {node} after the failed place", self.executor.minute, "WARN")
                return
            if self.robot.held != obj:
                break
        log.warning("robot still holds %s" if self.robot.held == obj else "%s left the hand on the way", obj)

    def _finish(self, relocation: Relocation, minute: int, done: bool, reason: str) -> None:
        """Record `relocation`'s outcome; one that only the person stood in the way of (the object still on its
        source) waits for the next snapshot instead."""
        graph = self.robot.observer.update()
        if (not done and IN_THE_WAY in reason and self.robot.held != relocation.obj
                and graph.parent_of(relocation.obj) == relocation.source):
            self.waiting.append(relocation)
            return
        ended = graph.parent_of(relocation.obj) or ""
        self.log.relocations.append(RelocationOutcome(minute, relocation, done, reason, ended))
        if done:
            self._placed_at[relocation.obj] = self.world.object_pose(relocation.obj)[0].copy()

    def _knocked_off(self, first: int) -> None:
        """Relocations from `first` on (this turn's) that were done, but whose object a later step of the turn moved
        more than COLLATERAL_M (a spoon set down beside the bowl knocked it off the table), are not done."""
        graph = self.robot.observer.update()
        for k in range(first, len(self.log.relocations)):
            o = self.log.relocations[k]
            placed = self._placed_at.pop(o.relocation.obj, None)
            if not o.done or placed is None:
                continue
            moved = float(np.linalg.norm(self.world.object_pose(o.relocation.obj)[0] - placed))
            if moved > COLLATERAL_M:
                now = graph.parent_of(o.relocation.obj) or ""
                reason = f"knocked off {o.ended_on} later in the robot's turn ({moved * 100:.0f} cm, now on {now})"
                self.log.relocations[k] = RelocationOutcome(o.minute, o.relocation, False, reason, now)
                self.event(f"robot knocked {o.relocation.obj} off {o.ended_on}", o.minute, "WARN")

    def _park(self) -> None:
        """Back to the parking pose with the arm tucked, out of the person's way."""
        try:
            self.robot.retract()
            self.robot.navigator.drive_to(DEFAULT_POSE, self.robot.tucked(), **FREE_MOTION)
        except NavigationError as error:
            log.warning("robot could not park: %s", error)

    def _collateral(self, before: np.ndarray, asked: set[str], minute: int) -> None:
        """Keep the objects no relocation named that moved more than COLLATERAL_M during the robot's turn."""
        moved = np.linalg.norm(self.world.object_positions() - before, axis=1)
        for i in np.flatnonzero(moved > COLLATERAL_M):
            name = self.world.object_names[i]
            if name not in asked:
                self.log.collateral.append((minute, name, round(float(moved[i]), 3)))
                self.event(f"robot displaced {name} by {moved[i] * 100:.0f} cm", minute, "WARN")

    def make_way(self, path: list[tuple[float, float]]) -> bool:
        """The person's walk along `path` (waypoints, m) is blocked only by the robot: it drives, arm tucked, to the
        nearest spot it reaches ROBOT_CLEARANCE_M (and a grid cell) from the whole path; whether it did. A robot
        left standing in a doorway (it could not park) had ended the person's day."""
        if self.robot.held is not None:
            return False
        started = float(self.world.data.time)
        pose = self.robot.navigator.clear_of(np.asarray(path), ROBOT_CLEARANCE_M + self.executor.spots.plan.resolution)
        if pose is None or np.allclose(pose[:2], self.robot.controller.q()[:2]):  # nowhere, or already clear of it
            return False
        try:
            self.robot.retract()
            self.robot.navigator.drive_to(pose, self.robot.tucked(), **FREE_MOTION)
        except NavigationError as error:
            log.warning("robot could not make way for the person: %s", error)
            return False
        self.log.robot_minutes += (float(self.world.data.time) - started) / 60.0
        self.event("robot made way for the person", self.executor.minute)
        return True

    def person_rects(self) -> list[tuple[float, float, float, float]]:
        """The square (x0, y0, x1, y1, m) PERSON_RADIUS_M around the person, for the robot's navigation."""
        x, y = self.executor.avatar.x, self.executor.avatar.y
        return [(x - PERSON_RADIUS_M, y - PERSON_RADIUS_M, x + PERSON_RADIUS_M, y + PERSON_RADIUS_M)]

    def robot_cells(self) -> np.ndarray:
        """Grid cells the person neither walks through nor sets anything down on: a disk around the robot's base."""
        x, y = self.robot.controller.q()[:2]
        return self.executor.spots.plan.disk_cells(x, y, ROBOT_CLEARANCE_M)

    def event(self, text: str, minute: float, level: str = "INFO") -> None:
        log.info("%.1f min: %s", minute, text)
        if self.recording is not None:
            self.recording.log_event(text, routine_minute=minute, level=level)
