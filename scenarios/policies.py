"""Policies over the assisted-day environment (`scenarios.env`): observation in, relocations asked for out.

`PsiPolicy` is the paper's robot: it rolls a predictor `window_min` ahead from the observed scene graph (with the
help it holds for the person back where it came from), turns
the first predicted changes into relocations with Psi (`scenarios.psi`), leaving alone what the person is using (where
they stand, and the places of their latest moves for a window), and remembers its own help (objects it
placed stay for the person; help left unused goes back; a failed relocation waits a window, or, when the cause is
in the object's own state (`scenarios.causes.LASTING`), until someone has moved the object). `OraclePredictor`
predicts from the unassisted replay of the same day (perfect prediction, for separating manipulation from
prediction). `RandomPolicy` asks for random relocations; `EmptyPolicy` never asks.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping, Sequence

import dm_env
import numpy as np

from homer_sim.clock import DEFAULT_WINDOW_MIN, GRID_MIN
from homer_sim.graph import INSIDE, ON, GraphError, SceneGraph
from homer_sim.home.layout import Layout
from homer_sim.person.executor import DayLog
from model.predictor import Rollout
from scenarios.causes import CAUSES, LASTING
from scenarios.psi import Holds, Plan, Relocation, anchor_of, psi, unused_help
from scenarios.task import NO_RELOCATION, SceneInfo

log = logging.getLogger(__name__)

PERSON_REACH = 0.7  # m from a furniture's footprint within which the person counts as using it


def furniture_near(layout: Layout, x: float, y: float, reach: float = PERSON_REACH) -> list[str]:
    """Furniture whose footprint is within `reach` m of the point (x, y) m (what a person there may be using)."""
    near = []
    for f in layout.furniture:
        c, s = abs(np.cos(f.yaw)), abs(np.sin(f.yaw))
        width, depth = f.size[0], f.size[1]  # local x is the depth (out of the front), local y the width
        half_x, half_y = (c * depth + s * width) / 2, (s * depth + c * width) / 2
        gap = np.hypot(max(abs(x - f.pos[0]) - half_x, 0.0), max(abs(y - f.pos[1]) - half_y, 0.0))
        if gap < reach:
            near.append(f.name)
    return near


def graph_of(scene: SceneInfo, observation: Mapping[str, np.ndarray]) -> SceneGraph:
    """The observed scene graph of an observation."""
    return SceneGraph(scene.nodes, scene.categories, np.asarray(observation["parent"]),
                      np.asarray(observation["relation"]))


def action_of(scene: SceneInfo, relocations: Sequence[Relocation]) -> np.ndarray:
    """The action asking for `relocations` in order: Shape (MAX, 2) int32 rows (object, destination) node indices,
    NO_RELOCATION rows after them."""
    action = np.full(scene.action_shape, NO_RELOCATION, dtype=np.int32)
    for k, r in enumerate(relocations):
        action[k] = (scene.index[r.obj], scene.index[r.destination])
    return action


class EmptyPolicy:
    """Never asks for anything: the person's day as if there were no robot (but with it parked in the room)."""

    def __init__(self, scene: SceneInfo) -> None:
        self.scene = scene

    def __call__(self, timestep: dm_env.TimeStep) -> np.ndarray:
        return action_of(self.scene, ())


class RandomPolicy:
    """At each tick where the robot is free, with probability `rate` asks to move one random object that is not
    in the person's hand onto a random piece of furniture or appliance."""

    def __init__(self, scene: SceneInfo, rng: np.random.Generator, rate: float = 0.3) -> None:
        self.scene, self.rng, self.rate = scene, rng, rate
        self.objects = np.flatnonzero(scene.movable)
        self.places = np.flatnonzero(np.isin(scene.categories, ("furniture", "appliance")))

    def __call__(self, timestep: dm_env.TimeStep) -> np.ndarray:
        obs = timestep.observation
        action = action_of(self.scene, ())
        if obs["minute"] < obs["robot_busy_until"] or self.rng.random() >= self.rate:
            return action
        free = self.objects[~np.asarray(obs["person_holding"])[self.objects]]
        obj = int(self.rng.choice(free))
        places = self.places[self.places != obs["parent"][obj]]
        action[0] = (obj, int(self.rng.choice(places)))
        return action


class PsiPolicy:
    """The paper's robot as a policy: predict, plan with Psi, remember the help it gave (see the module doc).

    threshold: the confidence a predicted move needs (default: the predictor's own, which
    `scenarios.predictors.predictor_for` tunes on validation days for the assistance objective). The robot acts
    on a move only when its first predicted step is within the predictor's `act_steps` (tuned with the threshold;
    0 or absent: the whole window), and asks the predictor about the arrangement the person left (`_as_left`)."""

    def __init__(self, scene: SceneInfo, predictor, window_min: int = DEFAULT_WINDOW_MIN,
                 threshold: float | None = None, recording=None) -> None:
        self.scene = scene
        self.predictor = predictor
        self.window_min = window_min
        self.window_steps = window_min // GRID_MIN
        self.threshold = float(predictor.params["threshold"]) if threshold is None else float(threshold)
        act = int(predictor.params.get("act_steps", 0))  # acts on moves predicted this many steps ahead (0: all)
        self.act_steps = min(act, self.window_steps) if act > 0 else self.window_steps
        self.recording = recording
        self.reset()

    def reset(self) -> None:
        """Forget the help given and the plans made (a new day)."""
        self.holds = Holds()
        self.returns: dict[str, Relocation] = {}  # unused help to put back, until tried or the person moves it
        self.failed: dict[str, tuple[float, str, str]] = {}  # object -> (retry after minute, cause, where it was)
        self.unwanted: dict[str, str] = {}  # object -> where its unused help was put back
        self.plans: list[tuple[int, Plan]] = []
        self._asked: dict[str, Relocation] = {}
        self._parents: np.ndarray | None = None  # the parents observed at the previous tick
        self._lately: tuple[float, frozenset[str]] = (-np.inf, frozenset())  # see `_watch`

    def __call__(self, timestep: dm_env.TimeStep) -> np.ndarray:
        """The relocations to ask for at this observation (none while the robot is still busy)."""
        obs = timestep.observation
        if timestep.first():
            self.reset()
        minute = int(obs["minute"])
        graph = graph_of(self.scene, obs)
        self._watch(graph, minute, self._learn(obs["outcomes"], graph))
        if minute < obs["robot_busy_until"]:
            return action_of(self.scene, ())
        plan = self.plan(obs)
        if plan.relocations or plan.skipped:  # kept for the day's report: what was asked, and what was left out why
            self.plans.append((minute, plan))
        asked = plan.relocations[: self.scene.action_shape[0]]
        self._asked = {r.obj: r for r in asked}
        return action_of(self.scene, asked)

    def plan(self, obs: Mapping[str, np.ndarray]) -> Plan:
        """Psi's plan at the observation's minute, after releasing holds the person used or that ran out."""
        minute = int(obs["minute"])
        graph = graph_of(self.scene, obs)
        nodes = self.scene.nodes
        carried = {nodes[i] for i in np.flatnonzero(obs["person_holding"])}
        grabbed_at = {nodes[i]: float(t) for i, t in enumerate(obs["person_took_at"]) if np.isfinite(t)}
        released = self.holds.update(graph, minute, used=carried, grabbed_at=grabbed_at)
        self.returns.update({r.obj: r for r in unused_help(released, graph, carried, grabbed_at)})
        self.returns = {o: r for o, r in self.returns.items() if graph.parent_of(o) == r.source and o not in carried}
        rollout = self.predictor.rollout(self._as_left(graph)[None], np.array([minute], dtype=np.float32),
                                         self.window_steps)
        self._log_prediction(graph, rollout, minute)
        open_now = {self.scene.articulations[i].split("/")[0] for i in np.flatnonzero(obs["openness"] > 0.1)}
        x, y = obs["person_position"]
        return psi(graph, self.predictor.movable, rollout, threshold=self.threshold, window_steps=self.act_steps,
                   containers=self.scene.containers, carried=carried,
                   excluded=lambda obj: self._excluded(obj, minute, graph), holds=self.holds, already_open=open_now,
                   in_use={*furniture_near(self.scene.layout, float(x), float(y)), *self._used_lately(minute)},
                   returns=tuple(self.returns.values()))

    def _as_left(self, graph: SceneGraph) -> np.ndarray:
        """The parents the predictor is asked about: the observed ones with the objects the robot holds for the
        person back where it took them from (the arrangement the person left; the predictor learned from days
        without a robot, and the help laid out would read as the activity already under way)."""
        parent = graph.parent.astype(np.int64)
        for hold in self.holds.active.values():
            if hold.source:
                parent[graph.index(hold.obj)] = graph.index(hold.source)
        return parent

    def _watch(self, graph: SceneGraph, minute: int, handled: set[int]) -> None:
        """Note the places of the person's latest moves: where the objects that changed parent since the previous
        tick came from and went to (and the furniture those are reached at), the robot's own relocations
        (`handled`, node indices) apart. The person is taken to be using them for a window after (`_used_lately`):
        the rule `model.metrics.robot_counts` tunes the threshold under. With only "where the person stands now",
        the robot cleared up straight after the person left (the cd into the tv stand, the water bottle onto the
        shelf, the fork into the sink), the moves the tuning never credited, and a quarter of its help was wrong."""
        parent = graph.parent
        if self._parents is not None:
            moved = [int(i) for i in np.flatnonzero((parent != self._parents) & self.predictor.movable)
                     if int(i) not in handled]
            places = {graph.nodes[p] for i in moved for p in (self._parents[i], parent[i]) if p >= 0}
            if places:
                anchors = {anchor_of(graph, self.predictor.movable, p) for p in places}
                self._lately = (minute, frozenset(places | anchors))
        self._parents = parent.copy()

    def _used_lately(self, minute: int) -> frozenset[str]:
        """The places of the person's latest moves while the window after them lasts (see `_watch`)."""
        since, places = self._lately
        return places if minute - since < self.window_min else frozenset()

    def _learn(self, outcomes: np.ndarray, graph: SceneGraph) -> set[int]:
        """Remember what the robot did with the relocations asked for at the previous tick (`graph`: now); the
        objects it tried to move (node indices)."""
        nodes = self.scene.nodes
        for obj, source, destination, done, ended, cause, minute in outcomes[outcomes[:, 0] != NO_RELOCATION]:
            relocation = self._asked.get(nodes[obj]) or Relocation(nodes[obj], nodes[source], nodes[destination],
                                                                   0, float("nan"))
            if relocation.put_back:  # tried once: if it failed, the predictor decides from now on
                self.returns.pop(relocation.obj, None)
                if done:  # not offered again until the person moves it (else help and put-back take turns all day)
                    self.unwanted[relocation.obj] = nodes[ended]
            if done and not relocation.put_back:
                self.holds.add(relocation.obj, nodes[ended], minute, minute + self.window_min,
                               source=relocation.source)
            elif not done:
                why = CAUSES[cause]
                retry_after = np.inf if why in LASTING else minute + self.window_min
                self.failed[relocation.obj] = (retry_after, why, graph.parent_of(relocation.obj))
        self._asked = {}
        return {int(o) for o in outcomes[outcomes[:, 0] != NO_RELOCATION][:, 0]}

    def _excluded(self, obj: str, minute: float, graph: SceneGraph) -> str | None:
        reason = self.scene.ungraspable.get(obj)
        if reason is not None:
            return f"not graspable: {reason}"
        if self.unwanted.get(obj) == graph.parent_of(obj):
            return "its help went unused and was put back; not offered again until the person moves it"
        retry_after, why, where = self.failed.get(obj, (-np.inf, "", ""))
        if minute >= retry_after or graph.parent_of(obj) != where:  # waited long enough, or moved since
            return None
        when = "until it has been moved" if np.isinf(retry_after) else f"before {retry_after:.0f} min"
        return f"failed earlier ({why}); not retried {when}"

    def _log_prediction(self, graph: SceneGraph, rollout: Rollout, minute: int) -> None:
        """The predicted graph at minute + window on `graph/predicted` (when the argmax is an in-tree)."""
        if self.recording is None:
            return
        parent = np.where(self.predictor.movable, rollout.parent[-1, 0], graph.parent)
        inside = {graph.index(c) for c in self.scene.containers} | {
            i for i, c in enumerate(graph.categories) if c == "room"}
        relation = np.where(parent == graph.parent, graph.relation,
                            np.where(np.isin(parent, list(inside)), INSIDE, ON)).astype(np.int8)
        try:
            predicted = SceneGraph(graph.nodes, graph.categories, parent, relation)
        except GraphError as error:
            log.info("predicted graph at %d min is no in-tree: %s", minute, error)
            return
        self.recording.log_scene_graph(predicted, routine_minute=minute + self.window_min, entity="graph/predicted")


class OraclePredictor:
    """Perfect prediction: the rollout is the unassisted replay of the same day (`reference`), with certainty.

    Has the `rollout`, `movable` and `params` a `PsiPolicy` uses from a predictor."""

    def __init__(self, reference: DayLog, movable: np.ndarray, grid_min: int = GRID_MIN) -> None:
        self.minutes = np.asarray(reference.minutes)
        self.parents = np.asarray(reference.parents, dtype=np.int64)  # (T, N)
        self.movable = np.asarray(movable, dtype=bool)
        self.grid_min = grid_min
        self.params = {"threshold": 0.5}

    def rollout(self, observed: np.ndarray, minute: np.ndarray, steps: int) -> Rollout:
        """The replay's parents at minute + 10, ..., minute + 10 * steps (the last snapshot past its end), each
        with probability 1. observed: Shape (B, N) parents at the query; minute: Shape (B,). Returns arrays of
        Shape (steps, B, N); `other` is the replay's parent where it differs from the observed one."""
        ahead = np.asarray(minute, dtype=float)[None, :] + self.grid_min * np.arange(1, steps + 1)[:, None]
        t = np.clip(np.searchsorted(self.minutes, ahead), 0, len(self.minutes) - 1)  # (S, B)
        parent = self.parents[t]
        moves = parent != np.asarray(observed)[None]
        return Rollout(parent, np.ones(parent.shape, dtype=np.float32), parent.copy(), moves.astype(np.float32))
