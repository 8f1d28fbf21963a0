"""The activity library: one folder per activity, one script file per variant.

Layout `<root>/<activity>/<variant>.txt`, the same as HOMER's `sourcedScriptsByActivity`, so an external
folder of scripts loads the same way. The project's own scripts live next to this file (`ACTIVITY_DIR`); they
are written for the default apartment (`homer_sim.home.apartment`).
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from homer_sim.person.scripts import Script, ScriptError, parse_script

ACTIVITY_DIR = Path(__file__).parent
"""The project's activity scripts: `ACTIVITY_DIR/<activity>/<variant>.txt`."""


def script_files(root: Path | str | None = None) -> list[Path]:
    """Every script file `<root>/<activity>/<name>.txt`, sorted by activity then name."""
    root = Path(root) if root is not None else ACTIVITY_DIR
    return sorted(p for p in root.glob("*/*.txt") if p.is_file())


def load_library(resolver: Callable[[str], str], root: Path | str | None = None) -> dict[str, list[Script]]:
    """activity -> its scripts sorted by variant name (the file stem), parsed with `resolver`.

    Every file is parsed; if some fail, the ScriptError of the first is raised with the others as notes. A
    root that is no folder or holds no script file is a ScriptError too.
    """
    folder = Path(root) if root is not None else ACTIVITY_DIR
    files = script_files(folder)
    if not files:
        reason = "no <activity>/<variant>.txt script files here" if folder.is_dir() else "no such folder"
        raise ScriptError(str(folder), [(0, reason)])
    library: dict[str, list[Script]] = {}
    failures: list[ScriptError] = []
    for path in files:
        text = path.read_text(encoding="utf-8-sig")
        try:
            script = parse_script(text, str(path), path.parent.name, path.stem, resolver)
        except ScriptError as error:
            failures.append(error)
            continue
        library.setdefault(script.activity, []).append(script)
    if failures:
        first = failures[0]
        for other in failures[1:]:
            first.add_note(str(other))
        raise first
    return {activity: sorted(scripts, key=lambda s: s.variant) for activity, scripts in sorted(library.items())}
