"""The layout validator accepts the apartment and rejects bad layouts with an error naming the node."""

from __future__ import annotations

from dataclasses import replace

import pytest

from homer_sim.errors import LayoutError
from homer_sim.graph import INSIDE, ON
from homer_sim.home.apartment import default_layout
from homer_sim.home.floorplan import floor_plan
from homer_sim.home.layout import Layout, ObjectDecl, Wall
from homer_sim.home.validate import blocked_when_open, validate_layout
from homer_sim.robot_spec import ROBOT


def _with_objects(layout: Layout, *extra: ObjectDecl) -> Layout:
    return replace(layout, objects=layout.objects + extra)


def _with_furniture_change(layout: Layout, name: str, **changes) -> Layout:
    return replace(layout, furniture=tuple(replace(f, **changes) if f.name == name else f for f in layout.furniture))


def test_default_layout_is_valid() -> None:
    validate_layout(default_layout())


def test_every_doorway_fits_the_robot() -> None:
    layout = default_layout()
    widths = [end - start for wall in layout.walls for start, end in wall.doorways]
    assert len(widths) == 4 and min(widths) >= ROBOT.min_doorway
    plan = floor_plan(layout)
    for wall in layout.walls:  # the robot's disk passes through the middle of each doorway
        for start, end in wall.doorways:
            mid = (start + end) / 2
            (ax, ay), (bx, by) = wall.start, wall.end
            x, y = ax + (bx - ax) * mid / wall.length, ay + (by - ay) * mid / wall.length
            assert plan.disk_is_free(x, y, ROBOT.footprint_radius + 0.1), (wall.name, x, y)


@pytest.mark.parametrize(
    ("layout", "node", "message"),
    [
        (lambda L: _with_objects(L, ObjectDecl("bowl_2", "bowl", "cupboardd", INSIDE)), "bowl_2", "unknown parent"),
        (lambda L: _with_objects(L, ObjectDecl("milk", "milk", "fridge", INSIDE)), "milk", "duplicate"),
        (lambda L: _with_objects(L, ObjectDecl("mug_2", "mug", "table_dining_room", INSIDE)), "mug_2",
         "not a container"),
        (lambda L: _with_objects(L, ObjectDecl("mug_2", "mugg", "table_dining_room", ON)), "mug_2",
         "unknown object class"),
        (lambda L: _with_objects(L, ObjectDecl("mug_2", "mug", "milk", ON)), "mug_2", "does not hold"),
        (lambda L: replace(L, walls=L.walls[:-1] + (Wall((3.5, 4.5), (3.5, 8.0), ((1.0, 1.8),), "narrow"),)),
         "narrow", "narrower"),
        (lambda L: _with_furniture_change(L, "bookshelf_bedroom", size=(0.8, 0.35, 1.6), params={"shelves": (1.45,)}),
         "bookshelf_bedroom", "out of the robot's reach"),
        (lambda L: _with_furniture_change(L, "cupboard", params={"shelves": (0.45, 1.3)}, size=(0.8, 0.6, 1.8)),
         "cupboard", "out of the robot's reach"),
        (lambda L: _with_furniture_change(L, "table_dining_room", pos=(1.9, 1.2)), "cupboard", "swing"),
        (lambda L: _with_furniture_change(L, "sofa_bedroom", facing="W"), "sofa_bedroom", "base pose"),
        (lambda L: _with_furniture_change(L, "bench", room="kitchen"), "bench", "unknown room"),
        (lambda L: _with_furniture_change(L, "bench", pos=(-0.5, 4.0)), "bench", "leaves room"),
    ],
    ids=["unknown-parent", "duplicate-name", "inside-non-container", "unknown-class", "object-not-support",
         "narrow-doorway", "shelf-too-high", "cupboard-shelf-too-high", "door-swing-blocked", "no-base-pose",
         "unknown-room", "outside-its-room"],
)
def test_bad_layouts_are_rejected_naming_the_node(layout, node: str, message: str) -> None:
    with pytest.raises(LayoutError, match=message) as error:
        validate_layout(layout(default_layout()))
    assert node in str(error.value)


def test_object_that_does_not_fit_is_rejected() -> None:
    books = (ObjectDecl(f"book_{k}", "book", "table_bedroom", ON) for k in range(12))
    crowded = _with_objects(default_layout(), *books)
    with pytest.raises(LayoutError, match="does not fit") as error:
        validate_layout(crowded)
    assert "book_" in str(error.value) and "table_bedroom" in str(error.value)


def test_rows_on_an_open_top_leave_a_finger_between_them() -> None:
    """On an open top the start layout keeps ROW_GAP between an object and the one behind it where the top has
    room (a dish rack packed 2.5 cm behind the chef's knife on the oven left no room for a finger), and falls back
    to SPOT_GAP where it has not."""
    from homer_sim.home.catalog import CATALOG
    from homer_sim.home.furniture import Place
    from homer_sim.home.placement import ROW_GAP, SPOT_GAP, pack_spot

    knife, rack = CATALOG["chef_knife"], CATALOG["dishrack"]
    deep = Place(ON, (0.0, 0.0, 0.85), (0.285, 0.335), 0.6)
    taken: list[tuple] = []
    front = pack_spot(deep, knife, taken, row_gap=ROW_GAP)
    behind = pack_spot(deep, rack, taken, row_gap=ROW_GAP)
    gap = (front[0] - knife.size[1] / 2) - (behind[0] + rack.size[1] / 2)  # place x runs to the front
    assert gap >= ROW_GAP - 1e-9
    shallow = Place(ON, (0.0, 0.0, 0.85), (0.18, 0.335), 0.6)  # 36 cm deep: no room for ROW_GAP
    taken = []
    pack_spot(shallow, knife, taken, row_gap=ROW_GAP)
    assert pack_spot(shallow, rack, list(taken), row_gap=ROW_GAP) is None
    assert pack_spot(shallow, rack, taken, row_gap=SPOT_GAP) is not None


def test_neighbours_reached_from_the_front_leave_a_finger_between_them() -> None:
    """Inside furniture, but for a drawer, the start layout keeps `inside_side_gap` beside each object: ROW_GAP
    where the place's objects fit side by side so (the cheese packed 2.5 cm beside the milk left a side grasp's
    finger no room), PALM_ROOM where one of them is lower than the palm is thick (the razor, held only by a palm
    pitched down over it), as much as they leave spread evenly where they do not (the shower's corner shelf), never
    under SPOT_GAP."""
    import itertools
    import math

    from homer_sim.home.catalog import CATALOG
    from homer_sim.home.furniture import furniture_geometry
    from homer_sim.home.placement import PALM_ROOM, ROW_GAP, SPOT_GAP, inside_side_gap, lengthwise, start_poses
    from homer_sim.robot_spec import ROBOT

    layout = default_layout()
    poses = start_poses(layout)
    furniture = layout.furniture_by_name()
    checked, palm = 0, 0
    for f in layout.furniture:
        for level, place in enumerate(furniture_geometry(f).places):
            objects = [o for o in layout.objects if o.parent == f.name and o.level == level]
            if place.relation != INSIDE or place.part is not None or len(objects) < 2:
                continue
            gap = inside_side_gap(layout, f, level, place)
            low = any(CATALOG[o.cls].size[2] < 2 * ROBOT.palm_half_size[2] for o in objects)
            assert SPOT_GAP <= gap <= (PALM_ROOM if low else ROW_GAP)
            c, s = math.cos(furniture[f.name].yaw), math.sin(furniture[f.name].yaw)
            boxes = []  # (from, to) across the cabinet's width, (from, to) along its depth
            for o in objects:
                cls = CATALOG[o.cls]
                wide, deep = (cls.size[1], cls.size[0]) if lengthwise(f, place, cls) else cls.size[:2]
                dx, dy = poses[o.name].pos[0] - f.pos[0], poses[o.name].pos[1] - f.pos[1]
                across, depth = -s * dx + c * dy, c * dx + s * dy
                boxes.append((across - wide / 2, across + wide / 2, depth - deep / 2, depth + deep / 2))
            for a, b in itertools.combinations(boxes, 2):
                if a[2] < b[3] and b[2] < a[3]:  # side by side in one row
                    assert max(b[0] - a[1], a[0] - b[1]) >= gap - 1e-6, (f.name, level)
            checked += gap >= ROW_GAP - 1e-9
            palm += low and gap >= PALM_ROOM - 1e-9
    assert checked >= 3  # the fridge's, the bathroom cabinet's shelves have room for a finger
    assert palm >= 2  # the bathroom cabinet's razor and soap shelves have room for the palm, 18 cm wide


def test_an_open_door_blocks_the_furniture_it_stands_in_front_of() -> None:
    layout = default_layout()
    blocked = blocked_when_open(layout)
    # The bathroom cabinet's door, hinged at the end towards the counter, swings open across the counter's front.
    assert "bathroom_counter" in blocked["bathroom_cabinet"]
    assert all(f not in furniture for f, furniture in blocked.items())
    assert "cupboard" not in blocked  # its door opens beside the counter's edge: the counter stays free
    # Hinged at the other end, the same door swings away from the counter.
    turned = tuple(replace(f, params={**f.params, "hinge": "right"}) if f.name == "bathroom_cabinet" else f
                   for f in layout.furniture)
    assert "bathroom_cabinet" not in blocked_when_open(replace(layout, furniture=turned))
