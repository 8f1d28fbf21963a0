"""Rerun recordings (.rrd) of the MuJoCo world: the only module of homer-sim that imports rerun.

A recording is written headless to one file (no viewer, no network). Layout of the entity tree:

- `world`: the Z-up root (static `ViewCoordinates`).
- `world/static/geom_<k>`: geoms of MuJoCo's world body (floor, walls), static, in world coordinates.
- `world/bodies/<body>`: one `Transform3D` per body, its world pose. Static bodies (welded to the world) are
  logged once as static; the others on the `physics_s` timeline whenever they moved.
- `world/bodies/<body>/geom_<k>`: the k-th geom of that body (k counts the body's geoms in model order), a
  static `Transform3D` with the geom's pose in the body frame plus its shape.
- `graph/observed` (or any entity passed in): `GraphNodes` and `GraphEdges` (child -> parent) of a scene
  graph on the `routine` timeline; `<entity>/relations` a `TextDocument` of "child RELATION parent" lines,
  because rerun's `GraphEdges` has no labels.
- `events`: `TextLog` rows.

Timelines (both rerun "duration" timelines, so the viewer shows them as clocks):
- `physics_s`: MuJoCo `data.time` in s.
- `routine`: the routine clock, stored as routine_minute * 60 s, so the viewer reads it as time of day
  (06:30:00 is routine minute 390). A float minute cannot go on a sequence timeline (integers only).

Wall-clock `log_time` is switched off: recordings depend on the simulated clocks only.

Body poses are buffered and sent by columns (`send_columns`, one call per body and chunk of POSE_CHUNK_ROWS
rows, and at `close`, or at interpreter exit if a run raised before `close`): one `log` call per body and pose
costs milliseconds per physics frame.
"""

from __future__ import annotations

import atexit
import logging
from collections import defaultdict
from pathlib import Path
from types import TracebackType
from typing import TYPE_CHECKING

import mujoco
import numpy as np
import pyarrow as pa
import rerun as rr
from rerun.chunk import RrdReader

from homer_sim.errors import HomerError
from homer_sim.transforms import wxyz_to_xyzw
from homer_sim.world import World

if TYPE_CHECKING:
    from homer_sim.graph import SceneGraph

log = logging.getLogger(__name__)

PHYSICS_TIMELINE = "physics_s"
ROUTINE_TIMELINE = "routine"
RECORD_PERIOD_S = 0.2  # physics s between pose rows of a RecordedWorld (5 Hz keeps a morning of robot work small)
POSE_PERIOD_S = 1.0 / 30.0  # at most 30 pose updates per second of physics time
MOVED_DISTANCE_M = 5e-4
MOVED_ANGLE_RAD = np.deg2rad(0.5)
VISIBLE_GEOM_GROUPS = (0, 1, 2)  # groups 3+ hold collision-only duplicates
PLANE_HALF_EXTENT_M = 50.0  # stands in for an infinite MuJoCo plane (size 0)
PLANE_THICKNESS_M = 1e-3
TEXT_LOG_LEVELS = ("CRITICAL", "ERROR", "WARN", "INFO", "DEBUG", "TRACE")
CATEGORY_COLORS = {  # RGBA, uint8
    "room": (110, 140, 200, 255),
    "furniture": (160, 110, 60, 255),
    "appliance": (140, 150, 160, 255),
    "prop": (120, 180, 120, 255),
    "decor": (200, 140, 200, 255),
    "object": (240, 160, 40, 255),
}
POSE_CHUNK_ROWS = 20_000  # buffered pose rows (one body at one time) sent together
_TIME_EPS_S = 1e-9  # absorbs float error when poses are logged exactly every POSE_PERIOD_S


class RecordingError(HomerError):
    """A recording used out of order (poses before geometry, logging after close) or given bad values."""


class Recording:
    """One .rrd file of one simulated run, owning its own `rr.RecordingStream` (never rerun's global one).

    path: the .rrd file; parent folders are created.
    app_id: rerun application id, shared by every recording of the project.
    """

    def __init__(self, path: str | Path, app_id: str = "homer-sim") -> None:
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._stream = rr.RecordingStream(application_id=app_id)
        self._stream.set_log_time_enabled(False)
        self._stream.save(self.path)
        self._closed = False
        self._body_paths: list[str] = []
        self._moving_ids = np.zeros(0, dtype=np.int64)  # Shape (M,), ids of bodies not welded to the world
        self._last_pos = np.zeros((0, 3))  # Shape (M, 3), last logged world positions in m
        self._last_quat = np.zeros((0, 4))  # Shape (M, 4), last logged world quaternions, wxyz
        self._last_pose_time_s: float | None = None
        # Pose rows not yet sent: (physics s, routine minute or NaN, body ids (k,), positions (k, 3) m,
        # quaternions (k, 4) xyzw), one entry per log_body_poses call that logged k bodies.
        self._pose_rows: list[tuple[float, float, np.ndarray, np.ndarray, np.ndarray]] = []
        self._pending_rows = 0
        self._physics_s: float | None = None
        self._routine_minute: float | None = None
        self._stream.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
        atexit.register(self.close)  # a run that raised before close still leaves its buffered poses in the file

    # --- lifecycle -----------------------------------------------------------------------------------
    def close(self) -> None:
        """Flush everything and close the file (writes the rrd footer). Safe to call twice."""
        if self._closed:
            return
        self._send_poses()
        self._stream.flush()
        self._stream.disconnect()
        self._closed = True
        atexit.unregister(self.close)

    def __enter__(self) -> Recording:
        return self

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        self.close()

    def _require_open(self) -> None:
        if self._closed:
            raise RecordingError(f"recording {self.path} is closed")

    def _stamp(self, physics_s: float | None, routine_minute: float | None) -> None:
        """Set exactly the given clocks for the next rows (rerun's time state is sticky per thread)."""
        self._stream.reset_time()
        if physics_s is not None:
            self._stream.set_time(PHYSICS_TIMELINE, duration=physics_s)
        if routine_minute is not None:
            self._stream.set_time(ROUTINE_TIMELINE, duration=routine_minute * 60.0)

    # --- geometry ------------------------------------------------------------------------------------
    def log_geometry(self, model: mujoco.MjModel, data: mujoco.MjData | None = None) -> None:
        """Log every visible geom (groups 0-2, alpha > 0) once as static, and the poses of static bodies.

        Static bodies (welded to the world: no joint on them or above them, not mocap) get their world
        pose as a static transform; their pose never depends on qpos, so it is computed on a scratch
        `MjData`. If `data` is given (after `mj_forward`), the current poses of the moving bodies are
        logged too, at `data.time`, so the scene is complete from the start.
        """
        self._require_open()
        self._body_paths = [_body_path(model, b) for b in range(model.nbody)]
        scratch = mujoco.MjData(model)
        mujoco.mj_kinematics(model, scratch)
        is_static = model.body_weldid == 0
        for body_id in np.flatnonzero(is_static)[1:]:  # body 0 is the world
            self._stream.log(
                self._body_paths[body_id],
                _transform(scratch.xpos[body_id], scratch.xquat[body_id]),
                static=True,
            )
        logged = 0
        for geom_id in range(model.ngeom):
            logged += self._log_geom(model, geom_id)
        self._moving_ids = np.flatnonzero(~is_static)
        self._last_pos = np.zeros((self._moving_ids.size, 3))
        self._last_quat = np.zeros((self._moving_ids.size, 4))
        self._last_pose_time_s = None
        log.debug("logged %d of %d geoms; %d moving bodies", logged, model.ngeom, self._moving_ids.size)
        if data is not None:
            self.log_body_poses(data)

    def _log_geom(self, model: mujoco.MjModel, geom_id: int) -> int:
        """Log one geom as static if it is visible; returns 1 if logged, else 0."""
        mat_id = model.geom_matid[geom_id]
        rgba = model.mat_rgba[mat_id] if mat_id >= 0 else model.geom_rgba[geom_id]
        if model.geom_group[geom_id] not in VISIBLE_GEOM_GROUPS or rgba[3] <= 0.0:
            return 0
        shape = _geom_shape(model, geom_id, np.round(np.clip(rgba, 0.0, 1.0) * 255).astype(np.uint8))
        if shape is None:
            return 0
        body_id = model.geom_bodyid[geom_id]
        k = geom_id - model.body_geomadr[body_id]
        parent = "world/static" if body_id == 0 else self._body_paths[body_id]
        pose = _transform(model.geom_pos[geom_id], model.geom_quat[geom_id])
        self._stream.log(f"{parent}/geom_{k}", pose, shape, static=True)
        return 1

    # --- poses ---------------------------------------------------------------------------------------
    def log_body_poses(self, data: mujoco.MjData, physics_time: float | None = None, force: bool = False) -> int:
        """Log the world pose of every moving body that moved since it was last logged.

        data: the live simulation data, after `mj_forward` or `mj_step` (reads `xpos`, `xquat`).
        physics_time: time on the `physics_s` timeline in s; defaults to `data.time`.
        "Moved" means more than MOVED_DISTANCE_M (0.5 mm) or MOVED_ANGLE_RAD (0.5 deg); the first call
        after `log_geometry` logs every moving body. A call less than POSE_PERIOD_S (1/30 s) of physics
        time after the previous logged call logs nothing. A clock that went backwards (a reset) logs.
        Rows also carry the current routine clock (see `set_routine_time`). `force` skips the rate limit
        (for kinematic moves, such as the person walking, that take routine time but no physics time).
        Returns the number of bodies logged.
        """
        self._require_open()
        if not self._body_paths:
            raise RecordingError("log_body_poses needs the model: call log_geometry(model) first")
        if data.xpos.shape[0] != len(self._body_paths):
            raise RecordingError(
                f"data has {data.xpos.shape[0]} bodies, the logged model {len(self._body_paths)}"
            )
        time_s = float(data.time if physics_time is None else physics_time)
        self._physics_s = time_s
        last = self._last_pose_time_s
        if not force and last is not None and 0.0 <= time_s - last < POSE_PERIOD_S - _TIME_EPS_S:
            return 0
        pos = data.xpos[self._moving_ids]
        quat = data.xquat[self._moving_ids]
        if last is None:
            moved = np.ones(self._moving_ids.size, dtype=bool)
        else:
            moved = _moved(self._last_pos, self._last_quat, pos, quat)
        self._last_pose_time_s = time_s
        if not moved.any():
            return 0
        moved_ids = self._moving_ids[moved]
        minute = np.nan if self._routine_minute is None else self._routine_minute
        self._pose_rows.append((time_s, minute, moved_ids, pos[moved], wxyz_to_xyzw(quat[moved])))
        self._pending_rows += moved_ids.size
        if self._pending_rows >= POSE_CHUNK_ROWS:
            self._send_poses()
        self._last_pos[moved] = pos[moved]
        self._last_quat[moved] = quat[moved]
        return int(moved_ids.size)

    def _send_poses(self) -> None:
        """Send the buffered pose rows by columns: per body, its rows with and without a routine time."""
        if not self._pose_rows:
            return
        counts = [ids.size for _, _, ids, _, _ in self._pose_rows]
        time_s = np.repeat([row[0] for row in self._pose_rows], counts)
        minute = np.repeat([row[1] for row in self._pose_rows], counts)
        body = np.concatenate([row[2] for row in self._pose_rows])
        pos = np.concatenate([row[3] for row in self._pose_rows])
        quat = np.concatenate([row[4] for row in self._pose_rows])
        self._pose_rows, self._pending_rows = [], 0
        order = np.argsort(body, kind="stable")  # per body, rows stay in logging order
        starts = np.flatnonzero(np.diff(body[order], prepend=-1))
        for rows in np.split(order, starts[1:]):
            timed = np.isfinite(minute[rows])
            for part in (rows[~timed], rows[timed]):
                if part.size == 0:
                    continue
                indexes = [rr.TimeColumn(PHYSICS_TIMELINE, duration=_nanoseconds(time_s[part]))]
                if np.isfinite(minute[part[0]]):
                    indexes.append(rr.TimeColumn(ROUTINE_TIMELINE, duration=_nanoseconds(minute[part] * 60.0)))
                self._stream.send_columns(self._body_paths[body[part[0]]], indexes,
                                          rr.Transform3D.columns(translation=pos[part], quaternion=quat[part]))

    # --- routine clock, scene graphs, events ---------------------------------------------------------
    def set_routine_time(self, routine_minute: float) -> None:
        """Set the routine clock (minutes since midnight) that later pose and event rows carry.

        Stored on the `routine` duration timeline as routine_minute * 60 s.
        """
        self._routine_minute = _check_minute(routine_minute)

    def log_scene_graph(
        self, graph: SceneGraph, routine_minute: float, entity: str = "graph/observed"
    ) -> None:
        """Log a scene graph at `routine_minute` on the `routine` timeline only.

        Nodes are the graph's node names (also their labels), coloured by category; edges point from child
        to parent. The relations go to `<entity>/relations` as text lines "child RELATION parent".
        Does not change the routine clock set by `set_routine_time`, so a predicted graph can be logged
        at a future minute.
        """
        self._require_open()
        self._stamp(None, _check_minute(routine_minute))
        unknown = sorted(set(graph.categories) - set(CATEGORY_COLORS))
        if unknown:
            raise RecordingError(f"unknown categories {unknown}; known: {', '.join(CATEGORY_COLORS)}")
        nodes = list(graph.nodes)
        edges = list(graph.edges())
        self._stream.log(
            entity,
            rr.GraphNodes(
                node_ids=nodes, labels=nodes, colors=[CATEGORY_COLORS[c] for c in graph.categories]
            ),
            rr.GraphEdges(edges=[(child, parent) for child, parent, _ in edges], graph_type="directed"),
        )
        relations = "\n".join(f"{child} {relation} {parent}" for child, parent, relation in edges)
        self._stream.log(f"{entity}/relations", rr.TextDocument(relations, media_type=rr.MediaType.TEXT))

    def log_event(self, text: str, routine_minute: float | None = None, level: str = "INFO") -> None:
        """Log a text event under `events`.

        routine_minute: the event's routine time in minutes; the row then carries only the routine
        timeline. If None, the row carries the current clocks (routine clock from `set_routine_time`,
        physics time of the latest `log_body_poses` call); at least one must be known.
        level: one of TEXT_LOG_LEVELS.
        """
        self._require_open()
        if level not in TEXT_LOG_LEVELS:
            raise RecordingError(f"unknown log level {level!r}; known: {', '.join(TEXT_LOG_LEVELS)}")
        if routine_minute is not None:
            self._stamp(None, _check_minute(routine_minute))
        elif self._routine_minute is None and self._physics_s is None:
            # rerun stores a row without any timeline as static: refuse instead of losing its time.
            raise RecordingError(
                "log_event needs routine_minute or a clock (set_routine_time, log_body_poses)"
            )
        else:
            self._stamp(self._physics_s, self._routine_minute)
        self._stream.log("events", rr.TextLog(text, level=level))

    def log_path(self, path: list[tuple[float, float]], routine_minute: float, entity: str = "world/person/path",
                 height: float = 0.02) -> None:
        """A walked path (world (x, y) waypoints in m) as a line strip just above the floor, on the routine
        timeline."""
        self._require_open()
        self._stamp(None, _check_minute(routine_minute))
        points = np.array([[x, y, height] for x, y in path], dtype=np.float32)
        self._stream.log(entity, rr.LineStrips3D([points], colors=[(240, 160, 40, 255)], radii=0.02))


# --- helpers ---------------------------------------------------------------------------------------------
def _body_path(model: mujoco.MjModel, body_id: int) -> str:
    """Entity path of a body; '/' in MJCF names (dm_control prefixes) is escaped, not nested."""
    name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, body_id) or f"body_{body_id}"
    return f"world/bodies/{rr.escape_entity_path_part(name)}"


def _transform(pos: np.ndarray, quat_wxyz: np.ndarray) -> rr.Transform3D:
    """A rerun transform from a position in m, Shape (3,), and a MuJoCo quaternion (w, x, y, z)."""
    return rr.Transform3D(translation=pos, quaternion=rr.Quaternion(xyzw=wxyz_to_xyzw(quat_wxyz)))


def _moved(last_pos: np.ndarray, last_quat: np.ndarray, pos: np.ndarray, quat: np.ndarray) -> np.ndarray:
    """Which bodies moved beyond the tolerances. Positions Shape (M, 3) in m, quaternions (M, 4) wxyz."""
    shifted = np.sum((pos - last_pos) ** 2, axis=1) > MOVED_DISTANCE_M**2
    # The angle between two unit quaternions is 2 * acos(|q1 . q2|).
    dot = np.abs(np.sum(quat * last_quat, axis=1))
    turned = dot < np.cos(MOVED_ANGLE_RAD / 2.0)
    return shifted | turned


def _geom_shape(model: mujoco.MjModel, geom_id: int, color: np.ndarray) -> rr.AsComponents | None:
    """The rerun archetype for one geom in its own frame. color: Shape (4,), uint8 RGBA."""
    size = model.geom_size[geom_id]
    geom_type = mujoco.mjtGeom(model.geom_type[geom_id])
    solid = rr.components.FillMode.Solid
    match geom_type:
        case mujoco.mjtGeom.mjGEOM_BOX:
            return rr.Boxes3D(half_sizes=[size], colors=[color], fill_mode=solid)
        case mujoco.mjtGeom.mjGEOM_SPHERE:
            return rr.Ellipsoids3D(half_sizes=[[size[0]] * 3], colors=[color], fill_mode=solid)
        case mujoco.mjtGeom.mjGEOM_ELLIPSOID:
            return rr.Ellipsoids3D(half_sizes=[size], colors=[color], fill_mode=solid)
        case mujoco.mjtGeom.mjGEOM_CAPSULE:
            # rerun's capsule runs from z=0 to z=length; MuJoCo's is centred on the geom origin.
            return rr.Capsules3D(
                lengths=[2.0 * size[1]],
                radii=[size[0]],
                translations=[[0.0, 0.0, -size[1]]],
                colors=[color],
                fill_mode=solid,
            )
        case mujoco.mjtGeom.mjGEOM_CYLINDER:
            return rr.Cylinders3D(lengths=[2.0 * size[1]], radii=[size[0]], colors=[color], fill_mode=solid)
        case mujoco.mjtGeom.mjGEOM_PLANE:
            half_x = size[0] if size[0] > 0 else PLANE_HALF_EXTENT_M
            half_y = size[1] if size[1] > 0 else PLANE_HALF_EXTENT_M
            return rr.Boxes3D(
                half_sizes=[[half_x, half_y, PLANE_THICKNESS_M / 2]],
                centers=[[0.0, 0.0, -PLANE_THICKNESS_M / 2]],  # top face at the plane
                colors=[color],
                fill_mode=solid,
            )
        case mujoco.mjtGeom.mjGEOM_MESH:
            return _mesh(model, int(model.geom_dataid[geom_id]), color)
    log.debug("geom %d of type %s is not recorded", geom_id, geom_type.name)
    return None


def _mesh(model: mujoco.MjModel, mesh_id: int, color: np.ndarray) -> rr.Mesh3D:
    """A mesh in its geom frame (MuJoCo already moved the vertices into it). color: uint8 RGBA."""
    vert_start, vert_count = model.mesh_vertadr[mesh_id], model.mesh_vertnum[mesh_id]
    face_start, face_count = model.mesh_faceadr[mesh_id], model.mesh_facenum[mesh_id]
    return rr.Mesh3D(
        vertex_positions=model.mesh_vert[vert_start : vert_start + vert_count],
        triangle_indices=model.mesh_face[face_start : face_start + face_count],  # indices local to the mesh
        albedo_factor=color,
    )


def _nanoseconds(seconds: np.ndarray) -> np.ndarray:
    """Durations in s, Shape (N,), as timedelta64[ns], rounded as rerun rounds a time set with `set_time`."""
    return np.round(seconds * 1e9).astype(np.int64).astype("timedelta64[ns]")


def _check_minute(routine_minute: float) -> float:
    minute = float(routine_minute)
    if not np.isfinite(minute):
        raise RecordingError(f"routine minute must be finite, got {routine_minute!r}")
    return minute


def read_recording(path: str | Path) -> dict[str, pa.Table]:
    """Read an .rrd file back: entity path (as logged, no leading '/') to one table of all its rows.

    Columns are named as rerun stores them: timelines (`physics_s`, `routine`, duration[ns]; null on
    static rows) and "Archetype:field" components (`Transform3D:translation`, each cell a list of
    instances). Rows are not sorted. Works on files without a footer too (an unclosed recording).
    """
    tables: dict[str, list[pa.Table]] = defaultdict(list)
    for chunk in RrdReader(path).stream():
        tables[chunk.entity_path.lstrip("/")].append(pa.Table.from_batches([chunk.to_record_batch()]))
    return {entity: pa.concat_tables(parts, promote_options="permissive") for entity, parts in tables.items()}


class RecordedWorld(World):
    """A World that logs body poses to `recording` (when set) while physics steps, at most every
    RECORD_PERIOD_S; `physics_offset` (s) is added to its clock, so runs that reset the world (one per trial)
    follow each other on the `physics_s` timeline."""

    recording: Recording | None = None
    physics_offset = 0.0

    def step(self, n: int = 1) -> None:
        super().step(n)
        if self.recording is not None and self.data.time - getattr(self, "_logged_s", -1.0) >= RECORD_PERIOD_S:
            self._logged_s = float(self.data.time)
            self.recording.log_body_poses(self.data, physics_time=self.physics_offset + self.data.time)

    def reset_settled(self) -> None:
        super().reset_settled()
        self._logged_s = -1.0
