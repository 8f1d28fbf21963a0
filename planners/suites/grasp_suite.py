"""`homer grasp-suite`: the grasp regression suite, and `register(subparsers)` for the `homer` parser.

Every robot-graspable object class in the apartment is picked several times by `planners.skills.Robot`, each
time from a randomised start pose on its home surface or shelf (position jitter, yaw) that keeps the gaps the
layout keeps to its neighbours and to furniture walls: this narrows the test to the start layout's spacing (no
object starts against a wall or touching another; see `_jitter_pose`). The scene is set up by
the suite, not the robot: the apartment's settled start state, the doors or drawer holding the object opened,
the object moved to its trial pose, the robot tucked in front of the furniture. From there on only physics
moves anything. A trial succeeds when the object is at least MIN_LIFT m above its start, stays there for
HOLD_SECONDS of physics, and slips less than MAX_SLIP m relative to the grip site meanwhile (no MuJoCo warning
or NaN either), and no other object moved more than `planners.suites.collateral.MAX_DISPLACEMENT` (a pick that
knocks a neighbour off its shelf is a failure, counted as `collateral`). Classes that
`planners.grasps.candidate.ungraspable_reason` rejects are listed as excluded, with that reason.

mujoco and the planners that need it are imported inside the functions that run trials, so `homer --help`
stays fast.
"""

from __future__ import annotations

import logging
import math
import sys
import time
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from homer_sim.errors import HomerError
from homer_sim.execution import IN_PROCESS, Backend
from homer_sim.graph import INSIDE
from homer_sim.home.apartment import default_layout
from homer_sim.home.catalog import CATALOG, FAMILIES
from homer_sim.home.placement import SPOT_GAP
from planners.suites.collateral import collateral_reason, displaced

if TYPE_CHECKING:
    from homer_sim.recording import RecordedWorld
    from homer_sim.world import World
    from planners.skills import Robot

log = logging.getLogger(__name__)

MIN_LIFT = 0.10  # m above the start height
HOLD_SECONDS = 3.0  # s of physics the lifted object must stay in the hand
MAX_SLIP = 0.005  # m the object may move relative to the grip site while held
JITTER = 0.025  # m: start position uniform within +-JITTER of the home position, in x and y
YAW_ON = math.pi  # rad: yaw jitter on open surfaces (top grasps take any yaw)
YAW_INSIDE = math.radians(20.0)  # rad: yaw jitter on shelves and in drawers (objects face the front)
OPEN_SETUP = 0.96  # openness the suite gives the door or drawer in front of the object
MAX_PENETRATION = 0.002  # m: a sampled start pose may not press deeper into anything
POSE_TRIES = 200  # a pose keeping the layout's gaps is rare for an object packed close (see `_jitter_pose`)
TARGET_OVERALL = 0.95
TARGET_CLASS = 0.8
DEFAULT_TRIALS = 3
QUICK_TRIALS = 1


@dataclass(frozen=True)
class TrialResult:
    """One pick of one object: success, why not, the lift (m) and slip (m) measured, wall time (s), trial number."""

    cls: str
    success: bool
    reason: str
    lift_m: float
    slip_m: float
    wall_s: float
    collateral: bool = False  # an otherwise successful pick that moved another object (`suites.collateral`)
    trial: int = 0


def suite_classes() -> tuple[dict[str, str], dict[str, str]]:
    """({class: the instance the suite picks}, {excluded class: reason}) over the apartment's movable objects,
    in layout order (the first instance of each class)."""
    from planners.grasps.candidate import ungraspable_reason

    included: dict[str, str] = {}
    excluded: dict[str, str] = {}
    for obj in default_layout().objects:
        if obj.cls in included or obj.cls in excluded:
            continue
        reason = ungraspable_reason(CATALOG[obj.cls])
        if reason is None:
            included[obj.cls] = obj.name
        else:
            excluded[obj.cls] = reason
    return included, excluded


def quick_subset(included: dict[str, str]) -> dict[str, str]:
    """The fast representative subset: one class of each shape family and one taken by a grip feature (a
    handle, a tie, a fold), the first of each in layout order."""
    kinds = [lambda c, f=family: c.family == f for family in FAMILIES] + [lambda c: c.handle is not None]
    chosen: dict[str, str] = {}
    for kind in kinds:
        cls = next((cls for cls in included if kind(CATALOG[cls]) and cls not in chosen), None)
        if cls is not None:
            chosen[cls] = included[cls]
    return chosen


# --- one trial ------------------------------------------------------------------------------------------
def _open_holder(world: World, name: str) -> None:
    """Open what closes over object `name`: every door of the cabinet it is in, or the drawer it lies in (its
    contents carried along with the drawer, as the open drawer would carry them)."""
    from homer_sim.home.furniture import furniture_geometry

    decl = world.layout.objects[world.object_index(name)]
    furniture = world.layout.furniture_by_name().get(decl.parent)
    if furniture is None or decl.level is None:
        return
    geometry = furniture_geometry(furniture)
    drawer = geometry.places[decl.level].part if decl.level < len(geometry.places) else None
    if drawer is not None:
        a = world.articulation(f"{furniture.name}/{drawer}")
        before = float(world.data.qpos[a.qpos_adr])
        world.set_openness(a.name, OPEN_SETUP)
        shift = (float(world.data.qpos[a.qpos_adr]) - before) * world.data.xaxis[a.joint_id]
        for rider in world.layout.objects:
            if rider.parent == decl.parent and rider.level == decl.level:
                pos, quat = world.object_pose(rider.name)
                world.set_object_pose(rider.name, pos + shift, quat, forward=False)
    elif decl.relation == INSIDE:
        for a in world.articulations.values():
            if a.furniture == furniture.name:
                world.set_openness(a.name, OPEN_SETUP, forward=False)
    import mujoco

    mujoco.mj_forward(world.model, world.data)


def _penetration(world: World, body: int) -> float:
    """Deepest penetration (m, >= 0) of any geom of `body` into anything, from the current contacts."""
    deepest = 0.0
    for c in world.data.contact[: world.data.ncon]:
        if body in (world.model.geom_bodyid[c.geom1], world.model.geom_bodyid[c.geom2]):
            deepest = max(deepest, -float(c.dist))
    return deepest


class _Gaps:
    """The gaps (m) between the geoms of one object's body and the collision geoms round it (its neighbours', the
    furniture's panels and boards, the floor; never the robot's, told by `robot_geom_ids`), each read up to
    SPOT_GAP: farther is SPOT_GAP. Built at the object's home pose, it keeps the geoms its jittered poses can
    come within SPOT_GAP of (the object swept over JITTER in x and y and any yaw) and their gaps there."""

    def __init__(self, world: World, body: int) -> None:
        from planners.motion.control import robot_geom_ids

        model, data = world.model, world.data
        self.world = world
        self.mine = np.flatnonzero(model.geom_bodyid == body)
        others = np.ones(model.ngeom, dtype=bool)
        others[self.mine] = False
        others[robot_geom_ids(model)] = False
        contype, conaffinity = model.geom_contype, model.geom_conaffinity
        for g in self.mine:  # only geoms that collide with one of the object's
            others &= ((contype & conaffinity[g]) | (contype[g] & conaffinity)) != 0
        centre = data.xpos[body]
        radius = max(float(np.linalg.norm(data.geom_xpos[g] - centre) + model.geom_rbound[g]) for g in self.mine)
        reach = radius + math.sqrt(2.0) * JITTER + SPOT_GAP  # the object's farthest reach from its home centre
        near = (np.linalg.norm(data.geom_xpos - centre, axis=1) < reach + model.geom_rbound) \
            | (model.geom_rbound == 0.0)  # a plane has no bound
        self.others = np.flatnonzero(others & near)
        self.home = self.now()

    def now(self) -> np.ndarray:
        """The gap (m, at most SPOT_GAP; negative where they overlap) to each of `self.others` at the current
        geom poses, shape (len(self.others),)."""
        import mujoco

        model, data = self.world.model, self.world.data
        gaps = np.full(len(self.others), SPOT_GAP)
        bound = model.geom_rbound
        for k, other in enumerate(self.others):
            for g in self.mine:
                apart = np.linalg.norm(data.geom_xpos[g] - data.geom_xpos[other])
                if bound[other] > 0.0 and apart > bound[g] + bound[other] + SPOT_GAP:  # bounding spheres apart
                    continue
                gaps[k] = min(gaps[k], mujoco.mj_geomDistance(model, data, int(g), int(other), SPOT_GAP, None))
        return gaps

    def kept(self) -> bool:
        """Whether the current pose keeps the gap the layout keeps to every geom round the object: SPOT_GAP, or the
        home pose's own gap where that is smaller (the board it stands on, a neighbour packed closer), less
        MAX_PENETRATION."""
        return bool(np.all(self.now() >= np.minimum(SPOT_GAP, self.home) - MAX_PENETRATION))


def _jitter_pose(world: World, name: str, rng: np.random.Generator) -> None:
    """Move object `name` to a random pose near where it rests: xy within JITTER, yaw within YAW_ON (open
    surfaces) or YAW_INSIDE (shelves, drawers). A pose that presses into anything, or that comes closer to a
    neighbour or to a furniture wall (a side panel, a shelf's back) than the layout keeps it (see `_Gaps`), is
    resampled; after POSE_TRIES the object stays at its home pose. So the suite tests picks from the spacing the
    layout keeps, not harder ones: no object starts against a wall or touching another, where the layout puts
    none (and where no finger fits)."""
    import mujoco

    decl = world.layout.objects[world.object_index(name)]
    yaw_range = YAW_INSIDE if decl.relation == INSIDE else YAW_ON
    home_pos, home_quat = world.object_pose(name)
    body = int(world.object_body_ids[world.object_index(name)])
    gaps = _Gaps(world, body)
    for _ in range(POSE_TRIES):
        dx, dy = rng.uniform(-JITTER, JITTER, size=2)
        yaw = float(rng.uniform(-yaw_range, yaw_range))
        turn = np.array([math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)])
        world.set_object_pose(name, home_pos + np.array([dx, dy, 0.0]), _quat_mul(turn, home_quat), forward=False)
        mujoco.mj_kinematics(world.model, world.data)
        mujoco.mj_collision(world.model, world.data)
        if _penetration(world, body) < MAX_PENETRATION and gaps.kept():
            mujoco.mj_forward(world.model, world.data)
            return
    world.set_object_pose(name, home_pos, home_quat)


def _quat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product a * b of wxyz quaternions (shape (4,))."""
    w1, x1, y1, z1 = a
    w2, x2, y2, z2 = b
    return np.array([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                     w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2])


def _robot_in_front(world: World, name: str, rng: np.random.Generator) -> Robot:
    """A fresh `Robot` standing tucked at a free base pose in front of the furniture that holds `name` (near
    `name` where no pose in front is free)."""
    import mujoco

    from planners.motion.navigation import NavigationError
    from planners.skills import Robot

    robot = Robot(world, rng)
    decl = world.layout.objects[world.object_index(name)]
    q = robot.tuck.copy()
    xy = tuple(world.object_pose(name)[0][:2])
    try:  # in front of the furniture; where nothing is free there, anywhere near (the pick finds its own pose)
        q[:3] = robot.navigator.stand_pose(decl.parent, xy)
    except NavigationError:
        q[:3] = robot.navigator.stand_near(xy)
    world.data.qpos[robot.controller.qpos_adr] = q
    world.data.qvel[robot.controller.dof_adr] = 0.0
    mujoco.mj_forward(world.model, world.data)
    robot.controller.target = robot.controller.q()
    robot.controller.command(robot.controller.target, grip=float(np.mean(q[robot.controller.n_body:])))
    return robot


def _relative_position(world: World, name: str) -> np.ndarray:
    """The object's position in the grip-site frame, m, shape (3,)."""
    grip = world.data.site("robot/grip")
    return grip.xmat.reshape(3, 3).T @ (world.object_pose(name)[0] - grip.xpos)


def run_trial(world: World, cls: str, name: str, rng: np.random.Generator) -> TrialResult:
    """Set the scene up (see the module doc), pick `name` of class `cls`, hold it HOLD_SECONDS, measure."""
    started = time.perf_counter()
    world.reset_settled()
    _open_holder(world, name)
    _jitter_pose(world, name, rng)
    try:
        robot = _robot_in_front(world, name, rng)
    except HomerError as error:
        return TrialResult(cls, False, f"set-up: {error}", 0.0, math.nan, time.perf_counter() - started)
    world.settle(max_seconds=2.0)
    robot.observer.observe_all()
    before = world.object_positions()
    start_z = float(world.object_pose(name)[0][2])
    parent = world.layout.objects[world.object_index(name)].parent
    picked = robot.pick(name, parent if parent in robot.navigator.furniture else None)
    lift = float(world.object_pose(name)[0][2]) - start_z

    def result(success: bool, reason: str, slip: float = math.nan, collateral: bool = False) -> TrialResult:
        return TrialResult(cls, success, reason, lift, slip, time.perf_counter() - started, collateral)

    if not picked.success:
        return result(False, picked.reason)
    held_at = _relative_position(world, name)
    world.step(int(round(HOLD_SECONDS / world.model.opt.timestep)))
    slip = float(np.linalg.norm(_relative_position(world, name) - held_at))
    lift = min(lift, float(world.object_pose(name)[0][2]) - start_z)
    if world.warnings() or world.has_nan():
        return result(False, f"{world.warnings()} MuJoCo warnings, NaN {world.has_nan()}", slip)
    if lift < MIN_LIFT:
        return result(False, f"lifted {lift * 100:.1f} cm, below {MIN_LIFT * 100:.0f} cm", slip)
    if slip > MAX_SLIP:
        return result(False, f"slipped {slip * 1000:.1f} mm in {HOLD_SECONDS:.0f} s", slip)
    found = displaced(world, before, skip={name})
    return result(False, collateral_reason(found), slip, True) if found else result(True, "", slip)


# --- the suite ------------------------------------------------------------------------------------------
def suite_world() -> RecordedWorld:
    """The suite's world: the apartment with the robot, its settled start computed (a worker's state)."""
    from homer_sim.recording import RecordedWorld
    from planners.robot import add_robot

    world = RecordedWorld(extras=[add_robot])
    world.reset_settled()  # the settled start is computed once, before the recorded clock starts
    return world


def suite_trial(world: RecordedWorld, run: tuple[str, str, int, int]) -> TrialResult:
    """Trial k of class `cls` (instance `name`) with seed `seed`, run = (cls, name, seed, k), on a suite world;
    its random stream comes from (seed, class, k) alone. A recording world gets the outcome as an event and
    its physics clock moved past the trial."""
    cls, name, seed, k = run
    outcome = replace(run_trial(world, cls, name, np.random.default_rng([seed, stable_hash(cls), k])), trial=k)
    if world.recording is not None:
        world.recording.log_event(describe(outcome), level="INFO" if outcome.success else "WARN")
        world.physics_offset += float(world.data.time)
    return outcome


def describe(outcome: TrialResult) -> str:
    """One line for the log: class, trial, ok or why not, lift, slip and wall time."""
    return (f"{outcome.cls} trial {outcome.trial}: " + ("ok" if outcome.success else f"FAILED {outcome.reason}")
            + f" (lift {outcome.lift_m:.3f} m, slip {outcome.slip_m:.4f} m, {outcome.wall_s:.1f} s)")


def run_suite(quick: bool = False, trials: int | None = None, seed: int = 0, progress: bool = True,
              classes: dict[str, str] | None = None, rrd: Path | None = None, backend: Backend = IN_PROCESS) -> dict:
    """Run `trials` picks of every included class (or of the quick subset, or of `classes`: {class:
    instance}) on `backend` (local processes or Ray tasks) and summarise them as the `grasp-suite` JSON object.
    Each trial's random stream is seeded from (seed, class name, trial number), so a trial does not depend on
    which other trials run, nor where. With `rrd` (in this process only), every trial is recorded there, one
    after the other on the physics clock, each outcome as an event."""
    from tqdm import tqdm

    from homer_sim.recording import Recording

    included, excluded = suite_classes()
    chosen = classes if classes is not None else (quick_subset(included) if quick else included)
    trials = trials if trials is not None else (QUICK_TRIALS if quick else DEFAULT_TRIALS)
    runs = [(cls, name, seed, k) for cls, name in chosen.items() for k in range(trials)]
    world = None
    if rrd is not None:
        if backend != IN_PROCESS:
            raise HomerError(f"a recording ({rrd}) holds the trials one after the other in one world; drop "
                             "--workers and --ray to record")
        world = suite_world()
        world.recording = Recording(rrd)
        world.recording.log_geometry(world.model, world.data)
    started = time.perf_counter()
    results: list[TrialResult] = []
    try:
        with backend.run(suite_trial, runs, suite_world, local_state=world) as trial_runs:
            for outcome in tqdm(trial_runs, total=len(runs), desc="grasp suite", unit="trial", disable=not progress,
                                file=sys.stderr):
                log.info(describe(outcome))
                results.append(outcome)
    finally:  # what was recorded stays readable when a trial raises
        if world is not None and world.recording is not None:
            world.recording.close()
    order = {cls: i for i, cls in enumerate(chosen)}
    results.sort(key=lambda r: (order[r.cls], r.trial))
    return summarise(results, excluded, len(included) + len(excluded), time.perf_counter() - started,
                     {"quick": quick, "seed": seed, "trials_per_class": trials, "rrd": str(rrd) if rrd else None,
                      "execution": trial_runs.usage()})


def stable_hash(text: str) -> int:
    """A process-independent non-negative integer from a string (Python's hash() is salted per process)."""
    return int.from_bytes(text.encode()[:16].ljust(16, b"\0"), "little") % (2**63)


def summarise(results: list[TrialResult], excluded: dict[str, str], n_classes: int, wall_s: float,
              extra: dict) -> dict:
    """The `grasp-suite` JSON object from trial results: `trials`, `overall`, `per_class` and `excluded` keep
    their meaning for scripts; `collateral` counts the trials failed only because another object moved; failure
    reasons per class, every trial's outcome and timing are extra keys."""
    per_class: dict[str, dict] = {}
    for r in results:
        entry = per_class.setdefault(r.cls, {"trials": 0, "successes": 0, "failures": [],
                                             "family": CATALOG[r.cls].family})
        entry["trials"] += 1
        entry["successes"] += int(r.success)
        if not r.success:
            entry["failures"].append(r.reason)
        else:  # the measured margins of the successful trials
            entry["min_lift_m"] = round(min(entry.get("min_lift_m", np.inf), r.lift_m), 4)
            entry["max_slip_m"] = round(max(entry.get("max_slip_m", 0.0), r.slip_m), 5)
    successes = sum(r.success for r in results)
    rates = [e["successes"] / e["trials"] for e in per_class.values()]
    return {
        "trials": len(results),
        "overall": successes / len(results) if results else 0.0,
        "collateral": sum(r.collateral for r in results),
        "per_class": per_class,
        "excluded": dict(excluded),
        "classes": n_classes,
        "excluded_fraction": len(excluded) / max(n_classes, 1),
        "worst_class_rate": min(rates) if rates else 0.0,
        "meets_targets": bool(results) and successes / len(results) >= TARGET_OVERALL
        and min(rates) >= TARGET_CLASS,
        "median_trial_wall_s": float(np.median([r.wall_s for r in results])) if results else 0.0,
        "results": [{"class": r.cls, "trial": r.trial, "success": r.success, "reason": r.reason, "lift_m": r.lift_m,
                     "slip_m": None if math.isnan(r.slip_m) else r.slip_m, "collateral": r.collateral}
                    for r in results],
        "wall_s": wall_s,
        **extra,
    }


def chosen_classes(names: list[str]) -> dict[str, str]:
    """{class: the instance the suite picks} for the included classes `names`; a HomerError names an unknown or
    excluded one and lists the valid names."""
    included, excluded = suite_classes()
    for name in names:
        if name not in included:
            why = f"excluded ({excluded[name]})" if name in excluded else "unknown"
            raise HomerError(f"grasp-suite class {name!r} is {why}; included: {', '.join(included)}")
    return {name: included[name] for name in names}


def format_table(result: dict) -> str:
    """The suite result as a plain-text table: per class, then excluded classes, then the overall rate."""
    lines = [f"{'class':<20} {'family':<9} {'ok':>5}"]
    for cls, e in result["per_class"].items():
        lines.append(f"{cls:<20} {e['family']:<9} {e['successes']:>2}/{e['trials']:<2}"
                     + (f"  {e['failures'][0]}" if e["failures"] else ""))
    lines += [f"excluded {cls}: {reason}" for cls, reason in result["excluded"].items()]
    lines.append(f"overall {result['overall']:.1%} of {result['trials']} trials; "
                 f"excluded {len(result['excluded'])} of {result['classes']} classes")
    return "\n".join(lines)
