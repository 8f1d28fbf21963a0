"""`homer replay-check`: a HOMER+ household's days replayed in our apartment, checked against the authors' graphs.

For an unpacked upstream `HouseholdX` folder (`scripts_train/NNN.txt` and `scripts_test/NNN.txt` produced
`processed_seqLM_coarse/train/NNN.pt` and `test/NNN.pt`), each day script is replayed physically
(`homer_sim.data.replay`) and compared with the authors' graph (read as `homer_sim.data.homer_plus` reads it):

- every 10 minutes, each movable object's parent in our observed graph against the authors' parent, both through
  the alias table (`homer_sim.person.aliases`): `agreement` is the share of object-steps that agree;
- after each action, each `<<Graph Changes>>` edge line against our observer: `+ obj REL parent` is seen when
  our object now rests on the parent, `- obj REL parent` when it no longer does (or is in the person's hands).

Every disagreement gets one cause: `missing object: NAME` and `missing furniture: NAME` (the authors have it,
our apartment has no node or alias for it), `different furniture` (the authors have several of that furniture,
our alias maps them onto one), `start placement differs` (not moved yet today and it starts elsewhere in our
apartment), `settled elsewhere` (our person moved it and it came to rest on something else), `change not seen
(+)`/`(-)`. A day that cannot run counts once per name it lacks as `day failed, missing object|furniture|scenery:
NAME` (scenery: a name the authors' graph does not hold, a light say), or as `day failed: <error type>`.
"""

from __future__ import annotations

import json
import re
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from tqdm import tqdm

from homer_sim.data.homer_plus import Household, read_day, read_household, upstream_folder
from homer_sim.data.replay import DayTask, Replayer, find_day_scripts, short_reason
from homer_sim.errors import HomerError
from homer_sim.person.day_scripts import DayScript, GraphChange
from homer_sim.person.scripts import ScriptError

_UNKNOWN = re.compile(r"unknown name '([^']+)'")
KINDS = {"object": "object", "prop": "object", "decor": "object", "furniture": "furniture", "appliance": "furniture"}


@dataclass
class Tally:
    """Counts over the days checked so far."""

    steps: int = 0
    agree: int = 0
    changes: int = 0
    seen: int = 0
    completed: int = 0
    causes: Counter = field(default_factory=Counter)
    failed: dict = field(default_factory=dict)


class HouseholdCheck:
    """The authors' household (classes, categories) and our replayer, to check one day after another."""

    def __init__(self, household_dir: str | Path) -> None:
        self.root = Path(household_dir)
        self.folder = upstream_folder(self.root)
        self.house: Household = read_household(self.folder)
        common = json.loads((self.folder / "common_data.json").read_text())
        self.classes = [common["node_classes"][i] for i in self.house.keep]
        self.repeated = {c for c, n in Counter(self.classes).items() if n > 1}
        self.kind_of = {c: KINDS.get(k, "object") for c, k in zip(self.classes, self.house.categories, strict=True)}
        self.replayer = Replayer()
        self.resolve = self.replayer.resolver
        self.ours = self.replayer.executor.nodes
        self.our_index = {name: k for k, name in enumerate(self.ours)}
        self.movable = set(self.replayer.world.object_names)

    def missing(self, name: str) -> str:
        return f"missing {self.kind_of.get(name, 'scenery')}: {name}"

    def check_day(self, task: DayTask, tally: Tally) -> None:
        """Replay day `task`, compare it with its graph file and add the results to `tally`."""
        graph_path = self.folder / task.split / f"{task.index:03d}.pt"
        if not graph_path.is_file():
            raise HomerError(f"{task.path}: no matching graph {graph_path}")
        theirs = read_day(graph_path, self.house, task.household, task.split)
        try:
            script = self.replayer.read(task.path)
        except ScriptError as error:
            names = sorted({m.group(1) for _, reason in error.errors for m in [_UNKNOWN.search(reason)] if m})
            tally.causes.update(f"day failed, {self.missing(n)}" for n in names)
            if not names:
                tally.causes[f"day failed: {type(error).__name__}"] += 1
            tally.failed[task.label] = short_reason(error)
            return
        try:
            seen = self._live(script, task)
        except HomerError as error:
            tally.causes[f"day failed: {type(error).__name__}"] += 1
            tally.failed[task.label] = short_reason(error)
            return
        tally.completed += 1
        tally.changes += len(seen)
        tally.seen += sum(ok for ok, _ in seen)
        tally.causes.update(cause for ok, cause in seen if not ok)
        self._compare_steps(theirs.minutes, theirs.parent, tally)

    def _live(self, script: DayScript, task: DayTask) -> list[tuple[bool, str]]:
        """Live the day; (seen, cause) for each graph change line, checked right after its action."""
        results: list[tuple[bool, str]] = []

        def after(index: int) -> None:
            changes = script.actions[index].changes
            if changes:
                graph = self.replayer.executor.observe()
                carried = set(self.replayer.executor.avatar.carried())
                results.extend(self._seen(change, graph, carried) for change in changes)

        self.record = self.replayer.live(script, task, after_action=after)
        return results

    def _seen(self, change: GraphChange, graph, carried: set[str]) -> tuple[bool, str]:
        for name in (change.obj, change.parent):
            if name not in self.resolve:
                return False, self.missing(name)
        obj, parent = self.resolve(change.obj), self.resolve(change.parent)
        now = graph.parent_of(obj)
        ok = now == parent if change.sign == "+" else (now != parent or obj in carried)
        return ok, f"change not seen ({change.sign})"

    def _compare_steps(self, minutes: np.ndarray, parents: np.ndarray, tally: Tally) -> None:
        ours = {m: p for m, p in zip(self.record.minutes, self.record.parents, strict=True)}
        moved = {}
        for minute, name, *_ in self.record.moves:
            moved.setdefault(name, minute)
        for step, minute in enumerate(minutes):
            if int(minute) not in ours:
                continue
            for i in np.flatnonzero(self.house.movable):
                tally.steps += 1
                cause = self._disagreement(i, int(parents[step, i]), ours[int(minute)], moved, int(minute))
                if cause is None:
                    tally.agree += 1
                else:
                    tally.causes[cause] += 1

    def _disagreement(self, i: int, their_parent: int, our_parents: np.ndarray, moved: dict, minute: int
                      ) -> str | None:
        """None when object i rests where the authors have it, else the cause."""
        name, parent = self.classes[i], self.classes[their_parent]
        for wanted in (name, parent):
            if wanted not in self.resolve:
                return self.missing(wanted)
        obj = self.resolve(name)
        if obj not in self.movable:
            return f"not movable here: {name}"
        if self.ours[our_parents[self.our_index[obj]]] == self.resolve(parent):
            return None
        if parent in self.repeated:
            return "different furniture"
        return "settled elsewhere" if moved.get(obj, np.inf) < minute else "start placement differs"


def replay_check(household_dir: str | Path, progress: bool = False) -> dict:
    """Replay and check every day of an unpacked HOMER+ household folder.

    Returns {"days", "days_completed", "agreement" (share of movable object-steps whose parent agrees, None when
    no day completed), "graph_changes_seen" (share of graph change edge lines seen, None without any), "causes"
    {cause: count} (object-steps, change lines, or failed days for `day failed...`), "failed" {day: reason}}."""
    check = HouseholdCheck(household_dir)
    tasks = find_day_scripts(check.root, check.root.name)
    tally = Tally()
    for task in tqdm(tasks, desc="days", unit="day", disable=not progress):
        check.check_day(task, tally)
    return {"days": len(tasks), "days_completed": tally.completed,
            "agreement": round(tally.agree / tally.steps, 4) if tally.steps else None,
            "graph_changes_seen": round(tally.seen / tally.changes, 4) if tally.changes else None,
            "causes": dict(tally.causes.most_common()), "failed": tally.failed}
