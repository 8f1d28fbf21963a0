"""The script language: parsing, errors, name resolution and the symbolic checker."""

from __future__ import annotations

from pathlib import Path

import pytest

from homer_sim.errors import HomerError
from homer_sim.graph import INSIDE, ON
from homer_sim.home.apartment import default_layout
from homer_sim.person.activities import load_library, script_files
from homer_sim.person.aliases import ALIASES, INSTANCES, SCENERY, Resolver, default_resolver
from homer_sim.person.scripts import TIME_VERBS, WORLD_VERBS, ScriptError, parse_script, symbolic_run

HOMER_SCRIPTS = Path(__file__).resolve().parents[3] / "shared" / "homer_reference" / "sourcedScriptsByActivity"
NODES = ("dining_room", "outside", "cupboard", "table_dining_room", "sink_dining_room", "bench", "bowl", "spoon",
         "milk", "fridge", "shoes", "keys")
resolve = Resolver(NODES)


def parse(text: str, activity: str = "breakfast"):
    return parse_script(text, "test.txt", activity, "0", resolve)


def errors_of(text: str) -> ScriptError:
    with pytest.raises(ScriptError) as info:
        parse(text)
    return info.value


def test_parses_blocks_actions_and_duration_range() -> None:
    script = parse("## 1-2\n[Walk] <cupboard>\n[Grab] <bowl>\n## 0.5-3.5\n[PutBack] <bowl> <table_dining_room>\n")
    assert [(b.min_min, b.max_min, len(b.actions), b.line) for b in script.blocks] == [(1, 2, 2, 1), (0.5, 3.5, 1, 4)]
    assert script.duration_range == (1.5, 5.5)
    put = script.blocks[1].actions[0]
    assert (put.verb, put.args, put.line, put.text) == ("putback", ("bowl", "table_dining_room"), 5,
                                                        "[PutBack] <bowl> <table_dining_room>")


def test_accepts_whitespace_case_comments_and_annotations() -> None:
    text = (
        "# a comment\n"
        "##1-2\n"
        "  [WALK]   <Cupboard>   \n"
        "[grab]<bowl>\n"
        "+<bowl>\n"
        "\n"
        "[PutBack]<bowl><table>\n"
        "-<bowl>\n"
        "## 5 - 10\r\n"
        "[Standup]\n"
        "[Sit] <table> (1)\n"
    )
    script = parse(text)
    assert script.duration_range == (6, 12)
    assert [(a.verb, a.args, a.line) for a in script.actions] == [
        ("walk", ("cupboard",), 3), ("grab", ("bowl",), 4), ("putback", ("bowl", "table_dining_room"), 7),
        ("standup", (), 10), ("sit", ("table_dining_room",), 11)]


def test_every_error_of_a_file_is_reported_at_once_with_line_numbers() -> None:
    text = (
        "[Walk] <cupboard>\n"          # 1: before any header
        "## 5-2\n"                     # 2: min > max
        "[Wlk] <cupboard>\n"           # 3: unknown verb
        "[Grab] <bowel>\n"             # 4: unknown name
        "[PutBack] <bowl>\n"           # 5: wrong arity
        "[Grab] bowl\n"                # 6: unreadable arguments
        "## two-three\n"               # 7: bad header
        "[Walk] <dining_room>\n"
    )
    error = errors_of(text)
    assert [line for line, _ in error.errors] == [1, 2, 3, 4, 5, 6, 7]
    assert (error.path, error.line) == ("test.txt", 1)
    assert "before the first" in error.reason
    lines = str(error).splitlines()
    assert len(lines) == 7 and lines[0].startswith("test.txt:1: ") and lines[3].startswith("test.txt:4: ")
    reasons = dict(error.errors)
    assert "min 5 is larger than max 2" in reasons[2]
    assert "unknown verb 'wlk'" in reasons[3] and "walk" in reasons[3]
    assert "'bowel'" in reasons[4] and "bowl" in reasons[4].split("closest known:")[1]
    assert "takes 2 argument(s), got 1" in reasons[5]
    assert isinstance(error, HomerError)


@pytest.mark.parametrize("text, reason", [
    ("", "no blocks"),
    ("## 1-2\n## 1-2\n[Walk] <bench>\n", "block has no actions"),
    ("## 1-2\n[Standup] <bench>\n", "takes 0 argument(s), got 1"),
    ("## 1-2\n[Walk]\n", "takes 1 argument(s), got 0"),
    ("## 1-2\n[Walk] <bench> <cupboard>\n", "takes 1 argument(s), got 2"),
    ("## 1-\n[Walk] <bench>\n", "bad block header"),
])
def test_single_errors(text: str, reason: str) -> None:
    assert reason in errors_of(text).reason


def test_verb_sets_are_disjoint_and_have_arities() -> None:
    assert not set(WORLD_VERBS) & set(TIME_VERBS)
    assert all(arities and arities <= {0, 1, 2} for arities in {**WORLD_VERBS, **TIME_VERBS}.values())


def test_library_folders_load_and_report_every_broken_file(tmp_path: Path) -> None:
    (tmp_path / "breakfast").mkdir()
    (tmp_path / "breakfast" / "1.txt").write_text("## 1-2\n[Walk] <cupboard>\n")
    (tmp_path / "breakfast" / "0.txt").write_text("## 1-2\n[Grab] <bowl>\n[PutBack] <bowl> <table>\n")
    library = load_library(resolve, tmp_path)
    assert [(s.activity, s.variant) for s in library["breakfast"]] == [("breakfast", "0"), ("breakfast", "1")]
    (tmp_path / "lunch").mkdir()
    (tmp_path / "lunch" / "0.txt").write_text("## 1-2\n[Walk] <sofa>\n")
    (tmp_path / "lunch" / "1.txt").write_text("[Walk] <bench>\n")
    with pytest.raises(ScriptError) as info:
        load_library(resolve, tmp_path)
    assert info.value.path.endswith("0.txt") and "'sofa'" in info.value.reason
    assert "1.txt:1: action before" in "\n".join(info.value.__notes__)
    with pytest.raises(ScriptError, match="no such folder"):
        load_library(resolve, tmp_path / "missing")


# --- names ---------------------------------------------------------------------------------------------------


def test_resolver_maps_exact_alias_and_scenery_names() -> None:
    resolver = default_resolver()
    assert resolver("bowl") == "bowl"
    assert resolver(" Kitchen_Counter ") == "kitchen_counter_left"
    assert resolver("nightstand") == "table_bedroom"
    assert resolver("faucet_bathroom") == "sink_bathroom"
    assert resolver("light_bedroom") == "bedroom"
    assert resolver.known[: len(resolver.nodes)] == tuple(sorted(resolver.nodes))
    with pytest.raises(KeyError, match="closest known: .*spoon"):
        resolver("spon")


def test_alias_targets_are_nodes_and_entries_without_target_are_left_out() -> None:
    nodes = set(default_resolver().nodes)
    assert set(ALIASES.values()) <= nodes and set(SCENERY.values()) <= nodes
    assert set(INSTANCES.values()) - {None} <= nodes
    assert not (set(ALIASES) | set(SCENERY)) & nodes
    assert "sink" not in Resolver(["bowl"]) and "bowl" in Resolver(["bowl"])


def test_instances_pick_the_piece_the_id_names_and_an_instance_without_counterpart_stays_unknown() -> None:
    resolver = default_resolver()
    assert resolver("kitchen_counter", 119) == "kitchen_counter_right"
    assert resolver("Kitchen_Counter", 123) == resolver("kitchen_counter") == "kitchen_counter_left"
    assert resolver("faucet", 20) == "sink_bathroom" and resolver("faucet") == "sink_dining_room"
    assert resolver("table", 1) == "table_dining_room"  # an id the table lacks: by the name
    assert resolver("water_glass") == "drinking_glass" and resolver.knows("chair")
    assert resolver("chair", 194) == "chair_bedroom" and resolver("chair", 271) == resolver("chair")
    resolver = Resolver(resolver.nodes, instances={**INSTANCES, "chair (194)": None})  # as if we lacked it
    assert not resolver.knows("chair", 194)
    with pytest.raises(KeyError, match="instance 194 of the HOMER\\+ apartment has no counterpart"):
        resolver("chair", 194)
    script = parse_script("## 1-2\n[Walk] <kitchen_counter> (119)\n[Sit] <sofa> (198)\n[Sit] <sofa>\n", "test.txt",
                          "reading", "0", resolver)
    assert [a.args for a in script.actions] == [("kitchen_counter_right",), ("sofa_bedroom",), ("sofa_home_office",)]
    with pytest.raises(ScriptError, match="test.txt:2: unknown name 'chair'"):
        parse_script("## 1-2\n[Sit] <chair> (194)\n", "test.txt", "reading", "0", resolver)


homer = pytest.mark.skipif(not HOMER_SCRIPTS.is_dir(), reason="the HOMER reference scripts are not here")


@homer
def test_every_name_in_the_homer_scripts_resolves() -> None:
    library = load_library(default_resolver(), HOMER_SCRIPTS)
    assert sum(len(scripts) for scripts in library.values()) == len(script_files(HOMER_SCRIPTS)) >= 22
    moved = {a.args[0] for s in sum(library.values(), []) for a in s.actions
             if a.verb in ("grab", "putback", "putin", "putobjback", "puton", "drop")}
    assert moved <= {o.name for o in default_layout().objects}


# --- symbolic checker -----------------------------------------------------------------------------------------

PARENTS = {"bowl": "cupboard", "spoon": "cupboard", "milk": "fridge", "shoes": "bench", "keys": "bench"}
ROOMS = {n: "dining_room" for n in ("cupboard", "fridge", "bench", "table_dining_room", "sink_dining_room")}
ROOMS |= {"dining_room": "dining_room", "outside": "outside"}


def run(text: str, activity: str = "breakfast", closed=("cupboard", "fridge"), **kwargs):
    return symbolic_run(parse(text, activity), PARENTS, {"cupboard", "fridge"}, closed, node_rooms=ROOMS, **kwargs)


def test_symbolic_run_tracks_parents_and_changes() -> None:
    result = run("## 1-2\n[Open] <cupboard>\n[Grab] <bowl>\n[Grab] <spoon>\n[Close] <cupboard>\n"
                 "## 8-10\n[PutBack] <bowl> <table_dining_room>\n[PutBack] <spoon> <bowl>\n")
    assert result.parents["bowl"] == "table_dining_room" and result.parents["spoon"] == "bowl"
    assert result.moved == {"bowl", "spoon"}
    assert [(c.line, c.block, c.obj) for c in result.changes] == [(7, 1, "bowl"), (8, 1, "spoon")]
    assert result.problems == () and result.warnings == ()


def test_symbolic_run_reports_hand_problems() -> None:
    result = run("## 1-2\n[Open] <cupboard>\n[Grab] <bowl>\n[Grab] <spoon>\n[Grab] <keys>\n"
                 "[PutBack] <milk> <bench>\n[PutBack] <spoon> <bowl>\n[Close] <cupboard>\n")
    assert [line for line, _ in result.problems] == [5, 6, 7, 8]
    assert "both hands are full" in result.problems[0][1]
    assert "not held" in result.problems[1][1]
    assert "held or worn" in result.problems[2][1]
    assert "still held at the end: bowl, spoon" in result.problems[3][1]


def test_symbolic_run_warns_about_closed_containers_only_for_what_is_inside() -> None:
    result = run("## 1-2\n[Grab] <bowl>\n[PutIn] <bowl> <fridge>\n[Open] <cupboard>\n",
                 relations={"bowl": INSIDE, "shoes": ON})
    assert [line for line, _ in result.warnings] == [2, 3, 4]
    assert "from cupboard, which is closed" in result.warnings[0][1]
    assert "into fridge" in result.warnings[1][1] and "left open" in result.warnings[2][1]
    on_top = symbolic_run(parse("## 1-2\n[Grab] <shoes>\n[PutObjBack] <shoes>\n"), PARENTS, {"bench"}, {"bench"},
                          relations={"shoes": ON})
    assert on_top.warnings == () and on_top.moved == frozenset()


def test_leaving_takes_carried_and_worn_things_outside() -> None:
    leave = run("## 1-2\n[PutOn] <shoes>\n[Grab] <keys>\n[Walk] <outside>\n", activity="leave_home")
    assert leave.problems == () and leave.held == ("keys",) and leave.worn == ("shoes",)
    assert leave.parents["keys"] == leave.parents["shoes"] == "outside"
    come = run("## 1-2\n[Walk] <dining_room>\n[PutBack] <keys> <bench>\n[PutOff] <shoes>\n[Drop] <shoes>\n",
               activity="come_home", held=leave.held, worn=leave.worn)
    assert come.problems == () and come.parents["keys"] == "bench" and come.parents["shoes"] == "dining_room"
    stuck = run("## 1-2\n[Grab] <keys>\n[Walk] <outside>\n")
    assert "still held" in stuck.problems[0][1]


def test_putobjback_and_putoff_need_a_grab_and_a_worn_object() -> None:
    result = run("## 1-2\n[PutObjBack] <keys>\n[PutOff] <keys>\n")
    assert [reason for _, reason in result.problems] == ["[putobjback] keys: not grabbed in this script",
                                                         "[putoff] keys: not worn"]
