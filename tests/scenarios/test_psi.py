"""Psi on hand-made scene graphs: first changes, thresholds, container order, skips and the hold rule."""

from __future__ import annotations

import numpy as np

from homer_sim.graph import INSIDE, ON, SceneGraph
from model.predictor import Rollout
from scenarios.psi import Holds, PlanStep, Relocation, plan_steps, psi, unused_help

NODES = ("kitchen", "cupboard", "fridge", "table", "sink", "bowl", "cereal", "milk", "spoon", "tray")
CATEGORIES = ("room", "furniture", "appliance", "furniture", "furniture", "object", "object", "object", "object",
              "object")
MOVABLE = np.array([c == "object" for c in CATEGORIES])
CONTAINERS = {"cupboard": ("cupboard/left", "cupboard/right"), "fridge": ("fridge/door",)}
IDX = {n: i for i, n in enumerate(NODES)}


def _graph(**where: str) -> SceneGraph:
    """The start: bowl, cereal and spoon in the cupboard, milk in the fridge, a tray on the table."""
    parents = {"cupboard": "kitchen", "fridge": "kitchen", "table": "kitchen", "sink": "kitchen",
               "bowl": "cupboard", "cereal": "cupboard", "milk": "fridge", "spoon": "cupboard", "tray": "table",
               **where}
    parent = np.array([-1] + [IDX[parents[n]] for n in NODES[1:]])
    relation = np.array([0] + [INSIDE if parents[n] in CONTAINERS else ON for n in NODES[1:]])
    return SceneGraph(NODES, CATEGORIES, parent, relation)


def _rollout(graph: SceneGraph, moves: dict[str, list[tuple[str, float]]], steps: int = 3) -> Rollout:
    """Per step s the predicted (parent, probability) of each listed object; others stay with probability 0.9.
    The second most likely parent of a mover is its observed one (probability 1 - p)."""
    parent = np.repeat(graph.parent.astype(np.int64)[None, None], steps, axis=0)
    confidence = np.full(parent.shape, 0.9, dtype=np.float32)
    other = np.full(parent.shape, IDX["sink"], dtype=np.int64)
    other_confidence = np.full(parent.shape, 0.05, dtype=np.float32)
    for name, per_step in moves.items():
        i = IDX[name]
        for s, (dest, p) in enumerate(per_step):
            parent[s, 0, i] = IDX[dest] if p >= 0.5 else graph.parent[i]
            confidence[s, 0, i] = max(p, 1 - p)
            if dest != NODES[graph.parent[i]]:
                other[s, 0, i], other_confidence[s, 0, i] = IDX[dest], p
    return Rollout(parent, confidence, other, other_confidence)


def _plan(graph, rollout, **kw):
    args = {"threshold": 0.0, "window_steps": 3, "containers": CONTAINERS, **kw}
    return psi(graph, MOVABLE, rollout, **args)


def test_nothing_is_planned_when_the_prediction_equals_the_state() -> None:
    graph = _graph()
    plan = _plan(graph, _rollout(graph, {}))
    assert plan.relocations == () and plan.steps == () and plan.skipped == ()


def test_only_the_first_predicted_change_counts() -> None:
    graph = _graph()
    rollout = _rollout(graph, {"bowl": [("cupboard", 0.1), ("table", 0.8), ("sink", 0.9)]})
    (relocation,) = _plan(graph, rollout).relocations
    assert (relocation.obj, relocation.source, relocation.destination) == ("bowl", "cupboard", "table")
    assert relocation.steps_ahead == 2 and abs(relocation.confidence - 0.8) < 1e-6
    # A window of one step ends before the first change: nothing to do.
    assert _plan(graph, rollout, window_steps=1).relocations == ()


def test_containers_are_opened_before_the_pick_and_closed_after_the_place() -> None:
    graph = _graph()
    rollout = _rollout(graph, {"cereal": [("table", 0.9)] * 3, "bowl": [("table", 0.9)] * 3,
                               "milk": [("cupboard", 0.2), ("table", 0.7), ("table", 0.7)]})
    plan = _plan(graph, rollout)
    assert [(s.action, s.target) for s in plan.steps] == [
        ("open", "cupboard/left"), ("open", "cupboard/right"),
        ("pick", "bowl"), ("place", "table"), ("pick", "cereal"), ("place", "table"),
        ("close", "cupboard/right"), ("close", "cupboard/left"),
        ("open", "fridge/door"), ("pick", "milk"), ("place", "table"), ("close", "fridge/door")]
    assert plan.steps[2] == PlanStep("pick", "bowl", "cupboard", "bowl")


def test_the_threshold_gates_moves_and_reports_them() -> None:
    graph = _graph()
    rollout = _rollout(graph, {"bowl": [("table", 0.4)] * 3, "cereal": [("table", 0.8)] * 3})
    assert {r.obj for r in _plan(graph, rollout, threshold=0.3).relocations} == {"bowl", "cereal"}
    plan = _plan(graph, rollout, threshold=0.5)
    assert [r.obj for r in plan.relocations] == ["cereal"]
    assert plan.skipped == ()  # bowl's argmax stays put: below 0.5 it is no move at all
    plan = _plan(graph, rollout, threshold=0.85)
    assert plan.relocations == ()
    (low, reason), = plan.skipped
    assert low.obj == "cereal" and "below the threshold 0.85" in reason


def test_carried_excluded_and_unplaceable_moves_are_skipped_with_reasons() -> None:
    graph = _graph()
    rollout = _rollout(graph, {"bowl": [("table", 0.9)] * 3, "cereal": [("table", 0.9)] * 3,
                               "spoon": [("bowl", 0.9)] * 3, "milk": [("table", 0.9)] * 3})
    plan = _plan(graph, rollout, carried=("bowl",), excluded=lambda o: "too flat" if o == "cereal" else None)
    assert [r.obj for r in plan.relocations] == ["milk"]
    reasons = {r.obj: why for r, why in plan.skipped}
    assert reasons["bowl"] == "in the person's hand" and reasons["cereal"] == "too flat"
    assert "destination bowl is a object" in reasons["spoon"]
    assert all(s.obj == "milk" for s in plan.steps if s.action in ("pick", "place"))


def test_an_open_door_standing_in_front_of_the_destination_is_closed_before_the_place() -> None:
    graph = _graph()
    moves = [Relocation("milk", "fridge", "table", 1, 0.9), Relocation("bowl", "cupboard", "table", 1, 0.9)]

    def steps(**kw):
        return [(s.action, s.target) for s in plan_steps(graph, MOVABLE, moves[:1], CONTAINERS, **kw)]

    assert steps() == [("open", "fridge/door"), ("pick", "milk"), ("place", "table"), ("close", "fridge/door")]
    assert steps(blocked={"fridge": {"table"}}) == [
        ("open", "fridge/door"), ("pick", "milk"), ("set_down", "milk"), ("close", "fridge/door"), ("pick", "milk"),
        ("place", "table")]
    assert steps(blocked={"fridge": {"sink"}}) == steps()
    assert steps(blocked={"fridge": {"table"}}, already_open={"fridge"}) == [("pick", "milk"), ("place", "table")]
    # The cupboard, kept open between two moves out of it, is closed for the place on the table, opened again after.
    moves = [Relocation("bowl", "cupboard", "sink", 1, 0.9), Relocation("milk", "fridge", "table", 1, 0.9),
             Relocation("cereal", "cupboard", "sink", 1, 0.9)]
    actions = [(s.action, s.target) for s in plan_steps(graph, MOVABLE, moves, CONTAINERS,
                                                        blocked={"cupboard": {"table"}})]
    assert actions == [
        ("open", "cupboard/left"), ("open", "cupboard/right"), ("pick", "bowl"), ("place", "sink"),
        ("open", "fridge/door"), ("pick", "milk"), ("set_down", "milk"), ("close", "fridge/door"),
        ("close", "cupboard/right"), ("close", "cupboard/left"), ("pick", "milk"), ("place", "table"),
        ("open", "cupboard/left"), ("open", "cupboard/right"), ("pick", "cereal"), ("place", "sink"),
        ("close", "cupboard/right"), ("close", "cupboard/left")]


def test_from_one_container_into_another_one_is_open_at_a_time() -> None:
    graph = _graph()
    plan = _plan(graph, _rollout(graph, {"milk": [("cupboard", 0.9)] * 3}))
    assert [(s.action, s.target, s.node) for s in plan.steps] == [
        ("open", "fridge/door", "fridge"), ("pick", "milk", "fridge"), ("set_down", "milk", ""),
        ("close", "fridge/door", "fridge"), ("open", "cupboard/left", "cupboard"),
        ("open", "cupboard/right", "cupboard"), ("pick", "milk", ""), ("place", "cupboard", "cupboard"),
        ("close", "cupboard/right", "cupboard"),
        ("close", "cupboard/left", "cupboard")]
    opened = _plan(graph, _rollout(graph, {"milk": [("cupboard", 0.9)] * 3}), already_open={"cupboard"})
    assert "set_down" not in [s.action for s in opened.steps]  # the destination open already: straight there
    # A container the person left open is neither opened nor closed by the robot.
    plan = _plan(graph, _rollout(graph, {"milk": [("cupboard", 0.9)] * 3}), already_open=("fridge",))
    assert ("open", "fridge/door") not in [(s.action, s.target) for s in plan.steps]
    assert ("close", "fridge/door") not in [(s.action, s.target) for s in plan.steps]


def test_a_room_is_a_destination_its_floor() -> None:
    graph = _graph()
    plan = _plan(graph, _rollout(graph, {"milk": [("kitchen", 0.9)] * 3}))
    assert [(r.obj, r.destination) for r in plan.relocations] == [("milk", "kitchen")] and plan.skipped == ()
    assert PlanStep("place", "kitchen", "kitchen", "milk") in plan.steps


def test_held_objects_stay_until_the_person_moves_them_or_the_window_passes() -> None:
    holds = Holds()
    on_table = _graph(bowl="table")
    holds.add("bowl", "table", minute=420.0, until=450.0)
    back = _rollout(on_table, {"bowl": [("cupboard", 0.9)] * 3})
    plan = _plan(on_table, back, holds=holds)
    assert plan.relocations == () and "held on table" in plan.skipped[0][1]
    (low, reason), = _plan(on_table, back, holds=holds, threshold=0.95).skipped  # below the threshold, but held
    assert low.obj == "bowl" and reason.startswith("held on table")
    assert holds.update(on_table, minute=440.0) == []  # still on the table, window not over
    released = holds.update(on_table, minute=451.0)  # the window passed: the robot may put it back
    assert [h.obj for h in released] == ["bowl"] and [r.obj for r in _plan(on_table, back, holds=holds).relocations] \
        == ["bowl"]
    holds.add("bowl", "table", minute=460.0, until=490.0)
    in_sink = _graph(bowl="sink")
    assert [h.obj for h in holds.update(in_sink, minute=470.0)] == ["bowl"]  # the person used it
    holds.add("cereal", "table", minute=460.0, until=490.0)
    assert [h.obj for h in holds.update(_graph(cereal="table"), 470.0, used={"cereal"})] == ["cereal"]


def test_help_the_person_did_not_use_goes_back_where_it_came_from_whatever_the_prediction() -> None:
    holds = Holds()
    on_table = _graph(bowl="table", cereal="table", milk="table")
    for obj, source in (("bowl", "cupboard"), ("cereal", "cupboard"), ("milk", "fridge")):
        holds.add(obj, "table", minute=400.0, until=430.0, source=source)
    grabbed_at = {"cereal": 425.0, "milk": 390.0}  # the person took the cereal; the milk only before the robot
    assert holds.update(on_table, 420.0, grabbed_at={"milk": 390.0}) == []
    released = holds.update(on_table, 440.0, grabbed_at=grabbed_at)
    assert sorted(h.obj for h in released) == ["bowl", "cereal", "milk"]
    returns = unused_help(released, on_table, grabbed_at=grabbed_at)
    assert [(r.obj, r.source, r.destination, r.put_back) for r in returns] == [
        ("bowl", "table", "cupboard", True), ("milk", "table", "fridge", True)]
    assert unused_help(released, _graph(bowl="sink", milk="table"), used={"milk"}) == []  # moved or in hand
    to_sink = _rollout(on_table, {"bowl": [("sink", 0.9)] * 3, "cereal": [("cupboard", 0.9)] * 3})
    plan = _plan(on_table, to_sink, returns=returns)
    assert {(r.obj, r.destination) for r in plan.relocations} == {("bowl", "cupboard"), ("milk", "fridge"),
                                                                  ("cereal", "cupboard")}
    assert [s.action for s in plan.steps if s.obj == "bowl"] == ["pick", "place"]


def test_nothing_is_taken_from_or_put_on_furniture_the_person_is_at() -> None:
    graph = _graph(bowl="table", cereal="table")
    rollout = _rollout(graph, {"bowl": [("cupboard", 0.9)] * 3, "milk": [("table", 0.9)] * 3,
                               "spoon": [("sink", 0.9)] * 3})
    plan = _plan(graph, rollout, in_use=("table",))
    assert [r.obj for r in plan.relocations] == ["spoon"]
    reasons = {r.obj: why for r, why in plan.skipped}
    assert reasons == {"bowl": "the person is at table", "milk": "the person is at table"}
    assert {r.obj for r in _plan(graph, rollout).relocations} == {"bowl", "milk", "spoon"}


def test_nothing_is_taken_to_or_from_outside() -> None:
    nodes = ("kitchen", "outside", "bench", "keys", "bag")
    categories = ("room", "room", "furniture", "object", "object")
    graph = SceneGraph(nodes, categories, np.array([-1, -1, 0, 2, 1]), np.array([0, 0, ON, ON, INSIDE]))
    parent = np.repeat(graph.parent.astype(np.int64)[None, None], 2, axis=0)
    parent[:, 0, 3], parent[:, 0, 4] = 1, 2  # keys go out, the bag comes in onto the bench
    confidence = np.full(parent.shape, 0.9, dtype=np.float32)
    rollout = Rollout(parent, confidence, parent.copy(), np.full(parent.shape, 0.05, dtype=np.float32))
    plan = psi(graph, np.array([c == "object" for c in categories]), rollout, threshold=0.0, window_steps=2,
               containers={})
    assert plan.relocations == () and plan.steps == ()
    assert sorted(r.obj for r, why in plan.skipped if "outside the apartment" in why) == ["bag", "keys"]


def test_a_failure_in_the_object_itself_waits_until_it_is_moved_others_a_window() -> None:
    """PsiPolicy's memory of failed relocations: 'fell out of the hand' is tried again after one window; 'lies
    fallen over' not until the object has been moved (the same attempt would fail the same way every tick)."""
    from types import SimpleNamespace

    from scenarios.causes import CAUSES
    from scenarios.policies import PsiPolicy
    from scenarios.task import NO_RELOCATION

    scene = SimpleNamespace(nodes=NODES, index=IDX, ungraspable={})
    policy = PsiPolicy(scene, SimpleNamespace(params={"threshold": 0.5}), window_min=30)
    graph = _graph()
    outcomes = np.full((4, 7), NO_RELOCATION, dtype=np.int32)
    for row, (obj, cause) in enumerate((("bowl", "fell out of the hand"), ("milk", "lies fallen over"))):
        outcomes[row] = (IDX[obj], IDX[graph.parent_of(obj)], IDX["table"], 0, IDX[graph.parent_of(obj)],
                         CAUSES.index(cause), 400)
    policy._learn(outcomes, graph)
    assert policy._excluded("bowl", 420, graph) and policy._excluded("milk", 420, graph)
    assert policy._excluded("bowl", 430, graph) is None  # a window later
    assert "until it has been moved" in policy._excluded("milk", 900, graph)
    assert policy._excluded("milk", 900, _graph(milk="table")) is None  # the person moved it


def test_help_put_back_unused_is_not_offered_again_until_the_person_moves_it() -> None:
    """A relocation of the robot's unused help back to its source, once done, keeps the object from being planned
    again: the same prediction would bring it out and the same window put it back, all day."""
    from types import SimpleNamespace

    from scenarios.policies import PsiPolicy
    from scenarios.psi import Relocation
    from scenarios.task import NO_RELOCATION

    scene = SimpleNamespace(nodes=NODES, index=IDX, ungraspable={})
    policy = PsiPolicy(scene, SimpleNamespace(params={"threshold": 0.5}), window_min=30)
    graph = _graph()
    home = graph.parent_of("bowl")
    policy._asked = {"bowl": Relocation("bowl", "table", home, 0, 1.0, put_back=True)}
    outcomes = np.full((4, 7), NO_RELOCATION, dtype=np.int32)
    outcomes[0] = (IDX["bowl"], IDX["table"], IDX[home], 1, IDX[home], 0, 400)
    policy._learn(outcomes, graph)
    assert "not offered again" in policy._excluded("bowl", 900, graph)
    assert policy._excluded("milk", 900, graph) is None  # only that object
    assert policy._excluded("bowl", 900, _graph(bowl="table")) is None  # the person moved it


def test_a_relocation_waiting_for_the_person_is_counted_when_it_can_no_longer_be_done() -> None:
    """A relocation the person stood in the way of waits for the next snapshot (`Helper.waiting`); if the person
    moves the object meanwhile, or the day ends first, it is recorded as not done, the person in the way its
    cause, never dropped uncounted."""
    from scenarios.assist import AssistLog, Helper
    from scenarios.causes import cause_of
    from scenarios.psi import Relocation

    helper = Helper.__new__(Helper)  # the bookkeeping only: no world, no robot
    helper.log, helper.recording = AssistLog(), None
    helper.waiting = [Relocation("bowl", "cupboard", "table", 1, 0.9)]
    assert helper.act([], _graph(bowl="sink"), MOVABLE, 400) == 400.0  # the person took the bowl meanwhile
    assert [(o.relocation.obj, o.done) for o in helper.log.relocations] == [("bowl", False)]
    assert helper.waiting == []
    helper.waiting = [Relocation("milk", "fridge", "table", 1, 0.9)]
    helper.end_day(1440)
    outcomes = helper.log.relocations
    assert [(o.relocation.obj, o.done) for o in outcomes] == [("bowl", False), ("milk", False)]
    assert {cause_of(o.reason) for o in outcomes} == {"the person in the way"}


def test_an_object_with_things_in_it_is_moved_only_with_them() -> None:
    """Carried along, what rests in a moved object would be displaced with no relocation naming it (a laundry basket
    went back to the bedroom with the clothes in it): such a move is skipped, unless those things move too."""
    graph = _graph(spoon="bowl")
    plan = _plan(graph, _rollout(graph, {"bowl": [("table", 0.9)] * 3}))
    assert plan.relocations == ()
    assert "spoon" in dict((r.obj, why) for r, why in plan.skipped)["bowl"]
    plan = _plan(graph, _rollout(graph, {"bowl": [("table", 0.9)] * 3, "spoon": [("sink", 0.9)] * 3}))
    assert {r.obj for r in plan.relocations} == {"bowl", "spoon"}


def test_the_places_of_the_persons_latest_moves_are_left_alone_for_a_window() -> None:
    """PsiPolicy takes the person to be using where they last moved things (what came from there and went there)
    for a window after, as the replay that tunes its threshold does (`model.metrics.robot_counts`); the robot's
    own relocations are not the person's moves."""
    from types import SimpleNamespace

    from scenarios.policies import PsiPolicy

    scene = SimpleNamespace(nodes=NODES, index=IDX, ungraspable={})
    policy = PsiPolicy(scene, SimpleNamespace(params={"threshold": 0.5}, movable=MOVABLE), window_min=30)
    policy._watch(_graph(), 400, set())
    assert policy._used_lately(400) == frozenset()  # nothing seen moving yet
    policy._watch(_graph(bowl="table"), 410, set())  # the person took the bowl out of the cupboard
    assert policy._used_lately(420) == {"cupboard", "table"}
    policy._watch(_graph(bowl="table"), 420, set())  # nothing moved since: the latest moves still count
    assert policy._used_lately(430) == {"cupboard", "table"}
    assert policy._used_lately(440) == frozenset()  # a window after them
    policy._watch(_graph(bowl="table", milk="sink"), 430, {IDX["milk"]})  # the robot's relocation
    assert policy._used_lately(430) == {"cupboard", "table"}
    policy._watch(_graph(bowl="table", milk="sink", spoon="bowl"), 440, set())  # into the bowl: at the table
    assert policy._used_lately(440) == {"cupboard", "bowl", "table"}
    graph = _graph(bowl="table", milk="sink", spoon="bowl")
    plan = _plan(graph, _rollout(graph, {"cereal": [("table", 0.9)] * 3}), in_use=policy._used_lately(440))
    assert plan.relocations == () and "the person is at" in plan.skipped[0][1]
