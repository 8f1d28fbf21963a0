"""The activity script language (VirtualHome style, as in the seed paper's appendix) and a symbolic checker.

A script is a list of blocks. `## <min>-<max>` opens a block whose duration range is in routine minutes
(floats allowed, `##1-2` and `## 5 - 10` accepted, min <= max); the block's action lines follow:

    ## 1-2
    [Walk] <cupboard>
    [Open] <cupboard>
    [Grab] <bowl>
    [PutBack] <bowl> <table_dining_room>

Action lines are `[Verb]`, `[Verb] <arg>` or `[Verb] <arg1> <arg2>` (no space needed between `]`, `>` and
`<`; a VirtualHome instance id such as `<table> (114)` is passed to the resolver, which maps the HOMER+ apartment's
instances and otherwise goes by the name). HOMER's crowd-sourced scripts sometimes leave the brackets out,
`Switchoff <light_bedroom>`: a verb followed by arguments is read the same. Verbs are case-insensitive.
Blank lines, `#` comments (a `#` not followed by another `#`) and annotation lines starting with `+<` or `-<`
are ignored. Names are resolved to node names by a callable (see `homer_sim.person.aliases.Resolver`).

Verbs that change the world (`WORLD_VERBS`): walk, grab, open, close, putback, putin, putobjback, puton,
putoff, drop. Every other accepted verb (`TIME_VERBS`) is a timed avatar action: the person walks to what it acts
on (unless holding it) and spends the action's time there; switchon and switchoff also keep the appliance's on/off
state (`Executor.switched_on`, logged in `DayLog.switches`). Unknown verbs are errors naming file and line.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass

from homer_sim.errors import HomerError, unknown_name
from homer_sim.graph import INSIDE, ON

WORLD_VERBS: dict[str, frozenset[int]] = {
    "walk": frozenset({1}),  # go to a node (an object: where it lies now; a room: into it)
    "grab": frozenset({1}),  # take an object into a free hand (two hands)
    "open": frozenset({1}),  # open an articulated container; on anything else it only takes time
    "close": frozenset({1}),  # close it again
    "putback": frozenset({2}),  # put a held object on/into the target as the target is built
    "putin": frozenset({2}),  # put a held object inside a container or on a room's floor
    "putobjback": frozenset({1}),  # put a held object back where it was grabbed from
    "puton": frozenset({1}),  # wear an object (taken into a hand first if not held)
    "putoff": frozenset({1}),  # take a worn object off, into a hand
    "drop": frozenset({1}),  # let a held object fall onto the floor where the person stands
}
"""Verbs that change where the person or an object is, with their accepted numbers of arguments."""

TIME_VERBS: dict[str, frozenset[int]] = {
    **{verb: frozenset({1}) for verb in (
        "find", "lookat", "turnto", "pointat", "sit", "lie", "eat", "drink", "wash", "rinse", "scrub", "wipe",
        "cut", "switchon", "switchoff", "plugin", "plugout", "push", "pull", "move", "type", "read", "watch",
        "touch", "greet", "squeeze",
    )},
    "pour": frozenset({2}),  # pour <what> <into>
    "standup": frozenset({0}),
    "sleep": frozenset({0, 1}),
    "wakeup": frozenset({0}),
}
"""Verbs that only take time (the person walks to what they act on), with their accepted argument counts."""

VERBS: dict[str, frozenset[int]] = {**WORLD_VERBS, **TIME_VERBS}


class ScriptError(HomerError):
    """One script file is malformed. `errors` lists every problem found as (line, reason), in line order;
    `line` and `reason` are the first of them. str() is `path:line: reason`, one line per problem."""

    def __init__(self, path: str, errors: Sequence[tuple[int, str]]) -> None:
        if not errors:
            raise ValueError("a ScriptError needs at least one error")
        self.path = str(path)
        self.errors = sorted(errors, key=lambda e: e[0])
        self.line, self.reason = self.errors[0]
        super().__init__("\n".join(f"{self.path}:{line}: {reason}" for line, reason in self.errors))


@dataclass(frozen=True)
class Action:
    """One action line: verb in lower case, arguments as resolved node names, its 1-based line and raw text."""

    verb: str
    args: tuple[str, ...]
    line: int
    text: str


@dataclass(frozen=True)
class Block:
    """Actions sharing one duration range [min_min, max_min] in routine minutes; `line` is its header line."""

    min_min: float
    max_min: float
    actions: tuple[Action, ...]
    line: int


@dataclass(frozen=True)
class Script:
    """A parsed script of `activity`; `variant` names it (the file stem), `path` is where it came from."""

    activity: str
    variant: str
    path: str
    blocks: tuple[Block, ...]

    @property
    def duration_range(self) -> tuple[float, float]:
        """(shortest, longest) total duration in routine minutes: the sums of the blocks' mins and maxes."""
        return sum(b.min_min for b in self.blocks), sum(b.max_min for b in self.blocks)

    @property
    def actions(self) -> tuple[Action, ...]:
        return tuple(a for b in self.blocks for a in b.actions)


_NUMBER = r"(\d+(?:\.\d*)?|\.\d+)"
_HEADER = re.compile(rf"^##\s*{_NUMBER}\s*-\s*{_NUMBER}$")
_ACTION = re.compile(r"^\[\s*([A-Za-z_]+)\s*\]\s*(.*)$")
_BARE_ACTION = re.compile(r"^([A-Za-z_]+)\s+(<.*)$")  # `Switchoff <light_bedroom>`: the brackets left out
_ARGUMENT = re.compile(r"\s*<([^<>]*)>(?:\s*\((\d+)\))?")


def _parse_header(text: str) -> tuple[float, float] | str:
    match = _HEADER.match(text)
    if match is None:
        return f"bad block header {text!r}; expected '## <min>-<max>' in minutes"
    low, high = float(match.group(1)), float(match.group(2))
    if low > high:
        return f"bad duration range {text!r}: min {low:g} is larger than max {high:g}"
    return low, high


def _split_arguments(rest: str) -> list[tuple[str, int | None]] | None:
    """(name between angle brackets, its id or None) for each argument of `rest`, or None when something else
    is there."""
    names, position = [], 0
    while position < len(rest):
        match = _ARGUMENT.match(rest, position)
        if match is None:
            return None if rest[position:].strip() else names
        names.append((match.group(1).strip(), None if match.group(2) is None else int(match.group(2))))
        position = match.end()
    return names


def parse_action(text: str, line: int, resolve: Callable[[str], str], errors: list) -> Action | None:
    """One action line -> Action, or None after appending (line, reason) to `errors`."""
    match = _ACTION.match(text) or _BARE_ACTION.match(text)
    names = _split_arguments(match.group(2)) if match else None
    if match is None or names is None:
        errors.append((line, f"cannot read {text!r}; expected '[Verb] <name>' or '[Verb] <name> <name>'"))
        return None
    verb = match.group(1).lower()
    if verb not in VERBS:
        errors.append((line, str(unknown_name("verb", verb, VERBS))))
        return None
    ok = True
    if len(names) not in VERBS[verb]:
        wanted = " or ".join(str(n) for n in sorted(VERBS[verb]))
        errors.append((line, f"[{match.group(1)}] takes {wanted} argument(s), got {len(names)}"))
        ok = False
    args = []
    for name, instance in names:
        try:
            args.append(resolve(name) if instance is None else resolve(name, instance))
        except KeyError as exc:
            errors.append((line, str(exc) if isinstance(exc, HomerError) else f"unknown name {name!r}"))
            ok = False
    return Action(verb, tuple(args), line, text) if ok else None


def parse_script(text: str, path: str, activity: str, variant: str, resolve: Callable[[str], str]) -> Script:
    """Parse a script file's text. Every problem of the file is collected and raised as one ScriptError.

    resolve: maps a name written in the script to a node name, raising KeyError for unknown names (the
    error's message is reported, so it should list the closest known names); called as resolve(name, id) for
    an argument written with a VirtualHome id, `<table> (114)` (see `homer_sim.person.aliases.Resolver`).
    """
    errors: list[tuple[int, str]] = []
    blocks: list[Block] = []
    header: tuple[float, float, int] | None = None
    actions: list[Action] = []

    def close_block() -> None:
        if header is None:
            return
        if not actions and not any(line > header[2] for line, _ in errors):
            errors.append((header[2], "block has no actions"))
        blocks.append(Block(header[0], header[1], tuple(actions), header[2]))

    for number, raw in enumerate(text.splitlines(), start=1):
        stripped = raw.strip()
        if not stripped or stripped.startswith(("+<", "-<")) or (stripped[0] == "#" and stripped[:2] != "##"):
            continue
        if stripped.startswith("##"):
            close_block()
            parsed = _parse_header(stripped)
            if isinstance(parsed, str):
                errors.append((number, parsed))
                parsed = (0.0, 0.0)
            header, actions = (parsed[0], parsed[1], number), []
            continue
        action = parse_action(stripped, number, resolve, errors)
        if header is None:
            errors.append((number, "action before the first '## <min>-<max>' block header"))
        elif action is not None:
            actions.append(action)
    close_block()
    if not blocks and not errors:
        errors.append((1, "script has no blocks"))
    if errors:
        raise ScriptError(path, errors)
    return Script(activity, variant, str(path), tuple(blocks))


# --- symbolic checker ---------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Change:
    """An object's parent became `parent` at action `line`, in block `block` (0-based) of the script."""

    line: int
    block: int
    obj: str
    parent: str


@dataclass(frozen=True)
class SymbolicResult:
    """What a script does to where objects are, without physics.

    parents: final parent of every object given; moved: objects whose parent changed at some point;
    changes: every parent change in order; held, worn: what the person holds and wears at the end;
    problems: hard errors as (line, reason) (the executor would fail or the script is wrong);
    warnings: (line, reason) the executor copes with (a closed container it opens itself, a door left open).
    """

    parents: dict[str, str]
    moved: frozenset[str]
    changes: tuple[Change, ...]
    held: tuple[str, ...]
    worn: tuple[str, ...]
    problems: tuple[tuple[int, str], ...]
    warnings: tuple[tuple[int, str], ...]


CARRYING_ACTIVITIES = frozenset({"leave_home"})
"""Activities that may end with objects in hand (they go outside with the person)."""
HANDS = 2


class _State:
    """The mutable state of one symbolic run."""

    def __init__(self, parents, relations, containers, closed, node_rooms, held, worn):
        self.parents = dict(parents)
        self.containers, self.closed = set(containers), set(closed)
        self.relations = {obj: INSIDE if parent in self.containers else ON for obj, parent in self.parents.items()}
        self.relations.update(relations or {})
        self.node_rooms = dict(node_rooms or {})
        self.rooms = set(self.node_rooms.values())
        self.held, self.worn = list(held), list(worn)
        self.grabbed_from: dict[str, tuple[str, int]] = {}
        self.opened: dict[str, int] = {}
        self.location: str | None = None
        self.changes: list[Change] = []
        self.problems: list[tuple[int, str]] = []
        self.warnings: list[tuple[int, str]] = []
        self.block = 0

    def room_of(self, node: str) -> str | None:
        seen = set()
        while node in self.parents and node not in seen:
            seen.add(node)
            node = self.parents[node]
        return node if node in self.rooms else self.node_rooms.get(node)

    def set_parent(self, obj: str, parent: str, relation: int, line: int) -> None:
        self.relations[obj] = relation
        if self.parents.get(obj) != parent:
            self.parents[obj] = parent
            self.changes.append(Change(line, self.block, obj, parent))

    def closed_around(self, node: str, relation: int | None = None) -> str | None:
        """The closed container that `node` (or something `relation` to `node`) is inside of, if any."""
        seen = set()
        while node not in seen:
            seen.add(node)
            if node in self.closed and relation == INSIDE:
                return node
            if node not in self.parents:
                return None
            node, relation = self.parents[node], self.relations.get(node)
        return None

    def take(self, obj: str, line: int, verb: str) -> bool:
        """Put `obj` into a free hand; False (with a problem) when that is impossible."""
        if obj not in self.parents:
            self.problems.append((line, f"[{verb}] {obj}: not a movable object"))
            return False
        if obj in self.held:
            self.problems.append((line, f"[{verb}] {obj}: already held"))
            return False
        if len(self.held) >= HANDS:
            self.problems.append((line, f"[{verb}] {obj}: both hands are full ({', '.join(self.held)})"))
            return False
        if obj in self.worn:  # the executor takes it off
            self.warnings.append((line, f"[{verb}] {obj}, which is worn: taken off"))
            self.worn.remove(obj)
        else:
            container = self.closed_around(obj)
            if container is not None:
                self.warnings.append((line, f"[{verb}] {obj} from {container}, which is closed"))
            self.grabbed_from[obj] = (self.parents[obj], self.relations[obj])
        self.held.append(obj)
        return True

    def put(self, obj: str, target: str, relation: int, line: int, verb: str) -> None:
        if obj not in self.held:
            self.problems.append((line, f"[{verb}] {obj}: not held"))
            return
        if target == obj or target in self.held or target in self.worn:
            self.problems.append((line, f"[{verb}] {obj} onto {target}, which is held or worn"))
            return
        container = self.closed_around(target, relation)
        if container is not None:
            self.warnings.append((line, f"[{verb}] {obj} into {container}, which is closed"))
        self.held.remove(obj)
        self.set_parent(obj, target, relation, line)

    def walk(self, target: str, line: int) -> None:
        room = self.room_of(target)
        if room is not None:
            self.location = room
        if self.location == "outside":
            for obj in self.held + self.worn:
                self.set_parent(obj, "outside", INSIDE, line)


def _step(state: _State, action: Action) -> None:
    verb, args, line = action.verb, action.args, action.line
    if verb == "walk":
        state.walk(args[0], line)
    elif verb == "grab":
        state.take(args[0], line, "grab")
    elif verb in ("open", "close") and args[0] in state.containers:
        if verb == "open":
            state.closed.discard(args[0])
            state.opened[args[0]] = line
        else:
            state.closed.add(args[0])
            state.opened.pop(args[0], None)
    elif verb == "putin":
        state.put(args[0], args[1], INSIDE, line, verb)
    elif verb == "putback":
        relation = INSIDE if args[1] in state.containers or args[1] in state.rooms else ON
        state.put(args[0], args[1], relation, line, verb)
    elif verb == "putobjback":
        origin = state.grabbed_from.get(args[0])
        if origin is None:
            state.problems.append((line, f"[putobjback] {args[0]}: not grabbed in this script"))
        else:
            state.put(args[0], origin[0], origin[1], line, verb)
    elif verb == "puton":
        if args[0] in state.worn:
            state.warnings.append((line, f"[puton] {args[0]}: already worn"))
        elif args[0] in state.held or state.take(args[0], line, "puton"):
            state.held.remove(args[0])
            state.worn.append(args[0])
    elif verb == "putoff":
        if args[0] not in state.worn:
            state.problems.append((line, f"[putoff] {args[0]}: not worn"))
        elif len(state.held) >= HANDS:
            state.problems.append((line, f"[putoff] {args[0]}: both hands are full ({', '.join(state.held)})"))
        else:
            state.worn.remove(args[0])
            state.held.append(args[0])
    elif verb == "drop":
        state.put(args[0], state.location or "floor", INSIDE, line, verb)


def symbolic_run(script: Script, parents: Mapping[str, str], containers: Iterable[str], closed: Iterable[str],
                 *, relations: Mapping[str, int] | None = None, node_rooms: Mapping[str, str] | None = None,
                 held: Iterable[str] = (), worn: Iterable[str] = ()) -> SymbolicResult:
    """Run `script` on parents only: hands (two), worn objects, each object's parent, open/closed containers.

    parents: object -> parent node at the start (the keys are the movable objects). containers: the
    articulated containers (open/close change them); closed: those closed at the start. relations: object ->
    `homer_sim.graph.ON` or `INSIDE` at the start (default: INSIDE when the parent is a container), so that
    taking something from the top of a closed dresser is fine. `putback` onto a container means INSIDE, as
    the executor does. node_rooms: every furniture and room -> its room (rooms map to themselves), so walking
    tracks the person's room: `drop` puts on that room's floor, and whatever is held or worn out there becomes
    INSIDE `outside`. held, worn: what the person holds and wears at the start (come_home after leave_home).
    """
    state = _State(parents, relations, containers, closed, node_rooms, held, worn)
    for index, block in enumerate(script.blocks):
        state.block = index
        for action in block.actions:
            _step(state, action)
    end = script.blocks[-1].actions[-1].line if script.blocks and script.blocks[-1].actions else 0
    if state.held and script.activity not in CARRYING_ACTIVITIES:
        state.problems.append((end, f"still held at the end: {', '.join(state.held)}"))
    for container, line in sorted(state.opened.items(), key=lambda kv: kv[1]):
        state.warnings.append((line, f"{container} opened here and left open"))
    moved = frozenset(c.obj for c in state.changes)
    return SymbolicResult(state.parents, moved, tuple(state.changes), tuple(state.held), tuple(state.worn),
                          tuple(state.problems), tuple(state.warnings))
