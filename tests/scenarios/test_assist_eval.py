"""`homer assist-eval` on a tiny dataset made here (1 household, 2 training days, 1 test day), up to 06:30: the
oracle sets the breakfast table at 06:00 for the person's 06:25 breakfast."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from homer_sim.data.generate import generate
from homer_sim.observe import SceneGraphObserver
from scenarios.assist_eval import markdown_table, summarise
from scenarios.causes import CAUSES, OTHER, cause_of
from scenarios.cli.main import main
from scenarios.env import run_episode
from scenarios.episodes import make_setup
from scenarios.policies import EmptyPolicy
from scenarios.scoring import day_result

pytestmark = pytest.mark.physics  # steps a whole apartment for seconds or more

UNTIL = 390  # 06:30
KEYS = {"relocations_planned", "relocations_done", "relocations_correct", "relocations_wrong", "fetches",
        "fetches_done_by_robot", "fetch_share", "collateral", "days", "wall_s_per_day"}


@pytest.fixture(scope="module")
def data(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("tiny") / "data"
    generate(out, 1, 2, 1, seed=0, progress=False)
    return out


def test_the_oracle_day_adds_up_and_beats_an_empty_plan(data: Path, tmp_path: Path,
                                                       capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "oracle"
    status = main(["assist-eval", "--data", str(data), "--method", "oracle", "--until", str(UNTIL), "--out", str(out),
                   "--quiet", "--json"])
    assert status == 0
    result = json.loads(capsys.readouterr().out)
    assert result["method"] == "oracle" and set(result["per_household"]) == {"household_a"}
    for row in (result["total"], result["per_household"]["household_a"]):
        assert KEYS <= set(row)
        not_done = row["relocations_planned"] - row["relocations_done"]
        assert not_done == sum(result["failures"].values()), result  # every relocation not done has a cause
        assert row["relocations_correct"] + row["relocations_wrong"] == row["relocations_done"]
    total = result["total"]
    assert total["days"] == 1 and total["fetches"] >= 4
    assert total["fetches_done_by_robot"] >= 2, result  # the oracle set out breakfast before the person came
    outcomes = result["fetch_outcomes"]  # every fetch made ahead or given a reason why not
    assert sum(outcomes.values()) == total["fetches"] and outcomes["made ahead"] == total["fetches_done_by_robot"]
    assert {p.name for p in out.iterdir()} >= {"assist_eval.json", "assist_eval.md", "assist_eval.png", "days"}
    assert "| household_a |" in (out / "assist_eval.md").read_text()

    # The same day with nothing asked of the robot: no fetch made ahead, nothing moved.
    setup = make_setup("dataset_day", data=str(data), household="household_a", end_min=UNTIL)
    assert run_episode(setup.env, EmptyPolicy(setup.env.scene)) == 0.0
    task = setup.env.task
    empty = day_result(task.log, task.reference, task.scene.nodes, task.scene.categories, (), 30,
                       until=UNTIL)
    assert empty["fetches"] == total["fetches"] and empty["fetches_done_by_robot"] == 0
    assert empty["fetch_outcomes"] == {"not predicted": total["fetches"]}
    day = json.loads((out / "days" / "household_a_000.json").read_text())
    assert day["return"] == total["fetches_done_by_robot"] - total["relocations_wrong"] > 0


def test_unknown_households_are_named_with_the_known_ones(data: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["assist-eval", "--data", str(data), "--households", "household_z", "--method", "oracle",
                 "--quiet"]) == 2
    assert "household_a" in capsys.readouterr().err


def test_failure_reasons_are_grouped_by_cause() -> None:
    reasons = {
        "place: clothes_dress fell out of the hand while carried": "fell out of the hand",
        "water_bottle: it has fallen over (lies on its side), and no grasp fits it so": "lies fallen over",
        "place: water_bottle ended ON table_home_office, not on bookshelf_home_office": "ended elsewhere",
        "place: no free base pose puts drinking_glass into dishwasher without it or the arm": "no free base pose",
        "cupboard did not open (open cupboard/left: openness 0.42, below 0.9)": "container did not open",
        "place: fork fell over on sink_dining_room": "fell over on the destination",
        "knocked off table_dining_room later in the robot's turn (75 cm, now on dining_room)": "knocked off later",
        "something new": OTHER,
    }
    assert {reason: cause_of(reason) for reason in reasons} == reasons
    assert set(reasons.values()) <= set(CAUSES)


def test_totals_add_days_up_and_take_the_median_wall_time() -> None:
    def day(household: str, planned: int, done: int, correct: int, fetches: int, helped: int, wall: float) -> dict:
        return {"household": household, "relocations_planned": planned, "relocations_done": done,
                "relocations_correct": correct, "relocations_wrong": done - correct, "fetches": fetches,
                "fetches_done_by_robot": helped, "collateral": 1, "robot_minutes": 2.0, "wall_s": wall,
                "error": "", "failures": {"no path": planned - done}}

    days = [day("a", 4, 3, 2, 10, 2, 30.0), day("a", 2, 2, 2, 10, 1, 50.0), day("b", 1, 0, 0, 5, 0, 10.0)]
    summary = summarise("markov", days, ["a", "b"])
    assert summary["per_household"]["a"] == {
        "relocations_planned": 6, "relocations_done": 5, "relocations_correct": 4, "relocations_wrong": 1,
        "fetches": 20, "fetches_done_by_robot": 3, "collateral": 2, "fetch_share": 0.15, "days": 2,
        "robot_minutes": 4.0, "wall_s_per_day": 40.0, "person_stopped": 0}
    assert summary["total"]["fetch_share"] == 0.12 and summary["total"]["wall_s_per_day"] == 30.0
    assert summary["failures"] == {"no path": 2}
    assert "| a | 2 | 6 | 5 | 4 | 1 |" in markdown_table(summary)


def test_a_relocation_knocked_off_later_in_the_turn_is_not_done(world) -> None:
    """The spoon set down beyond the bowl knocked the bowl off the table: the bowl's relocation, done when it was
    placed, is not done at the end of the robot's turn."""
    from types import SimpleNamespace

    from homer_sim.observe import SceneGraphObserver
    from scenarios.assist import AssistLog, Helper, RelocationOutcome
    from scenarios.psi import Relocation

    helper = Helper.__new__(Helper)  # the turn's bookkeeping only: no robot or person needed
    helper.world, helper.recording, helper.log = world, None, AssistLog()
    helper.robot = SimpleNamespace(observer=SceneGraphObserver(world))
    bowl, kept = Relocation("bowl", "cupboard", "table_dining_room", 1, 0.9), Relocation("milk", "fridge",
                                                                                         "table_dining_room", 1, 0.9)
    world.set_object_pose("bowl", (2.6, 2.2, 0.8))
    world.set_object_pose("milk", (2.3, 2.0, 0.86))
    world.settle(3.0)
    helper._placed_at = {r.obj: world.object_pose(r.obj)[0].copy() for r in (bowl, kept)}
    helper.log.relocations = [RelocationOutcome(360, r, True, "", "table_dining_room") for r in (bowl, kept)]
    world.set_object_pose("bowl", (2.8, 2.8, 0.1))  # onto the floor under the table
    world.settle(3.0)
    helper._knocked_off(0)
    knocked, still = helper.log.relocations
    assert not knocked.done and cause_of(knocked.reason) == "knocked off later" and knocked.ended_on == "dining_room"
    assert still.done and still.ended_on == "table_dining_room"


def test_a_skill_that_raises_fails_its_relocation_and_the_turn_goes_on(world) -> None:
    """A bug in a skill (here pick raising KeyError for the bowl) is that relocation's failure with the exception
    named, not the end of the day: the milk's relocation after it is still carried out."""
    from types import SimpleNamespace

    from homer_sim.observe import SceneGraphObserver
    from planners.skills import SkillResult
    from scenarios.assist import AssistLog, Helper
    from scenarios.psi import PlanStep, Relocation

    def pick(obj: str, node: str, into: str) -> SkillResult:
        if obj == bowl.obj:
            raise KeyError("dining_room")
        robot.held = obj
        return SkillResult(True)

    def place(target: str) -> SkillResult:
        robot.held = None
        return SkillResult(True)

    helper = Helper.__new__(Helper)  # the turn's bookkeeping only: the skills are the two above
    helper.world, helper.recording, helper.log, helper.waiting, helper._placed_at = world, None, AssistLog(), [], {}
    robot = helper.robot = SimpleNamespace(observer=SceneGraphObserver(world), held=None, pick=pick, place=place)
    bowl, milk = (Relocation("bowl", "cupboard", "table_dining_room", 1, 0.9),
                  Relocation("milk", "fridge", "table_dining_room", 1, 0.9))
    steps = [PlanStep("pick", r.obj, r.source, r.obj) for r in (bowl, milk)]
    steps = [steps[0], PlanStep("place", bowl.destination, bowl.destination, "bowl"), steps[1],
             PlanStep("place", milk.destination, milk.destination, "milk")]
    helper._carry_out(steps, [bowl, milk], 360, float(world.data.time))
    failed, carried = helper.log.relocations
    assert failed.relocation == bowl and not failed.done and cause_of(failed.reason) == "skill error"
    assert "KeyError" in failed.reason
    assert carried.relocation == milk and carried.done
    assert [s.success for s in helper.log.steps] == [False, True, True]


def test_a_put_down_that_raises_after_a_skill_error_stops_the_plan_not_the_day(world) -> None:
    """A place raising with the bowl in the hand, and the put-down after it raising too (the same bug): the bowl's
    relocation fails with the cause named, the robot, still holding it, stops the turn's plan, and nothing escapes
    to end the day (an unknown-node error did so twice over and ended a whole evaluation)."""
    from types import SimpleNamespace

    from homer_sim.observe import SceneGraphObserver
    from planners.skills import SkillResult
    from scenarios.assist import AssistLog, Helper
    from scenarios.psi import PlanStep, Relocation

    def pick(obj: str, node: str, into: str) -> SkillResult:
        robot.held = obj
        return SkillResult(True)

    def place(target: str) -> SkillResult:
        raise KeyError("")

    helper = Helper.__new__(Helper)  # the turn's bookkeeping only: no controller, so the put-down raises too
    helper.world, helper.recording, helper.log, helper.waiting, helper._placed_at = world, None, AssistLog(), [], {}
    robot = helper.robot = SimpleNamespace(observer=SceneGraphObserver(world), held=None, pick=pick, place=place)
    bowl, milk = (Relocation("bowl", "cupboard", "table_dining_room", 1, 0.9),
                  Relocation("milk", "fridge", "table_dining_room", 1, 0.9))
    steps = [PlanStep("pick", "bowl", bowl.source, "bowl"),
             PlanStep("place", bowl.destination, bowl.destination, "bowl"),
             PlanStep("pick", "milk", milk.source, "milk")]
    helper._carry_out(steps, [bowl, milk], 360, float(world.data.time))
    [failed] = helper.log.relocations
    assert failed.relocation == bowl and not failed.done and cause_of(failed.reason) == "skill error"
    assert robot.held == "bowl" and [s.step.action for s in helper.log.steps] == ["pick", "place"]


def test_drawers_an_open_failed_part_way_are_closed_again_and_untouched_ones_are_not(world) -> None:
    """A dresser whose first drawer opened only part way (0.66) and second not at all: the relocation into it fails
    as "did not open", the part-way drawer is closed again (left so, the clothes riding in it counted as displaced)
    and the untouched one is not driven to. The skills are stand-ins; the drawer's joint is really moved."""
    from types import SimpleNamespace

    from homer_sim.observe import SceneGraphObserver
    from planners.skills import SkillResult
    from scenarios.assist import AssistLog, Helper
    from scenarios.psi import PlanStep, Relocation

    part_way, untouched = "dresser/drawer_0", "dresser/drawer_1"
    closed: list[str] = []

    def set_openness(name: str, value: float) -> None:
        a = world.articulation(name)
        world.data.qpos[a.qpos_adr] = a.range[0] + value * (a.range[1] - a.range[0])

    def open_articulation(name: str) -> SkillResult:
        if name == part_way:
            set_openness(name, 0.66)
        return SkillResult(False, f"open {name}: openness {world.openness(name):.2f}, below 0.9")

    def close_articulation(name: str) -> SkillResult:
        closed.append(name)
        set_openness(name, 0.0)
        return SkillResult(True)

    helper = Helper.__new__(Helper)  # the turn's bookkeeping only: the skills are the stand-ins above
    helper.world, helper.recording, helper.log, helper.waiting, helper._placed_at = world, None, AssistLog(), [], {}
    helper.robot = SimpleNamespace(observer=SceneGraphObserver(world), held=None, open_articulation=open_articulation,
                                   close_articulation=close_articulation)
    socks = Relocation("clothes_socks", "washing_machine", "dresser", 1, 0.9)
    steps = [PlanStep("open", part_way, "dresser"), PlanStep("open", untouched, "dresser"),
             PlanStep("pick", socks.obj, socks.source, socks.obj), PlanStep("place", "dresser", "dresser", socks.obj),
             PlanStep("close", untouched, "dresser"), PlanStep("close", part_way, "dresser")]
    helper._carry_out(steps, [socks], 360, float(world.data.time))
    [failed] = helper.log.relocations
    assert not failed.done and failed.reason == "dresser did not open (open dresser/drawer_1: openness 0.00, below 0.9)"
    assert closed == [part_way]
    assert world.openness(part_way) == 0.0 and world.openness(untouched) == 0.0


def test_only_the_parts_a_relocation_needs_are_opened(world) -> None:
    """Something from the washing machine onto the dresser (placed on its top) opens the washing machine's door only:
    all three drawers, opened for such a place before, moved the jackets in them 3-7 cm and one stuck half open.
    Socks taken out of a drawer open that drawer only; into a cabinet, its door opens; off the dresser's top,
    nothing opens."""
    from types import SimpleNamespace

    from homer_sim.home.spots import Spots
    from scenarios.assist import Helper, containers_of
    from scenarios.psi import Relocation, plan_steps

    helper = Helper.__new__(Helper)  # the planning only: no robot or person needed
    helper.world, helper.containers = world, containers_of(world)
    helper.robot = SimpleNamespace(spots=Spots(world))
    graph = SceneGraphObserver(world).observe_all()
    movable = np.array([n in world.object_names for n in graph.nodes])
    out_of_a_drawer = Relocation("clothes_socks", "dresser", "washing_machine", 1, 0.9)
    assert graph.parent_of("clothes_socks") == "dresser" and graph.parent_of("clothes_jacket") == "dresser"
    assert helper._parts_needed([out_of_a_drawer], graph, movable) == {"dresser": ["dresser/drawer_0"],
                                                                "washing_machine": ["washing_machine/door"]}
    to_dresser = Relocation("laundry_detergent", "washing_machine", "dresser", 1, 0.9)
    assert helper._parts_needed([to_dresser], graph, movable) == {"washing_machine": ["washing_machine/door"]}
    off_the_top = Relocation("wallet", "dresser", "table_bedroom", 1, 0.9)
    needed = helper._parts_needed([off_the_top], graph, movable)
    assert needed == {} and [s.action for s in plan_steps(graph, movable, [off_the_top], needed)] == ["pick", "place"]
    into = Relocation("clothes_socks", "dresser", "kitchen_cabinet", 1, 0.9)
    assert helper._parts_needed([into], graph, movable)["kitchen_cabinet"] == ["kitchen_cabinet/door"]
