"""Recordings: geometry, rate-limited poses, scene graphs and events written to .rrd and read back."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import mujoco
import numpy as np
import pytest

from homer_sim.graph import INSIDE, NONE, ON, SceneGraph
from homer_sim.recording import (
    PHYSICS_TIMELINE,
    ROUTINE_TIMELINE,
    Recording,
    RecordingError,
    read_recording,
)
from homer_sim.transforms import wxyz_to_xyzw, xyzw_to_wxyz

SCENE_XML = """
<mujoco>
  <option timestep="0.002"/>
  <asset>
    <mesh name="tetra" vertex="0 0 0  0.1 0 0  0 0.1 0  0 0 0.1"/>
    <material name="red" rgba="0.9 0.1 0.1 1"/>
  </asset>
  <worldbody>
    <geom name="floor" type="plane" size="0 0 0.1" rgba="0.8 0.8 0.8 1"/>
    <body name="shelf" pos="2 0 0.5">
      <geom type="box" size="0.3 0.2 0.5" material="red"/>
    </body>
    <body name="falling_box" pos="0 0 1" euler="0.3 0.2 0.1">
      <freejoint/>
      <geom type="box" size="0.05 0.05 0.05"/>
    </body>
    <body name="resting_box" pos="1 1 0.05">
      <freejoint/>
      <geom type="box" size="0.05 0.05 0.05"/>
      <geom type="sphere" size="0.01" group="3"/>
    </body>
    <body name="capsule" pos="-1 0 0.5">
      <freejoint/>
      <geom type="capsule" size="0.03 0.1"/>
    </body>
    <body name="cylinder" pos="-1 1 0.5">
      <freejoint/>
      <geom type="cylinder" size="0.04 0.06"/>
    </body>
    <body name="tetra" pos="0 -1 0.5">
      <freejoint/>
      <geom type="mesh" mesh="tetra"/>
    </body>
  </worldbody>
</mujoco>
"""


def small_graph() -> SceneGraph:
    return SceneGraph(
        nodes=("kitchen", "table_kitchen", "bowl"),
        categories=("room", "furniture", "object"),
        parent=np.array([-1, 0, 1]),
        relation=np.array([NONE, INSIDE, ON]),
    )


def seconds(table, timeline: str) -> np.ndarray:
    """A duration timeline column (duration[ns]) in s."""
    return table.column(timeline).to_numpy() / np.timedelta64(1, "s")


def record(path: Path, steps: int) -> tuple[mujoco.MjModel, dict[float, tuple[np.ndarray, np.ndarray]], int]:
    """Record `steps` physics steps.

    Returns the model, (xpos, xquat) at the physics time of every call that logged, and the number of
    poses logged after the first call.
    """
    model = mujoco.MjModel.from_xml_string(SCENE_XML)
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    logged: dict[float, tuple[np.ndarray, np.ndarray]] = {}
    with Recording(path) as rec:
        rec.set_routine_time(420.0)
        rec.log_geometry(model, data)  # logs the first poses at t = 0
        logged[data.time] = (data.xpos.copy(), data.xquat.copy())
        total = 0
        for _ in range(steps):
            mujoco.mj_step(model, data)
            n = rec.log_body_poses(data)
            total += n
            if n:
                logged[data.time] = (data.xpos.copy(), data.xquat.copy())
        rec.log_scene_graph(small_graph(), routine_minute=430.0)
        rec.log_event("breakfast started", routine_minute=431.0)
        rec.log_event("settled")  # carries the current clocks
    return model, logged, total


def test_recording_round_trip(tmp_path: Path) -> None:
    path = tmp_path / "nested" / "day.rrd"
    model, logged, _ = record(path, steps=100)
    assert path.is_file() and path.stat().st_size > 0

    tables = read_recording(path)
    for entity in (
        "world",
        "world/static/geom_0",
        "world/bodies/shelf",
        "world/bodies/shelf/geom_0",
        "world/bodies/falling_box/geom_0",
        "world/bodies/capsule/geom_0",
        "world/bodies/cylinder/geom_0",
        "world/bodies/tetra/geom_0",
        "graph/observed",
        "graph/observed/relations",
        "events",
    ):
        assert entity in tables, f"{entity} missing; have {sorted(tables)}"
    assert "world/bodies/resting_box/geom_1" not in tables  # group 3 is collision-only

    # Geometry: shapes and local poses as MuJoCo has them.
    capsule = tables["world/bodies/capsule/geom_0"].to_pylist()[0]
    assert capsule["Capsules3D:lengths"] == pytest.approx([0.2])
    assert capsule["Capsules3D:translations"][0] == pytest.approx([0.0, 0.0, -0.1])
    tetra = tables["world/bodies/tetra/geom_0"].to_pylist()[0]
    assert len(tetra["Mesh3D:vertex_positions"]) == 4 and len(tetra["Mesh3D:triangle_indices"]) == 4
    tetra_id = model.body("tetra").geomadr[0]
    assert tetra["Transform3D:translation"][0] == pytest.approx(model.geom_pos[tetra_id], abs=1e-6)
    shelf_geom = tables["world/bodies/shelf/geom_0"].to_pylist()[0]
    assert shelf_geom["Boxes3D:colors"][0] == 0xE6_1A_1A_FF  # material red, packed RGBA
    shelf = tables["world/bodies/shelf"].to_pylist()
    assert len(shelf) == 1 and PHYSICS_TIMELINE not in shelf[0]  # static body: once, static
    assert shelf[0]["Transform3D:translation"][0] == pytest.approx([2.0, 0.0, 0.5])

    # Poses: the last logged translation and rotation are the body's pose at that time.
    falling = tables["world/bodies/falling_box"]
    times = seconds(falling, PHYSICS_TIMELINE)
    last = int(np.argmax(times))
    body_id = model.body("falling_box").id
    xpos, xquat = logged[max(logged)]
    assert times[last] == pytest.approx(max(logged), abs=1e-9)
    assert max(logged) > 0.1  # the body was logged while it fell, not only at t = 0
    translation = falling.column("Transform3D:translation")[last].as_py()[0]
    assert translation == pytest.approx(xpos[body_id], abs=1e-5)
    quaternion = falling.column("Transform3D:quaternion")[last].as_py()[0]
    assert quaternion == pytest.approx(wxyz_to_xyzw(xquat[body_id]), abs=1e-6)
    assert np.all(seconds(falling, ROUTINE_TIMELINE) == pytest.approx(420.0 * 60.0))

    # Scene graph and events on the routine timeline (minutes * 60 s).
    graph_row = tables["graph/observed"].to_pylist()[0]
    assert graph_row["GraphNodes:node_ids"] == ["kitchen", "table_kitchen", "bowl"]
    assert seconds(tables["graph/observed"], ROUTINE_TIMELINE)[0] == pytest.approx(430.0 * 60.0)
    assert PHYSICS_TIMELINE not in tables["graph/observed"].column_names  # routine timeline only
    relations = tables["graph/observed/relations"].to_pylist()[0]["TextDocument:text"]
    assert relations == ["table_kitchen INSIDE kitchen\nbowl ON table_kitchen"]
    events = tables["events"].sort_by(ROUTINE_TIMELINE).to_pylist()
    assert [e["TextLog:text"] for e in events] == [["settled"], ["breakfast started"]]
    assert events[0][PHYSICS_TIMELINE] is not None and events[1][PHYSICS_TIMELINE] is None


def test_pose_rate_limit_and_moved_filter(tmp_path: Path) -> None:
    model, logged, total = record(tmp_path / "rate.rrd", steps=500)  # 1 s of physics at 500 Hz
    tables = read_recording(tmp_path / "rate.rrd")
    falling_rows = tables["world/bodies/falling_box"].num_rows
    assert falling_rows <= 31
    assert len(logged) <= 31
    assert np.all(np.diff(sorted(logged)) >= 1.0 / 30.0 - 1e-9)
    # The resting box does not move, so after the first call it is never logged again.
    assert tables["world/bodies/resting_box"].num_rows < falling_rows / 2
    assert total + 5 == sum(tables[f"world/bodies/{b}"].num_rows for b in _moving_bodies(model))


def _moving_bodies(model: mujoco.MjModel) -> list[str]:
    return [model.body(b).name for b in range(1, model.nbody) if model.body_weldid[b] != 0]


def test_two_recordings_at_once_and_errors(tmp_path: Path) -> None:
    model = mujoco.MjModel.from_xml_string(SCENE_XML)
    data = mujoco.MjData(model)
    with Recording(tmp_path / "a.rrd") as a, Recording(tmp_path / "b.rrd") as b:
        with pytest.raises(RecordingError, match="log_geometry"):
            a.log_body_poses(data)
        with pytest.raises(RecordingError, match="log_event needs"):
            a.log_event("no clock yet")
        with pytest.raises(RecordingError, match="known: CRITICAL"):
            a.log_event("x", routine_minute=400.0, level="LOUD")
        a.log_event("only in a", routine_minute=400.0)
        b.log_event("only in b", routine_minute=401.0)
    assert read_recording(tmp_path / "a.rrd")["events"].to_pylist()[0]["TextLog:text"] == ["only in a"]
    assert read_recording(tmp_path / "b.rrd")["events"].to_pylist()[0]["TextLog:text"] == ["only in b"]
    with pytest.raises(RecordingError, match="closed"):
        a.log_event("late", routine_minute=402.0)


def test_wxyz_to_xyzw_round_trips() -> None:
    rng = np.random.default_rng(0)
    q = rng.normal(size=(100, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    xyzw = wxyz_to_xyzw(q)
    assert np.array_equal(xyzw[:, 3], q[:, 0]) and np.array_equal(xyzw[:, :3], q[:, 1:])
    assert np.array_equal(xyzw_to_wxyz(xyzw), q)
    assert np.array_equal(wxyz_to_xyzw(np.array([1.0, 0.0, 0.0, 0.0])), [0.0, 0.0, 0.0, 1.0])
    for single in q[:5]:
        assert np.array_equal(xyzw_to_wxyz(wxyz_to_xyzw(single)), single)
    with pytest.raises(ValueError, match="shape"):
        wxyz_to_xyzw(np.zeros(3))


def test_poses_sent_in_small_chunks_read_back_the_same(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Pose rows are buffered and sent by columns in chunks; the chunk size does not change what is recorded."""
    record(tmp_path / "one.rrd", steps=300)
    monkeypatch.setattr("homer_sim.recording.POSE_CHUNK_ROWS", 3)
    record(tmp_path / "many.rrd", steps=300)
    one, many = read_recording(tmp_path / "one.rrd"), read_recording(tmp_path / "many.rrd")
    assert sorted(one) == sorted(many)
    for body in _moving_bodies(mujoco.MjModel.from_xml_string(SCENE_XML)):
        a = one[f"world/bodies/{body}"].sort_by(PHYSICS_TIMELINE)
        b = many[f"world/bodies/{body}"].sort_by(PHYSICS_TIMELINE)
        assert a.num_rows == b.num_rows > 0
        for column in (PHYSICS_TIMELINE, ROUTINE_TIMELINE, "Transform3D:translation", "Transform3D:quaternion"):
            assert a.column(column).to_pylist() == b.column(column).to_pylist(), (body, column)


CRASHING_RUN = """
import sys, mujoco
from homer_sim.recording import Recording
model = mujoco.MjModel.from_xml_string(sys.argv[2]); data = mujoco.MjData(model); mujoco.mj_forward(model, data)
rec = Recording(sys.argv[1]); rec.set_routine_time(420.0); rec.log_geometry(model, data)
for _ in range(200):
    mujoco.mj_step(model, data); rec.log_body_poses(data)
raise RuntimeError("the run fails before close")
"""


def test_a_run_that_raises_before_close_keeps_its_buffered_poses(tmp_path: Path) -> None:
    path = tmp_path / "crashed.rrd"
    run = subprocess.run([sys.executable, "-c", CRASHING_RUN, str(path), SCENE_XML], capture_output=True, text=True,
                         cwd=Path(__file__).resolve().parents[2])
    assert run.returncode != 0 and "the run fails before close" in run.stderr
    record(tmp_path / "closed.rrd", steps=200)  # the same run, closed
    rows = read_recording(path)["world/bodies/falling_box"].num_rows
    assert rows == read_recording(tmp_path / "closed.rrd")["world/bodies/falling_box"].num_rows == 12
