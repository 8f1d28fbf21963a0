"""Compatibility with HOMER's activity scripts: run every script of a folder in our apartment.

Names map to ours through the explicit alias and scenery tables (`homer_sim.person.aliases`). Each script starts
from a state that makes sense for it: what it takes off is worn when it starts, and a script that begins
by coming in from outside starts outside. Every script file counts; a failure names the script, the line
and the reason.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from tqdm import tqdm

from homer_sim.errors import HomerError
from homer_sim.person.activities import script_files
from homer_sim.person.aliases import Resolver
from homer_sim.person.avatar import add_avatar
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
    world = World(extras=[add_avatar])
    executor = Executor(world)
    resolver = Resolver(world.layout.node_names())
    executed, failures = 0, []
    for path in tqdm(files, desc="scripts", unit="script", disable=not progress):
        relative = str(path.relative_to(root))
        try:
            script = parse_script(path.read_text(encoding="utf-8-sig"), relative, path.parent.name, path.stem,
                                  resolver)
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
    return {"scripts": len(files), "executed": executed, "failures": failures}
