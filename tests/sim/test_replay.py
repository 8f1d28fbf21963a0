"""Timed day scripts (HOMER+ format): parsing, the physical replay into our dataset, and `replay-check` against a
household folder built here (a day script and its matching graph file)."""

from __future__ import annotations

import json
import os
import re
import shutil
import tarfile
from collections import Counter
from pathlib import Path

import numpy as np
import pytest
import torch

from homer_sim.data.dataset import Dataset
from homer_sim.data.replay import Replayer, find_day_scripts, replay, start_layout
from homer_sim.data.replay_check import replay_check
from homer_sim.errors import HomerError
from homer_sim.graph import INSIDE, ON
from homer_sim.home.apartment import default_layout
from homer_sim.home.catalog import CATALOG
from homer_sim.home.placement import start_poses
from homer_sim.person.aliases import default_resolver
from homer_sim.person.day_scripts import GraphChange, parse_day_script
from homer_sim.person.scripts import ScriptError
from scenarios.cli.main import main

pytestmark = pytest.mark.physics  # steps a whole apartment for seconds or more

DAY = """breakfast (08:00 - 08:20)
watching_tv (08:20 - 1day - 00:40)


### breakfast-00.txt

[WALK] <dining_room> (11) [1]
480.0
## Breakfast until 08:20

[FIND] <bowl> (1001) [2]
481.0
[GRAB] <bowl> (1001) [3]
482.0
<<Graph Changes>>
   - bowl INSIDE cupboard
   + character HOLDS_RH bowl

[PUTBACK] <bowl> (1001) <table> (231) [4]
483.5
<<Graph Changes>>
   + bowl ON table
   + bowl INSIDE dining_room

483.5: bowl moved
<<Activity Change>>
### watching_tv-01.txt

[SWITCHON] <tv> (426) [1]
500.0
<<Graph Changes>>
   (s)426tv['OFF']->['ON']

[SIT] <sofa> (368) [2]
501.0
<<Graph Changes>>
   + bowl INSIDE cupboard

[STANDUP] [3]
515.0
[SWITCHOFF] <tv> (426) [4]
516.0
"""


def test_day_script_reads_header_minutes_and_edge_changes() -> None:
    day = parse_day_script(DAY, "000.txt", default_resolver())
    assert day.schedule == (("breakfast", 480.0, 500.0), ("watching_tv", 500.0, 1480.0))
    assert [(a.minute, a.activity, a.action.verb, a.action.args) for a in day.actions] == [
        (480.0, "breakfast", "walk", ("dining_room",)), (481.0, "breakfast", "find", ("bowl",)),
        (482.0, "breakfast", "grab", ("bowl",)), (483.5, "breakfast", "putback", ("bowl", "table_dining_room")),
        (500.0, "watching_tv", "switchon", ("tvstand_home_office",)),
        (501.0, "watching_tv", "sit", ("sofa_home_office",)), (515.0, "watching_tv", "standup", ()),
        (516.0, "watching_tv", "switchoff", ("tvstand_home_office",))]
    assert day.actions[2].changes == (GraphChange(16, "-", "bowl", "INSIDE", "cupboard"),)  # HOLDS_RH not compared
    assert day.actions[3].changes == (GraphChange(22, "+", "bowl", "ON", "table"),
                                      GraphChange(23, "+", "bowl", "INSIDE", "dining_room")) and day.end_min == 1480.0


@pytest.mark.parametrize(("line", "expected"), [
    ("[JUMP] <bowl> (1) [1]", "000.txt:7: unknown verb 'jump'"),
    ("[GRAB] <toaster> (1) [1]", "000.txt:7: unknown name 'toaster'"),
])
def test_unknown_verb_or_object_names_file_and_line(line: str, expected: str) -> None:
    text = DAY.replace("[WALK] <dining_room> (11) [1]", line)
    with pytest.raises(ScriptError) as caught:
        parse_day_script(text, "000.txt", default_resolver())
    assert str(caught.value).startswith(expected) and caught.value.line == 7


def test_action_without_minute_and_backwards_time_are_errors() -> None:
    with pytest.raises(ScriptError, match=r"000.txt:7: action has no minute"):
        parse_day_script(DAY.replace("480.0\n", "", 1), "000.txt", default_resolver())
    with pytest.raises(ScriptError, match=r"000.txt:13: minute 470 is before the previous action's 481"):
        parse_day_script(DAY.replace("482.0", "470.0"), "000.txt", default_resolver())


def _write_household(root: Path, day: str, nodes: list[tuple[str, int, str, int]], moves: list[tuple[int, int]]
                     ) -> Path:
    """A HOMER+-like household at `root`: day train/000 (`day`) and its graph. nodes: (class, id, category, parent
    index) with home first and the one movable object last; furniture is static. moves: (from minute, parent
    index) of the object."""
    (root / "scripts_train").mkdir(parents=True)
    (root / "scripts_train" / "000.txt").write_text(day)
    folder = root / "processed_seqLM_coarse"
    (folder / "train").mkdir(parents=True)
    common = {"node_ids": [n[1] for n in nodes], "node_classes": [n[0] for n in nodes], "dt": 10,
              "static_nodes": [n[1] for n in nodes if n[2] == "Furniture"], "node_categories": [n[2] for n in nodes],
              "activities": ["breakfast", "watching_tv"]}
    (folder / "common_data.json").write_text(json.dumps(common))
    times = torch.arange(360, 1441, 10, dtype=torch.float32)
    parents = torch.tensor([n[3] for n in nodes]).repeat(len(times), 1)
    for minute, parent in moves:
        parents[times >= minute, len(nodes) - 1] = parent
    edges = torch.nn.functional.one_hot(parents, len(nodes)).float()
    torch.save({"edges": edges, "times": times, "activity": torch.zeros(len(times), dtype=torch.long)},
               folder / "train" / "000.pt")
    return root


def _household(root: Path, their_bowl_back_at: int, day: str = DAY) -> Path:
    """Day train/000 (`day`) and its graph, where the bowl goes from the cupboard onto the table at 08:10 and back
    into the cupboard at minute `their_bowl_back_at`."""
    nodes = [("home", 1, "Home", 0), ("dining_room", 11, "Rooms", 0), ("table", 231, "Furniture", 1),
             ("cupboard", 100, "Furniture", 1), ("bowl", 1001, "placable_objects", 3)]
    return _write_household(root, day, nodes, [(490, 2), (their_bowl_back_at, 3)])


TABLES = """breakfast (08:00 - 10:00)

### breakfast-00.txt

[GRAB] <bowl> (1001) [1]
480.0
<<Graph Changes>>
   - bowl INSIDE cupboard

[PUTBACK] <bowl> (1001) <table> (114) [2]
482.0
<<Graph Changes>>
   + bowl ON table

[GRAB] <bowl> (1001) [3]
592.0
[PUTBACK] <bowl> (1001) <table> (270) [4]
595.0
<<Graph Changes>>
   - bowl ON table
   + bowl ON table
"""


FLOOR = """breakfast (08:00 - 10:00)

### breakfast-00.txt

[GRAB] <bowl> (1001) [1]
480.0
[PUTBACK] <bowl> (1001) <dining_room> (41) [2]
482.0
<<Graph Changes>>
   - bowl INSIDE cupboard
   + bowl ON dining_room

[GRAB] <bowl> (1001) [3]
592.0
[PUTBACK] <bowl> (1001) <table> (114) [4]
595.0
<<Graph Changes>>
   - bowl ON dining_room
   + bowl ON table
"""


# Their tables 114 and 270 are our dining-room and home-office ones (aliases.json): the bowl goes cupboard -> 114 at
# 08:02 -> 270 at 09:55, ours the same, so every step agrees; the last block's '- bowl ON table' is the table it left
# (114), not the one the action names, and is seen too.
TABLE_NODES = [("home", 1, "Home", 0), ("dining_room", 41, "Rooms", 0), ("home_office", 241, "Rooms", 0),
               ("table", 114, "Furniture", 1), ("table", 270, "Furniture", 2), ("cupboard", 117, "Furniture", 1),
               ("bowl", 1026, "placable_objects", 5)]
# VirtualHome hangs what lies on a floor from the room by ON: the bowl goes onto the dining-room floor at 08:02, then
# onto the table in the same room at 09:55; '- bowl ON dining_room' says it left the floor (it is still INSIDE the
# room), so ours on the table shows it.
FLOOR_NODES = [("home", 1, "Home", 0), ("dining_room", 41, "Rooms", 0), ("table", 114, "Furniture", 1),
               ("cupboard", 117, "Furniture", 1), ("bowl", 1026, "placable_objects", 3)]


@pytest.mark.physics
@pytest.mark.parametrize(("script", "nodes", "steps"), [(TABLES, TABLE_NODES, [(490, 3), (600, 4)]),
                                                          (FLOOR, FLOOR_NODES, [(490, 1), (600, 2)])],
                         ids=["tables told apart by id", "on a room is on its floor"])
def test_replay_check_agrees_on_every_step_and_line(tmp_path: Path, script: str, nodes: list, steps: list) -> None:
    result = replay_check(_write_household(tmp_path / "HouseholdT", script, nodes, steps))
    assert result == {"days": 1, "days_completed": 1, "agreement": 1.0, "graph_changes_seen": 1.0,
                      "agreement_known": 1.0, "graph_changes_seen_known": 1.0, "causes": {}, "failed": {}}


@pytest.mark.physics
def test_replay_lives_the_day_at_its_minutes_and_keeps_switch_state(tmp_path: Path) -> None:
    folder = _household(tmp_path / "HouseholdT", 2000)
    replayer = Replayer()
    task = find_day_scripts(folder)[0]
    record = replayer.live(replayer.read(task.path), task)
    assert record.moves == [(483.5, "bowl", "cupboard", "table_dining_room", "ON")]
    assert record.switches == [(500.0, "tvstand_home_office", "ON"), (516.0, "tvstand_home_office", "OFF")]
    assert replayer.executor.switched_on == set() and record.minutes == list(range(360, 1481, 10))
    result = replay(folder, tmp_path / "out", progress=False)
    assert result.pop("execution")["mode"] == "local" and result == {"days": 1, "completed": 1, "failed": {}}
    day = Dataset(tmp_path / "out").load("HouseholdT", "train")[0]
    assert day.moves == ((483.5, "bowl", "cupboard", "table_dining_room", "ON"),) and day.steps == 113
    first = (tmp_path / "out" / "HouseholdT" / "train" / "day_000.npz").read_bytes()
    assert replay(folder, tmp_path / "out", progress=False)["completed"] == 1  # resumed: nothing redone
    replay(folder, tmp_path / "again", progress=False)
    assert (tmp_path / "again" / "HouseholdT" / "train" / "day_000.npz").read_bytes() == first


@pytest.mark.physics
def test_replay_check_counts_agreement_changes_and_causes(tmp_path: Path) -> None:
    folder = _household(tmp_path / "HouseholdT", 600)
    result = replay_check(folder, out=tmp_path / "replayed")
    # 109 authors' steps of one movable bowl: 06:00-08:00 in the cupboard and 08:10-09:50 on the table agree
    # (13 + 11); from 10:00 the authors put it back into the cupboard, ours stayed where the person set it down.
    # Change lines: the grab's '- bowl INSIDE cupboard', the put's '+ bowl ON table' and '+ bowl INSIDE
    # dining_room' (the room it is in) are seen, the sit's '+ bowl INSIDE cupboard' is not.
    assert result == {"days": 1, "days_completed": 1, "agreement": round(24 / 109, 4),
                      "graph_changes_seen": round(3 / 4, 4), "agreement_known": round(24 / 109, 4),
                      "graph_changes_seen_known": round(3 / 4, 4),
                      "causes": {"settled elsewhere": 85, "change not seen (+)": 1}, "failed": {}}
    # --out wrote the day lived as a dataset of ours: the bowl in the cupboard, then on the table
    written = Dataset(tmp_path / "replayed")
    day, nodes = written.load("HouseholdT", "train")[0], list(written.meta.nodes)
    bowl = nodes.index("bowl")
    assert (day.parent[day.minutes < 480, bowl] == nodes.index("cupboard")).all()
    assert (day.parent[(day.minutes >= 490) & (day.minutes < 600), bowl] == nodes.index("table_dining_room")).all()
    other = _household(tmp_path / "HouseholdU", 600)
    with pytest.raises(HomerError, match="holds another dataset"):  # a folder of another replay is not mixed in
        replay_check(other, out=tmp_path / "replayed")


@pytest.mark.physics
def test_replay_check_leaves_out_and_counts_actions_on_things_we_lack(tmp_path: Path) -> None:
    # The bowl is put on a toaster we lack: that put-down and the bowl's grab are left out, the bowl stays in
    # the cupboard and the day goes on. Their bowl is on the table 08:10-09:50 (11 steps); ours never moved.
    day = DAY.replace("<bowl> (1001) <table> (231)", "<bowl> (1001) <toaster> (1117)")
    result = replay_check(_household(tmp_path / "HouseholdT", 600, day))
    # Both left-out actions' change lines are checked after the find before them: '- bowl INSIDE cupboard' and
    # '+ bowl ON table' are not seen there, '+ bowl INSIDE dining_room' is (the cupboard is in it), and so is
    # '+ bowl INSIDE cupboard' after the sit.
    assert result == {"days": 1, "days_completed": 1, "agreement": round(98 / 109, 4),
                      "graph_changes_seen": round(2 / 4, 4), "agreement_known": round(98 / 109, 4),
                      "graph_changes_seen_known": round(2 / 4, 4),
                      "causes": {"start placement differs": 11, "action left out, missing scenery: toaster": 1,
                                 "action left out, its put-down was": 1,
                                 "change not seen (-), its action left out": 1,
                                 "change not seen (+), its action left out": 1}, "failed": {}}
    with pytest.raises(ScriptError, match="000.txt:19: unknown name 'toaster'"):  # homer replay refuses it
        Replayer().read(tmp_path / "HouseholdT" / "scripts_train" / "000.txt")


def test_start_layout_moves_objects_to_the_parents_given_where_they_can_stand() -> None:
    layout = default_layout()
    moved, left = start_layout(layout, {"bowl": "table_dining_room", "spoon": "bowl", "milk": "cupboard",
                                        "trashbag": "trashcan", "knife": "knifeblock", "mail": "outside",
                                        "book": "no_such_thing"})
    starts = {o.name: (o.parent, o.relation) for o in moved.objects}
    assert starts["bowl"] == ("table_dining_room", ON) and starts["spoon"] == ("bowl", ON)
    assert starts["trashbag"] == ("trashcan", ON)  # declared before the trash can: placed after it all the same
    bag, can = start_poses(moved)["trashbag"].pos, start_poses(moved)["trashcan"].pos
    # in it, on its floor (on its rim, it tipped the can over): centred, its bottom below the rim
    assert np.allclose(bag[:2], can[:2]) and bag[2] - CATALOG["trashbag"].size[2] / 2 < can[2]
    assert starts["milk"] == ("cupboard", INSIDE)
    assert starts["mail"] == ("outside", INSIDE)  # on the porch's floor, clear of the groceries standing there
    porch = next(r.rect for r in layout.rooms if r.name == "outside")
    mail, groceries = (np.array(start_poses(moved)[name].pos[:2]) for name in ("mail", "groceries"))
    assert porch[0] < mail[0] < porch[2] and porch[1] < mail[1] < porch[3]
    assert np.linalg.norm(mail - groceries) > (np.hypot(*CATALOG["mail"].size[:2]) +
                                                np.hypot(*CATALOG["groceries"].size[:2])) / 2
    # a knife block holds nothing on it, an unknown parent: they stay where our apartment has them
    assert set(left) == {"knife", "book"}
    declared = {o.name: (o.parent, o.relation) for o in layout.objects}
    assert all(starts[name] == declared[name] for name in left)
    assert moved.node_names() == layout.node_names()  # the scene graph's node order is kept
    assert set(start_poses(moved)) == set(declared)
    assert start_layout(layout, {"plate": "bowl", "bowl": "plate"})[1] == ("bowl",)  # not on what stands on it
    # two on one object lie side by side on its top, not one inside the other
    both, left = start_layout(layout, {"toothbrush": "toothbrush_holder", "tooth_paste": "toothbrush_holder"})
    poses = {name: np.array(pose.pos[:2]) for name, pose in start_poses(both).items()}
    gap = np.linalg.norm(poses["toothbrush"] - poses["tooth_paste"])
    assert left == () and gap >= (CATALOG["toothbrush"].size[1] + CATALOG["tooth_paste"].size[1]) / 2
    assert all(np.linalg.norm(poses[name] - poses["toothbrush_holder"]) <= CATALOG["toothbrush_holder"].size[1] / 2
               for name in ("toothbrush", "tooth_paste"))
    # into drawers: when the first free one is where an object declared in that drawer must go (the pencil in the
    # filing cabinet's top drawer), the moved ones go into another (household A starts the headset and notebook there)
    filed, left = start_layout(layout, {"headset": "filing_cabinet", "notebook": "filing_cabinet"})
    assert left == () and {o.name for o in filed.objects if o.parent == "filing_cabinet"} >= {"headset", "notebook"}


def test_replay_reports_a_day_that_cannot_run_and_goes_on(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    folder = tmp_path / "scripts_test"
    folder.mkdir()
    (folder / "003.txt").write_text(DAY.replace("<bowl> (1001) <table>", "<cups> (1001) <table>"))
    assert main(["replay", str(folder), "--out", str(tmp_path / "out"), "--household", "H", "--json"]) == 1
    result = json.loads(capsys.readouterr().out)
    assert result["days"] == 1 and result["completed"] == 0
    assert list(result["failed"]) == ["H/test/003"]
    assert result["failed"]["H/test/003"].endswith("003.txt:19: unknown name 'cups'; closest known: "
                                                         "cup, cupboard")


SHARED = Path(os.environ.get("HOMER_SIM_SHARED", Path(__file__).resolve().parents[3] / "shared")) / "homer_plus"
ARCHIVE = SHARED / "HouseholdA.tar.gz"
CACHE = Path(os.environ.get("HOMER_SIM_CACHE", Path.home() / ".cache" / "homer-sim")) / "homer_plus"
MEMBERS = ["processed_seqLM_coarse/common_data.json", "scripts_train/000.txt", "processed_seqLM_coarse/train/000.pt",
           "scripts_test/000.txt", "processed_seqLM_coarse/test/000.pt"]


def _real_days(tmp_path: Path) -> Path:
    """Household A with its first training and test day, from the shared archive or an unpacked copy in the cache
    (as `homer_sim.data.homer_plus` users unpack it), into tmp_path."""
    folder = tmp_path / "HouseholdA"
    if ARCHIVE.is_file():
        with tarfile.open(ARCHIVE) as archive:
            for member in MEMBERS:
                archive.extract(f"HouseholdA/{member}", tmp_path, filter="data")
    else:
        for member in MEMBERS:
            (folder / member).parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(CACHE / "HouseholdA" / member, folder / member)
    return folder


@pytest.mark.skipif(not ARCHIVE.is_file() and not all((CACHE / "HouseholdA" / m).is_file() for m in MEMBERS),
                    reason=f"HOMER+ data found neither at {SHARED} nor unpacked at {CACHE}")
def test_replay_check_on_two_real_days_completes_them_and_counts_every_left_out_action(tmp_path: Path) -> None:
    folder = _real_days(tmp_path)
    result = replay_check(folder)
    assert result["days"] == result["days_completed"] == 2 and result["failed"] == {}
    assert 0 < result["agreement"] < 1 and 0 < result["graph_changes_seen"] < 1
    resolver = default_resolver()
    lacking = Counter()  # per action line naming something we lack: the first such name (with id if only it lacks)
    for script in (folder / "scripts_train" / "000.txt", folder / "scripts_test" / "000.txt"):
        for line in script.read_text().splitlines():
            names = [(n, int(i)) for n, i in re.findall(r"<([^<>]*)> \((\d+)\)", line)] if line[:1] == "[" else []
            missing = [n if n not in resolver else f"{n} ({i})" for n, i in names if not resolver.knows(n, i)]
            lacking.update(missing[:1])
    left_out = Counter({cause.split(": ", 1)[1]: n for cause, n in result["causes"].items()
                        if cause.startswith("action left out, missing")})
    assert left_out == lacking and "chair (194)" not in lacking and "toothbrush_holder" not in lacking


def test_replayed_day_is_written_over_the_span_of_the_authors_graphs() -> None:
    """Their scripts sleep on past midnight and our replay lives that; the day written for predictors stops at
    their last graph step, as theirs do (moves after it go with the steps)."""
    from homer_sim.data.dataset import Day
    from homer_sim.data.replay_check import over_span

    minutes = np.arange(360, 1531, 10, dtype=np.int32)
    parent = np.zeros((len(minutes), 3), dtype=np.int16)
    day = Day("HouseholdT", "train", 0, minutes, parent, np.zeros_like(parent, dtype=np.int8),
              moves=((480.0, "bowl", "cupboard", "table", "ON"), (1450.5, "bowl", "table", "sink", "INSIDE")))
    cut = over_span(day, 1440)
    assert cut.minutes[0] == 360 and cut.minutes[-1] == 1440 and cut.parent.shape == (109, 3)
    assert cut.moves == day.moves[:1]
