"""Synthetic households of toy routines, written as a real dataset folder (for tests and benchmarks).

The vocabulary is the apartment's (`homer_sim.home.apartment`: its rooms, furniture and objects' start places).
A household is one habit per activity: the probability of doing it on a day, a mean start minute, a spread
(minutes, normal jitter) and one script variant. A script is a list of (fraction of the duration, object,
destination) actions; the destination "home" is the object's start place. While the person is away, the
keys, wallet, phone and bag are INSIDE `outside`. A few unpredictable moves of miscellaneous objects are added
every day. Everything is deterministic given the numpy Generator passed in.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from homer_sim.clock import DAY_END_MIN, DAY_START_MIN, GRID_MIN
from homer_sim.data.dataset import DatasetMeta, Day, write_day, write_meta
from homer_sim.graph import INSIDE, NONE, ON
from homer_sim.home.apartment import default_layout

_LAYOUT = default_layout()
ROOMS = tuple(_LAYOUT.room_names())
FURNITURE = {f.name: (f.category, f.room) for f in _LAYOUT.furniture}  # name: (category, room)
HOME = {o.name: o.parent for o in _LAYOUT.objects}  # object: its start place
CONTAINERS = frozenset(ROOMS) | {"fridge", "cupboard", "dishwasher", "kitchen_cabinet", "dresser", "shower",
                                 "bathroom_cabinet", "trashcan", "basket_for_clothes", "sink_dining_room"}

Action = tuple[float, str, str]  # (fraction of the activity's duration 0..1, object, destination or "home")


def _script(text: str) -> tuple[Action, ...]:
    """'0 bowl table_dining_room; 1 bowl home' -> ((0.0, 'bowl', 'table_dining_room'), (1.0, 'bowl', 'home'))."""
    return tuple((float(f), o, d) for f, o, d in (a.split() for a in text.split(";")))


T, SINK, DESK = "table_dining_room", "sink_dining_room", "desk_home_office"
# activity: (duration range in minutes, script variants)
SCRIPTS: dict[str, tuple[tuple[float, float], tuple[tuple[Action, ...], ...]]] = {
    "brushing_teeth": ((5, 15), (_script("0 toothbrush sink_bathroom; .1 tooth_paste sink_bathroom; .9 tooth_paste "
                                         "home; 1 toothbrush home"),)),
    "showering": ((15, 35), (_script("0 towel shower; .1 shampoo bathroom_counter; 1 shampoo home; 1 towel "
                                     "basket_for_clothes"),
                             _script("0 towel shower; .5 razor sink_bathroom; 1 razor home; 1 towel home"))),
    "breakfast": ((20, 50), (_script(f"0 bowl {T}; .1 spoon {T}; .25 food_cereal {T}; .3 milk {T}; .75 milk home; "
                                     f".8 food_cereal home; 1 bowl {SINK}; 1 spoon {SINK}"),
                             _script(f"0 plate {T}; .1 knife {T}; .2 food_bread {T}; .3 food_butter {T}; .35 food_jam "
                                     f"{T}; .8 food_butter home; .85 food_jam home; 1 plate {SINK}; 1 knife {SINK}"),
                             _script(f"0 mug coffe_maker; .2 mug {T}; .3 food_apple {T}; .9 food_apple trashcan; "
                                     f"1 mug {SINK}"))),
    "lunch": ((25, 60), (_script(f"0 food_vegetable kitchen_counter_left; .1 cutting_board {SINK}; .2 cookingpot "
                                 f"stove; .5 plate {T}; .55 fork {T}; .6 cookingpot {SINK}; 1 plate {SINK}; 1 fork "
                                 f"{SINK}; 1 food_vegetable home"),
                         _script(f"0 food_bread {T}; .1 food_cheese {T}; .2 plate {T}; .8 food_cheese home; 1 plate "
                                 f"{SINK}; 1 food_bread home"))),
    "dinner": ((40, 90), (_script(f"0 food_rice stove; .05 cookingpot stove; .3 food_rice home; .5 plate {T}; .55 "
                                  f"fork {T}; .6 wine_glass {T}; .6 wine {T}; .65 cookingpot {SINK}; .9 wine home; "
                                  f"1 plate dishwasher; 1 fork dishwasher; 1 wine_glass {SINK}"),)),
    "wash_dishes": ((10, 25), (_script(" ;".join(f"{f} {o} home" for f, o in zip(np.linspace(0, 1, 10).round(2), (
        "bowl", "spoon", "plate", "knife", "fork", "mug", "cookingpot", "cutting_board", "wine_glass", "sponge"),
        strict=True))),)),
    "computer_work": ((60, 180), (_script(f"0 coffee_cup {DESK}; .05 water_bottle {DESK}; .9 water_bottle home; 1 "
                                          f"coffee_cup {SINK}"),
                                  _script(f"0 spectacles {DESK}; .1 notebook chair_home_office; .9 notebook home; 1 "
                                          f"spectacles home"))),
    "reading": ((30, 90), (_script("0 book sofa_bedroom; .05 spectacles sofa_bedroom; 1 book home; 1 spectacles home"),
                           _script("0 magazine bed; .9 magazine bookshelf_bedroom; 1 magazine home"))),
    "watching_tv": ((30, 120), (_script("0 remote_control sofa_home_office; .1 blanket sofa_home_office; 1 "
                                        "remote_control home; 1 blanket home"),)),
    "laundry": ((30, 70), (_script("0 clothes_shirt washing_machine; 0 clothes_socks washing_machine; .1 "
                                   "laundry_detergent bathroom_counter; .2 laundry_detergent home; 1 clothes_shirt "
                                   "dresser; 1 clothes_socks dresser; 1 towel home"),)),
    "cleaning": ((20, 50), (_script("0 vacuum_cleaner bedroom; .4 vacuum_cleaner dining_room; .9 vacuum_cleaner home; "
                                    ".1 disinfectant_wipes table_bedroom; 1 disinfectant_wipes home"),)),
    "kitchen_cleaning": ((10, 30), (_script(f"0 sponge {SINK}; .05 dish_soap {SINK}; .9 dish_soap home; 1 kitchentowel "
                                            f"{T}; 1 sponge home"),)),
    "taking_medication": ((3, 8), (_script(f"0 painkillers {T}; 0 drinking_glass {T}; 1 painkillers home; 1 "
                                           f"drinking_glass {SINK}"),)),
    "listening_to_music": ((20, 60), (_script("0 headset sofa_home_office; .05 cd cd_player; 1 cd home; 1 headset "
                                              "home"),)),
    "playing_music": ((20, 60), (_script("0 instrument_guitar chair_home_office; 1 instrument_guitar home"),)),
    "socializing": ((60, 150), (_script(f"0 deck_of_cards {T}; .1 food_donut {T}; .2 wine_glass {T}; .9 deck_of_cards "
                                        f"home; 1 wine_glass {SINK}; 1 food_donut trashcan"),)),
}
AWAY_OBJECTS = ("keys", "wallet", "cellphone", "bag")
NOISE_OBJECTS = ("magazine", "newspaper", "pen", "notebook", "mail", "candle", "cellphone", "water_bottle", "pillow",
                 "highlighter", "umbrella", "slippers", "cloth_napkin", "deodorant", "hairbrush", "food_donut")
NOISE_PLACES = ("table_dining_room", "sofa_home_office", "bed", "table_bedroom", "desk_home_office",
                "bathroom_counter", "bench", "kitchen_counter_right", "table_home_office", "sofa_bedroom")
SMALL_ACTIVITIES = ("breakfast", "brushing_teeth", "showering")
LAST_GRID_MIN = DAY_END_MIN - GRID_MIN


@dataclass(frozen=True)
class Habit:
    """How one household does one activity: daily probability, start minute mean and spread, script variant."""

    probability: float
    mean_min: float
    spread_min: float
    variant: int


@dataclass(frozen=True)
class Household:
    name: str
    habits: dict[str, Habit]
    leave_probability: float  # per day
    leave_mean_min: float
    away_range_min: tuple[float, float]
    noise_moves: float  # mean number of unpredictable moves per day


_ACTIVITY_WINDOWS = {  # activity: (probability range, mean start range in minutes)
    "brushing_teeth": ((0.85, 1.0), (400, 480)), "showering": ((0.6, 0.95), (390, 560)),
    "breakfast": ((0.55, 0.95), (420, 570)), "lunch": ((0.5, 0.9), (720, 810)), "dinner": ((0.7, 0.95), (1080, 1200)),
    "wash_dishes": ((0.4, 0.8), (1230, 1300)), "computer_work": ((0.3, 0.8), (540, 900)),
    "reading": ((0.2, 0.6), (1200, 1320)), "watching_tv": ((0.3, 0.7), (1140, 1280)),
    "laundry": ((0.1, 0.3), (600, 1000)), "cleaning": ((0.1, 0.35), (600, 1080)),
    "kitchen_cleaning": ((0.2, 0.5), (800, 1260)), "taking_medication": ((0.3, 0.9), (480, 1260)),
    "listening_to_music": ((0.1, 0.4), (900, 1300)), "playing_music": ((0.05, 0.3), (900, 1300)),
    "socializing": ((0.05, 0.3), (1000, 1250)),
}


def sample_household(name: str, rng: np.random.Generator, activities: tuple[str, ...] | None = None) -> Household:
    """A household: one habit per activity drawn from the ranges above (deterministic given `rng`)."""
    habits = {}
    for activity, ((p_lo, p_hi), (m_lo, m_hi)) in _ACTIVITY_WINDOWS.items():
        if activities is None or activity in activities:
            habits[activity] = Habit(float(rng.uniform(p_lo, p_hi)), float(rng.uniform(m_lo, m_hi)),
                                     float(rng.choice([10.0, 20.0, 30.0, 45.0])),
                                     int(rng.integers(len(SCRIPTS[activity][1]))))
    return Household(name, habits, float(rng.uniform(0.3, 0.8)), float(rng.uniform(540, 900)),
                     (120.0, float(rng.uniform(200, 360))), float(rng.uniform(1.0, 3.0)))


@dataclass(frozen=True)
class Apartment:
    """The node list of a synthetic apartment and its start layout.

    home_parent: Shape (N,), int, each node's start parent index (-1 for rooms).
    home_relation: Shape (N,), int, ON or INSIDE (NONE for rooms).
    """

    nodes: tuple[str, ...]
    categories: tuple[str, ...]
    movable: tuple[bool, ...]
    home_parent: np.ndarray
    home_relation: np.ndarray

    def index(self, name: str) -> int:
        return self.nodes.index(name)

    def meta(self, households: tuple[str, ...]) -> DatasetMeta:
        return DatasetMeta(self.nodes, self.categories, self.movable, households, GRID_MIN)


def _objects_of(activities: tuple[str, ...]) -> list[str]:
    used = [o for a in activities for script in SCRIPTS[a][1] for _, o, _ in script]
    used += [d for a in activities for script in SCRIPTS[a][1] for _, _, d in script if d in HOME]
    return list(dict.fromkeys(used + list(AWAY_OBJECTS) + ["candle", "chessboard", "perfume"]))


def make_apartment(size: str = "real") -> Apartment:
    """The full apartment (`size="real"`, every node of the default layout) or a small one for fast tests
    (`"small"`, about 30 nodes)."""
    objects = list(HOME) if size == "real" else _objects_of(SMALL_ACTIVITIES)
    places = {HOME[o] for o in objects} | {d for a in SCRIPTS for s in SCRIPTS[a][1] for _, o, d in s if o in objects}
    furniture = [f for f in FURNITURE if size == "real" or f in places or f == "coffe_maker"]
    nodes = (*ROOMS, *furniture, *objects)
    categories = ("room",) * len(ROOMS) + tuple(FURNITURE[f][0] for f in furniture) + ("object",) * len(objects)
    index = {n: i for i, n in enumerate(nodes)}
    parent = np.full(len(nodes), -1, dtype=np.int32)
    for f in furniture:
        parent[index[f]] = index[FURNITURE[f][1]]
    for o in objects:
        parent[index[o]] = index[HOME[o]]
    relation = np.array([NONE if p < 0 else INSIDE if nodes[p] in CONTAINERS else ON for p in parent], dtype=np.int8)
    movable = tuple(c == "object" for c in categories)
    return Apartment(nodes, categories, movable, parent, relation)


Event = tuple[float, str, str]  # (routine minute, object, destination node)


def _away_events(house: Household, rng: np.random.Generator) -> tuple[list[Event], tuple[float, float] | None]:
    if rng.random() >= house.leave_probability:
        return [], None
    leave = float(np.clip(rng.normal(house.leave_mean_min, 45.0), 480, 1200))
    back = min(leave + float(rng.uniform(*house.away_range_min)), 1380.0)
    events = [(leave + i, o, "outside") for i, o in enumerate(AWAY_OBJECTS)]
    return events + [(back + i, o, HOME[o]) for i, o in enumerate(AWAY_OBJECTS)], (leave, back)


def _activity_events(house: Household, rng: np.random.Generator, away: tuple[float, float] | None,
                     objects: set[str]) -> tuple[list[Event], list[tuple[str, float, float]]]:
    events, schedule = [], []
    for activity, habit in house.habits.items():
        (lo, hi), variants = SCRIPTS[activity]
        happens = rng.random() < habit.probability
        start = float(np.clip(rng.normal(habit.mean_min, habit.spread_min), DAY_START_MIN - 20, 1390))
        end = start + float(rng.uniform(lo, hi))
        if not happens or (away is not None and start < away[1] and end > away[0]):
            continue
        schedule.append((activity, start, end))
        for fraction, obj, dest in variants[habit.variant]:
            if obj in objects:
                events.append((start + fraction * (end - start), obj, HOME[obj] if dest == "home" else dest))
    return events, schedule


def _noise_events(house: Household, rng: np.random.Generator, away: tuple[float, float] | None,
                  nodes: set[str]) -> list[Event]:
    candidates = [o for o in NOISE_OBJECTS if o in nodes]
    places = [p for p in NOISE_PLACES if p in nodes]
    events = []
    for _ in range(int(rng.poisson(house.noise_moves))):
        obj, place, minute = str(rng.choice(candidates)), str(rng.choice(places)), float(rng.uniform(360, 1400))
        if away is not None and obj in AWAY_OBJECTS and away[0] - 10 <= minute <= away[1] + 10:
            continue
        events.append((minute, obj, place))
        if rng.random() < 0.5:
            events.append((minute + float(rng.uniform(30, 240)), obj, HOME[obj]))
    return events


def sample_day(apartment: Apartment, house: Household, split: str, index: int, rng: np.random.Generator) -> Day:
    """One day on the 10-minute grid from 06:00 to 23:50: parents after all events up to each grid minute."""
    nodes = set(apartment.nodes)
    objects = {n for n, m in zip(apartment.nodes, apartment.movable, strict=True) if m}
    away_events, away = _away_events(house, rng)
    activity_events, schedule = _activity_events(house, rng, away, objects)
    events = sorted(away_events + activity_events + _noise_events(house, rng, away, nodes))
    return day_from_events(apartment, house.name, split, index, events, tuple(schedule))


def day_from_events(apartment: Apartment, household: str, split: str, index: int, events: list[Event],
                    schedule: tuple[tuple[str, float, float], ...] = ()) -> Day:
    """Apply timed moves (minute, object, destination) to the start layout and sample the 10-minute grid."""
    minutes = np.arange(DAY_START_MIN, LAST_GRID_MIN + 1, GRID_MIN, dtype=np.int32)
    parent, relation = apartment.home_parent.copy(), apartment.home_relation.copy()
    parents, relations, moves, cursor = [], [], [], 0
    events = sorted(events)
    for minute in minutes:
        while cursor < len(events) and events[cursor][0] <= minute:
            when, obj, dest = events[cursor]
            i, j = apartment.index(obj), apartment.index(dest)
            if parent[i] != j:
                rel = INSIDE if dest in CONTAINERS else ON
                moves.append((float(when), obj, apartment.nodes[parent[i]], dest, "INSIDE" if rel == INSIDE else "ON"))
                parent[i], relation[i] = j, rel
            cursor += 1
        parents.append(parent.copy())
        relations.append(relation.copy())
    return Day(household, split, index, minutes, np.array(parents, dtype=np.int16), np.array(relations, dtype=np.int8),
               schedule, tuple(moves))


def write_synthetic_dataset(root: str | Path, rng: np.random.Generator, households: int = 5, train_days: int = 50,
                            test_days: int = 10, size: str = "real") -> DatasetMeta:
    """Write `households` synthetic households (train and test days) as a dataset folder; returns its meta."""
    apartment = make_apartment(size)
    names = tuple(f"household_{chr(ord('a') + h)}" for h in range(households))
    meta = apartment.meta(names)
    write_meta(root, meta)
    activities = None if size == "real" else SMALL_ACTIVITIES
    for name, house_rng in zip(names, rng.spawn(households), strict=True):
        house = sample_household(name, house_rng, activities)
        day_rngs = house_rng.spawn(train_days + test_days)
        for k in range(train_days + test_days):
            split, index = ("train", k) if k < train_days else ("test", k - train_days)
            write_day(root, sample_day(apartment, house, split, index, day_rngs[k]))
    return meta
