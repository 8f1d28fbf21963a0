"""Timed day scripts in the HOMER+ format: one whole day, every action with the routine minute it happened at.

    wake_up (06:00 - 06:10)                      header: the day's activities with their times
    sleep (21:04 - 1day - 01:04)                 (`1day - ` is the next day: 25:04 = minute 1504)

    ### brushing_teeth-07.txt                    an activity starts (variant file of the activity)
    [GRAB] <toothbrush> (1204) [4]               an action: verb, names with VirtualHome ids, its number
    371.0                                        the minute it happened at (minutes since midnight)
    <<Graph Changes>>                            what changed in the authors' graph after that action:
       - toothbrush ON bathroom_counter          an edge removed,
       + toothbrush INSIDE bathroom_cabinet      an edge added,
       (s)17bathroom_cabinet['CLOSED']->['OPEN'] a state change (read, not compared)
    ## Brush teeth until 06:13                   comments; `373.0: tooth_paste moved` notes and
                                                 `<<Activity Change>>` markers are ignored too

Verbs and names are read as in `homer_sim.person.scripts` (names resolved with their ids by a callable); every
problem of a file (an unknown verb or name, a missing minute) is collected into one `ScriptError` naming the
file and line.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from homer_sim.person.scripts import Action, ScriptError, parse_action

EDGE_RELATIONS = ("ON", "INSIDE")


@dataclass(frozen=True)
class GraphChange:
    """One edge line of a `<<Graph Changes>>` block, in the authors' names: `sign` is "+" (added) or "-"."""

    line: int
    sign: str
    obj: str
    relation: str
    parent: str


@dataclass(frozen=True)
class TimedAction:
    """An action of `activity` done at routine `minute`, and the edge changes the authors saw after it."""

    minute: float
    activity: str
    action: Action
    changes: tuple[GraphChange, ...] = ()


@dataclass(frozen=True)
class DayScript:
    """A parsed day: the header's (activity, start_min, end_min) entries and the timed actions in file order."""

    path: str
    schedule: tuple[tuple[str, float, float], ...]
    actions: tuple[TimedAction, ...]

    @property
    def end_min(self) -> float:
        """The last minute the day covers: the latest header end or action minute."""
        return max([e for _, _, e in self.schedule] + [a.minute for a in self.actions] + [0.0])


_ENTRY = re.compile(r"^([A-Za-z_]+)\s*\(\s*(\d+):(\d+)\s*-\s*(1day\s*-\s*)?(\d+):(\d+)\s*\)$")
_MINUTE = re.compile(r"^\d+(?:\.\d*)?$")
_NOTE = re.compile(r"^\d+(?:\.\d*)?:\s")
NUMBER_TAG = re.compile(r"\s*\[\d+\]$")  # an action's number at the end of its line, "[12]"
_EDGE = re.compile(r"^([+-])\s+(\S+)\s+([A-Z_]+)\s+(\S+)$")


def schedule_entry(text: str) -> tuple[str, float, float] | None:
    """(activity, start minute, end minute) of a header line "name (HH:MM - HH:MM)", or None for another line."""
    match = _ENTRY.match(text)
    if match is None:
        return None
    name, h1, m1, next_day, h2, m2 = match.groups()
    end = int(h2) * 60 + int(m2) + (1440 if next_day else 0)
    return name, float(int(h1) * 60 + int(m1)), float(end)


class _Reader:
    """The state of reading one file."""

    def __init__(self, path: str, resolve: Callable[[str], str]) -> None:
        self.path, self.resolve = path, resolve
        self.errors: list[tuple[int, str]] = []
        self.schedule: list[tuple[str, float, float]] = []
        self.actions: list[TimedAction] = []
        self.activity: str | None = None
        self.waiting: tuple[int, Action | None] | None = None  # an action line whose minute comes next
        self.in_changes = False

    def line(self, number: int, text: str) -> None:
        if self.waiting is not None:
            self._minute(number, text)
        elif text.startswith("###"):
            self.activity = Path(text[3:].strip()).stem.rsplit("-", 1)[0]
        elif text.startswith("#") or _NOTE.match(text) or text == "<<Activity Change>>":
            self.in_changes = False
        elif text.startswith("["):
            self.in_changes = False
            self._action(number, text)
        elif text == "<<Graph Changes>>":
            self.in_changes = bool(self.actions)
        elif self.in_changes:
            self._change(number, text)
        elif self.activity is None and schedule_entry(text) is not None:
            self.schedule.append(schedule_entry(text))
        else:
            self.errors.append((number, f"cannot read {text!r}; expected a header entry, '### <activity>-<n>.txt', "
                                        "an action, its minute, '<<Graph Changes>>' or a '##' comment"))

    def _action(self, number: int, text: str) -> None:
        if self.activity is None:
            self.errors.append((number, "action before the first '### <activity>-<n>.txt' line"))
        self.waiting = (number, parse_action(NUMBER_TAG.sub("", text), number, self.resolve, self.errors))

    def _minute(self, number: int, text: str) -> None:
        line, action = self.waiting
        self.waiting = None
        if not _MINUTE.match(text):
            self.errors.append((line, f"action has no minute on the next line (found {text!r})"))
        elif action is not None and self.activity is not None:
            self.actions.append(TimedAction(float(text), self.activity, action))

    def _change(self, number: int, text: str) -> None:
        match = _EDGE.match(text)
        if match is None or match.group(3) not in EDGE_RELATIONS:
            return  # a state change or another relation (the person's hands): read, not compared
        last = self.actions[-1]
        change = GraphChange(number, match.group(1), match.group(2), match.group(3), match.group(4))
        self.actions[-1] = TimedAction(last.minute, last.activity, last.action, (*last.changes, change))


def parse_day_script(text: str, path: str, resolve: Callable[[str], str]) -> DayScript:
    """Parse a HOMER+ day script; every problem is collected into one ScriptError (`path:line: reason`)."""
    reader = _Reader(str(path), resolve)
    for number, raw in enumerate(text.splitlines(), start=1):
        stripped = raw.strip()
        if stripped:
            reader.line(number, stripped)
        elif reader.waiting is None:
            reader.in_changes = False
    if reader.waiting is not None:
        reader.errors.append((reader.waiting[0], "action has no minute on the next line (end of file)"))
    if not reader.actions and not reader.errors:
        reader.errors.append((1, "day script has no actions"))
    if reader.errors:
        raise ScriptError(path, reader.errors)
    for before, after in zip(reader.actions, reader.actions[1:], strict=False):
        if after.minute < before.minute:
            raise ScriptError(path, [(after.action.line, f"minute {after.minute:g} is before the previous action's "
                                                         f"{before.minute:g}: actions must be in time order")])
    return DayScript(str(path), tuple(reader.schedule), tuple(reader.actions))


def read_day_script(path: str | Path, resolve: Callable[[str], str]) -> DayScript:
    """Read and parse the day script file at `path` (see `parse_day_script`)."""
    return parse_day_script(Path(path).read_text(encoding="utf-8-sig"), str(path), resolve)
