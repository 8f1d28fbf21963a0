"""`homer grasp-suite --relocations`: the relocation suite, every (object, from, to) move of a dataset's days.

The triples are the person's moves in the training days of a dataset made by `homer generate` (each day file
stores them and its `DayKey`). Each triple is tried once, from the apartment's state at its first occurrence:
the day is lived again exactly (`Generator.replay`, in a world that also holds the robot at its parking pose)
up to the last snapshot before the move at which the object rests on its source and is not in the person's
hand, or, where no snapshot has it so (put there and taken away again within one grid step, or in the person's
hand at each since they took it from there: a headset worn for hours, then put down elsewhere), up to the person's
last action before the move after which it does. Rests means at rest: the world is let come to rest there first
(SETTLE_S), for a thing the person put down may still roll (a vacuum cleaner set on the floor fell over and
rolled on past the next snapshot, and no snapshot observed it on the floor). From there only the robot acts,
with its real skills: it opens what closes over the source and the destination, picks the object, carries it,
places it, and closes what it opened (between two pieces of furniture that close, one at a time: the object is
set down on an open top between them, `relocate`).

Success: the scene-graph observer puts the object ON or INSIDE the destination, it stands as it should (an
object that is not cloth or a ball stands up, `Arm.fallen_over`), and no other object (but what rides on the
moved one) moved more than `planners.suites.collateral.MAX_DISPLACEMENT`. A triple the robot cannot be asked is
excluded with its reason: a source or destination outside the apartment (the robot stays in), an object the
robot cannot grasp (`ungraspable_reason`). Each failure gets a cause (the first word of its reason: the skill
that failed and what its reason says went wrong (`KINDS`), `wrong place`, `fell over`, `collateral`, `state`)
for the cause table.

mujoco and the planners that need it are imported inside the functions that run trials.
"""

from __future__ import annotations

import logging
import sys
import time
from collections import Counter
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from homer_sim.clock import GRID_MIN
from homer_sim.data.dataset import Dataset, Day
from homer_sim.execution import IN_PROCESS, Backend
from homer_sim.graph import OUTSIDE
from homer_sim.home.apartment import default_layout
from homer_sim.home.catalog import CATALOG
from homer_sim.home.validate import blocked_when_open
from planners.robot import PREFIX, ROBOT_CLEARANCE_M
from planners.suites.collateral import collateral_reason, displaced
from planners.suites.grasp_suite import stable_hash

log = logging.getLogger(__name__)

NO_FALL_FAMILIES = ("cloth", "sphere")  # shapes with no up to keep
REPLAYS = 4  # snapshots (latest first) at which the day is lived again to find the object on its source
SETTLE_S = 10.0  # s of physics at most the world is let come to rest where the day stops, before the robot acts
TARGET_OVERALL = 0.97
TARGET_CLASS = 0.9
QUICK_SIZE = 6
KINDS = ("fell out of the hand", "slipped", "no free base pose", "no path", "fell over", "has fallen over",
         "closed on nothing", "rose only", "unreachable", "no free spot", "leaves the arm's reach",
         "ended", "pushed")  # what a skill's failure reason says went wrong, for the cause table


@dataclass(frozen=True)
class Occurrence:
    """Triple (obj, source, destination) first moved by the person at routine `minute` of day `index` of
    `household`'s training days."""

    obj: str
    source: str
    destination: str
    household: str
    index: int
    minute: float

    @property
    def triple(self) -> str:
        return f"{self.obj}: {self.source} -> {self.destination}"


@dataclass(frozen=True)
class TripleResult:
    """One relocation: success, its failure cause and reason, where the object ended, wall time (s), and the other
    objects it moved more than MAX_DISPLACEMENT (name, m), counted whether or not a skill failed first."""

    occurrence: Occurrence
    cls: str
    success: bool
    cause: str
    reason: str
    ended_on: str
    wall_s: float
    collateral: tuple[tuple[str, float], ...] = ()


def occurrences(data: Path, households: list[str] | None = None, objects: list[str] | None = None
                ) -> list[Occurrence]:
    """The first occurrence of every (object, source, destination) move in the training days of the dataset
    at `data` (only `households`' days and `objects`' moves, where given), in household, day and minute order."""
    dataset = Dataset(data)
    dataset.require_nodes(default_layout().node_names())
    first: dict[tuple[str, str, str], Occurrence] = {}
    for household in households or list(dataset.meta.households):
        for day in dataset.days(household, "train"):
            for minute, obj, source, destination, _ in day.moves:
                if objects and obj not in objects:
                    continue
                first.setdefault((obj, source, destination),
                                 Occurrence(obj, source, destination, household, day.index, float(minute)))
    return list(first.values())


def exclusion_reason(occurrence: Occurrence, cls: str) -> str | None:
    """Why the robot cannot be asked to make this move, or None when it can."""
    from planners.grasps.candidate import ungraspable_reason

    if OUTSIDE in (occurrence.source, occurrence.destination):
        return "outside the apartment (the robot stays in)"
    reason = ungraspable_reason(CATALOG[cls])
    return f"not graspable: {reason}" if reason else None


def quick_subset(tried: list[Occurrence], classes: dict[str, str]) -> list[Occurrence]:
    """The fast representative subset: the first triple of each destination kind (furniture with doors,
    drawers, open surfaces, appliances...) by destination, at most QUICK_SIZE, one per object family."""
    chosen: list[Occurrence] = []
    families: set[str] = set()
    destinations: set[str] = set()
    for occurrence in tried:
        family = CATALOG[classes[occurrence.obj]].family
        if family in families or occurrence.destination in destinations:
            continue
        chosen.append(occurrence)
        families.add(family)
        destinations.add(occurrence.destination)
        if len(chosen) == QUICK_SIZE:
            break
    return chosen


# --- one trial ------------------------------------------------------------------------------------------
class _Stop(Exception):
    """Raised after the person's last action before a move, to stop living the day there."""


class Bench:
    """The suite's worlds: a generator for the person's days and the robot's world they are lived again in."""

    def __init__(self, data: Path) -> None:
        from homer_sim.data.generate import Generator, Sources
        from homer_sim.person.avatar import add_avatar
        from homer_sim.person.executor import Executor
        from homer_sim.world import World
        from planners.robot import add_robot

        self.dataset = Dataset(data)
        self.generator = Generator(Sources())
        self.world = World(extras=[add_avatar, add_robot])
        self.dataset.require_nodes(self.world.layout.node_names())
        self.executor = Executor(self.world)
        self.executor.dynamic_obstacles = self._robot_cells  # the person keeps clear of the robot, as in a day
        self.containers: dict[str, list[str]] = {}
        for art in self.world.articulations.values():
            self.containers.setdefault(art.furniture, []).append(art.name)
        self.blocked = blocked_when_open(self.world.layout)

    def _robot_cells(self) -> np.ndarray:
        """The floor cells within ROBOT_CLEARANCE_M of the robot's base (see `scenarios.assist`)."""
        base = self.world.data.qpos[[self.world.model.joint(PREFIX + n).qposadr[0] for n in ("base_x", "base_y")]]
        return self.executor.spots.plan.disk_cells(float(base[0]), float(base[1]), ROBOT_CLEARANCE_M)

    def day(self, occurrence: Occurrence) -> Day:
        from homer_sim.data.dataset import day_path, read_day

        return read_day(day_path(self.dataset.root, occurrence.household, "train", occurrence.index))

    def live_until(self, occurrence: Occurrence) -> str | None:
        """Live the occurrence's day up to the last snapshot before the move at which the object rests on its
        source outside the person's hand (the latest REPLAYS snapshots the recorded day has it there are tried),
        else up to the person's last action before the move after which it does (`_before_the_move`); the world is
        let come to rest there (SETTLE_S). None when found, else why not."""
        day = self.day(occurrence)
        last = int(occurrence.minute // GRID_MIN) * GRID_MIN
        nodes = self.dataset.meta.nodes
        obj, source = nodes.index(occurrence.obj), nodes.index(occurrence.source)
        recorded = [int(m) for m, parent in zip(day.minutes, day.parent[:, obj], strict=True)
                    if m <= last and parent == source]  # where the recorded day has it on its source
        for minute in recorded[::-1][:REPLAYS]:
            self.generator.replay(occurrence.household, day.replay_key(), day.schedule, executor=self.executor,
                                  end_min=minute)
            self.world.settle(max_seconds=SETTLE_S)
            if self._on_source(occurrence):
                return None
        return self._before_the_move(occurrence, day)

    def _before_the_move(self, occurrence: Occurrence, day: Day) -> str | None:
        """Live the occurrence's day again up to the person's last action before the move after which the object
        rests on its source outside the person's hand (found by living it once, then lived again up to there), then
        let the world come to rest; None when there is one, else why not. The whole day before the move is
        watched, not only its last grid step: an object the person took from its source and held through every
        snapshot until the move was last on its source when they took it."""
        last_free: list[int] = []

        def watch(index: int, events: list) -> None:
            if events[index][0] < occurrence.minute and self._on_source(occurrence):
                last_free.append(index)
            if index + 1 >= len(events) or events[index + 1][0] >= occurrence.minute:
                raise _Stop

        self._live(occurrence, day, watch)
        if not last_free:
            return (f"{occurrence.obj} rested on {occurrence.source} outside the person's hand at no snapshot and "
                    f"after no action of the day before the move")
        self._live(occurrence, day, lambda index, events: _stop_after(index, last_free[-1]))
        self.world.settle(max_seconds=SETTLE_S)
        return None

    def _live(self, occurrence: Occurrence, day: Day, after_action) -> None:
        """Live the occurrence's day from its start until `after_action(index, events)`, called after each of the
        person's actions, raises _Stop."""
        scripts = self.generator.scripts_for(occurrence.household)
        events, last = self.executor.begin_day(list(day.schedule), scripts, day.replay_key().streams()[1])
        try:
            self.executor.live(events, last, after_action=lambda index: after_action(index, events))
        except _Stop:
            pass

    def _on_source(self, occurrence: Occurrence) -> bool:
        """Whether the occurrence's object rests on its source now, outside the person's hand."""
        graph = self.executor.observer.update()
        return graph.parent_of(occurrence.obj) == occurrence.source and occurrence.obj not in set(
            self.executor.avatar.carried())


def _stop_after(index: int, last: int) -> None:
    if index >= last:
        raise _Stop


def relocate(robot, containers: dict[str, list[str]], obj: str, source: str, destination: str,
             blocked: dict[str, frozenset[str]] | None = None) -> str | None:
    """Open what closes over `source` and what `destination` is used behind (`parts_to_place`), pick `obj`, place
    it, close what was opened; None when every skill succeeded, else the first failure's reason prefixed with its
    skill. Where both close (two pieces of furniture with doors or drawers), one is open at a time: two open doors
    can leave no way between them (a cupboard's and the dishwasher's across the kitchen), and a full hand opens
    and closes nothing; so the object is set down on the nearest open top (`Robot.set_down`) while the source
    closes and the destination opens. So it is where the source's open doors stand in front of the destination
    (`blocked`: furniture -> what its open doors block, `blocked_when_open`); the set-down avoids such tops."""
    from planners.skills.parts import parts_to_open, parts_to_place

    graph = robot.observer.update()
    anchor = graph.anchor_of(source, robot.world.object_names)
    at = anchor if anchor in robot.navigator.furniture else None
    first = parts_to_open(robot.world, graph, containers.get(anchor, []), obj)
    second = [p for p in parts_to_place(robot.world, robot.spots, containers.get(destination, []), destination)
              if p not in first]
    blocked = blocked or {}
    both = bool(first and (second or destination in blocked.get(anchor, ())))
    failure = _open(robot, first if both else first + second)
    if failure is not None:
        return failure
    result = robot.pick(obj, at, into=destination)
    if not result.success:
        return f"pick: {result.reason}"
    if both:
        result = robot.set_down({*containers, *(f for fs in blocked.values() for f in fs)})
        failure = None if result.success else result.reason
        failure = failure or _close(robot, first) or _open(robot, second)
        if failure is not None:
            return failure
        result = robot.pick(obj, robot.observer.update().anchor_of(obj, robot.world.object_names), into=destination)
        if not result.success:
            return f"pick: {result.reason}"
    result = robot.place(destination)
    if not result.success:
        return f"place: {result.reason.removeprefix('place: ')}"
    return _close(robot, second if both else first + second)


def _open(robot, parts: list[str]) -> str | None:
    for part in parts:
        result = robot.open_articulation(part)
        if not result.success:
            return f"open {part}: {result.reason}"
    return None


def _close(robot, parts: list[str]) -> str | None:
    """Close `parts` in reverse order, each tried twice (as the assisted day's robot does); None, or the failure."""
    for part in parts[::-1]:
        result = robot.close_articulation(part)
        if not result.success:
            result = robot.close_articulation(part)
        if not result.success:
            return f"close {part}: {result.reason}"
    return None


def run_triple(bench: Bench, occurrence: Occurrence, cls: str, rng: np.random.Generator) -> TripleResult:
    """Live the day up to the move (see `Bench.live_until`), relocate the object, judge the outcome."""
    from homer_sim.errors import HomerError
    from planners.skills import Robot

    started = time.perf_counter()

    def result(cause: str, reason: str = "", ended: str = "", found: Sequence[tuple[str, float]] = ()) -> TripleResult:
        return TripleResult(occurrence, cls, not cause, cause, reason, ended, time.perf_counter() - started,
                            tuple(found))

    try:
        problem = bench.live_until(occurrence)
    except HomerError as error:
        problem = f"the day could not be lived again: {error}"
    if problem is not None:
        return result("state", problem)
    robot = Robot(bench.world, rng)
    before = bench.world.object_positions()
    try:
        failure = relocate(robot, bench.containers, occurrence.obj, occurrence.source, occurrence.destination,
                           bench.blocked)
    except Exception as error:  # a bug in a skill is this triple's failure, not the suite's end
        log.exception("%s", occurrence.triple)
        failure = f"error: {type(error).__name__} {error}"
    bench.world.settle(max_seconds=2.0)
    graph = robot.observer.update()
    ended = graph.parent_of(occurrence.obj) or ""
    riders = {occurrence.obj} | {n for n in bench.world.object_names if _rides_on(graph, n, occurrence.obj)}
    found = displaced(bench.world, before, skip=riders)
    if failure is not None:
        return result(cause_of(failure), failure, ended, found)
    if ended != occurrence.destination:
        return result("wrong place", f"{occurrence.obj} ended on {ended}", ended, found)
    if CATALOG[cls].family not in NO_FALL_FAMILIES and robot.arm.fallen_over(occurrence.obj):
        return result("fell over", f"{occurrence.obj} lies on its side on {ended}", ended, found)
    return result("collateral", collateral_reason(found), ended, found) if found else result("", "", ended)


def cause_of(failure: str) -> str:
    """The cause-table entry of a skill failure `failure` ("<skill>: <reason>"): the skill and the first of
    KINDS its reason names (the last one it names, where it lists several grasps' failures)."""
    skill = failure.split(":")[0].split(" ")[0]
    named = [(failure.rfind(kind), kind) for kind in KINDS if kind in failure]
    return f"{skill}: {max(named)[1]}" if named else skill


def _rides_on(graph, node: str, carrier: str) -> bool:
    """Whether `node` rests (through other objects) on `carrier`."""
    parent = graph.parent_of(node)
    while parent:
        if parent == carrier:
            return True
        parent = graph.parent_of(parent)
    return False


# --- the suite ------------------------------------------------------------------------------------------
def relocation_trial(bench: Bench, trial: tuple[Occurrence, str, int]) -> TripleResult:
    """Trial = (occurrence, its object's class, seed) on a worker's Bench: the task function of the execution
    backend; the random stream comes from (seed, triple) alone."""
    occurrence, cls, seed = trial
    return run_triple(bench, occurrence, cls, np.random.default_rng([seed, stable_hash(occurrence.triple)]))


def run_relocations(data: Path, quick: bool = False, seed: int = 0, progress: bool = True,
                    households: list[str] | None = None, backend: Backend = IN_PROCESS,
                    objects: list[str] | None = None) -> dict:
    """Try every triple of the dataset at `data` (or the quick subset; only `households`' days and `objects`'
    moves, where given) on `backend` (this process, local processes or Ray: on a cluster every node must see the
    dataset at `data`) and summarise as one JSON object.
    Each triple's random stream is seeded from (seed, triple), so a triple does not depend on which others run."""
    from tqdm import tqdm

    bench = Bench(data)
    classes = {o.name: o.cls for o in bench.world.layout.objects}
    found = occurrences(data, households, objects)
    excluded = {o.triple: why for o in found if (why := exclusion_reason(o, classes[o.obj])) is not None}
    tried = [o for o in found if o.triple not in excluded]
    if quick:
        tried = quick_subset(tried, classes)
    started = time.perf_counter()
    trials = [(occurrence, classes[occurrence.obj], seed) for occurrence in tried]
    done: dict[str, TripleResult] = {}
    with backend.run(relocation_trial, trials, Bench, (Path(data).resolve(),), bench) as run:
        for outcome in tqdm(run, total=len(trials), desc="relocation suite", unit="triple", disable=not progress,
                            file=sys.stderr):
            log.info("%s: %s (%.1f s)", outcome.occurrence.triple, "ok" if outcome.success else outcome.reason,
                     outcome.wall_s)
            done[outcome.occurrence.triple] = outcome
    return summarise([done[o.triple] for o in tried], excluded, time.perf_counter() - started,
                     {"quick": quick, "seed": seed, "data": str(data), "triples": len(found),
                      "execution": run.usage()})


def summarise(results: list[TripleResult], excluded: dict[str, str], wall_s: float, extra: dict) -> dict:
    """The relocation suite's JSON object: counts, per-class rates, the cause table and every triple."""
    per_class: dict[str, dict] = {}
    for r in results:
        entry = per_class.setdefault(r.cls, {"tried": 0, "successes": 0})
        entry["tried"] += 1
        entry["successes"] += int(r.success)
    for entry in per_class.values():
        entry["rate"] = entry["successes"] / entry["tried"]
    successes = sum(r.success for r in results)
    overall = successes / len(results) if results else 0.0
    worst = min((e["rate"] for e in per_class.values()), default=0.0)
    return {
        "tried": len(results), "successes": successes, "overall": overall,
        "excluded": dict(excluded), "n_excluded": len(excluded),
        "causes": dict(Counter(r.cause for r in results if not r.success).most_common()),
        "per_class": per_class, "worst_class_rate": worst,
        "with_collateral": sum(bool(r.collateral) for r in results),  # failed or not: what else each one moved
        "meets_targets": bool(results) and overall >= TARGET_OVERALL and worst >= TARGET_CLASS,
        "results": [{**asdict(r.occurrence), "class": r.cls, "success": r.success, "cause": r.cause,
                     "reason": r.reason, "ended_on": r.ended_on, "wall_s": round(r.wall_s, 2),
                     "collateral": {name: round(d, 3) for name, d in r.collateral}} for r in results],
        "wall_s": wall_s, **extra,
    }


def format_relocations(result: dict) -> str:
    """The relocation suite result as plain text: failures, excluded triples, causes, per class, overall."""
    lines = [f"FAILED {r['obj']}: {r['source']} -> {r['destination']}: {r['reason']}"
             + (f" (also moved {', '.join(r['collateral'])})" if r["collateral"] and r["cause"] != "collateral" else "")
             for r in result["results"] if not r["success"]]
    lines += [f"excluded {triple}: {why}" for triple, why in result["excluded"].items()]
    lines += [f"cause {cause:<14} {count}" for cause, count in result["causes"].items()]
    lines += [f"{cls:<20} {e['successes']:>3}/{e['tried']:<3}" for cls, e in result["per_class"].items()]
    lines.append(f"overall {result['overall']:.1%} of {result['tried']} triples tried; {result['n_excluded']} "
                 f"of {result['triples']} excluded; {result['with_collateral']} moved something else, failed or not")
    return "\n".join(lines)
