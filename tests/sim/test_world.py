"""The apartment compiles, steps cleanly, settles where it was declared, and its articulations move."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from homer_sim.check import MAX_DRIFT_M, run_world_check
from homer_sim.errors import UnknownNameError
from homer_sim.observe import SceneGraphObserver
from homer_sim.world import World


def test_inventory_matches_homer_vocabulary(world: World) -> None:
    graph = world.declared_graph()
    count = {c: graph.categories.count(c) for c in set(graph.categories)}
    assert count["room"] == 5 and set(graph.nodes[:5]) == {"bathroom", "dining_room", "bedroom", "home_office",
                                                           "outside"}
    assert count["furniture"] >= 20 and count["appliance"] >= 5
    assert count["object"] + count.get("prop", 0) >= 75
    for name in ("cupboard", "kitchen_cabinet", "kitchen_counter_left", "kitchen_counter_right", "sink_dining_room",
                 "sink_bathroom", "table_dining_room", "table_bedroom", "bathroom_cabinet", "bathroom_counter",
                 "shower", "dresser", "bookshelf_dining_room", "bookshelf_home_office", "bookshelf_bedroom",
                 "sofa_home_office", "sofa_bedroom", "desk_home_office", "tvstand_home_office", "bench", "shoe_rack",
                 "fridge", "dishwasher", "stove", "washing_machine", "coffe_maker"):
        assert name in graph.nodes, name
    for name in ("bowl", "plate", "mug", "spoon", "fork", "knife", "food_cereal", "milk", "food_bread", "toothbrush",
                 "tooth_paste", "towel", "remote_control", "book", "keys", "shoes", "keyboard"):
        assert name in world.object_names, name


def test_articulations_have_handles_limits_damping(world: World) -> None:
    hinged = {a.furniture for a in world.articulations.values() if a.joint_type == "hinge"}
    assert {"cupboard", "kitchen_cabinet", "bathroom_cabinet", "fridge", "dishwasher", "washing_machine"} <= hinged
    sliding = {a.furniture for a in world.articulations.values() if a.joint_type == "slide"}
    assert {"dresser", "desk_home_office"} <= sliding
    model = world.model
    for a in world.articulations.values():
        assert model.jnt_limited[a.joint_id] and a.range[1] > a.range[0]
        assert model.dof_damping[a.dof_adr] > 0
        assert model.site(f"{a.name}/handle").id >= 0
    assert model.opt.enableflags & int(mujoco.mjtEnableBit.mjENBL_SLEEP)
    assert model.opt.cone == mujoco.mjtCone.mjCONE_ELLIPTIC


def test_ten_seconds_no_warnings_no_nan_no_drift_graph_matches() -> None:
    result = run_world_check(seconds=10.0)
    assert result["warnings"] == 0
    assert not result["nan"]
    assert result["physics_s"] == pytest.approx(10.0)
    assert result["max_drift_m"] < MAX_DRIFT_M
    assert result["graph_matches_layout"], result["mismatches"]


def test_openness_set_and_read(world: World) -> None:
    world.reset()
    assert all(v == pytest.approx(0.0, abs=1e-9) for v in world.all_openness().values())
    world.set_openness("fridge", 1.0)
    world.set_openness("dresser/drawer_1", 0.5)
    assert world.openness("dresser/drawer_1") == pytest.approx(0.5, abs=1e-9)
    world.step(250)
    assert world.openness("fridge") > 0.99  # damped, no spring: an open door stays open
    with pytest.raises(UnknownNameError, match="dresser/drawer_0"):
        world.openness("dresser")  # three drawers: the name is ambiguous, the error lists them


def test_drawer_carries_its_contents(world: World) -> None:
    world.reset()
    observer = SceneGraphObserver(world)
    world.settle(3.0)
    observer.observe_all()
    before, _ = world.object_pose("clothes_socks")
    joint = world.articulation("dresser/drawer_0")
    speed = 0.25  # m/s, a hand pulling the handle
    for _ in range(600):  # 1.2 s: the drawer moves 0.3 m
        world.data.qvel[joint.dof_adr] = speed
        world.step(1)
    world.data.qvel[joint.dof_adr] = 0.0
    world.settle(3.0)
    travel = world.data.qpos[joint.qpos_adr]
    after, _ = world.object_pose("clothes_socks")
    assert travel == pytest.approx(0.3, abs=0.03)
    assert np.linalg.norm(after[:2] - before[:2]) == pytest.approx(travel, abs=0.02)
    graph = observer.update()
    assert (graph.parent_of("clothes_socks"), graph.relation_of("clothes_socks")) == ("dresser", "INSIDE")


def test_a_vacuum_cleaner_fallen_on_its_side_stops_rolling_on_the_floor(world: World) -> None:
    """Furniture and floors resist rolling: a vacuum cleaner (a 28 cm cylinder) fallen on its side and set rolling at
    0.3 m/s comes to rest within a metre (with no rolling friction it rolled across the kitchen for minutes)."""
    k = world.object_index("vacuum_cleaner")
    adr = int(world.object_qpos_adr[k])
    dof = int(world.object_dof_adr[k])
    world.data.qpos[adr:adr + 3] = (3.0, 1.3, 0.14)  # on the kitchen floor between the counters and the table
    world.data.qpos[adr + 3:adr + 7] = (np.sqrt(0.5), np.sqrt(0.5), 0.0, 0.0)  # its axis along y: it rolls along x
    world.data.qvel[dof:dof + 6] = (0.3, 0.0, 0.0, 0.0, 0.3 / 0.14, 0.0)
    mujoco.mj_forward(world.model, world.data)
    start = world.object_pose("vacuum_cleaner")[0]
    world.step(int(5.0 / world.model.opt.timestep))
    assert world.objects_at_rest()[k]
    assert 0.02 < np.linalg.norm(world.object_pose("vacuum_cleaner")[0] - start) < 1.0
