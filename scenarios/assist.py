"""The assisted day: while the person lives their schedule, the robot observes, predicts, plans with Psi and acts.

At every 10-minute snapshot (the executor's `after_tick` hook) the robot reads the observed scene graph, rolls the
predictor `window_min` ahead, turns the first predicted changes into a plan (`scenarios.psi`) and carries it out
with its skills in physics. The physics seconds it spends pass on the routine clock: the person's next actions
wait until the robot is done (they take turns; the robot then drives back to its parking pose, out of the way).
Failures are kept with the skill's reason and the relocation is not retried within its window.

The reference is the same day replayed without the robot: the same schedule and the same physics random stream in
an apartment without a robot, so what the person would have moved unassisted is known.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from homer_sim.clock import DEFAULT_WINDOW_MIN
from homer_sim.errors import HomerError
from homer_sim.graph import INSIDE, ON, GraphError, SceneGraph
from homer_sim.home.catalog import CATALOG
from homer_sim.person.avatar import add_avatar
from homer_sim.person.executor import DayLog, Executor
from homer_sim.recording import RecordedWorld
from homer_sim.world import World
from planners.grasps.candidate import ungraspable_reason
from planners.motion.control import FREE_MOTION
from planners.motion.navigation import NavigationError
from planners.robot import DEFAULT_POSE, add_robot
from planners.skills import Robot, SkillResult
from scenarios.psi import Holds, Plan, PlanStep, Relocation, psi, unused_help

log = logging.getLogger(__name__)

PERSON_REACH = 0.7  # m from a furniture's footprint within which the person counts as using it
FALLBACK_PLACES = 3  # places tried to put an object down after a failed place
ROBOT_MIN_THRESHOLD = 0.5  # the robot acts on a move only when it is more likely than staying: robot time costs
# routine minutes and a wrong move is worse than a missed one (the tuned threshold may be lower)


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
    """What the robot planned and did over an assisted run, and the person's day as it went."""

    plans: list[tuple[int, Plan]] = field(default_factory=list)
    steps: list[StepOutcome] = field(default_factory=list)
    relocations: list[RelocationOutcome] = field(default_factory=list)
    robot_minutes: float = 0.0
    day: DayLog | None = None
    error: str = ""  # why the person could not go on, if they could not (the run stops there)


def containers_of(world: World) -> dict[str, tuple[str, ...]]:
    """Furniture with doors or drawers -> its articulation names."""
    found: dict[str, list[str]] = {}
    for art in world.articulations.values():
        found.setdefault(art.furniture, []).append(art.name)
    return {k: tuple(v) for k, v in found.items()}


class Assistant:
    """The robot in an apartment with the person: `after_tick` is the executor's hook."""

    def __init__(self, predictor, window_min: int = DEFAULT_WINDOW_MIN, threshold: float | None = None, recording=None,
                 rng: np.random.Generator | None = None) -> None:
        self.world = RecordedWorld(extras=[add_avatar, add_robot])
        self.world.recording = recording
        self.recording = recording
        self.executor = Executor(self.world, recording=recording)
        self.executor.dynamic_obstacles = self._robot_cells
        self.robot = Robot(self.world, rng if rng is not None else np.random.default_rng(0))
        self.predictor = predictor
        self.window_min = window_min
        self.window_steps = window_min // 10
        tuned = max(float(predictor.params["threshold"]), ROBOT_MIN_THRESHOLD)
        self.threshold = tuned if threshold is None else float(threshold)
        self.containers = containers_of(self.world)
        self.holds = Holds()
        self.returns: dict[str, Relocation] = {}  # unused help to put back, until tried or the person moves it
        self.failed: dict[str, tuple[float, str]] = {}  # object -> (retry after minute, reason)
        self.busy_until = -np.inf
        self.log = AssistLog()

    # --- the hook -------------------------------------------------------------------------------------------
    def after_tick(self, minute: int) -> float:
        """Observe, predict, plan and act at grid minute `minute`; returns the routine minute the robot is done."""
        if minute < self.busy_until:
            return self.busy_until
        day = self.executor.log
        graph = SceneGraph(self.executor.nodes, self.executor.observer.categories, day.parents[-1], day.relations[-1])
        carried = set(self.executor.avatar.carried())
        grabbed_at = self.executor.grabbed_at
        released = self.holds.update(graph, minute, used=carried, grabbed_at=grabbed_at)
        self.returns.update({r.obj: r for r in unused_help(released, graph, carried, grabbed_at)})
        self.returns = {o: r for o, r in self.returns.items() if graph.parent_of(o) == r.source and o not in carried}
        rollout = self.predictor.rollout(graph.parent[None].astype(np.int64), np.array([minute], dtype=np.float32),
                                         self.window_steps)
        self._log_prediction(graph, rollout, minute)
        open_now = {f for f, parts in self.containers.items() if any(self.world.openness(p) > 0.1 for p in parts)}
        plan = psi(graph, self.predictor.movable, rollout, threshold=self.threshold, window_steps=self.window_steps,
                   containers=self.containers, carried=carried, excluded=lambda obj: self._excluded(obj, minute),
                   holds=self.holds, already_open=open_now, in_use=self._person_at(),
                   returns=tuple(self.returns.values()))
        if not plan.relocations:
            return float(minute)
        self.log.plans.append((minute, plan))
        started = float(self.world.data.time)
        self._carry_out(plan, minute, started)
        self._park()
        spent = (float(self.world.data.time) - started) / 60.0
        self.log.robot_minutes += spent
        self.busy_until = minute + spent
        self._event(f"robot done after {spent:.1f} min", self.busy_until)
        return self.busy_until

    def _excluded(self, obj: str, minute: float) -> str | None:
        cls = CATALOG[self.world.layout.objects[self.world.object_index(obj)].cls]
        reason = ungraspable_reason(cls)
        if reason is not None:
            return f"not graspable: {reason}"
        retry_after, why = self.failed.get(obj, (-np.inf, ""))
        return f"failed earlier ({why}); not retried before {retry_after:.0f} min" if minute < retry_after else None

    # --- acting ---------------------------------------------------------------------------------------------
    def _carry_out(self, plan: Plan, minute: int, started: float) -> None:
        """Run the plan's steps; a failed open skips what needs that container, a failed pick skips its place."""
        failed_containers: dict[str, str] = {}
        picked: dict[str, SkillResult] = {}
        by_obj = {r.obj: r for r in plan.relocations}
        for step in plan.steps:
            if self.robot.held is not None and step.action != "place":
                self._event(f"robot stops the plan: it still holds {self.robot.held}", minute, "ERROR")
                break
            now = minute + (float(self.world.data.time) - started) / 60.0
            if self.recording is not None:
                self.recording.set_routine_time(now)
            result = self._run(step, failed_containers, picked, by_obj)
            if result is None:
                continue
            self.log.steps.append(StepOutcome(now, step, result.success, result.reason,
                                              float(self.world.data.time) - started))
            self._event(f"robot {step.action} {step.target}: " + ("ok" if result.success else result.reason), now,
                        "INFO" if result.success else "WARN")
            if step.action == "open" and not result.success:
                failed_containers[step.node] = result.reason
            elif step.action == "pick":
                picked[step.obj] = result
                if not result.success:
                    self._finish(by_obj[step.obj], minute, False, result.reason)
            elif step.action == "place":
                self._finish(by_obj[step.obj], minute, result.success, result.reason)

    def _run(self, step: PlanStep, failed_containers: dict[str, str], picked: dict[str, SkillResult],
             by_obj: dict[str, Relocation]) -> SkillResult | None:
        """One skill call, or None when the step is skipped because an earlier one failed."""
        if step.action == "open":
            return self.robot.open_articulation(step.target)
        if step.action == "close":
            if step.node in failed_containers:
                return None
            result = self.robot.close_articulation(step.target)
            if not result.success:  # one more try: a door left open blocks the person
                self._event(f"robot close {step.target} failed ({result.reason}); trying again", self.executor.minute,
                            "WARN")
                result = self.robot.close_articulation(step.target)
            return result
        if step.action == "pick":
            blocked = [c for c in (step.node, by_obj[step.obj].destination) if c in failed_containers]
            if blocked:
                reason = f"{blocked[0]} did not open ({failed_containers[blocked[0]]})"
                picked[step.obj] = SkillResult(False, reason)
                self._finish(by_obj[step.obj], -1, False, reason)
                return None
            return self.robot.pick(step.obj, step.node, into=by_obj[step.obj].destination)
        if not picked.get(step.obj, SkillResult(False)).success:
            return None
        result = self.robot.place(step.target)
        if not result.success and self.robot.held == step.obj:  # do not keep it in the hand: put it down
            self._put_down(step.obj, by_obj[step.obj].source)
        return result

    def _put_down(self, obj: str, source: str) -> None:
        """After a failed place: put the held object back where it came from, else on the nearest furniture
        with a top (at most FALLBACK_PLACES tries)."""
        x, y = self.robot.controller.q()[:2]
        tops = sorted((np.hypot(f.pos[0] - x, f.pos[1] - y), f.name) for f in self.world.layout.furniture
                      if f.name not in self.containers and self.robot.spots.places_of(f.name, ON))
        for node in [source, *(name for _, name in tops)][:FALLBACK_PLACES]:
            if node in self.robot.navigator.furniture and self.robot.place(node).success:
                self._event(f"robot put {obj} down on {node} after the failed place", self.executor.minute, "WARN")
                return
        log.warning("robot still holds %s" if self.robot.held == obj else "%s left the hand on the way", obj)

    def _finish(self, relocation: Relocation, minute: int, done: bool, reason: str) -> None:
        query = minute if minute >= 0 else int(self.log.plans[-1][0])
        graph = self.robot.observer.update()
        ended = graph.parent_of(relocation.obj) or ""
        self.log.relocations.append(RelocationOutcome(query, relocation, done, reason, ended))
        if relocation.put_back:  # tried once: if it failed, the predictor decides from now on
            self.returns.pop(relocation.obj, None)
        if done and not relocation.put_back:
            self.holds.add(relocation.obj, ended, query, query + self.window_min, source=relocation.source)
        elif not done:
            self.failed[relocation.obj] = (query + self.window_min, reason)

    def _park(self) -> None:
        """Back to the parking pose with the arm tucked, out of the person's way."""
        try:
            self.robot.retract()
            self.robot.navigator.drive_to(DEFAULT_POSE, self.robot.tucked(), **FREE_MOTION)
        except NavigationError as error:
            log.warning("robot could not park: %s", error)

    def _person_at(self) -> list[str]:
        """Furniture whose footprint is within PERSON_REACH m of the person (what they may be using now)."""
        x, y = self.executor.avatar.x, self.executor.avatar.y
        near = []
        for f in self.world.layout.furniture:
            c, s = abs(np.cos(f.yaw)), abs(np.sin(f.yaw))
            width, depth = f.size[0], f.size[1]  # local x is the depth (out of the front), local y the width
            half_x, half_y = (c * depth + s * width) / 2, (s * depth + c * width) / 2
            gap = np.hypot(max(abs(x - f.pos[0]) - half_x, 0.0), max(abs(y - f.pos[1]) - half_y, 0.0))
            if gap < PERSON_REACH:
                near.append(f.name)
        return near

    def _robot_cells(self) -> np.ndarray:
        """Grid cells the person must not walk through: a disk around the robot's base."""
        plan = self.executor.spots.plan
        blocked = np.zeros_like(self.executor.spots.blocked)
        x, y = self.robot.controller.q()[:2]
        xs, ys = plan.cell_centers(0, blocked.shape[0], 0, blocked.shape[1])
        blocked[np.hypot(xs - x, ys - y) < 0.55] = True
        return blocked

    # --- recording ------------------------------------------------------------------------------------------
    def _event(self, text: str, minute: float, level: str = "INFO") -> None:
        log.info("%.1f min: %s", minute, text)
        if self.recording is not None:
            self.recording.log_event(text, routine_minute=minute, level=level)

    def _log_prediction(self, graph: SceneGraph, rollout, minute: int) -> None:
        """The predicted graph at minute + window on `graph/predicted` (when the argmax is an in-tree)."""
        if self.recording is None:
            return
        parent = np.where(self.predictor.movable, rollout.parent[-1, 0], graph.parent)
        inside = {graph.index(c) for c in self.containers} | {i for i, c in enumerate(graph.categories) if c == "room"}
        relation = np.where(parent == graph.parent, graph.relation,
                            np.where(np.isin(parent, list(inside)), INSIDE, ON)).astype(np.int8)
        try:
            predicted = SceneGraph(graph.nodes, graph.categories, parent, relation)
        except GraphError as error:
            log.info("predicted graph at %d min is no in-tree: %s", minute, error)
            return
        self.recording.log_scene_graph(predicted, routine_minute=minute + self.window_min, entity="graph/predicted")


def run_assisted(assistant: Assistant, replay: Callable[..., DayLog], end_min: float | None = None) -> AssistLog:
    """Live a day with the robot's help; returns the robot's log with the person's day in it. `replay` is the
    day's `Generator.replay` with household, key and entries bound, so the assisted day is the reference day
    by construction. An action the person cannot carry out (the robot left something in the way, say) ends the
    run; its reason is kept."""
    try:
        replay(executor=assistant.executor, after_tick=assistant.after_tick, end_min=end_min)
    except HomerError as error:
        assistant.log.error = str(error)
        assistant._event(f"the person could not go on: {error}", assistant.executor.minute, "ERROR")
    assistant.log.day = assistant.executor.log
    return assistant.log
