"""Scoring an assisted run against the same day without the robot (the reference replay).

A relocation the robot made at query minute t is correct when, in the reference, the person's first move of
that object within (t, t + window] goes to the same destination (the paper's metric, `model.metrics`); done but
not correct is wrong. A fetch is a move of the person's in the reference onto or into furniture; the robot had
made it ahead when it had done a relocation of that object to that place within the window before.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Mapping, Sequence

import numpy as np

from homer_sim.clock import GRID_MIN
from homer_sim.person.executor import DayLog
from model.metrics import first_change
from scenarios.assist import AssistLog, RelocationOutcome
from scenarios.causes import cause_of
from scenarios.psi import Plan


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


def is_correct(outcome: RelocationOutcome, reference: DayLog, index: Mapping[str, int], window_steps: int) -> bool:
    """Whether a relocation was done and went where the person alone would first have moved the object."""
    r = outcome.relocation
    return outcome.done and reference_truth(reference, outcome.minute, index[r.obj], window_steps) == index[
        r.destination]


def person_fetches(reference: DayLog, rooms: set[str], until: float | None = None) -> list[tuple[float, str, str]]:
    """(routine minute, object, furniture) of each move of the person's onto or into furniture in `reference`, up
    to routine minute `until` (None: all)."""
    return [(minute, obj, to) for minute, obj, _, to, _ in reference.moves
            if to and to not in rooms and (until is None or minute <= until)]


def made_ahead(fetch: tuple[float, str, str], relocations: Sequence[RelocationOutcome], window_min: int) -> bool:
    """Whether a done relocation took the fetch's object to its place within `window_min` before it."""
    minute, obj, to = fetch
    return any(o.done and o.relocation.obj == obj and o.relocation.destination == to
               and minute - window_min <= o.minute <= minute for o in relocations)


class Fetches:
    """The reference's fetches, credited once each as the run passes them (the reward's positive part)."""

    def __init__(self, reference: DayLog, rooms: set[str], window_min: int, until: float | None = None) -> None:
        self.pending = person_fetches(reference, rooms, until)
        self.window_min = window_min
        self.credited = 0

    def credit(self, relocations: Sequence[RelocationOutcome], up_to: float) -> int:
        """How many fetches up to routine minute `up_to` the robot had made ahead (each counted once)."""
        due = [f for f in self.pending if f[0] <= up_to]
        self.pending = [f for f in self.pending if f[0] > up_to]
        helped = sum(made_ahead(f, relocations, self.window_min) for f in due)
        self.credited += helped
        return helped


def fetches(assist: AssistLog, reference: DayLog, rooms: set[str], window_min: int,
            until: float | None = None) -> dict:
    """The person's fetches (in the reference day, up to routine minute `until`) and how many of them the robot
    had already done."""
    moves = person_fetches(reference, rooms, until)
    helped = sum(made_ahead(m, assist.relocations, window_min) for m in moves)
    return {"fetches": len(moves), "fetches_done_by_robot": helped,
            "fetch_share": round(helped / len(moves), 3) if moves else None}


SKIP_KINDS: tuple[tuple[str, str], ...] = (
    ("in the person's hand", "in the person's hand"),
    ("the person is at", "the person was there"),
    ("outside the apartment", "outside the apartment"),
    ("not graspable", "not graspable"),
    ("below the threshold", "below the threshold"),
    ("the robot places only on", "destination not placeable"),
    ("held on", "held for the person"),
    ("help went unused", "help went unused before"),
    ("failed earlier", "failed earlier"),
)
"""Why Psi left a predicted move out (the first phrase found in its reason), as a short kind."""


def why_not_ahead(fetch: tuple[float, str, str], relocations: Sequence[RelocationOutcome], skipped: Sequence[dict],
                  window_min: int) -> str:
    """Why the robot had not made the person's `fetch` (minute, object, place) ahead: "made ahead"; "tried: <cause>"
    (a relocation of it there within the window failed); "skipped: <kind>" (Psi left that move out, `SKIP_KINDS`);
    "moved elsewhere" (the robot took the object somewhere else); or "not predicted" (no plan in the window
    names that move)."""
    minute, obj, to = fetch
    if made_ahead(fetch, relocations, window_min):
        return "made ahead"
    near = [o for o in relocations if o.relocation.obj == obj and minute - window_min <= o.minute <= minute]
    tried = [o for o in near if o.relocation.destination == to]
    if tried:
        return "tried: " + cause_of(tried[-1].reason)  # not done (else it was made ahead)
    left = [s["reason"] for s in skipped if s["object"] == obj and s["to"] == to
            and minute - window_min <= s["minute"] <= minute]
    if left:
        return "skipped: " + next((kind for phrase, kind in SKIP_KINDS if phrase in left[-1]), "other")
    return "moved elsewhere" if near else "not predicted"


def score(assist: AssistLog, reference: DayLog, nodes: tuple[str, ...], window_steps: int,
          plans: Sequence[tuple[int, Plan]] = ()) -> dict:
    """Relocations planned, done, and correct against the reference (done but not correct: wrong), with each
    one's details; `plans` (the policy's, if it made any) give each relocation's confidence and why some were
    left out."""
    index = {n: i for i, n in enumerate(nodes)}
    asked = {(minute, r.obj): r for minute, plan in plans for r in plan.relocations}
    rows = []
    for outcome in assist.relocations:
        r = asked.get((outcome.minute, outcome.relocation.obj), outcome.relocation)
        truth = reference_truth(reference, outcome.minute, index[r.obj], window_steps)
        rows.append({"minute": outcome.minute, "object": r.obj, "from": r.source, "to": r.destination,
                     "confidence": None if np.isnan(r.confidence) else round(r.confidence, 3),
                     "put_back": r.put_back, "done": outcome.done, "reason": outcome.reason,
                     "cause": None if outcome.done else cause_of(outcome.reason), "ended_on": outcome.ended_on,
                     "person_unassisted": nodes[truth] if truth >= 0 else None,
                     "correct": outcome.done and truth == index[r.destination]})
    skipped = [{"minute": m, "object": r.obj, "to": r.destination, "reason": why}
               for m, plan in plans for r, why in plan.skipped]
    return {"relocations_planned": len(rows), "relocations_done": sum(r["done"] for r in rows),
            "relocations_correct": sum(r["correct"] for r in rows),
            "relocations_wrong": sum(r["done"] and not r["correct"] for r in rows), "relocations": rows,
            "skipped": skipped}


def end_state(assist: AssistLog, reference: DayLog, nodes: tuple[str, ...]) -> dict:
    """Where the objects the robot moved are at the end of the run, against where the person alone had left them
    then (the reference's snapshot at the run's last minute, else its last): tidy-up is judged here, since the
    paper's metrics count only the person's moves."""
    index = {n: i for i, n in enumerate(nodes)}
    moved = sorted({o.relocation.obj for o in assist.relocations if o.done})
    last = assist.day.minutes[-1] if assist.day.minutes else None
    then = reference.minutes.index(last) if last in reference.minutes else -1
    final, alone = assist.day.parents[-1], reference.parents[then]
    elsewhere = {obj: {"assisted": nodes[final[index[obj]]], "unassisted": nodes[alone[index[obj]]]}
                 for obj in moved if final[index[obj]] != alone[index[obj]]}
    return {"robot_moved": len(moved), "robot_moved_left_as_unassisted": len(moved) - len(elsewhere),
            "left_elsewhere": elsewhere}


def day_result(assist: AssistLog, reference: DayLog, nodes: tuple[str, ...], categories: tuple[str, ...],
               plans: Sequence[tuple[int, Plan]], window_min: int, grid_min: int = GRID_MIN,
               until: float | None = None) -> dict:
    """Everything measured on one assisted run (JSON-ready): `score`, `fetches` (and why each was or was not made
    ahead, counted by kind: `why_not_ahead`) and `end_state`, the robot's
    minutes and skill calls, collateral (objects displaced that no relocation named), failures by cause, the
    person's observed moves and why they stopped early, if they did; `until`: the routine minute the run was cut
    at (None: the whole day)."""
    result = score(assist, reference, nodes, window_min // grid_min, plans)
    rooms = {n for n, c in zip(nodes, categories, strict=True) if c == "room"}
    result.update(fetches(assist, reference, rooms, window_min, until))
    result["fetch_outcomes"] = dict(sorted(Counter(
        why_not_ahead(f, assist.relocations, result["skipped"], window_min)
        for f in person_fetches(reference, rooms, until)).items()))
    result.update(end_state(assist, reference, nodes))
    causes = Counter(row["cause"] for row in result["relocations"] if not row["done"])
    result.update({"robot_minutes": round(assist.robot_minutes, 2), "error": assist.error,
                   "collateral": len(assist.collateral),
                   "collateral_moves": [{"minute": m, "object": o, "moved_m": d} for m, o, d in assist.collateral],
                   "failures": dict(sorted(causes.items())),
                   "robot_steps": [{"minute": round(s.minute, 2), "action": s.step.action, "target": s.step.target,
                                    "success": s.success, "reason": s.reason} for s in assist.steps],
                   "observed_moves": [list(m) for m in assist.day.moves]})
    return result
