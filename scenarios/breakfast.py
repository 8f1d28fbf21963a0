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
from functools import partial
from pathlib import Path

import numpy as np

from homer_sim.clock import clock_text
from homer_sim.person.executor import DayLog
from homer_sim.recording import Recording
from model.metrics import first_change
from scenarios.assist import Assistant, AssistLog, run_assisted
from scenarios.breakfast_data import DataSpec, check_meta, ensure_dataset, ensure_predictor, make_generator

log = logging.getLogger(__name__)

MORNING_END_MIN = 510  # 08:30: breakfast starts at 07:00 and is cleared away by about 07:50
DEMO_DAY = ("test", 0)
FULL_DAY_TRAIN_DAYS = 20  # a full assisted day's household: days to fit its predictor on (about 2 s each)


@dataclass(frozen=True)
class Morning:
    """Which day: the dataset split and day index, whether the person skips breakfast, when to stop (routine
    minute; None: the whole day)."""

    split: str = DEMO_DAY[0]
    index: int = DEMO_DAY[1]
    skip_breakfast: bool = False
    end_min: int | None = MORNING_END_MIN


def reference_truth(reference: DayLog, minute: int, obj_index: int, window_steps: int) -> int:
    """The node index the person first moved object `obj_index` to within (minute, minute + window] in the
    reference day, or -1 if they did not move it (first change, as model.metrics counts it)."""
    minutes = np.asarray(reference.minutes)
    if minute not in minutes:
        return -1
    t = int(np.flatnonzero(minutes == minute)[0])
    parents = np.asarray(reference.parents)
    future = parents[t + 1 : t + 1 + window_steps]
    if len(future) == 0:
        return -1
    _, destination = first_change(parents[t][None], future[None], np.array([len(future)]))
    return int(destination[0, obj_index])


def fetches(assist: AssistLog, reference: DayLog, rooms: set[str], window_min: int) -> dict:
    """The person's fetches (in the reference day, each move of an object onto or into furniture) and how many of
    them the robot had already done: a done relocation of that object to that place within `window_min` before."""
    moves = [(minute, obj, to) for minute, obj, _, to, _ in reference.moves if to and to not in rooms]
    done = [(o.minute, o.relocation.obj, o.relocation.destination) for o in assist.relocations if o.done]
    helped = sum(any(obj == d_obj and to == d_to and minute - window_min <= d_minute <= minute
                     for d_minute, d_obj, d_to in done) for minute, obj, to in moves)
    return {"fetches": len(moves), "fetches_done_by_robot": helped,
            "fetch_share": round(helped / len(moves), 3) if moves else None}


def score(assist: AssistLog, reference: DayLog, nodes: tuple[str, ...], window_steps: int) -> dict:
    """Relocations planned, done, and correct against the reference (done but not correct: wrong), with each
    one's details."""
    index = {n: i for i, n in enumerate(nodes)}
    rows = []
    for outcome in assist.relocations:
        r = outcome.relocation
        truth = reference_truth(reference, outcome.minute, index[r.obj], window_steps)
        rows.append({"minute": outcome.minute, "object": r.obj, "from": r.source, "to": r.destination,
                     "confidence": round(r.confidence, 3), "put_back": r.put_back, "done": outcome.done,
                     "reason": outcome.reason, "ended_on": outcome.ended_on,
                     "person_unassisted": nodes[truth] if truth >= 0 else None,
                     "correct": outcome.done and truth == index[r.destination]})
    skipped = [{"minute": m, "object": r.obj, "to": r.destination, "reason": why}
               for m, plan in assist.plans for r, why in plan.skipped]
    return {"relocations_planned": len(rows), "relocations_done": sum(r["done"] for r in rows),
            "relocations_correct": sum(r["correct"] for r in rows),
            "relocations_wrong": sum(r["done"] and not r["correct"] for r in rows), "relocations": rows,
            "skipped": skipped}


def end_state(assist: AssistLog, reference: DayLog, nodes: tuple[str, ...]) -> dict:
    """Where the objects the robot moved are at the end of the run, against where the person alone left them (the
    reference's last snapshot): tidy-up is judged here, since the paper's metrics count only the person's moves."""
    index = {n: i for i, n in enumerate(nodes)}
    moved = sorted({o.relocation.obj for o in assist.relocations if o.done})
    final, alone = assist.day.parents[-1], reference.parents[-1]
    elsewhere = {obj: {"assisted": nodes[final[index[obj]]], "unassisted": nodes[alone[index[obj]]]}
                 for obj in moved if final[index[obj]] != alone[index[obj]]}
    return {"robot_moved": len(moved), "robot_moved_left_as_unassisted": len(moved) - len(elsewhere),
            "left_elsewhere": elsewhere}


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


def assisted_run(rrd: Path | None, morning: Morning = Morning(), spec: DataSpec | None = None) -> MorningRun:
    """A day (or its morning) of `spec.household` with the robot helping, scored against the same day without it:
    the cached dataset and predictor, the reference replay, the assisted run, the recording; keeps the logs."""
    spec = spec or DataSpec()
    stages: dict[str, float] = {}
    clock = time.perf_counter()

    def stage(name: str) -> None:
        nonlocal clock
        now = time.perf_counter()
        stages[name] = round(now - clock, 2)
        clock = now

    generator = make_generator()
    dataset, generated_s = ensure_dataset(generator, spec)
    check_meta(dataset.meta, generator.world.layout.node_names())
    stage("dataset (cached)" if generated_s == 0 else "dataset (generated)")
    predictor, trained_s = ensure_predictor(dataset, spec)
    stage("predictor (cached)" if trained_s == 0 else "predictor (trained)")

    day = dataset.load(spec.household, morning.split)[morning.index]
    entries = [] if morning.skip_breakfast else [tuple(e) for e in day.schedule]
    reference = generator.replay(spec.household, day.replay_key(), entries, end_min=morning.end_min)
    stage("reference replay")

    recording = None
    if rrd is not None:

        recording = Recording(rrd)
    assistant = Assistant(predictor, spec.window_min, recording=recording, rng=np.random.default_rng(spec.seed))
    if recording is not None:
        recording.log_geometry(assistant.world.model, assistant.world.data)
    assist = run_assisted(assistant, partial(generator.replay, spec.household, day.replay_key(), entries),
                          morning.end_min)
    stage("assisted run")
    if recording is not None:
        recording.close()
        stage("recording")
    result = score(assist, reference, dataset.meta.nodes, spec.window_min // dataset.meta.grid_min)
    rooms = {n for n, c in zip(dataset.meta.nodes, dataset.meta.categories, strict=True) if c == "room"}
    result.update(fetches(assist, reference, rooms, spec.window_min))
    result.update(end_state(assist, reference, dataset.meta.nodes))
    result.update({"rrd": str(rrd) if rrd is not None else None, "household": spec.household,
                   "day": f"{morning.split}/{morning.index}", "schedule": [list(e) for e in entries],
                   "method": spec.method, "threshold": assistant.threshold, "window_min": spec.window_min,
                   "robot_minutes": round(assist.robot_minutes, 2), "error": assist.error,
                   "robot_steps": [{"minute": round(s.minute, 2), "action": s.step.action, "target": s.step.target,
                                    "success": s.success, "reason": s.reason} for s in assist.steps],
                   "observed_moves": [list(m) for m in assist.day.moves], "stages_s": stages})
    return MorningRun(result, assist, reference, dataset.meta.nodes)


def format_summary(result: dict) -> list[str]:
    """Human-readable lines of a `run_breakfast` result."""
    lines = [f"{result['household']} {result['day']}: " + (", ".join(
        f"{a} {clock_text(s)}-{clock_text(e)}" for a, s, e in result["schedule"]) or "no breakfast today"),
        f"predictor {result['method']} (threshold {result['threshold']:.2f}), window {result['window_min']} min"]
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
