"""`homer replay`: timed day scripts (the HOMER+ format, `homer_sim.person.day_scripts`) lived physically in our
apartment at the scripts' minutes, written as dataset days (`homer_sim.data.dataset`).

One day is one task: the person starts the day from the start layout, each action runs at its minute through the
executor (as generation does), the scene graph is read every 10 minutes. A day's random stream (free spots) is
seeded from its split and number, so a day gives the same bytes whatever the worker count or backend. Days are written
atomically; an interrupted run resumes with the days not yet written. A day that cannot run (a name our apartment
lacks, an action that fails) is logged with its reason in `generation.log` and the run goes on.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from tqdm import tqdm

from homer_sim import __version__
from homer_sim.clock import DAY_END_MIN
from homer_sim.data.dataset import SPLITS, DatasetMeta, Day, day_path, write_day, write_meta
from homer_sim.data.generate import world_meta
from homer_sim.data.stats import LOG_NAME
from homer_sim.errors import HomerError, LayoutError
from homer_sim.execution import IN_PROCESS, Backend
from homer_sim.graph import INSIDE, ON
from homer_sim.home.catalog import CATALOG
from homer_sim.home.floorplan import floor_plan
from homer_sim.home.furniture import furniture_geometry
from homer_sim.home.layout import Layout, ObjectDecl, Room
from homer_sim.home.placement import start_poses
from homer_sim.home.spots import keep_out_rects
from homer_sim.person.aliases import Resolver
from homer_sim.person.avatar import add_avatar
from homer_sim.person.day_scripts import DayScript, read_day_script
from homer_sim.person.executor import ActionError, DayLog, Executor
from homer_sim.person.scripts import ScriptError
from homer_sim.world import World

SPLIT_FOLDERS = {f"scripts_{split}": split for split in SPLITS}
FLOOR_STEP = 0.05  # m between the floor points tried for an object that starts on a room's floor
FLOOR_GAP = 0.05  # m an object that starts on a floor keeps from walls, furniture and other things there


@dataclass(frozen=True)
class DayTask:
    """One day script to replay and where its day goes in the dataset."""

    path: Path
    household: str
    split: str
    index: int

    @property
    def label(self) -> str:
        return f"{self.household}/{self.split}/{self.index:03d}"


def _numbered(folder: Path) -> list[Path]:
    return sorted((p for p in folder.glob("*.txt") if p.stem.isdigit()), key=lambda p: int(p.stem))


def find_day_scripts(scripts: str | Path, household: str | None = None) -> list[DayTask]:
    """The day scripts at `scripts`: a HouseholdX folder (its scripts_train/ and scripts_test/), a folder of
    NNN.txt (split test if it is named scripts_test, else train) or one NNN.txt file. `household` names the
    household in the dataset (default: the HouseholdX folder's name, else "replay")."""
    root = Path(scripts)
    if root.is_file():
        folders = [root.parent]
    elif any((root / name).is_dir() for name in SPLIT_FOLDERS):
        folders = [root / name for name in SPLIT_FOLDERS if (root / name).is_dir()]
    else:
        folders = [root]
    house_dir = folders[0].parent if folders[0].name in SPLIT_FOLDERS else None
    household = household or (house_dir.name if house_dir is not None else "replay")
    files = [root] if root.is_file() else [p for folder in folders for p in _numbered(folder)]
    if not files or not all(p.stem.isdigit() and p.suffix == ".txt" for p in files):
        raise HomerError(f"{root}: no day scripts found (expected NNN.txt files, or scripts_train/ and "
                         "scripts_test/ folders of them)")
    return [DayTask(p, household, SPLIT_FOLDERS.get(p.parent.name, "train"), int(p.stem)) for p in files]


def short_reason(error: HomerError) -> str:
    """A one-line reason: the first problem of a ScriptError (with how many more), else the error's text."""
    if isinstance(error, ScriptError):
        more = f" (and {len(error.errors) - 1} more problems)" if len(error.errors) > 1 else ""
        return f"{error.path}:{error.line}: {error.reason}{more}"
    return f"{type(error).__name__}: {str(error).splitlines()[0]}"


def start_layout(layout: Layout, parents: Mapping[str, str]) -> tuple[Layout, tuple[str, ...]]:
    """`layout` with its objects starting on the parents given (object -> furniture, object or room: INSIDE
    furniture that has places inside, else ON; ON an object that holds others; on a room's floor), each where it
    fits beside the others (packed as `start_poses` packs the declared layout; on a floor at the free spot
    nearest the room's centre, see `_floor_spot`); the objects keep their order. Returns the layout and the
    objects left at their declared start: an unknown parent, an object that holds nothing or stands on this one,
    or no room left there."""
    furniture = layout.furniture_by_name()
    rooms = {r.name: r for r in layout.rooms}
    objects = {o.name: o for o in layout.objects}  # their order is kept: it is the scene graph's node order
    left: list[str] = []
    for name, parent in parents.items():
        decl = objects.get(name)
        if decl is None or decl.parent == parent:
            continue
        if parent in furniture:
            places = furniture_geometry(furniture[parent]).places
            relation = INSIDE if any(p.relation == INSIDE for p in places) else ON
            # any place, else each in turn: the first free one may be where an object declared there must go
            levels = [None, *(k for k, p in enumerate(places) if p.relation == relation)]
            options = [replace(decl, parent=parent, relation=relation, level=k, at=None) for k in levels]
        elif parent in objects and CATALOG[objects[parent].cls].supports and name not in _below(objects, parent):
            options = [replace(decl, parent=parent, relation=ON, level=None, at=None)]
        elif parent in rooms and (at := _floor_spot(layout, decl, rooms[parent], objects)) is not None:
            options = [replace(decl, parent=parent, relation=INSIDE, level=None, at=at)]
        else:
            options = []
        for moved in options:
            trial = {**objects, name: moved}
            candidate = replace(layout, objects=tuple(trial.values()))
            try:
                start_poses(candidate)
            except LayoutError:
                continue
            objects, layout = trial, candidate
            break
        else:
            left.append(name)
    return layout, tuple(left)


def _floor_spot(layout: Layout, decl: ObjectDecl, room: Room, objects: Mapping[str, ObjectDecl]
                ) -> tuple[float, float] | None:
    """Where `decl` starts on the floor of `room`: the free point nearest the room's centre (on a 5 cm grid) whose
    disk (the object's footprint turned any way) keeps clear of walls, furniture, the swing of doors and drawers,
    and of what already stands on that floor; None if there is none."""
    plan, keep_out = floor_plan(layout), keep_out_rects(layout)
    radius = math.hypot(*CATALOG[decl.cls].size[:2]) / 2 + FLOOR_GAP
    others = [(o.at, math.hypot(*CATALOG[o.cls].size[:2]) / 2) for o in objects.values()
              if o.parent == room.name and o.at is not None and o.name != decl.name]
    x0, y0, x1, y1 = room.rect
    xs, ys = np.meshgrid(np.arange(x0 + radius, x1 - radius, FLOOR_STEP), np.arange(y0 + radius, y1 - radius,
                                                                                     FLOOR_STEP))
    points = np.column_stack([xs.ravel(), ys.ravel()])
    centre = np.array([(x0 + x1) / 2, (y0 + y1) / 2])
    for x, y in points[np.argsort(np.linalg.norm(points - centre, axis=1), kind="stable")]:
        if all(math.dist((x, y), at) >= radius + r for at, r in others) and plan.disk_is_free(x, y, radius,
                                                                                               keep_out):
            return round(float(x), 3), round(float(y), 3)
    return None


def _below(objects: Mapping[str, ObjectDecl], name: str) -> list[str]:
    """`name` and the objects it stands on, one on another, down to furniture or a room."""
    chain = [name]
    while objects[chain[-1]].parent in objects and objects[chain[-1]].parent not in chain:
        chain.append(objects[chain[-1]].parent)
    return chain


class Replayer:
    """One worker's simulator: a World with an avatar and the person's executor (`layout`: the apartment to
    build, by default ours)."""

    def __init__(self, recording=None, layout: Layout | None = None) -> None:
        self.world = World(layout, extras=[add_avatar])
        self.executor = Executor(self.world, recording=recording)
        self.resolver = Resolver(self.world.layout.node_names())

    def read(self, path: str | Path) -> DayScript:
        """Parse a day script with this apartment's names (a ScriptError names file and line of each problem)."""
        return read_day_script(path, self.resolver)

    def live(self, script: DayScript, task: DayTask, after_action: Callable[[int], None] | None = None,
             on_error: Callable[[int, ActionError], None] | None = None) -> DayLog:
        """Live `script` as day `task`: each action at its minute, snapshots every 10 minutes; after_action gets the
        index of each action once it is done, on_error the index and error of an action that failed, and the day
        goes on (see `Executor.live`; without on_error a failed action ends the day)."""
        self.executor.start_day(np.random.default_rng([SPLITS.index(task.split), task.index]))
        self.executor.log.schedule = [tuple(entry) for entry in script.schedule]
        events = [(a.minute, a.activity, a.action) for a in script.actions]
        return self.executor.live(events, max(float(DAY_END_MIN), script.end_min), after_action=after_action,
                                  on_error=on_error)

    def day(self, task: DayTask) -> Day:
        """Read and live day `task` into our dataset's Day (no DayKey: a replayed day is redone from its script)."""
        return as_day(task, self.live(self.read(task.path), task))

    def run(self, task: DayTask) -> tuple[DayTask, Day | None, dict]:
        """(task, day or None, log record with the failure's reason if the day could not run)."""
        started = time.perf_counter()
        try:
            day, reason = self.day(task), None
        except HomerError as error:
            day, reason = None, short_reason(error)
        info = {"day": task.label, "script": str(task.path), "wall_s": round(time.perf_counter() - started, 3)}
        return task, day, {**info, "failed": reason} if reason else info

    def meta(self, households: list[str], extra: dict) -> DatasetMeta:
        return world_meta(self.world, households, extra)


def as_day(task: DayTask, record: DayLog) -> Day:
    """The lived day `record` of `task` as our dataset's Day."""
    return Day(task.household, task.split, task.index, np.array(record.minutes, dtype=np.int32),
               np.array(record.parents, dtype=np.int16), np.array(record.relations, dtype=np.int8),
               tuple(record.schedule), tuple(record.moves))


def replay_task(replayer: Replayer, task: DayTask) -> tuple[DayTask, Day | None, dict]:
    """One day of `replay` on a worker's Replayer: the task function of the execution backend."""
    return replayer.run(task)


def check_existing(out: Path, meta: DatasetMeta) -> None:
    """Refuse `out` unless it is new, empty, or this same replay's dataset (to resume)."""
    path = out / "meta.json"
    if path.exists():
        existing = json.loads(path.read_text())
        if existing.get("nodes") != list(meta.nodes) or existing.get("replay") != meta.extra["replay"]:
            raise HomerError(f"{out} holds another dataset ({existing.get('replay') or existing.get('generator')}); "
                             "replay into a new folder")
    elif out.exists() and any(out.iterdir()):
        raise HomerError(f"{out} exists and is not a homer-sim dataset; choose an empty or new folder")


def replay(scripts: str | Path, out: str | Path, backend: Backend = IN_PROCESS, household: str | None = None,
           progress: bool = True) -> dict:
    """Replay every day script at `scripts` into the dataset folder `out` (resuming an interrupted run), the days
    lived on `backend` (this process, local processes or Ray tasks: on a cluster every node must see the scripts
    at their absolute paths) and written here.

    Returns {"days": scripts found, "completed": days in the folder, "failed": {day: reason}, "execution"}."""
    out = Path(out)
    tasks = [replace(task, path=task.path.resolve()) for task in find_day_scripts(scripts, household)]
    probe = Replayer()
    meta = probe.meta([tasks[0].household], {"replay": {"scripts": str(Path(scripts).resolve()),
                                                        "homer_sim": __version__}})
    check_existing(out, meta)
    write_meta(out, meta)
    todo = [t for t in tasks if not day_path(out, t.household, t.split, t.index).exists()]
    failed = {}
    with open(out / LOG_NAME, "a") as log_file, backend.run(replay_task, todo, Replayer, (), probe) as run:
        for task, day, info in tqdm(run, total=len(todo), desc="days", unit="day", disable=not progress):
            if day is not None:
                write_day(out, day)
            else:
                failed[task.label] = info["failed"]
            log_file.write(json.dumps(info, sort_keys=True) + "\n")
            log_file.flush()
    completed = sum(day_path(out, t.household, t.split, t.index).exists() for t in tasks)
    return {"days": len(tasks), "completed": completed, "failed": dict(sorted(failed.items())),
            "execution": run.usage()}
