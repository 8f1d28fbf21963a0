"""Psi: from the observed scene graph and a predicted rollout, the relocations the robot should make, as a plan.

The paper's formulation: Psi(X_t, X_hat_{t+delta}) -> R, where an object's relocation goes from its parent at t to
its *first* predicted destination within the window (later predicted moves of the same object do not count). The
first change is found exactly as the metrics count it (`model.metrics.gate` and `first_change`), so what the robot
does is what the evaluation scores.

The plan orders the relocations into robot steps: a container (furniture with doors or drawers) is opened before
anything is taken from or put into it, with an empty hand, and closed after its last use, again with an empty hand.
Relocations are skipped, with a reason, for objects in the person's hand, objects the robot cannot grasp, moves
below the confidence threshold, destinations the robot cannot place on, and objects the robot itself placed and
still holds for the person (`Holds`): the robot never undoes its own help before the person has used it. Help
the person left unused until its window passed is put back where it came from (`unused_help`), whatever the
prediction says.

Pure logic: numpy and the model's metric functions, no physics.
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from homer_sim.graph import OUTSIDE, SceneGraph
from model.metrics import first_change, gate
from model.predictor import Rollout

PLACEABLE_CATEGORIES = ("furniture", "appliance", "room")  # what the robot's place skill puts objects on or into
# (a room: on a free spot of its floor)


@dataclass(frozen=True)
class Relocation:
    """Move `obj` from `source` to `destination` (node names), predicted `steps_ahead` grid steps after the query
    with probability `confidence` (0..1) for that destination; `put_back`: not a prediction but the robot's unused
    help going back (`unused_help`)."""

    obj: str
    source: str
    destination: str
    steps_ahead: int
    confidence: float
    put_back: bool = False


@dataclass(frozen=True)
class PlanStep:
    """One robot skill call: `action` is open/close (target: articulation `<furniture>/<part>`), pick (target: the
    object, `node`: the furniture to stand at, "" for where the robot set it down), place (target: the destination
    node, `node` the same) or set_down (target: the held object, put down for a while on an open top near by)."""

    action: str
    target: str
    node: str = ""
    obj: str = ""


@dataclass(frozen=True)
class Plan:
    """The relocations to make, in order; those left out with their reasons; the robot steps that make them."""

    relocations: tuple[Relocation, ...]
    skipped: tuple[tuple[Relocation, str], ...]
    steps: tuple[PlanStep, ...]


@dataclass(frozen=True)
class Hold:
    """The robot put `obj` on `node` (taking it from `source`) at routine minute `since`; it stays there until
    `until` (min) or until the person takes it."""

    obj: str
    node: str
    since: float
    until: float
    source: str = ""

    def touched(self, graph: SceneGraph, used: Collection[str], grabbed_at: Mapping[str, float]) -> bool:
        """Whether the person has used the object since the hold began: the observed graph shows it away from
        `node`, it is in `used` (e.g. seen in the person's hand), or `grabbed_at` (object -> last minute the
        person took it in hand) is not before `since`."""
        return (graph.parent_of(self.obj) != self.node or self.obj in used
                or grabbed_at.get(self.obj, -np.inf) >= self.since)


class Holds:
    """Objects the robot placed for the person, kept where it put them (the robot's own help is not undone)."""

    def __init__(self) -> None:
        self.active: dict[str, Hold] = {}

    def add(self, obj: str, node: str, minute: float, until: float, source: str = "") -> None:
        """Hold `obj` on `node` (brought from `source`) from routine minute `minute` to `until`."""
        self.active[obj] = Hold(obj, node, float(minute), float(until), source)

    def update(self, graph: SceneGraph, minute: float, used: Collection[str] = (),
               grabbed_at: Mapping[str, float] | None = None) -> list[Hold]:
        """Release holds whose window has passed (until < minute) or whose object the person used (`Hold.touched`);
        returns them."""
        grabbed_at = grabbed_at or {}
        released = [h for h in self.active.values() if h.until < minute or h.touched(graph, used, grabbed_at)]
        for hold in released:
            del self.active[hold.obj]
        return released

    def reason(self, obj: str) -> str | None:
        hold = self.active.get(obj)
        if hold is None:
            return None
        return f"held on {hold.node} for the person (placed at {hold.since:.0f} min, until {hold.until:.0f} min)"


def unused_help(released: Sequence[Hold], graph: SceneGraph, used: Collection[str] = (),
                grabbed_at: Mapping[str, float] | None = None) -> list[Relocation]:
    """Relocations that put back what the robot brought and the person did not use (the paper's skipped breakfast):
    for each released hold whose object is still where the robot put it and untouched since, back to its source."""
    grabbed_at = grabbed_at or {}
    return [Relocation(h.obj, h.node, h.source, 0, 1.0, put_back=True) for h in released
            if h.source and not h.touched(graph, used, grabbed_at)]


def first_moves(observed: np.ndarray, rollout: Rollout, threshold: float, window_steps: int,
                batch: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each node's first predicted move within the window, gated by `threshold` as `model.metrics.gate` does.

    observed: Shape (N,) int, parents at the query step. rollout: arrays of Shape (S, B, N); `batch` picks the query.
    Returns changed (N,) bool, destination (N,) int (-1 where unchanged), step (N,) int (1-based, 0 where unchanged).
    """
    one = Rollout(*(None if a is None else np.asarray(a)[:, batch : batch + 1]
                    for a in (rollout.parent, rollout.confidence, rollout.other, rollout.other_confidence,
                              rollout.other_margin)))
    observed = np.asarray(observed, dtype=np.int64)[None]
    predicted = gate(one, observed, threshold, margin=True)  # (1, S, N); thresholds tuned on the margin (paper, assist)
    steps = np.array([min(window_steps, predicted.shape[1])])
    changed, destination = first_change(observed, predicted, steps)
    differs = predicted[0] != observed  # (S, N)
    step = np.where(changed[0], differs.argmax(axis=0) + 1, 0)
    return changed[0], destination[0], step


def destination_confidence(rollout: Rollout, step: int, node: int, destination: int, batch: int = 0) -> float:
    """Probability of `destination` for `node` at 1-based predicted step `step` (0 if the rollout does not say)."""
    s = step - 1
    if rollout.parent[s, batch, node] == destination:
        return float(rollout.confidence[s, batch, node])
    if rollout.other[s, batch, node] == destination:
        return float(rollout.other_confidence[s, batch, node])
    return 0.0


def predicted_relocations(graph: SceneGraph, movable: np.ndarray, rollout: Rollout, threshold: float,
                          window_steps: int, batch: int = 0) -> tuple[list[Relocation], list[Relocation]]:
    """(relocations that pass the threshold, argmax moves that do not), for the movable nodes of `graph`.

    movable: Shape (N,) bool. Each relocation is (object, parent at t, first predicted destination) with the step of
    that first change; with threshold 0 the two lists are the argmax moves and nothing.
    """
    movable = np.asarray(movable, dtype=bool)
    gated = first_moves(graph.parent, rollout, threshold, window_steps, batch)
    argmax = first_moves(graph.parent, rollout, 0.0, window_steps, batch)
    passed, below = [], []
    for (changed, destination, step), out in ((gated, passed), (argmax, below)):
        for i in np.flatnonzero(changed & movable):
            if out is below and gated[0][i]:
                continue
            dest, k = int(destination[i]), int(step[i])
            out.append(Relocation(graph.nodes[i], graph.nodes[int(graph.parent[i])], graph.nodes[dest], k,
                                  destination_confidence(rollout, k, int(i), dest, batch)))
    return passed, below


def anchor_of(graph: SceneGraph, movable: np.ndarray, node: str) -> str:
    """The first non-movable node at or above `node` (the furniture, appliance or room it is reached at);
    movable: Shape (N,) bool over the graph's nodes."""
    return graph.anchor_of(node, {graph.nodes[i] for i in np.flatnonzero(movable)})


def plan_relocations(graph: SceneGraph, movable: np.ndarray, relocations: Sequence[Relocation],
                     containers: Mapping[str, Sequence[str]], skip: Callable[[Relocation], str | None],
                     already_open: Collection[str] = ()) -> Plan:
    """Order relocations into robot steps, leaving out those `skip` gives a reason for and those whose
    destination the robot cannot place on.

    Relocations run in order of their first predicted step, grouped by the furniture they are taken from; an
    object headed into another relocated object goes after it. The steps are `plan_steps` of that order.
    """
    movable = np.asarray(movable, dtype=bool)
    kept, skipped = [], []
    for relocation in relocations:
        reason = skip(relocation) or unplaceable(graph, relocation.destination)
        if reason is None:
            kept.append(relocation)
        else:
            skipped.append((relocation, reason))
    kept.sort(key=lambda r: (r.steps_ahead, anchor_of(graph, movable, r.source), r.obj))
    moving = {r.obj for r in kept}
    kept.sort(key=lambda r: r.destination in moving)  # stable: objects headed into moved objects go last
    return Plan(tuple(kept), tuple(skipped), plan_steps(graph, movable, kept, containers, already_open))


def unplaceable(graph: SceneGraph, destination: str) -> str | None:
    """Why the robot cannot place on `destination` (None if it can: furniture, appliances and rooms' floors)."""
    category = graph.categories[graph.index(destination)]
    if category in PLACEABLE_CATEGORIES:
        return None
    return f"destination {destination} is a {category}; the robot places only on {' or '.join(PLACEABLE_CATEGORIES)}"


def plan_steps(graph: SceneGraph, movable: np.ndarray, relocations: Sequence[Relocation],
               containers: Mapping[str, Sequence[str]], already_open: Collection[str] = (),
               blocked: Mapping[str, Collection[str]] | None = None) -> tuple[PlanStep, ...]:
    """The robot steps that make `relocations` in the order given: pick at the object's furniture, place on the
    destination.

    containers: furniture name -> the articulations to open (`<furniture>/<part>`; the assisted day passes those
    the relocations need, `scenarios.assist.Helper._parts_needed`); they are opened
    before the first relocation that takes from or puts into it and closed after the last one (only containers
    the plan opened: those in `already_open` stay as the person left them). A relocation from one container into
    another that is still closed has one open at a time: picked, set down, the containers the plan opened closed,
    the destination opened, picked again and placed (two open doors can leave no way between them, and a full
    hand opens nothing). So has a relocation onto furniture that a container the plan opened stands in front of
    when open (`blocked`: container -> such furniture, see `homer_sim.home.validate.blocked_when_open`).
    """
    blocked = blocked or {}
    movable = np.asarray(movable, dtype=bool)

    def used_containers(r: Relocation) -> list[str]:
        ends = (anchor_of(graph, movable, r.source), r.destination)
        return [c for c in dict.fromkeys(ends) if c in containers]

    steps: list[PlanStep] = []
    opened: list[str] = []
    for k, r in enumerate(relocations):
        source_anchor = anchor_of(graph, movable, r.source)
        shut = r.destination not in opened and r.destination not in already_open
        in_front = any(r.destination in blocked.get(c, ()) for c in {*opened, *used_containers(r)} - {*already_open})
        one_at_a_time = (len(used_containers(r)) == 2 and shut) or in_front
        for container in [source_anchor] if one_at_a_time else used_containers(r):
            if container in containers and container not in opened and container not in already_open:
                steps += [PlanStep("open", part, container) for part in containers[container]]
                opened.append(container)
        steps.append(PlanStep("pick", r.obj, source_anchor, r.obj))
        if one_at_a_time:
            steps.append(PlanStep("set_down", r.obj, "", r.obj))
            for container in opened[::-1]:
                steps += [PlanStep("close", part, container) for part in containers[container]][::-1]
            opened = [r.destination] if r.destination in containers else []
            steps += [PlanStep("open", part, r.destination) for part in containers.get(r.destination, ())]
            steps.append(PlanStep("pick", r.obj, "", r.obj))
        steps.append(PlanStep("place", r.destination, r.destination, r.obj))
        later = {c for rest in relocations[k + 1 :] for c in used_containers(rest)}
        for container in [c for c in opened if c not in later][::-1]:
            steps += [PlanStep("close", part, container) for part in containers[container]][::-1]
            opened.remove(container)
    return tuple(steps)


def psi(graph: SceneGraph, movable: np.ndarray, rollout: Rollout, *, threshold: float, window_steps: int,
        containers: Mapping[str, Sequence[str]], carried: Collection[str] = (),
        excluded: Callable[[str], str | None] = lambda obj: None, holds: Holds | None = None,
        already_open: Collection[str] = (), in_use: Collection[str] = (),
        returns: Sequence[Relocation] = ()) -> Plan:
    """The robot's plan for one query: relocations from `graph` (observed at t) to the rollout's first predicted
    destinations within `window_steps` grid steps, gated by `threshold`, ordered by `plan_relocations`.

    carried: objects in the person's hand. excluded: object name -> why the robot cannot grasp it (None if it can).
    holds: objects the robot placed and keeps for the person. in_use: the places the person is using (the furniture
    they are at now; `PsiPolicy` adds those of their latest moves for a window); nothing is taken from them or put
    on them (the robot does not clear a table the person eats at); nothing
    is taken to or from `outside` (the robot stays in the apartment). Nor is an object with things on or in it
    that no relocation moves: carried along, they would be displaced (a laundry basket predicted back to the
    bedroom went there with the clothes still in it, 5.5 m from the washing machine the person took them to). Moves
    that do not reach the threshold are reported among the skipped ones. returns: relocations made whatever the
    prediction (`unused_help`); they replace the predicted moves of their objects.
    """
    passed, below = predicted_relocations(graph, movable, rollout, threshold, window_steps)
    returned = {r.obj for r in returns}
    passed = [*returns, *(r for r in passed if r.obj not in returned)]
    below = [r for r in below if r.obj not in returned]
    moving = {r.obj for r in passed}

    def skip(r: Relocation) -> str | None:
        if r.obj in carried:
            return "in the person's hand"
        riders = [graph.nodes[i] for i in np.flatnonzero(graph.parent == graph.index(r.obj))
                  if graph.nodes[i] not in moving]
        if riders:
            return f"{', '.join(riders)} on or in it would be carried along, moved by no relocation"
        held = holds.reason(r.obj) if holds is not None else None
        busy = [n for n in (anchor_of(graph, movable, r.source), r.destination) if n in in_use]
        if OUTSIDE in (graph.room_of(r.source), graph.room_of(r.destination)):
            return "outside the apartment (the robot stays in; the person takes what they need along)"
        return held or (f"the person is at {busy[0]}" if busy else None) or excluded(r.obj)

    plan = plan_relocations(graph, movable, passed, containers, skip, already_open)
    held = holds.reason if holds is not None else lambda obj: None  # a held object is left for that, not the
    # threshold (the predictor is asked about it back at its source, so its argmax "moves" it there)
    low = tuple((r, held(r.obj) or f"confidence {r.confidence:.2f} below the threshold {threshold:.2f}")
                for r in below)
    return Plan(plan.relocations, plan.skipped + low, plan.steps)
