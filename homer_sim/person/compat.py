"""Compatibility with HOMER's activity scripts: run every script of a folder in our apartment.

Names map to ours through the explicit alias and scenery tables (`homer_sim.person.aliases`). Each script starts
from a state that makes sense for it: what it takes off is worn when it starts, and a script that begins
by coming in from outside starts outside. Every script file counts; a failure names the script, the line
and the reason.

The HOMER+ day scripts embed the HOMER activity scripts they were made from as `### <activity>-<variant>.txt`
blocks (`homer_sim.person.day_scripts`); `homer_plus_scripts` takes each distinct block out as an activity script
of its own, so that they can be run the same way (`homer compat-check --from-homer-plus HouseholdX`).
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from pathlib import Path

import numpy as np
from tqdm import tqdm

from homer_sim.errors import HomerError
from homer_sim.person.activities import script_files
from homer_sim.person.aliases import Resolver
from homer_sim.person.avatar import add_avatar
from homer_sim.person.day_scripts import NUMBER_TAG, schedule_entry
from homer_sim.person.executor import ActionError, Executor
from homer_sim.person.scripts import Script, ScriptError, parse_script
from homer_sim.world import World

START_MIN = 480.0  # routine minute a compatibility run starts at (08:00)
HANDLING = ("grab", "putback", "putin", "putobjback", "puton", "putoff", "drop")


def _worn_at_start(script: Script) -> list[str]:
    """Objects the script takes off (putoff) before it puts them on or takes them: worn from the start."""
    seen: set[str] = set()
    worn = []
    for action in script.actions:
        if action.verb not in HANDLING or not action.args:
            continue
        name = action.args[0]
        if action.verb == "putoff" and name not in seen:
            worn.append(name)
        seen.add(name)
    return worn


def _starts_outside(script: Script) -> bool:
    walks = [a.args[0] for a in script.actions if a.verb == "walk" and a.args]
    return bool(walks) and walks[0] == "outside" and any(w != "outside" for w in walks[1:])


def _prepare(executor, script: Script) -> None:
    for name in _worn_at_start(script):
        executor.wear(name)
    if _starts_outside(script):
        executor.go("outside")


def run_script(executor, script: Script, seed: int = 0) -> None:
    """Run one script alone, from the start layout at 08:00, over the middle of its duration range."""
    low, high = script.duration_range
    executor.start_day(np.random.default_rng(seed))
    _prepare(executor, script)
    executor.run_activity(script, START_MIN, START_MIN + (low + high) / 2)


def compat_check(scripts_dir: str | Path, progress: bool = False) -> dict:
    """{"scripts", "executed", "failures": [{"script", "line", "reason"}]} over every .txt file of the folder."""
    root = Path(scripts_dir)
    files = script_files(root)
    if not files:
        raise HomerError(f"{root}: no scripts found (expected <activity>/<name>.txt files)")
    sources = [(str(path.relative_to(root)), path.read_text(encoding="utf-8-sig")) for path in files]
    return compat_check_texts(sources, progress)


def compat_check_texts(sources: Iterable[tuple[str, str]], progress: bool = False) -> dict:
    """`compat_check` over (name, text) pairs, each name `<activity>/<variant>.txt`."""
    sources = list(sources)
    world = World(extras=[add_avatar])
    executor = Executor(world)
    resolver = Resolver(world.layout.node_names())
    executed, failures = 0, []
    for relative, text in tqdm(sources, desc="scripts", unit="script", disable=not progress):
        path = Path(relative)
        try:
            script = parse_script(text, relative, path.parent.name, path.stem, resolver)
            run_script(executor, script)
        except ScriptError as error:
            failures += [{"script": relative, "line": line, "reason": reason} for line, reason in error.errors]
            continue
        except ActionError as error:
            failures.append({"script": relative, "line": error.line, "reason": error.reason})
            continue
        except HomerError as error:
            failures.append({"script": relative, "line": 0, "reason": str(error)})
            continue
        executed += 1
    return {"scripts": len(sources), "executed": executed, "failures": failures}


_BLOCK = re.compile(r"^###\s*(\S+?)-([^-\s]+)\.txt$")


def _day_blocks(path: Path) -> list[tuple[str, str, float, list[str]]]:
    """(activity, variant, minutes its header entry gives it, action lines) for each `###` block of a day script;
    the n-th block belongs to the n-th entry of the day's header."""
    durations, blocks = [], []
    for raw in path.read_text(encoding="utf-8-sig").splitlines():
        text = raw.strip()
        entry = schedule_entry(text)
        block = _BLOCK.match(text)
        if entry is not None and not blocks:
            durations.append(entry[2] - entry[1])
        elif block is not None:
            if len(blocks) >= len(durations):
                raise HomerError(f"{path}: block {text!r} has no entry in the day's header")
            blocks.append((block.group(1), block.group(2), durations[len(blocks)], []))
        elif text.startswith("[") and blocks:
            blocks[-1][3].append(NUMBER_TAG.sub("", text))
    return blocks


def homer_plus_scripts(household: str | Path) -> list[tuple[str, str]]:
    """Each distinct `### <activity>-<variant>.txt` block of the HOMER+ day scripts under `household` (its
    `scripts_train/` and `scripts_test/`, or a folder of NNN.txt) as an activity script: (`<activity>/<variant>.txt`,
    text). The actions are the block's, in order, with their VirtualHome ids; one `## <min>-<max>` block spans the
    shortest to the longest time the days' headers give the activity, so a failure's line n is the block's action
    n - 1. A variant whose actions differ between days is an error."""
    root = Path(household)
    folders = [root / split for split in ("scripts_train", "scripts_test") if (root / split).is_dir()] or [root]
    files = sorted(p for folder in folders for p in folder.glob("*.txt"))
    if not files:
        raise HomerError(f"{root}: no HOMER+ day scripts (NNN.txt in scripts_train/, scripts_test/ or the folder)")
    actions: dict[str, list[str]] = {}
    spans: dict[str, list[float]] = {}
    for path in files:
        for activity, variant, minutes, lines in _day_blocks(path):
            name = f"{activity}/{variant}.txt"
            if actions.setdefault(name, lines) != lines:
                raise HomerError(f"{path}: block {activity}-{variant}.txt differs from its first occurrence")
            spans.setdefault(name, []).append(minutes)
    return [(name, "\n".join([f"## {min(spans[name]):g}-{max(spans[name]):g}", *actions[name]]) + "\n")
            for name in sorted(actions)]
