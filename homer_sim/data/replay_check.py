"""`homer replay-check`: a HOMER+ household's days replayed in our apartment, checked against the authors' graphs.

For an unpacked upstream `HouseholdX` folder (`scripts_train/NNN.txt` and `scripts_test/NNN.txt` produced
`processed_seqLM_coarse/train/NNN.pt` and `test/NNN.pt`), each day script is replayed physically
(`homer_sim.data.replay`) and compared with the authors' graph (read as `homer_sim.data.homer_plus` reads it).
The day starts from the authors' arrangement at its first step: each object we have starts on our counterpart of
the authors' parent where it fits (`start_layout`), on the room's floor where their parent is a room (VirtualHome
hangs what lies on a floor from the room: `floor` is one of their ignored classes, and their day scripts put the
guitar back `ON home_office`); their props, what stands in a knife block, or does not fit there start where our
apartment declares them, and count as `start placement differs` until moved.

- every 10 minutes, each movable object's parent in our observed graph against the authors' parent, both through
  the alias table (`homer_sim.person.aliases`): `agreement` is the share of object-steps that agree,
  `agreement_known` the share among the object-steps whose object and parent we have;
- after each action, each `<<Graph Changes>>` edge line against our observer: `+ obj REL parent` is seen when
  our object now rests on the parent, `- obj REL parent` when it no longer does (or is in the person's hands); an
  INSIDE line on a room by the room our object is in, an ON line on a room by whether it rests on that floor.

Names go through the alias table with the authors' VirtualHome ids, so their three kitchen counters map to
our counters as `aliases.json` says. Unlike `homer replay`, which refuses a day naming something we lack, the check
lives the rest of such a day: each action naming a thing we lack is left out and counted as `action left out,
missing object|furniture|scenery: NAME` (scenery: a name the authors' graph does not hold), and so is the grab of
an object whose put-down was left out (`action left out, its put-down was`), so that it stays where it is rather
than in the person's hand. The graph change lines of a left-out action are checked after the action before it.

Every disagreement gets one cause: `missing object: NAME` and `missing furniture: NAME` (the authors have it,
our apartment has no node or alias for it), `different furniture` (the authors have several of that furniture,
our alias maps them onto one), `in that room, on furniture here` (the authors have it in a room on nothing they
track, ours stands on furniture in that room), `start placement differs` (not moved yet today and it starts
elsewhere in our apartment), `settled elsewhere` (our person moved it and it came to rest on something else),
`not movable here: NAME` (a thing we have as fixed), `change not seen (+)`/`(-)` (with `, its action left out`
for the lines of an action left out). A day that still cannot run counts as `day failed: <error type>`.
"""

from __future__ import annotations

import json
import re
from collections import Counter
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
from tqdm import tqdm

from homer_sim import __version__
from homer_sim.data.dataset import Day, write_day, write_meta
from homer_sim.data.homer_plus import Household, read_day, read_household, upstream_folder
from homer_sim.data.replay import (
    DayTask,
    Replayer,
    as_day,
    check_existing,
    find_day_scripts,
    short_reason,
    start_layout,
)
from homer_sim.errors import HomerError
from homer_sim.execution import IN_PROCESS, Backend
from homer_sim.home.apartment import default_layout
from homer_sim.person.aliases import Resolver
from homer_sim.person.day_scripts import DayScript, GraphChange, TimedAction, read_day_script
from homer_sim.person.executor import ActionError

_ARGUMENT_ID = re.compile(r"<([^<>]*)>\s*\((\d+)\)")
LACKING = "?"
"""Prefix of a name we lack in an action's arguments while the check reads a day (no node name starts with it)."""
PUTS = frozenset({"putback", "putin"})
MISSING = "missing "
"""How the causes of things we lack begin."""
KINDS = {"object": "object", "prop": "object", "decor": "object", "furniture": "furniture", "appliance": "furniture"}


@dataclass
class Tally:
    """Counts over the days checked so far."""

    steps: int = 0
    agree: int = 0
    known_steps: int = 0  # object-steps whose object and authors' parent both map to ours
    changes: int = 0
    seen: int = 0
    known_changes: int = 0  # change lines whose object and parent both map to ours
    completed: int = 0
    causes: Counter = field(default_factory=Counter)
    failed: dict = field(default_factory=dict)
    day: Day | None = None  # the day lived, when one day's tally (not summed by `add`)

    def add(self, other: Tally) -> None:
        """Count `other`'s days in too."""
        for name in ("steps", "agree", "known_steps", "changes", "seen", "known_changes", "completed"):
            setattr(self, name, getattr(self, name) + getattr(other, name))
        self.causes.update(other.causes)
        self.failed.update(other.failed)


class HouseholdCheck:
    """The authors' household (classes, categories) and our replayer, to check one day after another."""

    def __init__(self, household_dir: str | Path) -> None:
        self.root = Path(household_dir)
        self.folder = upstream_folder(self.root)
        self.house: Household = read_household(self.folder)
        common = json.loads((self.folder / "common_data.json").read_text())
        self.classes = [common["node_classes"][i] for i in self.house.keep]
        self.ids = list(self.house.ids)
        self.repeated = {c for c, n in Counter(self.classes).items() if n > 1}
        self.kind_of = {c: KINDS.get(k, "object") for c, k in zip(self.classes, self.house.categories, strict=True)}
        self.layout = default_layout()
        self.resolve = Resolver(self.layout.node_names())
        self.ours = self.layout.node_names()
        self.our_index = {name: k for k, name in enumerate(self.ours)}
        self.movable = {o.name for o in self.layout.objects}
        self.rooms = set(self.layout.room_names())
        self._replayers: dict[tuple, Replayer] = {}

    def replayer_for(self, start: np.ndarray) -> Replayer:
        """A replayer of our apartment with the objects starting where the authors' graph row `start` has them
        (through the alias table, where they fit; see `start_layout`), one per distinct start. Their props (the
        knife block, the trash can: category Props) stand where ours are set up: no script of theirs moves
        them and their graph gives them only a room, at every step (on the floor for a trash can; what a knife
        block stands on is not in it)."""
        key = tuple(int(p) for p in start)
        if key not in self._replayers:
            parents = {}
            for i in np.flatnonzero(self.house.movable):
                obj, parent = self.resolve_index(i), self.resolve_index(int(start[i]))
                if obj in self.movable and parent is not None and self.house.categories[i] != "prop":
                    parents[obj] = parent
            self._replayers[key] = Replayer(layout=start_layout(self.layout, parents)[0])
        return self._replayers[key]

    def missing(self, name: str) -> str:
        """The cause for a thing we lack: its kind (by the authors' category) and name."""
        return f"{MISSING}{self.kind_of.get(name.split(' (')[0], 'scenery')}: {name}"

    def label(self, name: str, instance: int | None) -> str:
        """How a thing we lack is named in causes: with its id when only that instance of the class is lacking."""
        return f"{name} ({instance})" if instance is not None and self.resolve.knows(name) else name

    def node(self, name: str, instance: int | None = None) -> str | None:
        """Our node for the authors' `name` with VirtualHome id `instance`, or None."""
        return self.resolve(name, instance) if self.resolve.knows(name, instance) else None

    def candidates(self, name: str, instance: int | None) -> set[str]:
        """Our nodes the authors' `name` may be: of its id if known, else of every instance of its class."""
        instances = [instance] if instance is not None else [k for c, k in zip(self.classes, self.ids, strict=True)
                                                             if c == name] or [None]
        return {node for k in instances if (node := self.node(name, k)) is not None}

    def lenient(self, name: str, instance: int | None = None) -> str:
        """The resolver for reading a day here: a name we lack becomes LACKING + name instead of an error."""
        if self.resolve.knows(name, instance):
            return self.resolve(name, instance)
        return LACKING + self.label(name, instance)

    def runnable(self, script: DayScript, tally: Tally) -> tuple[DayScript, list[list[tuple[GraphChange, bool]]]]:
        """The day without the actions naming things we lack (counted in `tally`) and, for each kept action, the
        change lines to check after it: its own and those of the left-out actions right after it, as (change,
        whether its action was left out)."""
        actions = script.actions
        out = {k for k, a in enumerate(actions) if any(n.startswith(LACKING) for n in a.action.args)}
        for k in sorted(out):
            lacking = next(n for n in actions[k].action.args if n.startswith(LACKING))[len(LACKING):]
            tally.causes[f"action left out, {self.missing(lacking)}"] += 1
            verb, args = actions[k].action.verb, actions[k].action.args
            if verb in PUTS and not args[0].startswith(LACKING):
                grab = next((j for j in range(k - 1, -1, -1) if j not in out and actions[j].action.args[:1] ==
                             args[:1] and actions[j].action.verb in PUTS | {"grab"}), None)
                if grab is not None and actions[grab].action.verb == "grab":
                    out.add(grab)
                    tally.causes["action left out, its put-down was"] += 1
        kept: list[TimedAction] = []
        checks: list[list[tuple[GraphChange, bool]]] = []
        early: list[tuple[GraphChange, bool]] = []  # changes of left-out actions before the first kept one
        for k, action in enumerate(actions):
            if k not in out:
                kept.append(action)
                checks.append([*early, *((change, False) for change in action.changes)])
                early = []
            elif checks:
                checks[-1].extend((change, True) for change in action.changes)
            else:
                early.extend((change, True) for change in action.changes)
        return DayScript(script.path, script.schedule, tuple(kept)), checks

    def check_day(self, task: DayTask, tally: Tally) -> None:
        """Replay day `task`, compare it with its graph file and add the results to `tally`."""
        graph_path = self.folder / task.split / f"{task.index:03d}.pt"
        if not graph_path.is_file():
            raise HomerError(f"{task.path}: no matching graph {graph_path}")
        theirs = read_day(graph_path, self.house, task.household, task.split)
        self.replayer = self.replayer_for(theirs.parent[0])
        try:
            script, checks = self.runnable(read_day_script(task.path, self.lenient), tally)
            if not script.actions:
                raise HomerError("no action left to run")
            seen = self._live(script, checks, task)
        except HomerError as error:
            tally.causes[f"day failed: {type(error).__name__}"] += 1
            tally.failed[task.label] = short_reason(error)
            return
        tally.completed += 1
        tally.day = over_span(as_day(task, self.record), int(theirs.minutes[-1]))
        tally.causes.update(self.action_failures)
        tally.changes += len(seen)
        tally.seen += sum(ok for ok, _ in seen)
        tally.known_changes += sum(ok or not cause.startswith(MISSING) for ok, cause in seen)
        tally.causes.update(cause for ok, cause in seen if not ok)
        self._compare_steps(theirs.minutes, theirs.parent, tally)

    def _live(self, script: DayScript, checks: list[list[tuple[GraphChange, bool]]], task: DayTask
              ) -> list[tuple[bool, str]]:
        """Live the day; (seen, cause) for each graph change line, checked right after its action. An action that
        fails is counted in `action_failures` by its reason, and the day goes on."""
        results: list[tuple[bool, str]] = []
        self.action_failures = Counter()

        def after(index: int) -> None:
            if checks[index]:
                executor = self.replayer.executor
                graph = executor.observe()
                carried = set(executor.avatar.carried())
                person_room = self.layout.room_at(executor.avatar.x, executor.avatar.y)
                ids = {n: int(i) for n, i in _ARGUMENT_ID.findall(script.actions[index].action.text)}
                for change, left_out in checks[index]:
                    moved_within = any(c.sign == "+" and (c.obj, c.parent) == (change.obj, change.parent)
                                       for c, _ in checks[index]) and change.sign == "-"
                    ok, cause = self._seen(change, graph, carried, person_room, ids, moved_within)
                    if not ok and left_out and not cause.startswith(MISSING):
                        cause = f"{cause}, its action left out"
                    results.append((ok, cause))

        def failed(index: int, error: ActionError) -> None:
            self.action_failures[f"action failed: {error.reason}"] += 1

        self.record = self.replayer.live(script, task, after_action=after, on_error=failed)
        return results

    def _seen(self, change: GraphChange, graph, carried: set[str], person_room: str | None, ids: dict[str, int],
              moved_within: bool) -> tuple[bool, str]:
        """Whether our graph shows `change`. `ids` are the VirtualHome ids the action wrote (which counter): a
        class of several pieces without one there may be any of them; `moved_within`: a `-` line whose object
        the block also adds to that class, so it left another piece than the one the action names. An INSIDE line
        on a room (VirtualHome keeps every object INSIDE its room as well) is judged by the room our object is in:
        the person's while it is carried; an ON line on a room is its floor (their guitar is `+ ON home_office`
        when put down there, `- ON home_office` when put on the office chair, in the same room), judged as
        furniture is: whether our object rests on that room's floor."""
        names = (change.obj, change.parent)
        nodes = [self.candidates(name, ids.get(name)) for name in names]
        if moved_within and ids.get(change.parent) is not None:
            nodes[1] = self.candidates(change.parent, None) - {self.node(change.parent, ids[change.parent])}
        for name, found in zip(names, nodes, strict=True):
            if not found:
                return False, self.missing(self.label(name, ids.get(name)))
        objs, parents = nodes
        obj = min(objs)
        if parents <= self.rooms and change.relation == "INSIDE":
            now = person_room if obj in carried else self.room_of(graph, obj)
            ok = (now in parents) == (change.sign == "+")
        else:
            now = graph.parent_of(obj)
            ok = now in parents if change.sign == "+" else (now not in parents or obj in carried)
        return ok, f"change not seen ({change.sign})"

    def room_of(self, graph, node: str) -> str | None:
        """The room `node` is in, by its parents in `graph`."""
        for _ in range(len(self.ours)):
            if node is None or node in self.rooms:
                return node
            node = graph.parent_of(node)
        return None

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
                tally.known_steps += cause is None or not cause.startswith(MISSING)
                if cause is None:
                    tally.agree += 1
                else:
                    tally.causes[cause] += 1

    def resolve_index(self, i: int) -> str | None:
        """Our node for the authors' node i (by class and VirtualHome id), or None."""
        return self.node(self.classes[i], self.ids[i])

    def _room_at_step(self, our_parents: np.ndarray, k: int) -> str | None:
        """The room our node k is in, by the parent indices of one step."""
        for _ in range(len(self.ours)):
            if k < 0 or self.ours[k] in self.rooms:
                return None if k < 0 else self.ours[k]
            k = int(our_parents[k])
        return None

    def _disagreement(self, i: int, their_parent: int, our_parents: np.ndarray, moved: dict, minute: int
                      ) -> str | None:
        """None when object i rests where the authors have it, else the cause."""
        name, parent = self.classes[i], self.classes[their_parent]
        obj, our_parent = self.resolve_index(i), self.resolve_index(their_parent)
        for k, node in ((i, obj), (their_parent, our_parent)):
            if node is None:
                return self.missing(self.label(self.classes[k], self.ids[k]))
        if obj not in self.movable:
            return f"not movable here: {name}"
        if self.ours[our_parents[self.our_index[obj]]] == our_parent:
            return None
        if our_parent in self.rooms and self._room_at_step(our_parents, self.our_index[obj]) == our_parent:
            return "in that room, on furniture here"
        if parent in self.repeated:
            return "different furniture"
        return "settled elsewhere" if moved.get(obj, np.inf) < minute else "start placement differs"


def over_span(day: Day, last_minute: int) -> Day:
    """`day` up to routine minute `last_minute`, the authors' last graph step (midnight): their day scripts sleep on
    to 01:15 and our replay lives that, but their graphs stop at midnight. A dataset of days 7-20 steps longer than
    theirs, the quiet hours after midnight, scores predictors on other queries (a periodic prior, fitted over those
    hours as well, spreads the night's arrangement into the morning): FreMEn's prior lost 0.033 of F1 to the
    authors' graphs with the night in, 0.012 without. Moves after it are dropped with the steps."""
    keep = day.minutes <= last_minute
    moves = tuple(m for m in day.moves if m[0] <= last_minute)
    return replace(day, minutes=day.minutes[keep], parent=day.parent[keep], relation=day.relation[keep], moves=moves)


def check_task(check: HouseholdCheck, task: DayTask) -> Tally:
    """One day of `replay_check` on a worker's HouseholdCheck: the task function of the execution backend."""
    tally = Tally()
    check.check_day(task, tally)
    return tally


def replay_check(household_dir: str | Path, progress: bool = False, days: int | None = None,
                 backend: Backend = IN_PROCESS, out: str | Path | None = None) -> dict:
    """Replay and check every day of an unpacked HOMER+ household folder (the first `days` of them, training days
    first, when given), the days on `backend` (this process, local processes or Ray tasks). With `out`, each
    completed day is also written there as a dataset of ours (from the authors' start arrangement, an action that
    failed left out as the check leaves it, up to the authors' last graph step: `over_span`), to score predictors
    on our physical replay.

    Returns {"days", "days_completed", "agreement" (share of movable object-steps whose parent agrees, None when
    no day completed), "graph_changes_seen" (share of graph change edge lines seen, None without any),
    "agreement_known" and "graph_changes_seen_known" (the same over the object-steps and lines whose object and
    parent we have: what the replay gets right of what it can represent), "causes"
    {cause: count} (object-steps, change lines, left-out actions, or failed days for `day failed...`; largest
    first), "failed" {day: reason}}."""
    check = HouseholdCheck(household_dir)
    tasks = find_day_scripts(check.root, check.root.name)[:days]
    total = Tally()
    if out is not None:
        out = Path(out)
        meta = Replayer().meta([check.root.name], {"replay": {"scripts": str(check.root.resolve()),
                                                              "homer_sim": __version__, "start": "authors'"}})
        check_existing(out, meta)
        write_meta(out, meta)
    with backend.run(check_task, tasks, HouseholdCheck, (str(Path(household_dir).resolve()),), check) as run:
        for tally in tqdm(run, total=len(tasks), desc="days", unit="day", disable=not progress):
            total.add(tally)
            if out is not None and tally.day is not None:
                write_day(out, tally.day)

    def share(part: int, whole: int) -> float | None:
        return round(part / whole, 4) if whole else None

    return {"days": len(tasks), "days_completed": total.completed, "agreement": share(total.agree, total.steps),
            "graph_changes_seen": share(total.seen, total.changes),
            "agreement_known": share(total.agree, total.known_steps),
            "graph_changes_seen_known": share(total.seen, total.known_changes),
            "causes": dict(sorted(total.causes.items(), key=lambda kv: (-kv[1], kv[0]))),
            "failed": dict(sorted(total.failed.items()))}
