"""The assisted day as a task and a `dm_env.Environment`: one episode per day, one step per 10-minute snapshot.

The lifecycle follows dm_control's `control.Task` and composer: `AssistTask.initialize_episode` replays the day
without the robot (the reference the reward is judged against, lived on a window past the episode's end so the
last relocations are judged too) and starts the person's day up to its first snapshot; at each step
`before_step` has the robot carry out the relocations the action asks for and `after_step` lets the person
live on to the next snapshot; then `get_observation`, `get_reward` and
`should_terminate_episode`. `AssistEnv` drives a task as dm_env expects (`reset`, `step`, specs).

Observation (what a robot could perceive; never the person's schedule or intentions): the observed scene graph
as arrays (`parent`, `relation`), door and drawer `openness`, the robot's base pose, what it holds and until
when it is busy, the routine `minute`, the person's position, what they hold and when they last took each object
in hand, and the outcomes of the relocations asked for at the previous step. Action: Shape (MAX_RELOCATIONS, 2)
int32 rows (object, destination) as node indices, carried out in order; rows of NO_RELOCATION ask for nothing.
Reward: the person's fetches the robot had made ahead of them (within `window_min` before), minus the robot's
wrong moves (done, but not where the person alone would first have moved the object within the window).
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import dm_env
import numpy as np
from dm_env import specs

from homer_sim.clock import DAY_START_MIN, DEFAULT_WINDOW_MIN, GRID_MIN
from homer_sim.data.generate import Generator, Sources
from homer_sim.days import DayKey
from homer_sim.errors import HomerError
from homer_sim.graph import SceneGraph
from homer_sim.home.catalog import CATALOG
from homer_sim.home.layout import Layout
from homer_sim.person.avatar import add_avatar
from homer_sim.person.executor import DayLog, DayRun, Executor
from homer_sim.recording import RecordedWorld
from planners.grasps.candidate import ungraspable_reason
from planners.robot import add_robot
from scenarios.assist import Helper, RelocationOutcome, containers_of
from scenarios.causes import CAUSES, cause_of
from scenarios.psi import Relocation, unplaceable
from scenarios.scoring import Fetches, is_correct

log = logging.getLogger(__name__)

NO_RELOCATION = -1
MAX_RELOCATIONS = 64  # rows of an action: relocations asked for at one snapshot
OUTCOME_FIELDS = ("object", "source", "destination", "done", "ended_on", "cause", "minute")
"""Columns of the `outcomes` observation (node indices, 0/1, a `scenarios.causes.CAUSES` index, routine minute)."""


@dataclass(frozen=True)
class SceneInfo:
    """The map the robot knows: node names and categories, which nodes are movable objects, the doors and
    drawers (in `openness` order) and the furniture they belong to, the objects its gripper cannot take (with
    why), and the apartment's layout."""

    nodes: tuple[str, ...]
    categories: tuple[str, ...]
    movable: np.ndarray
    articulations: tuple[str, ...]
    containers: Mapping[str, tuple[str, ...]]
    ungraspable: Mapping[str, str]
    layout: Layout
    index: Mapping[str, int] = field(init=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "index", {n: i for i, n in enumerate(self.nodes)})

    @property
    def action_shape(self) -> tuple[int, int]:
        return (MAX_RELOCATIONS, 2)


@dataclass(frozen=True)
class DayPlan:
    """One episode's day: the household, the day's identity (its physics stream, the same for the reference and
    the assisted run), the schedule entries (activity, start min, end min), the routine minute to stop after
    (None: the whole day), and the seed of the robot's own random stream for the day (None: the task's stream
    goes on from the last day)."""

    household: str
    key: DayKey
    entries: tuple[tuple[str, float, float], ...]
    end_min: int | None = None
    robot_seed: tuple[int, ...] | None = None

    @property
    def label(self) -> str:
        return f"{self.key.split}/{self.key.index}"


class AssistTask:
    """The assisted day's lifecycle over a World with the person and the robot (see the module doc)."""

    def __init__(self, days: Sequence[DayPlan], seed: int = 0, window_min: int = DEFAULT_WINDOW_MIN,
                 reference: Generator | None = None, recording=None) -> None:
        """days: the episodes' days, in turn (`days` may be replaced between episodes). seed: the robot's random
        stream. reference: the generator (an apartment without the robot, the households' scripts) that replays
        the days unassisted (built when None)."""
        if not days:
            raise HomerError("an assisted-day task needs at least one day")
        self.days = tuple(days)
        self.window_min = window_min
        self.recording = recording
        self.world = RecordedWorld(extras=[add_avatar, add_robot])
        self.world.recording = recording
        self.executor = Executor(self.world, recording=recording)
        self.rng = np.random.default_rng(seed)
        self.helper = Helper(self.world, self.executor, self.rng, recording)
        self.generator = reference or Generator(Sources())
        self.scene = scene_info(self.world, self.executor)
        self.episodes = 0
        self.log = self.helper.log
        self.reference = DayLog()

    # --- lifecycle ------------------------------------------------------------------------------------------
    def initialize_episode(self) -> None:
        """Replay the next day without the robot, then start it with the robot up to its first snapshot."""
        day = self.days[self.episodes % len(self.days)]
        if self.episodes > 0 or day.robot_seed is not None:  # a fresh robot in the start state
            self.world.reset()
            rng = self.rng if day.robot_seed is None else np.random.default_rng(list(day.robot_seed))
            self.helper = Helper(self.world, self.executor, rng, self.recording)
        self.episodes += 1
        self.day = day
        past_end = None if day.end_min is None else day.end_min + self.window_min  # truth for the last window
        self.reference = self.generator.replay(day.household, day.key, list(day.entries), end_min=past_end)
        self.log = self.helper.log
        self.fetches = Fetches(self.reference, set(self.scene.layout.room_names()), self.window_min, day.end_min)
        self.busy_until, self.free_at, self.reward = 0.0, -np.inf, 0.0
        self.outcomes: list[RelocationOutcome] = []
        scripts = self.generator.scripts_for(day.household)  # the stream of Generator.replay, stepped here
        events, last = self.executor.begin_day(list(day.entries), scripts, day.key.streams()[1])
        self.run = DayRun(self.executor, events, last, day.end_min)
        self.log.day = self.executor.log  # the person's day as it goes
        minute = self._advance()
        self.ended = minute is None  # the person could not even reach the first snapshot
        self.minute = DAY_START_MIN if minute is None else minute

    def before_step(self, action: np.ndarray) -> None:
        """The robot carries out the relocations `action` asks for (nothing while it is still busy)."""
        minute = self.minute
        first = len(self.log.relocations)
        relocations = self._relocations(action, minute)
        if minute < self.busy_until:
            self.free_at = self.busy_until
        else:
            self.free_at = self.helper.act(relocations, self.graph(), self.scene.movable, minute)
            if relocations:
                self.busy_until = self.free_at
        self.outcomes = self.log.relocations[first:]
        wrong = sum(o.done and not is_correct(o, self.reference, self.scene.index, self.window_min // GRID_MIN)
                    for o in self.outcomes)
        self.reward = float(self.fetches.credit(self.log.relocations, up_to=minute) - wrong)

    def after_step(self) -> None:
        """The person lives on to the next snapshot (the episode ends when the day does or they cannot go on)."""
        minute = self._advance()
        self.ended = minute is None
        self.minute = self.minute if minute is None else minute
        if self.ended:  # the reference's fetches after the last snapshot, counted with what the robot did before
            self.helper.end_day(self.minute)
            self.reward += self.fetches.credit(self.log.relocations, up_to=np.inf)

    def get_reward(self) -> float:
        return self.reward

    def should_terminate_episode(self) -> bool:
        return self.ended

    @property
    def truncated(self) -> bool:
        """Whether the episode ended because the day was cut at its `end_min` (not the day's end or an error)."""
        return self.ended and self.run.ended_early and not self.log.error

    # --- observation ----------------------------------------------------------------------------------------
    def graph(self) -> SceneGraph:
        """The scene graph observed at the current snapshot."""
        day = self.executor.log
        return SceneGraph(self.scene.nodes, self.scene.categories, day.parents[-1], day.relations[-1])

    def get_observation(self) -> dict[str, np.ndarray]:
        n, index = len(self.scene.nodes), self.scene.index
        graph, robot, person = self.graph(), self.helper.robot, self.executor.avatar
        holding = np.zeros(n, dtype=bool)
        holding[[index[o] for o in person.carried()]] = True
        took_at = np.full(n, -np.inf)
        for obj, minute in self.executor.grabbed_at.items():
            took_at[index[obj]] = minute
        outcomes = np.full((MAX_RELOCATIONS, len(OUTCOME_FIELDS)), NO_RELOCATION, dtype=np.int32)
        for k, o in enumerate(self.outcomes):
            r = o.relocation
            outcomes[k] = (index[r.obj], index[r.source], index[r.destination], o.done,
                           index.get(o.ended_on, NO_RELOCATION), CAUSES.index(cause_of(o.reason)) if not o.done
                           else NO_RELOCATION, o.minute)
        return {
            "minute": np.float64(self.minute),
            "parent": graph.parent.astype(np.int32), "relation": graph.relation.astype(np.int8),
            "openness": np.array([self.world.openness(a) for a in self.scene.articulations]),
            "robot_pose": robot.controller.q()[:3].astype(np.float64),
            "robot_holding": np.int32(index[robot.held] if robot.held is not None else NO_RELOCATION),
            "robot_busy_until": np.float64(self.busy_until),
            "person_position": np.array([person.x, person.y]),
            "person_holding": holding, "person_took_at": took_at, "outcomes": outcomes,
        }

    def observation_spec(self) -> dict[str, specs.Array]:
        n, a = len(self.scene.nodes), len(self.scene.articulations)
        return {
            "minute": specs.Array((), np.float64, "minute"),
            "parent": specs.BoundedArray((n,), np.int32, -1, n - 1, "parent"),
            "relation": specs.BoundedArray((n,), np.int8, 0, 2, "relation"),
            "openness": specs.Array((a,), np.float64, "openness"),
            "robot_pose": specs.Array((3,), np.float64, "robot_pose"),
            "robot_holding": specs.BoundedArray((), np.int32, NO_RELOCATION, n - 1, "robot_holding"),
            "robot_busy_until": specs.Array((), np.float64, "robot_busy_until"),
            "person_position": specs.Array((2,), np.float64, "person_position"),
            "person_holding": specs.Array((n,), bool, "person_holding"),
            "person_took_at": specs.Array((n,), np.float64, "person_took_at"),
            "outcomes": specs.Array((MAX_RELOCATIONS, len(OUTCOME_FIELDS)), np.int32, "outcomes"),
        }

    def action_spec(self) -> specs.BoundedArray:
        return specs.BoundedArray(self.scene.action_shape, np.int32, NO_RELOCATION, len(self.scene.nodes) - 1,
                                  "relocations")

    # --- helpers --------------------------------------------------------------------------------------------
    def _advance(self) -> int | None:
        """The next snapshot's minute (None when the day is over or the person could not go on)."""
        try:
            return self.run.advance(self.free_at)
        except HomerError as error:
            self.log.error = str(error)
            self.helper.event(f"the person could not go on: {error}", self.executor.minute, "ERROR")
            return None

    def _relocations(self, action: np.ndarray, minute: int) -> list[Relocation]:
        """The relocations `action` asks for; those the robot cannot attempt now are recorded as not done."""
        self.action_spec().validate(action)
        graph, scene, carried = self.graph(), self.scene, set(self.executor.avatar.carried())
        rows = [(int(o), int(d)) for o, d in np.asarray(action) if o != NO_RELOCATION]
        objects = [o for o, _ in rows]
        if len(set(objects)) < len(objects) or any(d == NO_RELOCATION for _, d in rows):
            raise HomerError(f"an action names each object once, with a destination; got rows {rows}")
        if minute < self.busy_until:
            return []
        asked = []
        for obj, dest in rows:
            name, destination = scene.nodes[obj], scene.nodes[dest]
            why = None if scene.movable[obj] else f"{name} is a {scene.categories[obj]}, not a movable object"
            if why or unplaceable(graph, destination):
                raise HomerError(f"cannot relocate {name} to {destination}: {why or unplaceable(graph, destination)}")
            relocation = Relocation(name, graph.nodes[int(graph.parent[obj])], destination, 0, float("nan"))
            refusal = ("in the person's hand" if name in carried else
                       f"not graspable: {scene.ungraspable[name]}" if name in scene.ungraspable else
                       "already there" if relocation.source == destination else None)
            if refusal is None:
                asked.append(relocation)
            else:
                self.helper.refuse(relocation, minute, refusal)
        return asked


def scene_info(world, executor: Executor) -> SceneInfo:
    """What the robot knows of the apartment `world` (see SceneInfo)."""
    nodes = executor.nodes
    categories = tuple(executor.observer.categories)
    classes = {o.name: CATALOG[o.cls] for o in world.layout.objects}
    ungraspable = {name: why for name, cls in classes.items() if (why := ungraspable_reason(cls)) is not None}
    return SceneInfo(tuple(nodes), categories, np.isin(np.asarray(nodes), list(world.object_names)),
                     tuple(world.articulations), containers_of(world), ungraspable, world.layout)


class AssistEnv(dm_env.Environment):
    """A dm_env over an `AssistTask`: `reset` starts the next day, `step` is one 10-minute snapshot."""

    def __init__(self, task: AssistTask) -> None:
        self.task = task
        self._reset_next_step = True

    @property
    def scene(self) -> SceneInfo:
        return self.task.scene

    def reset(self) -> dm_env.TimeStep:
        self.task.initialize_episode()
        self._reset_next_step = self.task.should_terminate_episode()
        return dm_env.restart(self.task.get_observation())

    def step(self, action: np.ndarray) -> dm_env.TimeStep:
        if self._reset_next_step:
            return self.reset()
        self.task.before_step(action)
        self.task.after_step()
        observation, reward = self.task.get_observation(), self.task.get_reward()
        if not self.task.should_terminate_episode():
            return dm_env.transition(reward, observation)
        self._reset_next_step = True
        if self.task.truncated:
            return dm_env.truncation(reward, observation)
        return dm_env.termination(reward, observation)

    def observation_spec(self) -> dict[str, specs.Array]:
        return self.task.observation_spec()

    def action_spec(self) -> specs.BoundedArray:
        return self.task.action_spec()

    def render(self, height: int = 480, width: int = 640, azimuth: float = 90.0, elevation: float = -60.0,
               distance: float = 12.5) -> np.ndarray:
        """An RGB image of the apartment now, Shape (height, width, 3) uint8, from a free camera looking at the
        apartment's centre (`azimuth`, `elevation` in degrees, `distance` in m). Headless: set MUJOCO_GL=egl
        (or osmesa) before mujoco is imported."""
        from scenarios.render import render_world

        return render_world(self.task.world, height, width, azimuth, elevation, distance)


def run_episode(env: AssistEnv, policy: Callable[[dm_env.TimeStep], np.ndarray]) -> float:
    """One episode (day) of `policy` in `env`; returns its return (sum of rewards)."""
    return play(env, env.reset(), policy)


def play(env: AssistEnv, timestep: dm_env.TimeStep, policy: Callable[[dm_env.TimeStep], np.ndarray]) -> float:
    """Step `env` with `policy` from `timestep` (the episode's first) to the episode's end; returns the return."""
    total = 0.0
    while not timestep.last():
        timestep = env.step(policy(timestep))
        total += timestep.reward
    return total
