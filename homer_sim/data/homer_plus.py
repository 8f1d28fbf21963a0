"""Import one household of HOMER+ (the authors' follow-up dataset) into our dataset format.

Upstream layout (one household, as in the HOMER_PLUS repository): `HouseholdX/processed_seqLM_coarse/` with
`common_data.json` (node_ids, node_classes, node_categories, static_nodes, dt, ...) and `train/NNN.pt`,
`test/NNN.pt`, each a dict of tensors: `edges` float (T, N, N), one one-hot row per node giving its parent at each
step (rooms hang from a `home` node, `home` from itself); `times` (T,) minutes from midnight; `activity` (T,).

Conversion: the `home` node is dropped (rooms become our roots, parent -1); repeated class names get their
VirtualHome id appended (`kitchen_counter_119`); rooms and the static nodes are not movable; day NNN.pt becomes
day_NNN in the same split. HOMER+ does not record ON or INSIDE per step, so every non-room node is stored ON (the
meta says so). Each day's schedule comes from its per-step activity labels, its moves from its parent changes.
Files are read with torch.load(..., weights_only=True) only; every file is checked before anything is written,
and the household folder appears in DIR by one rename.
"""

from __future__ import annotations

import json
import os
import shutil
import tempfile
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from homer_sim.data.dataset import GRID_MIN, SPLITS, Dataset, DatasetError, DatasetMeta, Day, write_day, write_meta
from homer_sim.graph import NONE, ON, GraphError, validate_in_tree

UPSTREAM_FOLDER = "processed_seqLM_coarse"
CATEGORIES = {"Rooms": "room", "Furniture": "furniture", "Appliances": "appliance", "Decor": "decor",
              "Props": "prop", "placable_objects": "object"}
HOME_CATEGORY = "Home"
RELATIONS_NOTE = "HOMER+ records no ON/INSIDE per step; every non-room node is stored ON"


@dataclass(frozen=True)
class Household:
    """The household-wide part of common_data.json, converted.

    ids: (N,) VirtualHome ids, home dropped. keep: (N,) upstream index of each kept node. home: upstream index of
    `home`. names, categories, movable: ours. activities: upstream activity names (index of `activity`).
    """

    ids: tuple[int, ...]
    keep: np.ndarray
    home: int
    names: tuple[str, ...]
    categories: tuple[str, ...]
    movable: tuple[bool, ...]
    activities: tuple[str, ...]

    @property
    def upstream_nodes(self) -> int:
        return len(self.keep) + 1


def upstream_folder(path: str | Path) -> Path:
    """The folder holding common_data.json: PATH itself or PATH/processed_seqLM_coarse."""
    path = Path(path)
    for folder in (path / UPSTREAM_FOLDER, path):
        if (folder / "common_data.json").is_file():
            return folder
    raise DatasetError(f"{path}: not a HOMER+ household (no common_data.json in it or in {UPSTREAM_FOLDER}/); "
                       "give the unpacked HouseholdX folder")


def read_household(folder: Path) -> Household:
    """Read and convert common_data.json; raises DatasetError naming the file and the bad field."""
    path = folder / "common_data.json"
    try:
        common = json.loads(path.read_text())
        ids, classes, cats = common["node_ids"], common["node_classes"], common["node_categories"]
        static, dt, activities = set(common["static_nodes"]), int(common["dt"]), tuple(common["activities"])
    except (OSError, json.JSONDecodeError, KeyError, TypeError, ValueError) as error:
        raise DatasetError(f"{path}: unreadable HOMER+ common data ({type(error).__name__}: {error})") from None
    if not len(ids) == len(classes) == len(cats) or cats.count(HOME_CATEGORY) != 1:
        raise DatasetError(f"{path}: node_ids, node_classes, node_categories of lengths {len(ids)}, {len(classes)}, "
                           f"{len(cats)} with {cats.count(HOME_CATEGORY)} '{HOME_CATEGORY}' node(s); need equal "
                           "lengths and one home")
    if dt != GRID_MIN:
        raise DatasetError(f"{path}: dt {dt} min; homer-sim predicts on a {GRID_MIN}-minute grid")
    unknown = sorted({c for c in cats if c not in CATEGORIES and c != HOME_CATEGORY})
    if unknown:
        raise DatasetError(f"{path}: unknown node categories {unknown}; known: {', '.join(CATEGORIES)}, Home")
    home = cats.index(HOME_CATEGORY)
    keep = np.array([i for i in range(len(ids)) if i != home])
    repeated = {c for c, k in Counter(classes).items() if k > 1}
    names = tuple(f"{classes[i]}_{ids[i]}" if classes[i] in repeated else classes[i] for i in keep)
    categories = tuple(CATEGORIES[cats[i]] for i in keep)
    movable = tuple(c != "room" and ids[i] not in static for i, c in zip(keep, categories, strict=True))
    return Household(tuple(int(ids[i]) for i in keep), keep, home, names, categories, movable, activities)


def _load(path: Path) -> dict:
    """torch.load with weights_only=True; any failure becomes a DatasetError naming the file."""
    import torch

    try:
        blob = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as error:  # torch raises many kinds (RuntimeError, UnpicklingError, EOFError, ...)
        first = str(error).strip().splitlines()[0] if str(error).strip() else ""
        raise DatasetError(f"{path}: corrupted or truncated HOMER+ day ({type(error).__name__}: {first[:200]})"
                           ) from None
    if not isinstance(blob, dict) or not {"edges", "times"} <= set(blob):
        raise DatasetError(f"{path}: not a HOMER+ day (need a dict with 'edges' and 'times')")
    return blob


def read_day(path: Path, house: Household, name: str, split: str) -> Day:
    """One upstream day file -> our Day; raises DatasetError naming the file on a wrong shape or content."""
    blob = _load(path)
    edges, times = blob["edges"].numpy(), blob["times"].numpy()
    n = house.upstream_nodes
    if edges.ndim != 3 or edges.shape[1:] != (n, n) or times.shape != (edges.shape[0],) or edges.shape[0] < 2:
        raise DatasetError(f"{path}: edges {tuple(edges.shape)} and times {tuple(times.shape)}; need (T, {n}, {n}) "
                           f"and (T,) with T >= 2, for the {n} nodes of common_data.json")
    if not np.all((edges == 0) | (edges == 1)) or not np.all(edges.sum(axis=-1) == 1):
        raise DatasetError(f"{path}: edges are not one parent (a one-hot row) per node and step")
    upstream = edges.argmax(axis=-1)[:, house.keep]  # (T, N) upstream parent index
    rooms = np.array([c == "room" for c in house.categories])
    if np.any((upstream == house.home) != rooms[None]):
        raise DatasetError(f"{path}: only rooms may hang from home, and every room must")
    index = np.full(n, -1, dtype=np.int64)
    index[house.keep] = np.arange(len(house.keep))
    parent = index[upstream].astype(np.int16)
    relation = np.where(rooms, NONE, ON).astype(np.int8)
    try:
        for row in np.unique(parent, axis=0):
            validate_in_tree(house.names, house.categories, row, relation)
    except GraphError as error:
        raise DatasetError(f"{path}: not a scene graph ({error})") from None
    minutes = np.round(times).astype(np.int32)
    activity = blob["activity"].numpy() if "activity" in blob else None
    return Day(name, split, int(path.stem), minutes, parent, np.broadcast_to(relation, parent.shape).copy(),
               _schedule(minutes, activity, house.activities), _moves(minutes, parent, house.names))


def _schedule(minutes: np.ndarray, activity: np.ndarray | None, names: Sequence[str]
              ) -> tuple[tuple[str, float, float], ...]:
    """Runs of one activity label: (name, first minute, minute the next run starts or the day ends)."""
    if activity is None or activity.shape != minutes.shape:
        return ()
    starts = np.flatnonzero(np.r_[True, activity[1:] != activity[:-1]])
    ends = np.r_[starts[1:], len(minutes) - 1]
    return tuple((names[a] if 0 <= a < len(names) else str(int(a)), float(minutes[s]), float(minutes[e]))
                 for a, s, e in zip(activity[starts], starts, ends, strict=True))


def _moves(minutes: np.ndarray, parent: np.ndarray, names: Sequence[str]) -> tuple[tuple, ...]:
    """(minute, object, from, to, relation) for every parent change between consecutive steps."""
    steps, nodes = np.nonzero(parent[1:] != parent[:-1])
    return tuple((float(minutes[t + 1]), names[i], names[parent[t, i]], names[parent[t + 1, i]], "ON")
                 for t, i in zip(steps, nodes, strict=True))


def read_split(folder: Path, house: Household, name: str, split: str) -> list[Day]:
    """Every NNN.pt of one split folder, in file-number order; raises DatasetError if there is none."""
    files = sorted((folder / split).glob("*.pt"), key=lambda p: (len(p.stem), p.stem))
    bad = [p.name for p in files if not p.stem.isdigit()]
    if not files or bad:
        raise DatasetError(f"{folder / split}: " + (f"unexpected files {bad[:3]}; HOMER+ days are NNN.pt" if bad
                                                    else "no day files (NNN.pt)"))
    return [read_day(path, house, name, split) for path in files]


def household_meta(house: Household, households: tuple[str, ...]) -> DatasetMeta:
    """Our dataset meta for the converted nodes."""
    extra = {"source": "HOMER+", "relations": RELATIONS_NOTE, "virtualhome_ids": list(house.ids)}
    return DatasetMeta(house.names, house.categories, house.movable, households, GRID_MIN, extra=extra)


def import_household(path: str | Path, out: str | Path, name: str | None = None) -> dict:
    """Convert one HOMER+ household at `path` into the dataset folder `out` (created, or extended when it holds
    other households with the same nodes). `name` defaults to the household folder's name.

    Every file is read and checked first; the days are then written to a temporary folder inside `out` and moved
    into place by one rename, and meta.json is rewritten atomically last. Returns a summary dict.
    """
    folder = upstream_folder(path)
    name = name or (folder.parent.name if folder.name == UPSTREAM_FOLDER else folder.name)
    out = Path(out)
    house = read_household(folder)
    existing = _existing_meta(out, house, name)
    days = {split: read_split(folder, house, name, split) for split in SPLITS}
    meta = household_meta(house, (*(existing.households if existing else ()), name))
    created = not out.exists()
    out.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(prefix=f".import-{name}-", dir=out))
    try:
        for split_days in days.values():
            for day in split_days:
                write_day(staging, day)
        os.replace(staging / name, out / name)
        write_meta(out, meta)
    except BaseException:
        shutil.rmtree(out / name, ignore_errors=True) if not (existing and name in existing.households) else None
        raise
    finally:
        shutil.rmtree(staging, ignore_errors=True)
        if created and not any(out.iterdir()):
            out.rmdir()
    return {"household": name, "out": str(out), "nodes": len(house.names), "movable": int(sum(house.movable)),
            **{f"{split}_days": len(d) for split, d in days.items()},
            "moves": sum(len(d.moves) for split_days in days.values() for d in split_days)}


def _existing_meta(out: Path, house: Household, name: str) -> DatasetMeta | None:
    """The meta of a dataset already at `out` if the household can join it; DatasetError otherwise."""
    if not (out / "meta.json").is_file():
        if out.exists() and any(p for p in out.iterdir()):
            raise DatasetError(f"{out}: exists, is not empty and holds no dataset (no meta.json); give a new folder")
        return None
    meta = Dataset(out).meta
    if meta.nodes != house.names or meta.movable != house.movable:
        raise DatasetError(f"{out}: its dataset has other nodes ({len(meta.nodes)} vs {len(house.names)}); import "
                           "this household into a new folder")
    if name in meta.households or (out / name).exists():
        raise DatasetError(f"{out}: already holds household {name!r}; give another --name or another folder")
    return meta
