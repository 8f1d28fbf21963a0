"""The standalone MJCF export: it loads from its folder alone and is the same model as the in-memory world."""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np
import pytest

from homer_sim.errors import HomerError
from homer_sim.home.export import MESH_DIR, export_mjcf, mesh_file_names
from homer_sim.world import World

MASS_RTOL = 1e-6
AABB_TOL = 1e-5  # m
DRIFT_TOL = 1e-6  # m, qpos of the exported vs the in-memory model after the same steps
SECONDS = 1.0


@pytest.fixture(scope="module")
def exported(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return export_mjcf(tmp_path_factory.mktemp("export") / "apartment")  # a folder that does not exist yet


@pytest.fixture(scope="module")
def reference(apartment: World) -> mujoco.MjModel:
    return apartment.model


@pytest.fixture(scope="module")
def loaded(exported: Path) -> mujoco.MjModel:
    return mujoco.MjModel.from_xml_path(str(exported))


def _mesh_aabb(model: mujoco.MjModel, mesh_id: int) -> np.ndarray:
    """(2, 3) lower and upper corners in m of a mesh's vertices in its mesh frame."""
    start, count = model.mesh_vertadr[mesh_id], model.mesh_vertnum[mesh_id]
    vertices = model.mesh_vert[start : start + count]
    return np.stack([vertices.min(axis=0), vertices.max(axis=0)])


def _names(model: mujoco.MjModel, kind: mujoco.mjtObj, count: int) -> list[str]:
    return [mujoco.mj_id2name(model, kind, i) for i in range(count)]


def test_export_writes_xml_and_one_file_per_mesh(exported: Path, reference: mujoco.MjModel) -> None:
    assert exported.name == "apartment.xml" and exported.is_file()
    mesh_files = sorted((exported.parent / MESH_DIR).glob("*.obj"))
    assert len(mesh_files) == reference.nmesh > 0
    text = exported.read_text()
    assert "vertex=" not in text and "face=" not in text
    assert 'meshdir="meshes"' in text


def test_export_has_the_same_elements(loaded: mujoco.MjModel, reference: mujoco.MjModel) -> None:
    for count in ("nbody", "ngeom", "njnt", "nsite", "nmesh"):
        assert getattr(loaded, count) == getattr(reference, count), count
    body = mujoco.mjtObj.mjOBJ_BODY
    assert _names(loaded, body, loaded.nbody) == _names(reference, body, reference.nbody)
    mesh = mujoco.mjtObj.mjOBJ_MESH
    assert _names(loaded, mesh, loaded.nmesh) == _names(reference, mesh, reference.nmesh)


def test_export_keeps_masses_and_meshes(loaded: mujoco.MjModel, reference: mujoco.MjModel) -> None:
    np.testing.assert_allclose(loaded.body_mass, reference.body_mass, rtol=MASS_RTOL, atol=0.0)
    np.testing.assert_array_equal(loaded.mesh_vertnum, reference.mesh_vertnum)
    for mesh_id in range(reference.nmesh):
        np.testing.assert_allclose(_mesh_aabb(loaded, mesh_id), _mesh_aabb(reference, mesh_id), atol=AABB_TOL)


def test_exported_model_steps_like_the_original(loaded: mujoco.MjModel, reference: mujoco.MjModel) -> None:
    steps = round(SECONDS / loaded.opt.timestep)
    data, data_reference = mujoco.MjData(loaded), mujoco.MjData(reference)
    mujoco.mj_step(loaded, data, nstep=steps)
    mujoco.mj_step(reference, data_reference, nstep=steps)
    assert np.all(np.isfinite(data.qpos)) and np.all(np.isfinite(data.qvel))
    assert sum(w.number for w in data.warning) == 0
    assert np.max(np.abs(data.qpos - data_reference.qpos)) < DRIFT_TOL


def test_second_export_needs_overwrite(exported: Path) -> None:
    with pytest.raises(HomerError, match="apartment.xml"):
        export_mjcf(exported.parent)
    assert export_mjcf(exported.parent, overwrite=True) == exported


def test_export_refuses_a_file_as_folder(tmp_path: Path) -> None:
    not_a_folder = tmp_path / "file"
    not_a_folder.write_text("")
    with pytest.raises(HomerError, match="not a directory"):
        export_mjcf(not_a_folder)


def test_mesh_file_names_are_safe_and_distinct() -> None:
    files = mesh_file_names(["bowl_wall03", "a/b", "a_b", "A_B", "x y"])
    assert files == {
        "bowl_wall03": "bowl_wall03.obj",
        "a/b": "a_b.obj",
        "a_b": "a_b_1.obj",
        "A_B": "A_B_2.obj",
        "x y": "x_y.obj",
    }
