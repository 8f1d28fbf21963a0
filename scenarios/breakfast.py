"""The breakfast demo: a morning of the breakfast household with the robot helping, scored against the same morning
without it.

Stages (each timed): the cached dataset (generated on the first run), the cached predictor (trained on the first
run), the unassisted reference replay, the assisted run, and the recording. Relocations are scored as the paper
scores them: a relocation the robot made at query minute t is correct when, in the reference, the person's first
move of that object within (t, t + window] goes to the same destination.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass
from pathlib import Path

from homer_sim.clock import clock_text
from homer_sim.person.executor import DayLog
from scenarios.assist import AssistLog
from scenarios.breakfast_data import DataSpec, check_meta, ensure_dataset, ensure_predictor, make_generator
from scenarios.policies import PsiPolicy
from scenarios.predictors import method_source, thresholds
from scenarios.scoring import day_result
from scenarios.task import AssistEnv, AssistTask, DayPlan, run_episode

log = logging.getLogger(__name__)

MORNING_END_MIN = 510  # 08:30: breakfast starts at 07:00 and is cleared away by about 07:50
DEMO_DAY = ("test", 0)
FULL_DAY_TRAIN_DAYS = 50  # a full assisted day's household: training days, as in the paper setup (about 1 s each)


@dataclass(frozen=True)
class Morning:
    """Which day: the dataset split and day index, whether the person skips breakfast, when to stop (routine
    minute; None: the whole day)."""

    split: str = DEMO_DAY[0]
    index: int = DEMO_DAY[1]
    skip_breakfast: bool = False
    end_min: int | None = MORNING_END_MIN


@dataclass(frozen=True)
class MorningRun:
    """A demo run: the summary (JSON-ready), the robot's log with the assisted day, the unassisted reference."""

    result: dict
    assist: AssistLog
    reference: DayLog
    nodes: tuple[str, ...]


def run_breakfast(rrd: Path | None, morning: Morning = Morning(), spec: DataSpec | None = None) -> dict:
    """The whole demo; returns the summary (JSON-ready), with the wall seconds of every stage."""
    return assisted_run(rrd, morning, spec).result


def run_full_day(rrd: Path | None, household: str) -> dict:
    """One whole test day of `household` (one of the project's) with the robot helping; its summary."""
    return assisted_run(rrd, Morning(end_min=None), DataSpec(train_days=FULL_DAY_TRAIN_DAYS, test_days=1,
                                                             household=household)).result


@dataclass(frozen=True)
class MorningSetup:
    """The assisted-day environment of a morning, the predictor fitted for its household and its checkpoint info
    (tunings), and the wall seconds of making them (dataset, predictor)."""

    env: AssistEnv
    predictor: object
    info: dict
    nodes: tuple[str, ...]
    stages_s: dict[str, float]


def morning_setup(morning: Morning = Morning(), spec: DataSpec | None = None, recording=None) -> MorningSetup:
    """The cached dataset and predictor of `spec.household` (made on the first run) and an environment whose
    episode is the day `morning` names."""
    spec = spec or DataSpec()
    started = time.perf_counter()
    generator = make_generator()
    dataset, generated_s = ensure_dataset(generator, spec)
    check_meta(dataset.meta, generator.world.layout.node_names())
    stages = {"dataset (cached)" if generated_s == 0 else "dataset (generated)": time.perf_counter() - started}
    predictor, info, trained_s = ensure_predictor(dataset, spec)
    stages["predictor (cached)" if trained_s == 0 else "predictor (trained)"] = (
        time.perf_counter() - started - sum(stages.values()))
    env = AssistEnv(AssistTask([morning_plan(dataset, morning, spec)], seed=spec.seed,
                               window_min=spec.window_min, reference=generator, recording=recording))
    return MorningSetup(env, predictor, info, dataset.meta.nodes, {k: round(v, 2) for k, v in stages.items()})


def assisted_run(rrd: Path | None, morning: Morning = Morning(), spec: DataSpec | None = None) -> MorningRun:
    """A day (or its morning) of `spec.household` with the robot helping, scored against the same day without it:
    the cached dataset and predictor, the assisted-day environment run by Psi (its reset replays the day without
    the robot), the recording; keeps the logs."""
    spec = spec or DataSpec()
    recording = None
    if rrd is not None:
        from homer_sim.recording import Recording

        recording = Recording(rrd)
    setup = morning_setup(morning, spec, recording)
    env, stages = setup.env, dict(setup.stages_s)
    if recording is not None:
        recording.log_geometry(env.task.world.model, env.task.world.data)
    policy = PsiPolicy(env.scene, setup.predictor, spec.window_min, recording=recording)
    started = time.perf_counter()
    episode_return = run_episode(env, policy)
    stages["assisted run (and its reference replay)"] = round(time.perf_counter() - started, 2)
    if recording is not None:
        started = time.perf_counter()
        recording.close()
        stages["recording"] = round(time.perf_counter() - started, 2)
    assist, reference = env.task.log, env.task.reference
    result = day_result(assist, reference, env.scene.nodes, env.scene.categories, policy.plans, spec.window_min,
                        until=morning.end_min)
    result.update({"rrd": str(rrd) if rrd is not None else None, "household": spec.household,
                   "day": f"{morning.split}/{morning.index}", "schedule": [list(e) for e in env.task.day.entries],
                   "method": setup.predictor.method, "method_from": method_source(spec.method),
                   "threshold": policy.threshold, "thresholds": thresholds(setup.info, spec.window_min),
                   "window_min": spec.window_min,
                   "return": episode_return, "stages_s": stages})
    return MorningRun(result, assist, reference, setup.nodes)


def morning_plan(dataset, morning: Morning, spec: DataSpec) -> DayPlan:
    """The day `morning` names in the cached dataset of `spec`, as an episode of the assisted-day task."""
    day = dataset.load(spec.household, morning.split)[morning.index]
    entries = () if morning.skip_breakfast else tuple(tuple(e) for e in day.schedule)
    return DayPlan(spec.household, day.replay_key(), entries, morning.end_min)


def format_summary(result: dict) -> list[str]:
    """Human-readable lines of a `run_breakfast` result."""
    lines = [f"{result['household']} {result['day']}: " + (", ".join(
        f"{a} {clock_text(s)}-{clock_text(e)}" for a, s, e in result["schedule"]) or "no breakfast today"),
        f"predictor {result['method']} ({result['method_from']}), threshold {result['threshold']:.2f} (tuned on "
        f"validation days for the assistance objective; {result['thresholds']['paper']:.2f} for the paper's), window "
        f"{result['window_min']} min"]
    for r in result["relocations"]:
        status = "done" if r["done"] else f"FAILED: {r['reason']}"
        verdict = "correct" if r["correct"] else f"person would have moved it to {r['person_unassisted']}"
        why = "unused, put back" if r["put_back"] else f"p {r['confidence']:.2f}"
        lines.append(f"  {clock_text(r['minute'])} {r['object']}: {r['from']} -> {r['to']} ({why}) "
                     f"{status}; {verdict if r['done'] else ''}".rstrip("; "))
    lines.append(f"relocations planned {result['relocations_planned']}, done {result['relocations_done']}, "
                 f"correct {result['relocations_correct']}, wrong {result['relocations_wrong']}; robot busy "
                 f"{result['robot_minutes']:.1f} routine min")
    if result["fetches"]:
        lines.append(f"the robot had already done {result['fetches_done_by_robot']} of the person's "
                     f"{result['fetches']} fetches ({100 * result['fetch_share']:.0f}%)")
    if result["robot_moved"]:
        lines.append(f"at the end, {result['robot_moved_left_as_unassisted']} of the {result['robot_moved']} objects "
                     "the robot moved are where the person alone would have left them" + "".join(
                         f"; {obj} on {w['assisted']}, not {w['unassisted']}"
                         for obj, w in result["left_elsewhere"].items()))
    if result["error"]:
        lines.append(f"the run stopped early: {result['error']}")
    lines.append("stages: " + ", ".join(f"{k} {v:.1f} s" for k, v in result["stages_s"].items()))
    lines.append(f"recording: {result['rrd']}" if result["rrd"] else "recording: none (use --rrd PATH)")
    return lines
