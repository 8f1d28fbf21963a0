"""The object catalog and its MuJoCo geometry: sizes, masses, resting stability and real cavities."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from homer_sim.errors import UnknownNameError
from homer_sim.home.catalog import CATALOG, FAMILIES, ObjectClass, object_class
from homer_sim.home.shapes import add_object_geoms, cavity, rest_height

SPACING = 1.2  # m between object origins on the test floor
DROP = 0.001  # m above rest height at spawn
CONTAINERS = ("bowl", "mug", "drinking_glass", "cookingpot", "trashcan", "basket_for_clothes")
# A marble-like test object (2 cm, 20 g) with the catalog's contact parameters.
BALL = ObjectClass("test_ball", "sphere", (0.02, 0.02, 0.02), 0.02, (1.0, 0.0, 0.0, 1.0))


def _scene() -> mujoco.MjSpec:
    """An empty scene: ground plane, 2 ms steps, elliptic cones, impratio 10, sleeping on."""
    spec = mujoco.MjSpec()
    spec.option.timestep = 0.002
    spec.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    spec.option.impratio = 10
    spec.option.enableflags |= mujoco.mjtEnableBit.mjENBL_SLEEP
    spec.worldbody.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[30, 30, 0.1])
    return spec


def _place(spec: mujoco.MjSpec, cls: ObjectClass, name: str, xy: tuple[float, float]) -> None:
    """A free body of class `cls` resting DROP above the floor at (x, y) in m."""
    body = spec.worldbody.add_body(name=name, pos=[xy[0], xy[1], rest_height(cls) + DROP])
    body.add_freejoint()
    add_object_geoms(spec, body, cls, name)


def _grid(index: int) -> tuple[float, float]:
    """Floor position in m of the index-th object on a 10-wide grid."""
    return (index % 10) * SPACING, (index // 10) * SPACING


@pytest.fixture(scope="module")
def all_classes() -> mujoco.MjModel:
    """One model holding one instance of every class, body i + 1 being the i-th class of CATALOG."""
    spec = _scene()
    for index, name in enumerate(CATALOG):
        _place(spec, CATALOG[name], name, _grid(index))
    return spec.compile()


def _geom_world_extent(
    model: mujoco.MjModel, data: mujoco.MjData, geom: int
) -> tuple[np.ndarray, np.ndarray]:
    """World AABB (low, high), each shape (3,) in m, of one box, cylinder, sphere or mesh geom."""
    pos, rot = data.geom_xpos[geom], data.geom_xmat[geom].reshape(3, 3)
    size, kind = model.geom_size[geom], model.geom_type[geom]
    if kind == mujoco.mjtGeom.mjGEOM_MESH:
        mesh = model.geom_dataid[geom]
        start, count = model.mesh_vertadr[mesh], model.mesh_vertnum[mesh]
        points = model.mesh_vert[start : start + count] @ rot.T + pos
        return points.min(axis=0), points.max(axis=0)
    if kind == mujoco.mjtGeom.mjGEOM_BOX:
        half = np.abs(rot) @ size
    elif kind == mujoco.mjtGeom.mjGEOM_SPHERE:
        half = np.full(3, size[0])
    else:
        assert kind == mujoco.mjtGeom.mjGEOM_CYLINDER, kind
        axis = rot[:, 2]
        half = np.abs(axis) * size[1] + size[0] * np.sqrt(np.clip(1.0 - axis**2, 0.0, 1.0))
    return pos - half, pos + half


def test_catalog_values() -> None:
    assert len(CATALOG) >= 75
    for name, cls in CATALOG.items():
        assert cls.name == name
        assert cls.family in FAMILIES, name
        assert cls.category in ("object", "prop"), name
        assert cls.mass > 0, name
        assert min(cls.size) >= 0.005, name
        assert len(cls.rgba) == 4, name
    assert CATALOG["knifeblock"].category == CATALOG["trashcan"].category == "prop"
    assert all(CATALOG[name].supports for name in ("plate", "bowl", "cutting_board", "trashcan"))
    assert CATALOG["umbrella"].lying and not CATALOG["water_bottle"].lying


def test_every_class_rests_still(all_classes: mujoco.MjModel) -> None:
    model = all_classes
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    start = data.xpos[1:].copy()
    while data.time < 5.0:
        mujoco.mj_step(model, data)
    assert np.all(np.isfinite(data.qpos)) and np.all(np.isfinite(data.qvel))
    assert [warning.number for warning in data.warning] == [0] * len(data.warning)
    moved = np.linalg.norm(data.xpos[1:] - start, axis=1)
    tilt_deg = np.degrees(np.arccos(np.clip(data.xmat[1:, 8], -1.0, 1.0)))
    names = list(CATALOG)
    worst_move, worst_tilt = int(np.argmax(moved)), int(np.argmax(tilt_deg))
    assert moved[worst_move] < 0.005, (names[worst_move], moved[worst_move])
    assert tilt_deg[worst_tilt] < 2.0, (names[worst_tilt], tilt_deg[worst_tilt])


def test_geoms_inside_bounding_box_and_mass(all_classes: mujoco.MjModel) -> None:
    model = all_classes
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    for index, (name, cls) in enumerate(CATALOG.items()):
        body = index + 1
        assert model.body(body).name == name
        assert model.body_mass[body] == pytest.approx(cls.mass, rel=1e-6), name
        half = np.asarray(cls.size) / 2.0
        geoms = range(model.body_geomadr[body], model.body_geomadr[body] + model.body_geomnum[body])
        extents = [_geom_world_extent(model, data, geom) for geom in geoms]
        low = np.min([extent[0] for extent in extents], axis=0) - data.xpos[body]
        high = np.max([extent[1] for extent in extents], axis=0) - data.xpos[body]
        assert np.all(low >= -half - 0.001) and np.all(high <= half + 0.001), (name, low, high, half)
        assert low[2] == pytest.approx(-half[2], abs=1e-6), name  # rests on its bottom


def test_grip_features_stand_on_top_of_their_bodies(all_classes: mujoco.MjModel) -> None:
    model = all_classes
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    handled = [(index + 1, cls) for index, cls in enumerate(CATALOG.values()) if cls.handle is not None]
    assert len(handled) >= 10
    for body, cls in handled:
        handle = model.geom(f"{cls.name}/handle").id
        assert model.geom_bodyid[handle] == body
        low, high = _geom_world_extent(model, data, handle) - data.xpos[body]
        length, width, height = cls.handle
        assert high - low == pytest.approx([length, width, height], abs=1e-6), cls.name
        assert high[2] == pytest.approx(cls.size[2] / 2, abs=1e-6), cls.name  # its top is the object's top
        main = model.geom(f"{cls.name}/main").id
        assert _geom_world_extent(model, data, main)[1][2] - data.xpos[body][2] == pytest.approx(
            cls.size[2] / 2 - height, abs=1e-6), cls.name  # the body ends where the feature begins


def test_names_are_prefixed_and_instances_coexist() -> None:
    spec = _scene()
    _place(spec, CATALOG["mug"], "mug_a", (0.0, 0.0))
    _place(spec, CATALOG["mug"], "mug_b", (0.5, 0.0))
    model = spec.compile()
    assert model.geom("mug_a/bottom").bodyid == model.body("mug_a").id
    assert model.mesh("mug_b_wall00").id >= 0
    walls = [model.geom(g).name for g in range(model.ngeom) if model.geom(g).name.startswith("mug_a/wall")]
    assert 10 <= len(walls) <= 16
    handle = model.geom("mug_a/handle_grip").id
    assert model.geom_pos[handle][0] > 0.0  # the handle is on +x


@pytest.mark.parametrize("name", CONTAINERS)
def test_cavity_is_real(name: str) -> None:
    cls = object_class(name)
    inside = cavity(cls)
    assert inside is not None and inside.rim_radius > BALL.size[0] and inside.rim_z > inside.floor_z
    spec = _scene()
    _place(spec, cls, name, (0.0, 0.0))
    origin_z = rest_height(cls) + DROP
    center = np.array([inside.center_xy[0], inside.center_xy[1], 0.0])
    ball = spec.worldbody.add_body(name="ball", pos=list(center + [0, 0, origin_z + inside.rim_z + 0.05]))
    ball.add_freejoint()
    add_object_geoms(spec, ball, BALL, "ball")
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)

    geomid = np.array([-1], dtype=np.int32)
    ray_start = center + [0.0, 0.0, origin_z + inside.rim_z + 0.001]
    distance = mujoco.mj_ray(model, data, ray_start, np.array([0.0, 0.0, -1.0]), None, 1, -1, geomid)
    assert model.geom(geomid[0]).name == f"{name}/bottom"
    assert distance == pytest.approx(inside.rim_z - inside.floor_z + 0.001, abs=1e-4)

    while data.time < 3.0:
        mujoco.mj_step(model, data)
    container = model.body(name).id
    local = data.xmat[container].reshape(3, 3).T @ (data.xpos[model.body("ball").id] - data.xpos[container])
    radial = math.hypot(local[0] - inside.center_xy[0], local[1] - inside.center_xy[1])
    assert radial < inside.rim_radius, (name, radial)
    assert inside.floor_z < local[2] < inside.rim_z, (name, local)
    assert [warning.number for warning in data.warning] == [0] * len(data.warning)


def test_unknown_class_names_closest() -> None:
    with pytest.raises(UnknownNameError) as caught:
        object_class("bowel")
    message = str(caught.value)
    assert "'bowel'" in message
    assert message.split("closest known: ")[1].startswith("bowl")
