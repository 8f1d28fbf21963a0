"""`homer generate`, `homer dataset stats`, `homer simulate-day`, `homer compat-check`, `homer replay`,
`homer replay-check`, `homer import homer-plus`: the person's days as data."""

from __future__ import annotations

import argparse
from pathlib import Path

from homer_sim.clock import clock_text
from homer_sim.days import DayKey
from homer_sim.errors import HomerError
from homer_sim.execution import IN_PROCESS
from scenarios.cli.common import add_backend_arguments, backend_from_args, describe_usage, emit


def cmd_generate(args: argparse.Namespace) -> int:
    from homer_sim.data.generate import Sources, generate

    for name in ("households", "train_days", "test_days"):
        if getattr(args, name) < (1 if name == "households" else 0):
            raise HomerError(f"--{name.replace('_', '-')} must be positive, not {getattr(args, name)}")
    sources = Sources(str(args.habits) if args.habits else None, str(args.scripts) if args.scripts else None)
    result = generate(args.out, args.households, args.train_days, args.test_days, args.seed, backend_from_args(args),
                      sources, progress=not args.json)
    emit(result, args.json, [f"wrote {result['days_written']} days for {', '.join(result['households'])} "
                             f"to {result['out']} in {result['wall_s']} s ({describe_usage(result['execution'])})"])
    return 0

def cmd_dataset_stats(args: argparse.Namespace) -> int:
    from homer_sim.data.stats import dataset_stats

    result = dataset_stats(args.data)
    lines = [f"{'household':<14} {'days':>5} {'steps/day':>10} {'moves/day':>10} {'objects used':>13}"]
    for name, h in result["households"].items():
        lines.append(f"{name:<14} {h['days']:>5} {h['steps_per_day']:>10.1f} {h['moves_per_day']:>10.1f} "
                     f"{h['objects_used']:>13}")
    wall = result["wall_s_per_day"]
    lines.append(f"wall seconds per simulated day: {wall:.2f}" if wall is not None else "no generation log")
    emit(result, args.json, lines)
    return 0

def cmd_simulate_day(args: argparse.Namespace) -> int:
    from homer_sim.data.generate import Generator, Sources
    from homer_sim.recording import Recording

    recording = Recording(args.rrd) if args.rrd else None
    generator = Generator(Sources(), recording=recording)
    if recording is not None:
        recording.log_geometry(generator.world.model, generator.world.data)
    names = list(generator.households)
    if args.household not in names:
        from homer_sim.errors import unknown_name

        raise unknown_name("household", args.household, names)
    key = DayKey(args.seed, names.index(args.household), args.split, args.day)
    day, info = generator.simulate(args.household, key)
    if recording is not None:
        recording.close()
    moves = int(((day.parent[1:] != day.parent[:-1])).sum())
    result = {"household": args.household, "steps": day.steps, "grid_moves": moves, "schedule": day.schedule,
              "events": len(day.moves), "attempts": info["attempts"], "wall_s": info["wall_s"],
              "rrd": str(args.rrd) if args.rrd else None}
    lines = [f"{a:<22} {clock_text(s)}-{clock_text(e)}"
             for a, s, e in day.schedule]
    lines.append(f"{day.steps} grid steps, {moves} object moves between steps, {info['wall_s']} s wall")
    emit(result, args.json, lines)
    return 0

def cmd_compat_check(args: argparse.Namespace) -> int:
    from homer_sim.person.compat import compat_check, compat_check_texts, homer_plus_scripts

    if args.from_homer_plus is not None:
        result = compat_check_texts(homer_plus_scripts(args.from_homer_plus), progress=not args.json)
    else:
        result = compat_check(args.scripts, progress=not args.json)
    share = result["executed"] / result["scripts"]
    lines = [f"{result['executed']} of {result['scripts']} scripts executed ({share:.0%})"]
    lines += [f"  {f['script']}:{f['line']}: {f['reason']}" for f in result["failures"]]
    emit(result, args.json, lines)
    return 0


def cmd_replay(args: argparse.Namespace) -> int:
    from homer_sim.data.replay import DayTask, Replayer, find_day_scripts, replay

    if args.rrd is None:
        result = replay(args.scripts, args.out, backend_from_args(args), args.household, progress=not args.json)
        lines = [f"{result['completed']} of {result['days']} days in {args.out}"]
        lines += [f"  {day}: {reason}" for day, reason in result["failed"].items()]
        emit(result, args.json, lines)
        return 0 if not result["failed"] else 1
    from homer_sim.data.dataset import write_day, write_meta
    from homer_sim.recording import Recording

    if backend_from_args(args) != IN_PROCESS:
        raise HomerError("--rrd records one day in this process; drop --workers and --ray")
    tasks = find_day_scripts(args.scripts, args.household)
    if len(tasks) != 1:
        raise HomerError(f"--rrd records one day; {args.scripts} holds {len(tasks)} day scripts: give one NNN.txt")
    recording = Recording(args.rrd)
    replayer = Replayer(recording=recording)
    recording.log_geometry(replayer.world.model, replayer.world.data)
    task: DayTask = tasks[0]
    day = replayer.day(task)
    recording.close()
    write_meta(args.out, replayer.meta([task.household], {"replay": {"scripts": str(task.path.resolve())}}))
    write_day(args.out, day)
    result = {"days": 1, "completed": 1, "failed": {}, "rrd": str(args.rrd)}
    emit(result, args.json, [f"replayed {task.label} into {args.out}, recording in {args.rrd}"])
    return 0


def cmd_replay_check(args: argparse.Namespace) -> int:
    from homer_sim.data.replay_check import replay_check

    result = replay_check(args.household, progress=not args.json, days=args.days, backend=backend_from_args(args),
                          out=args.out)

    def share(x: float | None) -> str:
        return "n/a" if x is None else f"{x:.1%}"

    lines = [f"{result['days_completed']} of {result['days']} days completed; parent agreement "
             f"{share(result['agreement'])}, graph changes seen {share(result['graph_changes_seen'])}",
             f"over the objects and parents we have: agreement {share(result['agreement_known'])}, graph changes "
             f"seen {share(result['graph_changes_seen_known'])}", "causes:"]
    lines += [f"  {count:>7}  {cause}" for cause, count in result["causes"].items()]
    emit(result, args.json, lines)
    return 0


def cmd_import_homer_plus(args: argparse.Namespace) -> int:
    from homer_sim.data.homer_plus import import_household

    result = import_household(args.path, args.out, args.name)
    emit(result, args.json, [f"{k}: {v}" for k, v in result.items()])
    return 0


def add_commands(subparsers: argparse._SubParsersAction) -> None:
    """Add `generate`, `dataset stats`, `simulate-day`, `compat-check` and `import homer-plus` to the parser."""
    gen = subparsers.add_parser("generate", help="simulate households' days into a HOMER-like dataset")
    gen.add_argument("--households", type=int, default=5, help="how many households (5)")
    gen.add_argument("--train-days", type=int, default=50, help="training days per household (50)")
    gen.add_argument("--test-days", type=int, default=10, help="test days per household (10)")
    gen.add_argument("--seed", type=int, default=0, help="dataset seed (0)")
    gen.add_argument("--out", type=Path, required=True, help="dataset folder (created; an interrupted run resumes)")
    add_backend_arguments(gen, "days")
    gen.add_argument("--habits", type=Path, default=None,
                     help="households from a HOMER personaBasedSchedules folder instead of ours")
    gen.add_argument("--scripts", type=Path, default=None,
                     help="activity scripts from a folder laid out <activity>/<name>.txt instead of ours")
    gen.add_argument("--json", action="store_true", help="print one JSON object (no progress bar)")
    gen.set_defaults(func=cmd_generate)

    dataset = subparsers.add_parser("dataset", help="inspect a dataset")
    dataset_commands = dataset.add_subparsers(dest="dataset_command", required=True, metavar="DATASET_COMMAND")
    stats = dataset_commands.add_parser("stats", help="steps, moves and objects used per household")
    stats.add_argument("data", type=Path, help="dataset folder")
    stats.add_argument("--json", action="store_true", help="print one JSON object")
    stats.set_defaults(func=cmd_dataset_stats)

    day = subparsers.add_parser("simulate-day", help="simulate one day of one household, recorded with rerun")
    day.add_argument("--household", default="household_a", help="household name (household_a)")
    day.add_argument("--seed", type=int, default=0, help="seed (0)")
    day.add_argument("--day", type=int, default=0, help="day index (0)")
    day.add_argument("--split", choices=("train", "test"), default="train")
    day.add_argument("--rrd", type=Path, default=None, help="write a rerun recording of the day here")
    day.add_argument("--json", action="store_true", help="print one JSON object")
    day.set_defaults(func=cmd_simulate_day)

    compat = subparsers.add_parser("compat-check", help="run every script of a HOMER-style folder in our apartment")
    source = compat.add_mutually_exclusive_group(required=True)
    source.add_argument("--scripts", type=Path, help="folder laid out <activity>/<name>.txt")
    source.add_argument("--from-homer-plus", type=Path, metavar="HOUSEHOLD",
                        help="the activity scripts embedded in a HOMER+ household's day scripts (each distinct "
                        "'### <activity>-<variant>.txt' block once, as '## <min>-<max>' and its actions, so line n is "
                        "the block's action n - 1; a HouseholdX folder or a folder of NNN.txt)")
    compat.add_argument("--json", action="store_true", help="print one JSON object")
    compat.set_defaults(func=cmd_compat_check)

    rep = subparsers.add_parser(
        "replay", help="live timed day scripts (HOMER+ format) physically into a dataset",
        description="Each day script NNN.txt (a HouseholdX folder with scripts_train/ and scripts_test/, a folder "
        "of NNN.txt, or one file) is lived in our apartment at its actions' minutes and written as day NNN of "
        "its split. A day that cannot run is reported with its reason and the run goes on; exit status 1 then.")
    rep.add_argument("scripts", type=Path, help="a HouseholdX folder, a folder of NNN.txt day scripts, or one file")
    rep.add_argument("--out", type=Path, required=True, help="dataset folder (created; an interrupted run resumes)")
    add_backend_arguments(rep, "days")
    rep.add_argument("--household", default=None, help="household name (default: the HouseholdX folder's name)")
    rep.add_argument("--rrd", type=Path, default=None, help="record the day with rerun here (one day script only)")
    rep.add_argument("--json", action="store_true", help='print {"days", "completed", "failed": {day: reason}}')
    rep.set_defaults(func=cmd_replay)

    check = subparsers.add_parser(
        "replay-check", help="replay a HOMER+ household and compare with the authors' graphs",
        description="Replays every day script of an unpacked HouseholdX folder (scripts_train/, scripts_test/, "
        "processed_seqLM_coarse/) from the authors' start arrangement and compares each movable object's parent every "
        "10 minutes, and each <<Graph Changes>> edge line after its action, with the authors' graphs; disagreements "
        "are counted by cause. Actions naming things we lack are left out and counted (homer replay refuses them).")
    check.add_argument("household", type=Path, help="the unpacked HouseholdX folder")
    check.add_argument("--days", type=int, default=None,
                       help="check only the first N days (training days first, in number order)")
    check.add_argument("--out", type=Path, default=None,
                       help="also write the completed days here as a dataset, each up to the authors' last graph "
                       "step (to score predictors on the replay with homer evaluate --data OUT); a new or empty "
                       "folder, or one this check wrote")
    add_backend_arguments(check, "days")
    check.add_argument("--json", action="store_true",
                       help='print {"days", "days_completed", "agreement", "graph_changes_seen", "agreement_known", '
                       '"graph_changes_seen_known", "causes", "failed"}')
    check.set_defaults(func=cmd_replay_check)

    imports = subparsers.add_parser("import", help="convert external data into a homer-sim dataset")
    import_commands = imports.add_subparsers(dest="import_command", required=True, metavar="FORMAT")
    homer_plus = import_commands.add_parser(
        "homer-plus", help="one HOMER+ household (HouseholdX/processed_seqLM_coarse) -> dataset folder",
        description="Read common_data.json, train/*.pt and test/*.pt (weights only) of one household and write it "
        "into DIR, keeping the upstream train/test split; a DIR holding other HOMER+ households gains this one.")
    homer_plus.add_argument("path", type=Path, help="the unpacked HouseholdX folder (or its processed_seqLM_coarse)")
    homer_plus.add_argument("--out", type=Path, required=True, help="dataset folder to create or extend")
    homer_plus.add_argument("--name", default=None, help="household name in the dataset (default: the folder's)")
    homer_plus.add_argument("--json", action="store_true", help="print one JSON object")
    homer_plus.set_defaults(func=cmd_import_homer_plus)
