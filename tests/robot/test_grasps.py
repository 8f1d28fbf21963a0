"""Grasp poses from an object's shape (no physics): widths, depths and directions checked in numbers."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from homer_sim.home.catalog import CATALOG
from homer_sim.home.shapes import handle_boxes
from planners.grasps.above import (
    RAISED_HOLD,
    lying_as,
    offset_grasps,
    raised_grasps,
    rim_approach,
    squared_grasps,
    top_grasps,
)
from planners.grasps.candidate import (
    FINGER_HALF_THICKNESS,
    GRIPPER_OPEN,
    MAX_WIDTH,
    OFFSET_MARGIN,
    PAD_HALF,
    SHELF_APPROACH,
    SUPPORT_CLEARANCE,
    TOP_MARGIN,
    TOP_NARROW_MARGIN,
    Family,
    GraspKind,
    disturbed,
)
from planners.grasps.features import handle_grasps
from planners.grasps.geometry import footprint
from planners.grasps.ranking import rank_from_above
from planners.grasps.shelf import (
    PALM_MARGIN,
    ROLL,
    ROLL_TIP_CLEARANCE,
    ROUND_PAST,
    along_offset,
    along_span,
    palm_aside,
    palm_blockers,
    palm_gap,
    palm_shift,
    rolled_grasps,
    shelf_grasps,
    side_grasps,
)

OUT = np.array([1.0, 0.0])  # out of the furniture's front, towards the robot


def _yawed(angle_deg: float) -> np.ndarray:
    half = math.radians(angle_deg) / 2
    return np.array([math.cos(half), 0.0, 0.0, math.sin(half)])


def test_a_round_object_turned_on_a_shelf_is_as_wide_as_its_diameter() -> None:
    paper = CATALOG["toilet_paper"]  # 11 cm across: its turned bounding box (14 cm at 20 degrees) would not fit
    position = np.array([0.0, 0.0, paper.size[2] / 2])
    grasps = side_grasps(paper, position, _yawed(20.0), OUT, front=-np.inf)
    assert grasps and paper.size[0] <= MAX_WIDTH
    assert grasps[0].pre_opening == pytest.approx(min(GRIPPER_OPEN, paper.size[0] / 2 + 0.01))


def test_side_grasps_of_a_round_object_reach_past_its_centre() -> None:
    wipes = CATALOG["disinfectant_wipes"]
    position = np.array([0.0, 0.0, wipes.size[2] / 2])
    for grasp in side_grasps(wipes, position, _yawed(0.0), OUT, front=-np.inf):
        along = float(grasp.position[0])  # grip site out of the object's centre, towards the robot
        assert along - PAD_HALF <= -ROUND_PAST + 1e-9  # the pads' far end lies past the centre
    # held at its front edge (the palm kept in front of a front plane 6 cm out): no grasp rather than a squeeze
    assert side_grasps(wipes, position, _yawed(0.0), OUT, front=0.06) == []


def test_a_turned_box_gets_grasps_square_to_its_own_faces() -> None:
    veg = CATALOG["food_vegetable"]  # 15 x 10 cm: turned 30 degrees, 16 cm across the front, 10 cm square to a face
    position = np.array([0.0, 0.0, veg.size[2] / 2])
    grasps = shelf_grasps(veg, position, _yawed(30.0), OUT, front=0.2)
    faced = [g for g in grasps if g.label.endswith("-faced")]
    # across the front nothing fits; only front to back, last ("-along", the pads in the approach's plane), and
    # side grasps halfway to the face (see the next test)
    assert faced and not [g for g in grasps if not g.label.endswith(("-faced", "-along", "-halfway"))]
    for grasp in faced:  # the fingers close along one of the object's own axes
        finger = grasp.rotation[:, 1]
        assert min(abs(math.degrees(math.atan2(finger[1], finger[0])) - a) for a in (30, 120, -60, -150)) < 1e-6
    assert shelf_grasps(veg, position, _yawed(0.0), OUT, front=0.2) != []  # square already: no "-faced" copies
    assert not [g for g in shelf_grasps(veg, position, _yawed(0.0), OUT, 0.2) if g.label.endswith("-faced")]


def test_a_box_turned_past_four_degrees_also_gets_side_grasps_halfway_to_its_face() -> None:
    """The rice (16 x 6 cm, long side front to back) turned 18 degrees: after those square to its face, side
    grasps approached 9 degrees off the front, the pads past the front plane no further than square ones."""
    rice = CATALOG["food_rice"]
    position = np.array([0.0, 0.0, rice.size[2] / 2])
    grasps = shelf_grasps(rice, position, _yawed(18.0), OUT, front=0.12)
    kinds = [g.label for g in grasps]
    halfway = [g for g in grasps if g.label.endswith("-halfway")]
    assert [g.label for g in halfway] == ["side-halfway", "side-high-halfway"]
    assert max(kinds.index(g.label) for g in grasps if g.label.endswith("-faced") and "-along" not in g.label) < (
        kinds.index("side-halfway"))
    for grasp in halfway:
        x = grasp.rotation[:, 0]
        assert math.degrees(math.atan2(-x[1], -x[0])) == pytest.approx(9.0)
        assert (grasp.position[:2] @ -x[:2]) <= 0.12 / math.cos(math.radians(9.0)) - 0.027 + 1e-9
        assert grasp.pre_opening <= GRIPPER_OPEN
    assert not [g for g in shelf_grasps(rice, position, _yawed(3.5), OUT, 0.12) if g.label.endswith("-halfway")]


def test_grasps_from_above_open_wide_then_narrow_and_stop_above_the_support() -> None:
    paste = CATALOG["tooth_paste"]  # 19 x 4.5 x 3.5 cm: only across its narrow side
    position = np.array([0.0, 0.0, paste.size[2] / 2])
    grasps = top_grasps(paste, position, _yawed(0.0), np.array([-1.0, 0.0]))
    assert [g.label for g in grasps] == ["top", "top-narrow"]
    assert [g.pre_opening for g in grasps] == pytest.approx([paste.size[1] / 2 + TOP_MARGIN,
                                                             paste.size[1] / 2 + TOP_NARROW_MARGIN])
    tip_z = grasps[0].position[2] - PAD_HALF  # the hand points down: the fingertips are below the grip site
    assert tip_z == pytest.approx(SUPPORT_CLEARANCE)


def test_handled_objects_are_taken_by_the_handle_from_above_or_pitched_into_a_shelf() -> None:
    bag = CATALOG["bag"]  # 35 x 15 x 30 cm, its 14 x 2.5 x 6 cm handle along its x
    length, width, height = bag.handle
    body_top = bag.size[2] - height
    position = np.array([0.0, 0.0, bag.size[2] / 2])
    from_above = handle_grasps(bag, position, _yawed(30.0))
    assert [g.label for g in from_above] == ["handle", "handle-turned", "handle-narrow", "handle-turned-narrow"]
    first = from_above[0]
    finger = first.rotation[:, 1]
    assert abs(math.degrees(math.atan2(finger[1], finger[0]))) == pytest.approx(120.0)  # across the handle
    assert first.pre_opening == pytest.approx(width / 2 + TOP_MARGIN)
    assert first.position[2] - PAD_HALF >= body_top + SUPPORT_CLEARANCE - 1e-9  # the fingertips stay off the body
    assert first.position[2] < bag.size[2]  # and the pads hold the handle
    assert [g.label for g in top_grasps(bag, position, _yawed(30.0), np.zeros(2))] == [g.label for g in from_above]
    pitched = shelf_grasps(bag, position, _yawed(0.0), OUT, front=0.2)  # the handle runs front to back
    assert pitched and all(g.label.startswith("handle-") and g.rotation[2, 0] < -0.4 for g in pitched)  # down
    for g in pitched:
        pitch = math.asin(-g.rotation[2, 0])
        tip_drop = PAD_HALF * math.sin(pitch) + FINGER_HALF_THICKNESS * math.cos(pitch)
        assert g.position[2] - tip_drop >= body_top + SUPPORT_CLEARANCE - 1e-9
        assert g.pre_opening == pytest.approx(width / 2 + TOP_MARGIN)
    across = shelf_grasps(bag, position, _yawed(90.0), OUT, front=0.2)  # 14 cm along the front: opened fully
    assert across and all(g.pre_opening == GRIPPER_OPEN for g in across)
    comforter = CATALOG["comforter"]  # its 50 cm fold along the front: no grasp
    assert shelf_grasps(comforter, np.array([0.0, 0.0, comforter.size[2] / 2]), _yawed(90.0), OUT, 0.3) == []


def test_the_palm_keeps_in_front_of_a_tall_neighbour_by_its_upper_edge() -> None:
    """Pitched 30 degrees down, the palm's front face leans in as it rises: its upper edge (0.035 m behind the
    grip site and 0.03 m off it, in the face) lies 0.035 cos 30 - 0.03 sin 30 = 0.0153 m out of the grip site,
    so a tall neighbour whose front is 0.08 m out needs the grip site 0.08 + PALM_MARGIN - 0.0153 m out."""
    pitch = math.radians(30.0)
    upper = 0.035 * math.cos(pitch) - 0.03 * math.sin(pitch)
    assert palm_shift(pitch, 0.13, [(0.08, 0.36)]) == pytest.approx(0.08 + PALM_MARGIN - upper)
    # one whose top lies below the face's low edge (0.035 sin 30 - 0.03 cos 30 = -0.0085 m) is passed over
    assert palm_shift(pitch, 0.13, [(0.08, 0.13 - 0.0085 - PALM_MARGIN - 0.001)]) == 0.0


def test_only_neighbours_within_the_palm_width_block_it() -> None:
    out, across = np.array([0.0, 1.0, 0.0]), np.array([-1.0, 0.0, 0.0])
    box = CATALOG["oil"]  # 7 cm square
    beside = footprint(box, np.array([0.08, 0.045, 0.2]), _yawed(0.0))  # 8 cm aside, its front 8 cm out
    far = footprint(box, np.array([0.3, 0.045, 0.2]), _yawed(0.0))  # 30 cm aside: past the 18 cm palm
    blockers = palm_blockers([(beside, 0.36), (far, 0.36)], np.zeros(3), out, across)
    assert len(blockers) == 1
    assert blockers[0] == (pytest.approx(0.045 + 0.035), 0.36)


def test_a_grasp_in_a_drawer_comes_down_over_the_drawer_front() -> None:
    cd = CATALOG["cd"]  # 1 cm thin: the grip site 2.8 cm over the drawer's floor, the fingertips 3 mm over it
    position = np.array([0.0, 0.0, 0.575])
    grasp = top_grasps(cd, position, _yawed(0.0), np.array([1.0, 0.0]))[0]
    approach = rim_approach(grasp, 0.712, 0.03)  # the front's top 13.7 cm over the floor
    tips = grasp.position[2] + approach - PAD_HALF  # the open fingertips' height at the approach point
    assert tips == pytest.approx(0.712 + 0.03)
    assert approach > grasp.approach
    assert rim_approach(grasp, 0.6, 0.03) == grasp.approach  # a low front: the usual approach is high enough


def test_a_rolled_straight_down_grasp_keeps_the_pads_and_lowers_the_wrist() -> None:
    deck = CATALOG["deck_of_cards"]  # 2 cm high on a shelf: straight down, the wrist meets the shelf above
    position = np.array([0.0, 0.0, 0.82 + deck.size[2] / 2])
    grasps = shelf_grasps(deck, position, _yawed(0.0), OUT, 0.06)
    down = next(g for g in grasps if g.label == "shelf-90" and abs(g.rotation[:2, 1] @ OUT) > 0.99)
    rolled = [g for g in grasps if g.label.startswith("shelf-90-rolled")]
    assert [g.label for g in rolled] == ["shelf-90-rolled+", "shelf-90-rolled-"]
    direct = rolled_grasps(down, 0.82, 0.84)
    assert all(np.allclose(a.rotation, b.rotation) and np.allclose(a.position, b.position)
               for a, b in zip(rolled, direct, strict=True))
    tip_drop = PAD_HALF * math.cos(ROLL) + FINGER_HALF_THICKNESS * math.sin(ROLL)
    for g in rolled:
        assert np.allclose(g.rotation[:, 1], down.rotation[:, 1])  # the pads close on the same faces
        assert float(-g.rotation[2, 0]) == pytest.approx(math.cos(ROLL))  # the grip x leans ROLL off down
        assert g.position[2] - tip_drop == pytest.approx(0.82 + SUPPORT_CLEARANCE)  # the lowest fingertip corner
        start = g.position[2] - g.approach * g.rotation[2, 0]
        assert start - tip_drop == pytest.approx(0.84 + ROLL_TIP_CLEARANCE)  # over the top on the way in
        wrist_drop = 0.29 - 0.29 * float(-g.rotation[2, 0])
        assert wrist_drop > 0.06  # the wrist 0.29 m up the grip x: 6.8 cm lower than straight down


def test_an_off_centre_grasp_keeps_the_near_finger_beside_the_object() -> None:
    charger = CATALOG["charger"]  # 6 x 4.5 cm: across its 4.5 cm side the fingers open fully, 8 cm each
    position = np.array([0.0, 0.0, charger.size[2] / 2])
    grasp = top_grasps(charger, position, _yawed(0.0), np.array([1.0, 0.0]))[0]
    moved = offset_grasps(charger, _yawed(0.0), grasp)
    assert [g.label for g in moved] == ["top-offset+", "top-offset-"]
    for g in moved:
        shift = float(np.linalg.norm(g.position - grasp.position))
        assert g.pre_opening == GRIPPER_OPEN
        assert GRIPPER_OPEN - shift - 0.045 / 2 == pytest.approx(OFFSET_MARGIN)  # the near finger still clears it
        assert abs(float((g.position - grasp.position) @ grasp.rotation[:, 1])) == pytest.approx(shift)
    wide = replace(charger, size=(0.2, 0.14, 0.03))  # 14 cm across: the palm would move only 5 mm, no try
    assert offset_grasps(wide, _yawed(0.0), top_grasps(wide, position, _yawed(0.0), np.zeros(2))[0]) == []


def test_in_a_drawer_off_centre_grasps_that_push_along_its_runners_come_last() -> None:
    charger = CATALOG["charger"]  # 6 x 4.5 cm: taken across its narrow side (y) or, turned, along x
    position = np.array([0.0, 0.0, charger.size[2] / 2])
    top, turned = top_grasps(charger, position, _yawed(0.0), np.array([1.0, 0.0]))[:2]
    assert abs(top.rotation[1, 1]) == pytest.approx(1.0) and abs(turned.rotation[0, 1]) == pytest.approx(1.0)
    along_x, along_y = offset_grasps(charger, _yawed(0.0), turned), offset_grasps(charger, _yawed(0.0), top)
    pairs = [(g, True) for g in along_x + along_y]
    assert rank_from_above(pairs) == along_x + along_y  # out of a drawer: as given (one group)
    assert rank_from_above(pairs, np.array([-1.0, 0.0, 0.0])) == along_y + along_x  # a drawer sliding along x
    assert rank_from_above(pairs, np.array([0.0, 1.0])) == along_x + along_y  # along y
    centred = [(turned, False)]  # a centred grasp keeps its place, whatever its travel
    assert rank_from_above(pairs + centred, np.array([1.0, 0.0]))[0] is turned


def test_squared_grasps_turn_the_palm_to_the_drawer_walls_and_open_past_the_turned_box() -> None:
    charger = CATALOG["charger"]  # 6 x 4.5 cm, turned 15 degrees in a drawer whose front faces -x
    position = np.array([0.0, 0.0, charger.size[2] / 2])
    squared = squared_grasps(charger, position, _yawed(-75.0), math.pi)
    assert [g.label for g in squared] == ["top-squared", "top-turned-squared", "top-narrow-squared",
                                         "top-turned-narrow-squared"]
    top = squared[0]
    assert abs(top.rotation[0, 1]) == pytest.approx(1.0)  # the finger travel along the drawer's depth
    span = 0.06 * math.cos(math.radians(75.0)) + 0.045 * math.sin(math.radians(75.0))  # the turned box along it
    assert top.pre_opening == pytest.approx(span / 2 + TOP_MARGIN, abs=1e-6)  # to the micrometre
    assert squared[2].pre_opening == pytest.approx(span / 2 + TOP_NARROW_MARGIN, abs=1e-6)
    assert squared_grasps(charger, position, _yawed(-89.0), math.pi) == []  # a degree off square: no new grasp
    assert squared_grasps(CATALOG["candle"], np.array([0.0, 0.0, 0.05]), _yawed(-75.0), math.pi) == []  # round




def test_a_box_turned_past_four_degrees_is_taken_square_to_its_face_first() -> None:
    dryer = CATALOG["hairdryer"]  # 24 x 9 cm, its long side into the furniture
    position = np.array([0.0, 0.0, dryer.size[2] / 2])
    turned = shelf_grasps(dryer, position, _yawed(6.0), OUT, front=0.2)  # 6.8 degrees slipped 14 mm
    assert turned[0].label.endswith("-faced") and any(not g.label.endswith("-faced") for g in turned)
    slightly = shelf_grasps(dryer, position, _yawed(3.5), OUT, front=0.2)
    assert not slightly[0].label.endswith("-faced") and any(g.label.endswith("-faced") for g in slightly)


def test_a_bin_is_pinched_deep_at_its_far_rim_lifted_clear_and_hung() -> None:
    from homer_sim.home.shapes import cavity
    from planners.grasps.features import HANG_RISE, RIM_CLEARANCE, RIM_DEEP

    cls = CATALOG["basket_for_clothes"]  # 44 x 44 x 32 cm, straight walls
    sz = cls.size[2]
    position = np.array([0.0, 0.0, sz / 2])
    hollow = cavity(cls)
    grasps = top_grasps(cls, position, _yawed(0.0), np.array([-1.0, 0.0]))  # the robot on -x
    first = grasps[0]
    assert first.label == "rim" and first.hang
    assert first.position[0] == pytest.approx(hollow.rim_radius + 0.004)  # the far rim, +x
    assert first.position[2] == pytest.approx(sz - RIM_DEEP)  # the pads' whole 5 cm length on the wall
    assert first.rotation[:, 1] @ np.array([1.0, 0.0, 0.0]) == pytest.approx(1.0)  # closing radially
    # whatever it tilts about the pinch, the bottom edge across the bin stays RIM_CLEARANCE above the floor
    far = math.hypot(2 * hollow.rim_radius, RIM_DEEP - sz)
    assert first.position[2] + first.lift - far >= RIM_CLEARANCE - 1e-9
    # and hanging straight below the pinch, its centre ends HANG_RISE above where it stood
    offset = first.position - position
    assert first.lift - (np.linalg.norm(offset) - offset[2]) >= HANG_RISE - 1e-9
    near = [g.position[0] < 0 for g in grasps]  # its near rim, after every far pinch, not hung
    assert 0 < sum(near) < len(near) and near == sorted(near)
    assert all(not g.hang for g, n in zip(grasps, near, strict=True) if n)
    bowl = top_grasps(CATALOG["bowl"], np.array([0.0, 0.0, 0.035]), _yawed(0.0), np.array([-1.0, 0.0]))[0]
    assert bowl.label == "rim" and not bowl.hang and bowl.lift == 0.0 and bowl.position[0] < 0  # flared: near rim


def _fingers_on_a_handle(cls, position: np.ndarray, yaw_deg: float, grasp) -> bool:
    """Whether the footprint of a rim pinch's fingers from above (both fingers, opened, each FINGER_HALF_THICKNESS
    either side of the travel) reaches onto one of a pot's side handles, sampled."""
    from planners.grasps.features import FINGER_HALF_TRAVEL

    yaw = math.radians(yaw_deg)
    turn = np.array([[math.cos(yaw), math.sin(yaw)], [-math.sin(yaw), math.cos(yaw)]])  # world to body
    travel, across = turn @ grasp.rotation[:2, 1], turn @ grasp.rotation[:2, 2]
    point = turn @ (grasp.position[:2] - position[:2])
    reach = grasp.pre_opening + FINGER_HALF_TRAVEL
    for a in np.linspace(-reach, reach, 41):
        for b in np.linspace(-FINGER_HALF_THICKNESS, FINGER_HALF_THICKNESS, 9):
            p = point + a * travel + b * across
            if any(abs(p[0] - c[0]) <= h[0] and abs(p[1] - c[1]) <= h[1] for c, h in handle_boxes(cls)):
                return True
    return False


@pytest.mark.parametrize("name", ["cookingpot", "sauce_pan"])
def test_rim_pinches_of_a_pot_skip_the_rim_at_its_side_handles(name: str) -> None:
    """With a side handle pointing at or away from the robot, the rim point the pinches start from (a pot's straight
    wall: the far one) lies at a handle: the outer finger comes down on the handle plate. Such points are skipped
    for points farther round the rim, still three on each side (the far rim's, then the near rim's)."""
    cls = CATALOG[name]
    position = np.array([0.0, 0.0, cls.size[2] / 2])
    for yaw in (0.0, 15.0, 180.0, 200.0):  # a handle at or near the robot (on +x)
        grasps = top_grasps(cls, position, _yawed(yaw), np.array([1.0, 0.0]))
        assert [g.label for g in grasps] == ["rim"] * 6, yaw
        assert all(g.position[0] < 0 for g in grasps[:3]) and all(g.position[0] > 0 for g in grasps[3:]), yaw
        assert not any(_fingers_on_a_handle(cls, position, yaw, g) for g in grasps), yaw
    clear = top_grasps(cls, position, _yawed(90.0), np.array([1.0, 0.0]))  # the handles to either side
    assert clear[0].position[0] < 0 and abs(clear[0].position[1]) < 1e-9  # straight walls: the far rim first, as before


def test_a_pot_on_a_shelf_gets_no_front_rim_pinch_at_a_handle() -> None:
    from homer_sim.home.shapes import cavity
    from planners.grasps.features import tilted_rims

    cls = CATALOG["cookingpot"]
    position, out = np.array([0.0, 0.0, cls.size[2] / 2]), np.array([1.0, 0.0, 0.0])
    assert tilted_rims(cavity(cls), position, 0.0, 0.0, out, ()) != []
    assert tilted_rims(cavity(cls), position, 0.0, 0.0, out, handle_boxes(cls)) == []  # the +x handle at the front
    assert tilted_rims(cavity(cls), position, math.pi / 2, 0.0, out, handle_boxes(cls)) != []  # handles aside


def test_hanging_turns_the_hand_until_the_load_is_straight_below() -> None:
    from planners.grasps.features import hang_rotation
    from planners.grasps.geometry import top_rotation

    rotation = top_rotation(0.0)  # pointing down, fingers along x, z along -y
    grip = np.array([0.2, 0.0, 0.5])
    com = grip + np.array([-0.14, 0.0, -0.25])
    turned = hang_rotation(rotation, grip, com)
    assert turned @ turned.T == pytest.approx(np.eye(3))
    assert turned[:, 2] == pytest.approx(rotation[:, 2])  # about the horizontal axis square to the load
    moved = turned @ rotation.T @ (com - grip)
    assert moved == pytest.approx([0.0, 0.0, -math.hypot(0.14, 0.25)])


def test_a_pot_on_a_shelf_is_taken_by_the_handle_facing_the_front_short_of_its_wall() -> None:
    from homer_sim.home.shapes import WALL_THICKNESS, handle_boxes
    from planners.grasps.features import POT_HANDLE_GAP, pot_handle_grasps

    cls = CATALOG["cookingpot"]  # handles on body -x and +x
    position = np.array([0.0, 0.0, cls.size[2] / 2])
    out = np.array([1.0, 0.0, 0.0])
    grasps = pot_handle_grasps(cls, position, _yawed(10.0), out)
    assert [g.label for g in grasps] == ["pot-handle-0", "pot-handle-30", "pot-handle-45", "pot-handle-60"]
    (centre, half), _ = handle_boxes(cls)
    h = np.array([math.cos(math.radians(10.0)), math.sin(math.radians(10.0)), 0.0])  # the +x handle, turned
    face = centre[0] - half[0] + WALL_THICKNESS["pot"]
    for g in grasps:
        assert g.hang and g.lift > 0.15
        assert g.rotation[:, 0] @ h < 0 and abs(g.rotation[:, 0] @ np.cross([0, 0, 1.0], h)) < 1e-9  # towards the pot
        tip = g.position + PAD_HALF * g.rotation[:, 0] - position  # the pads' inner end
        assert tip[:2] @ h[:2] == pytest.approx(face + POT_HANDLE_GAP)
        assert g.position[2] - position[2] == pytest.approx(centre[2])
    assert grasps[0].rotation[:, 1] == pytest.approx([0, 0, 1.0])  # level: closing on the plate's thickness
    assert grasps[0].pre_opening == pytest.approx(half[2] + 0.015)
    assert abs(grasps[1].rotation[2, 1]) < 1e-9 and grasps[1].pre_opening == pytest.approx(half[1] + 0.015)
    assert pot_handle_grasps(cls, position, _yawed(90.0), out) == []  # neither handle faces the front


def test_along_grasps_close_front_to_back_past_what_the_pads_sweep() -> None:
    """A 7 cm jar (10 cm tall) on a cupboard's floor between a tall bottle 8.7 cm aside and a side wall: the
    18 cm palm face on does not fit, edge on (6 cm) it does. Pitched 60 degrees, gripped 2 cm below its top, the
    pads sweep the back's top edge (sin 60 * 0.035 + cos 60 * 0.02 = 0.0403 m along the travel) and the front down
    to where the fingertip passes (0.035 cos 60 + 0.0866 h = -PAD_HALF: h = -0.0491 m, -0.0549 m along it)."""
    pitch = math.radians(60.0)
    least, greatest = along_span(0.07, -0.08, 0.02, pitch, SHELF_APPROACH)
    low = -(PAD_HALF + 0.035 * math.cos(pitch)) / math.sin(pitch)
    assert greatest == pytest.approx(0.035 * math.sin(pitch) + 0.02 * math.cos(pitch), abs=1e-6)
    assert least == pytest.approx(-0.035 * math.sin(pitch) + low * math.cos(pitch), abs=1e-3)
    # the palm's face, 0.035 m behind the grip site, clears the top front corner by 0.035 - (cos 60 * 0.035 +
    # sin 60 * 0.02) = 0.0002 m
    assert palm_gap(0.07, -0.08, 0.02, pitch, (least + greatest) / 2) == pytest.approx(
        0.035 - 0.035 * math.cos(pitch) - 0.02 * math.sin(pitch), abs=1e-9)
    jam, oil = CATALOG["food_jam"], CATALOG["oil"]
    position = np.array([0.0, 0.0, jam.size[2] / 2])
    bottle = (footprint(oil, np.array([0.02, 0.122, 0.14]), _yawed(0.0)), 0.28)  # 12.2 cm aside, 2 cm further out
    along = [g for g in shelf_grasps(jam, position, _yawed(0.0), OUT, 0.085, [bottle]) if g.label.endswith("-along")]
    # at 30 degrees the open out-finger's tip (0.061 m out and down the travel) would strike the floor
    assert [g.label for g in along] == ["shelf-45-along", "shelf-60-along"]
    for g in along:
        tip = g.position - g.pre_opening * g.rotation[:, 1] + PAD_HALF * g.rotation[:, 0]
        assert tip[2] >= SUPPORT_CLEARANCE
        assert g.position[1] == pytest.approx(0.0)  # the bottle leaves the 6 cm palm room: not moved aside
    g = along[-1]
    assert g.rotation[:, 1] == pytest.approx([-math.sin(pitch), 0.0, math.cos(pitch)], abs=1e-9)  # in and up
    assert g.rotation[:, 0] == pytest.approx([-math.cos(pitch), 0.0, -math.sin(pitch)], abs=1e-9)
    # the palm kept PALM_MARGIN off the top front corner: the grip site backs out along the approach
    back = PALM_MARGIN - palm_gap(0.07, -0.08, 0.02, pitch, (least + greatest) / 2)
    assert (g.position - np.array([0.0, 0.0, 0.08])) @ g.rotation[:, 0] == pytest.approx(-back, abs=1e-9)
    close = (footprint(oil, np.array([0.02, 0.055, 0.14]), _yawed(0.0)), 0.28)  # 2 cm off the jar's side
    assert not [g for g in shelf_grasps(jam, position, _yawed(0.0), OUT, 0.085, [close]) if g.label.endswith("-along")]


def test_a_turned_box_gets_along_grasps_in_its_own_plane_first() -> None:
    """The tea (13 x 7.5 cm, long side front to back) turned 19 degrees: pads closing front to back in the
    approach's plane meet one of its faces across an edge, and it crept 8 mm out of them in the suite's hold;
    "-along-faced" grasps close in the box's own vertical plane, and come before those; none for a square box."""
    tea = CATALOG["tea"]
    position = np.array([0.0, 0.0, tea.size[2] / 2])
    grasps = shelf_grasps(tea, position, _yawed(180.0 + 19.0), OUT, 0.2)
    kinds = [g.label for g in grasps]
    faced = [g for g in grasps if g.label.endswith("-along-faced")]
    plain = [k for k in kinds if k.endswith("-along")]
    assert faced and plain and max(kinds.index(g.label) for g in faced) < min(kinds.index(k) for k in plain)
    axis = np.array([math.cos(math.radians(19.0)), math.sin(math.radians(19.0))])
    for grasp in faced:  # the finger travel's level part lies along the box's long axis
        finger = grasp.rotation[:2, 1] / np.linalg.norm(grasp.rotation[:2, 1])
        assert abs(finger @ axis) == pytest.approx(1.0)
    assert not [k for k in (g.label for g in shelf_grasps(tea, position, _yawed(180.0), OUT, 0.2)) if "faced" in k]


def test_an_along_grasp_moves_aside_for_the_palm_only_as_far_as_the_pads_stay_on() -> None:
    """Neighbour points 3.5 cm aside: the 6 cm palm needs 0.03 + PALM_MARGIN = 0.04 m: the grip site moves the
    least step (of 9 within reach 0.0224 m either way, 0.0056 m apart) that clears them, 0.0056 m away. Points 2.9
    cm one side and 5 cm the other leave 7.9 cm, less than the 8 needed: the step with the most room, -0.0112 m."""
    assert along_offset([0.035], 0.0224) == pytest.approx(-0.0056)
    assert along_offset([0.029, -0.05], 0.0224) == pytest.approx(-0.0112)
    assert along_offset([], 0.0224) == 0.0


def test_a_ball_is_taken_front_to_back_before_across_pitched() -> None:
    """Held across with the hand pitched 30 degrees, the grip site 2 cm below its top and pushed 2.7 cm out by
    neighbours (the fridge's low shelf), an 8 cm apple meets the pads cos 30 * 0.027 + sin 30 * 0.02 = 0.033 m
    along them, past their 2.5 cm half length, and creeps 5 mm in 3 s: front to back first."""
    apple = CATALOG["food_apple"]
    kinds = [g.label for g in shelf_grasps(apple, np.array([0.0, 0.0, apple.size[2] / 2]), _yawed(0.0), OUT, 0.1)]
    along = [k for k in kinds if k.endswith("-along")]
    across = [k for k in kinds if k.startswith("shelf-") and not k.endswith("-along")]
    assert along and across and kinds.index(along[-1]) < kinds.index(across[0])


def test_a_pitched_grasp_moves_aside_off_a_neighbour_in_front_at_the_palm_edge() -> None:
    """The butter behind the milk's corner (as in the fridge): centred, the 18 cm palm must stand in front of the
    milk, where the pads hold only the butter's front edge; moved along the front away from it, the palm's band
    misses the milk and the pads close on the butter, the near finger OFFSET_MARGIN beside it."""
    butter, milk = CATALOG["food_butter"], CATALOG["milk"]  # 11 x 7 x 4 cm; 7 cm square, 20 cm tall
    position = np.array([0.0, 0.0, 0.47])
    neighbour = (footprint(milk, np.array([0.04, 0.113, 0.55]), _yawed(0.0)), 0.65)  # 4 cm out, 11 cm aside
    quat = _yawed(0.0)  # 11 cm deep, 7 cm along the front
    grasps = [g for g in shelf_grasps(butter, position, quat, OUT, 0.1, [neighbour]) if g.label.startswith("shelf-")]
    aside = [g for g in grasps if g.label.endswith("-aside")]
    assert [g.label for g in aside] == ["shelf-30-aside", "shelf-45-aside", "shelf-60-aside"]
    for g in aside:
        moved = g.position[1]  # OUT is +x: along the front is y; away from the milk
        assert moved < -0.005
        assert g.pre_opening <= GRIPPER_OPEN
        assert g.pre_opening - abs(moved) >= 0.07 / 2 + OFFSET_MARGIN - 1e-9  # the near finger passes beside it
        assert g.position[0] <= 0.11 / 2 - 0.015 / 2 + 1e-9  # the pads on the butter, not its front edge
    out, across = np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])
    # nothing in the way: no move; nowhere to go: None
    assert palm_aside(math.radians(30), 0.478, [], position, out, across, 0.11, 0.02)[0] == 0.0
    assert palm_aside(math.radians(30), 0.478, [neighbour], position, out, across, 0.16, 0.0) is None


def test_an_object_shoved_or_turned_by_a_failed_grasp_counts_as_disturbed() -> None:
    here = np.array([0.4, 0.65, 0.475])
    assert not disturbed(here, _yawed(69.0), here + [0.003, 0.0, 0.0], _yawed(70.0))  # settling: 3 mm, 1 degree
    assert disturbed(here, _yawed(69.0), here + [0.007, -0.017, 0.0], _yawed(69.0))  # shoved 1.8 cm
    assert disturbed(here, _yawed(69.0), here, _yawed(62.0))  # turned 7 degrees
    assert disturbed(here, _yawed(178.0), here, _yawed(-178.0))  # 4 degrees across the half turn


def test_raised_grasps_pass_over_a_low_neighbour_and_still_hold_the_top() -> None:
    """A charger (3 cm tall) with a CD (1 cm) lying flat beside it: from above at the usual height the fingertips
    come down to 0.3 cm over the support, into the CD; raised, they stay 0.5 cm over the CD's top and the pads
    still hold the charger's top 1.5 cm."""
    charger = CATALOG["charger"]
    position = np.array([0.0, 0.0, charger.size[2] / 2])
    grasps = top_grasps(charger, position, _yawed(0.0), np.array([-1.0, 0.0]))
    assert min(g.position[2] for g in grasps) - PAD_HALF == pytest.approx(SUPPORT_CLEARANCE)
    raised = raised_grasps(charger, position, grasps)
    assert [g.label for g in raised] == [f"{g.label}-raised" for g in grasps]
    for low, high in zip(grasps, raised, strict=True):
        assert high.position[:2] == pytest.approx(low.position[:2]) and np.array_equal(high.rotation, low.rotation)
        assert high.position[2] - PAD_HALF == pytest.approx(charger.size[2] - RAISED_HOLD)  # the pads' lower end
        assert high.position[2] - PAD_HALF > CATALOG["cd"].size[2] + 0.004  # over the CD
    assert raised_grasps(charger, position, raised) == []  # raised already
    rim = replace(grasps[0], kind=GraspKind(Family.RIM))
    assert raised_grasps(charger, position, [rim]) == []  # only grasps from above



def _turn(axis: tuple[float, float, float], angle: float) -> np.ndarray:
    """Rotation matrix of `angle` rad about unit `axis` (Rodrigues)."""
    k = np.array(axis, dtype=float)
    cross = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * cross + (1 - math.cos(angle)) * cross @ cross


def test_a_fallen_object_is_grasped_as_the_box_it_makes_lying() -> None:
    cylinder = CATALOG["painkillers"]  # 4 cm across, 8 cm tall
    d, h = cylinder.size[0], cylinder.size[2]
    for roll in (0.0, 0.7, 2.0):  # a cylinder on its side lies so at any roll about its axis
        rotation = _turn((0.0, 0.0, 1.0), 0.4) @ _turn((0.0, 1.0, 0.0), math.pi / 2) @ _turn((0.0, 0.0, 1.0), roll)
        lying = lying_as(cylinder, rotation)
        assert lying is not None
        cls, yaw = lying
        assert cls.size == pytest.approx((h, d, d))  # its axis along the new x, level
        assert math.remainder(yaw - 0.4 - math.pi, math.pi) == pytest.approx(0.0, abs=1e-9)
        assert top_grasps(cls, np.zeros(3), np.array([math.cos(yaw / 2), 0, 0, math.sin(yaw / 2)]), np.zeros(2))
    box = CATALOG["food_bread"]  # 25 x 11 x 11 cm, rolled a quarter about its length onto a side
    cls, _ = lying_as(box, _turn((1.0, 0.0, 0.0), math.pi / 2))
    assert cls.size == pytest.approx((box.size[0], box.size[2], box.size[1]))
    assert lying_as(box, _turn((1.0, 0.0, 0.0), math.pi / 4)) is None  # on an edge
    assert lying_as(cylinder, _turn((1.0, 0.0, 0.0), math.pi / 4)) is None  # leaning, not lying
    assert lying_as(CATALOG["mug"], _turn((1.0, 0.0, 0.0), math.pi / 2)) is None  # a handle and a cavity
