"""The HOMER-like dataset format: types, writing and reading. numpy and json only (no mujoco, no rerun).

Layout of a dataset folder (format version 2):

    DIR/meta.json                      nodes, categories, movable mask, households, grid, format version
    DIR/<household>/<split>/day_NNN.npz  one simulated day (split is "train" or "test")
    DIR/generation.log                 timings and retries (never read back into the data)

A day file holds, for T grid steps every `grid_min` routine minutes and N nodes:
    minutes   (T,)   int32   routine minute of each step (minutes since midnight)
    parent    (T, N) int16   each node's parent index at that step, -1 for rooms
    relation  (T, N) int8    0 none (rooms), 1 ON, 2 INSIDE
    info      ()     str     JSON: household, split, index, key (the `DayKey` the day was simulated from:
                             seed, household index, split, index, attempt), schedule [[activity, start,
                             end]], moves [[minute, object, from, to, relation]]
Version 1 files have no key (only the attempt, as "seed"): they read, but their days cannot be replayed.
Parent arrays are compact (T x N), never dense N x N adjacency. Files are written to a temporary name and
renamed, so a day is either complete or absent; zip entries carry a fixed timestamp, so the same day gives
the same bytes.
"""

from __future__ import annotations

import io
import json
import os
import zipfile
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from homer_sim.clock import GRID_MIN
from homer_sim.days import DayKey
from homer_sim.errors import HomerError
from homer_sim.graph import SceneGraph

FORMAT_VERSION = 2
READABLE_VERSIONS = (1, 2)  # version 1 days have no DayKey
SPLITS = ("train", "test")
_ZIP_DATE = (1980, 1, 1, 0, 0, 0)


class DatasetError(HomerError):
    """A dataset folder or file that is missing, corrupted or of another format version."""


@dataclass(frozen=True)
class DatasetMeta:
    nodes: tuple[str, ...]
    categories: tuple[str, ...]
    movable: tuple[bool, ...]
    households: tuple[str, ...]
    grid_min: int = GRID_MIN
    version: int = FORMAT_VERSION
    extra: dict = field(default_factory=dict, compare=False, hash=False)

    @property
    def movable_mask(self) -> np.ndarray:
        return np.array(self.movable, dtype=bool)

    def to_json(self) -> dict:
        return {"version": self.version, "grid_min": self.grid_min, "nodes": list(self.nodes),
                "categories": list(self.categories), "movable": list(self.movable),
                "households": list(self.households), **self.extra}

    @classmethod
    def from_json(cls, raw: dict) -> DatasetMeta:
        if raw.get("version") not in READABLE_VERSIONS:
            raise DatasetError(f"dataset format version {raw.get('version')!r}; this homer-sim reads versions "
                               f"{', '.join(map(str, READABLE_VERSIONS))}: generate the dataset again")
        known = {"version", "grid_min", "nodes", "categories", "movable", "households"}
        return cls(tuple(raw["nodes"]), tuple(raw["categories"]), tuple(bool(m) for m in raw["movable"]),
                   tuple(raw["households"]), int(raw["grid_min"]), int(raw["version"]),
                   {k: v for k, v in raw.items() if k not in known})


@dataclass(frozen=True)
class Day:
    """One simulated day of one household: the scene graph on the routine grid, the schedule, the moves."""

    household: str
    split: str
    index: int
    minutes: np.ndarray
    parent: np.ndarray
    relation: np.ndarray
    schedule: tuple[tuple[str, float, float], ...] = ()
    moves: tuple[tuple[float, str, str, str, str], ...] = ()
    key: DayKey | None = None  # None for days not simulated from a key (imported, scripted, format 1)

    def __post_init__(self) -> None:
        t, n = self.parent.shape
        if self.minutes.shape != (t,) or self.relation.shape != (t, n):
            raise DatasetError(f"day {self.household}/{self.split}/{self.index}: arrays of mismatched shapes")

    @property
    def steps(self) -> int:
        return len(self.minutes)

    def graph(self, step: int, meta: DatasetMeta) -> SceneGraph:
        return SceneGraph(meta.nodes, meta.categories, self.parent[step], self.relation[step])

    def info(self) -> dict:
        return {"household": self.household, "split": self.split, "index": self.index,
                "key": self.key.to_json() if self.key is not None else None,
                "schedule": [list(s) for s in self.schedule], "moves": [list(m) for m in self.moves]}

    def replay_key(self) -> DayKey:
        """The key to replay this day with; a DatasetError for a day saved without one."""
        if self.key is None:
            raise DatasetError(f"day {self.household}/{self.split}/{self.index} has no DayKey (it was imported, "
                               "replayed from a day script, or written in dataset format 1), so it cannot be "
                               "replayed; generate such days with `homer generate`")
        return self.key


def day_path(root: Path, household: str, split: str, index: int) -> Path:
    return Path(root) / household / split / f"day_{index:03d}.npz"


def _npy_bytes(array: np.ndarray) -> bytes:
    buffer = io.BytesIO()
    np.lib.format.write_array(buffer, np.ascontiguousarray(array), allow_pickle=False)
    return buffer.getvalue()


def write_day(root: str | Path, day: Day) -> Path:
    """Write one day atomically (temporary file, then rename) with deterministic bytes."""
    path = day_path(Path(root), day.household, day.split, day.index)
    path.parent.mkdir(parents=True, exist_ok=True)
    arrays = {
        "minutes": day.minutes.astype(np.int32),
        "parent": day.parent.astype(np.int16),
        "relation": day.relation.astype(np.int8),
        "info": np.array(json.dumps(day.info(), sort_keys=True)),
    }
    tmp = path.with_suffix(".npz.tmp")
    with zipfile.ZipFile(tmp, "w", compression=zipfile.ZIP_DEFLATED) as archive:
        for name, array in arrays.items():
            entry = zipfile.ZipInfo(f"{name}.npy", date_time=_ZIP_DATE)
            entry.compress_type = zipfile.ZIP_DEFLATED
            archive.writestr(entry, _npy_bytes(array))
    os.replace(tmp, path)
    return path


def read_day(path: str | Path) -> Day:
    """Read a day file; raises DatasetError naming the file if it is missing or corrupted."""
    path = Path(path)
    try:
        with np.load(path, allow_pickle=False) as archive:
            info = json.loads(archive["info"].item())
            return Day(info["household"], info["split"], int(info["index"]), archive["minutes"],
                       archive["parent"], archive["relation"],
                       tuple((a, float(s), float(e)) for a, s, e in info["schedule"]),
                       tuple((float(m[0]), *m[1:]) for m in info["moves"]),
                       DayKey.from_json(info["key"]) if info.get("key") else None)
    except FileNotFoundError:
        raise DatasetError(f"{path}: no such day file") from None
    except (OSError, ValueError, KeyError, zipfile.BadZipFile, json.JSONDecodeError) as error:
        raise DatasetError(f"{path}: corrupted day file ({error})") from None


def write_meta(root: str | Path, meta: DatasetMeta) -> Path:
    path = Path(root) / "meta.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".json.tmp")
    tmp.write_text(json.dumps(meta.to_json(), indent=1, sort_keys=True) + "\n")
    os.replace(tmp, path)
    return path


class Dataset:
    """A dataset folder: its metadata and lazy access to its days."""

    def __init__(self, root: str | Path) -> None:
        self.root = Path(root)
        meta_path = self.root / "meta.json"
        if not meta_path.is_file():
            raise DatasetError(f"{self.root}: not a homer-sim dataset (no meta.json)")
        try:
            self.meta = DatasetMeta.from_json(json.loads(meta_path.read_text()))
        except (json.JSONDecodeError, KeyError, TypeError) as error:
            raise DatasetError(f"{meta_path}: corrupted metadata ({error})") from None

    def day_indices(self, household: str, split: str) -> list[int]:
        folder = self.root / household / split
        if household not in self.meta.households:
            raise DatasetError(f"unknown household {household!r}; known: {', '.join(self.meta.households)}")
        return sorted(int(p.stem.split("_")[1]) for p in folder.glob("day_*.npz")) if folder.is_dir() else []

    def days(self, household: str, split: str) -> Iterator[Day]:
        for index in self.day_indices(household, split):
            yield read_day(day_path(self.root, household, split, index))

    def load(self, household: str, split: str) -> list[Day]:
        return list(self.days(household, split))

    def require_nodes(self, nodes: Sequence[str]) -> None:
        """Refuse (DatasetError) a dataset whose nodes are not `nodes`, those of the apartment the caller
        simulates: a dataset made with another apartment or object catalogue would be replayed and indexed
        against the wrong bodies."""
        if tuple(self.meta.nodes) == tuple(nodes):
            return
        ours, theirs = tuple(nodes), tuple(self.meta.nodes)
        first = next((k for k, (a, b) in enumerate(zip(theirs, ours, strict=False)) if a != b), min(len(ours),
                                                                                               len(theirs)))
        differ = (f"node {first}: {theirs[first] if first < len(theirs) else 'none'!r} in the dataset, "
                  f"{ours[first] if first < len(ours) else 'none'!r} here")
        raise DatasetError(f"{self.root}: made with another apartment or object catalogue ({len(theirs)} nodes, "
                           f"this apartment has {len(ours)}; first difference at {differ}); generate the dataset "
                           "again with `homer generate`")
