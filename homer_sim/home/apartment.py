"""The default apartment: four rooms and `outside`, HOMER-named furniture and appliances, 80+ objects.

Plan (m, x east, y north): dining room with the kitchen [0, 6] x [0, 4.5], home office [6, 10] x [0, 4.5],
bathroom [0, 3.5] x [4.5, 8], bedroom [3.5, 10] x [4.5, 8], and `outside`, a porch beyond the front door
in the west wall. Doorways are 1.0 m wide. Every furniture instance is named after where it is.
"""

from __future__ import annotations

from functools import cache

from homer_sim.graph import INSIDE, ON
from homer_sim.home.layout import Furniture, Layout, ObjectDecl, Room, Wall

WHITE = (0.92, 0.92, 0.9, 1.0)
STEEL = (0.75, 0.76, 0.78, 1.0)

ROOMS = (
    Room("dining_room", (0.0, 0.0, 6.0, 4.5)),
    Room("home_office", (6.0, 0.0, 10.0, 4.5)),
    Room("bathroom", (0.0, 4.5, 3.5, 8.0)),
    Room("bedroom", (3.5, 4.5, 10.0, 8.0)),
    Room("outside", (-3.0, 0.8, 0.0, 3.8)),
)

WALLS = (
    Wall((0.0, 0.0), (10.0, 0.0), name="south"),
    Wall((10.0, 0.0), (10.0, 8.0), name="east"),
    Wall((0.0, 8.0), (10.0, 8.0), name="north"),
    Wall((0.0, 0.0), (0.0, 8.0), ((1.8, 2.8),), name="west_front_door"),
    Wall((6.0, 0.0), (6.0, 4.5), ((3.2, 4.2),), name="dining_office"),
    Wall((0.0, 4.5), (10.0, 4.5), ((2.2, 3.2), (4.4, 5.4)), name="middle"),
    Wall((3.5, 4.5), (3.5, 8.0), name="bathroom_bedroom"),
)


def _f(name, cls, kind, room, pos, facing, size, category="furniture", on=None, **params) -> Furniture:
    return Furniture(name, cls, kind, room, pos, facing, size, category, on, params)


FURNITURE = (
    # Kitchen row along the south wall of the dining room, fronts facing north.
    _f("fridge", "fridge", "cabinet", "dining_room", (0.5, 0.4), "N", (0.7, 0.7, 1.45), "appliance",
       shelves=(0.45, 0.85), hinge="right", rgba=WHITE, door_mass=5.0),
    _f("cupboard", "cupboard", "cabinet", "dining_room", (1.3, 0.35), "N", (0.8, 0.6, 1.3),
       shelves=(0.45, 0.85)),
    _f("kitchen_counter_left", "kitchen_counter", "block", "dining_room", (2.1, 0.35), "N", (0.8, 0.6, 0.9)),
    _f("sink_dining_room", "sink", "sink", "dining_room", (2.9, 0.35), "N", (0.8, 0.6, 0.9)),
    _f("dishwasher", "dishwasher", "cabinet", "dining_room", (3.6, 0.35), "N", (0.6, 0.6, 0.85), "appliance",
       shelves=(0.45,), rgba=STEEL, plinth=0.08),
    _f("stove", "stove", "block", "dining_room", (4.25, 0.35), "N", (0.7, 0.6, 0.9), "appliance",
       rgba=(0.2, 0.2, 0.22, 1.0)),
    _f("kitchen_counter_right", "kitchen_counter", "block", "dining_room", (5.0, 0.35), "N", (0.8, 0.6, 0.9)),
    _f("kitchen_cabinet", "kitchen_cabinet", "cabinet", "dining_room", (5.65, 1.4), "W", (0.8, 0.6, 0.9),
       shelves=(0.45,), top_place=True),
    _f("microwave", "microwave", "cabinet", "dining_room", (5.53, 1.5), "W", (0.5, 0.36, 0.3), "appliance",
       on="kitchen_cabinet", plinth=0.02, hinge="left", rgba=STEEL, door_mass=1.0),
    _f("coffe_maker", "coffe_maker", "cabinet", "dining_room", (1.85, 0.25), "N", (0.22, 0.25, 0.35), "appliance",
       on="kitchen_counter_left", shelves=(0.19,), plinth=0.01, door=False, rgba=(0.1, 0.1, 0.1, 1.0)),
    # Dining and entrance.
    _f("table_dining_room", "table", "table", "dining_room", (2.8, 2.3), "N", (1.4, 0.9, 0.75), access="all"),
    _f("bookshelf_dining_room", "bookshelf", "shelf", "dining_room", (1.5, 4.275), "S", (1.0, 0.35, 1.2),
       shelves=(0.42, 0.82)),
    _f("shoe_rack", "shoe_rack", "shelf", "dining_room", (0.225, 3.2), "E", (0.6, 0.35, 0.5), shelves=(0.25,)),
    _f("bench", "bench", "block", "dining_room", (0.25, 3.975), "E", (0.85, 0.4, 0.45)),
    _f("mat", "mat", "flat", "dining_room", (0.45, 2.3), "E", (0.8, 0.6, 0.01), "decor"),
    # Home office.
    _f("desk_home_office", "desk", "desk", "home_office", (9.6, 1.9), "W", (1.4, 0.7, 0.75)),
    _f("filing_cabinet", "filing_cabinet", "drawers", "home_office", (9.64, 0.8), "W", (0.5, 0.6, 1.0), drawers=3,
       rgba=(0.55, 0.57, 0.6, 1.0)),
    _f("chair_home_office", "chair", "chair", "home_office", (9.7, 3.3), "W", (0.5, 0.5, 0.9)),
    _f("bookshelf_home_office", "bookshelf", "shelf", "home_office", (6.8, 0.225), "N", (1.0, 0.35, 1.2),
       shelves=(0.42, 0.82)),
    _f("tvstand_home_office", "tvstand", "shelf", "home_office", (8.4, 0.275), "N", (1.2, 0.45, 0.5),
       shelves=(0.25,)),
    _f("table_home_office", "table", "table", "home_office", (7.9, 2.0), "N", (1.0, 0.5, 0.45), access="all"),
    _f("sofa_home_office", "sofa", "sofa", "home_office", (8.2, 4.025), "S", (2.0, 0.85, 0.85)),
    # Bedroom.
    _f("bed", "bed", "block", "bedroom", (8.95, 6.2), "W", (1.6, 2.0, 0.55), access="all",
       rgba=(0.85, 0.85, 0.95, 1.0)),
    _f("table_bedroom", "table", "table", "bedroom", (9.7, 7.45), "W", (0.5, 0.5, 0.6)),
    _f("dresser", "dresser", "drawers", "bedroom", (5.8, 7.7), "S", (1.2, 0.5, 0.9), drawers=3),
    _f("bookshelf_bedroom", "bookshelf", "shelf", "bedroom", (7.2, 7.775), "S", (0.8, 0.35, 1.2),
       shelves=(0.42, 0.82)),
    _f("sofa_bedroom", "sofa", "sofa", "bedroom", (3.975, 7.0), "E", (1.6, 0.85, 0.85)),
    # Bathroom.
    _f("shower", "shower", "shower", "bathroom", (0.525, 7.45), "E", (1.0, 0.95, 2.0)),
    _f("toilet", "toilet", "block", "bathroom", (0.375, 5.5), "E", (0.4, 0.65, 0.75), no_place=True, rgba=WHITE),
    _f("sink_bathroom", "sink", "sink", "bathroom", (1.95, 7.7), "S", (0.7, 0.5, 0.85), basin_depth=0.14),
    _f("bathroom_counter", "bathroom_counter", "block", "bathroom", (2.75, 7.7), "S", (0.9, 0.5, 0.85),
       rgba=WHITE),
    _f("bathroom_cabinet", "bathroom_cabinet", "cabinet", "bathroom", (3.25, 6.8), "W", (0.8, 0.4, 1.2),
       shelves=(0.45, 0.85), rgba=WHITE),
    _f("bathroom_shelf", "bathroom_shelf", "shelf", "bathroom", (0.225, 6.4), "E", (0.8, 0.35, 1.0),
       shelves=(0.45,), rgba=WHITE),
    _f("washing_machine", "washing_machine", "cabinet", "bathroom", (3.15, 5.5), "W", (0.6, 0.6, 0.85),
       "appliance", top_place=True, rgba=WHITE, plinth=0.15),
    # What HOMER's activity scripts name beyond its graph, placed where nothing stood.
    _f("chair_bedroom", "chair", "chair", "bedroom", (4.75, 5.7), "E", (0.5, 0.5, 0.9)),
    _f("drying_rack", "drying_rack", "shelf", "bedroom", (6.9, 4.725), "N", (1.2, 0.4, 1.0), shelves=(0.5,)),
    _f("shredder", "shredder", "block", "home_office", (7.55, 0.2), "N", (0.4, 0.3, 0.6), "appliance",
       no_place=True, rgba=(0.2, 0.2, 0.22, 1.0)),
    _f("oven", "oven", "cabinet", "dining_room", (3.8, 4.16), "S", (0.75, 0.65, 0.85), "appliance",
       shelves=(0.4,), hinge="left", rgba=STEEL, door_mass=4.0, plinth=0.08, top_place=True),
)


def _objects(parent: str, relation: int, names: str, level: int | None = None) -> tuple[ObjectDecl, ...]:
    return tuple(ObjectDecl(n, n, parent, relation, level) for n in names.split())


def _floor(room: str, name: str, x: float, y: float) -> ObjectDecl:
    return ObjectDecl(name, name, room, INSIDE, at=(x, y))


OBJECTS = (
    *_objects("cupboard", INSIDE, "bowl plate spoon fork", level=1),
    *_objects("cupboard", INSIDE, "mug coffee_cup drinking_glass wine_glass", level=2),
    *_objects("cupboard", INSIDE, "food_cereal food_rice tea", level=0),
    # the coffee tin (10 cm) stands with its ground coffee and filters: seven boxes and tins on the cupboard's
    # bottom shelf left 3 cm beside the rice, where a side grasp's open finger needs more, the more so shifted
    # 2.5 cm; six leave 4 cm
    *_objects("bookshelf_dining_room", ON, "coffee", level=0),
    *_objects("cupboard", INSIDE, "oil food_jam", level=0),
    *_objects("fridge", INSIDE, "milk food_cheese food_butter", level=1),
    *_objects("fridge", INSIDE, "food_vegetable food_apple wine", level=0),
    *_objects("kitchen_counter_left", ON, "knifeblock cutting_board knife food_bread"),
    *_objects("kitchen_counter_right", ON, "sponge kitchentowel food_donut"),
    *_objects("kitchen_cabinet", INSIDE, "cookingpot dish_soap", level=0),
    *_objects("kitchen_cabinet", INSIDE, "disinfectant_wipes trashbag cloth_napkin", level=1),
    *_objects("bookshelf_dining_room", ON, "magazine newspaper candle", level=1),
    *_objects("bookshelf_dining_room", ON, "deck_of_cards chessboard", level=2),
    *_objects("shoe_rack", ON, "shoes", level=0),
    *_objects("shoe_rack", ON, "slippers", level=1),
    *_objects("bench", ON, "mail keys umbrella"),
    _floor("dining_room", "trashcan", 5.3, 2.7),
    *_objects("desk_home_office", ON, "keyboard mouse laptop headset notebook pen highlighter", level=0),
    *_objects("desk_home_office", INSIDE, "charger cd", level=1),
    *_objects("bookshelf_home_office", ON, "water_bottle", level=1),
    *_objects("tvstand_home_office", ON, "remote_control cd_player", level=2),
    *_objects("sofa_home_office", ON, "instrument_guitar"),
    _floor("home_office", "vacuum_cleaner", 6.4, 1.8),
    *_objects("bed", ON, "comforter pillow"),
    *_objects("table_bedroom", ON, "alarm_clock spectacles cellphone"),
    *_objects("dresser", INSIDE, "clothes_shirt clothes_socks", level=0),
    *_objects("dresser", INSIDE, "clothes_pants clothes_dress", level=1),
    *_objects("dresser", INSIDE, "clothes_jacket", level=2),
    *_objects("dresser", ON, "wallet bag", level=3),
    *_objects("bookshelf_bedroom", ON, "book", level=1),
    *_objects("sofa_bedroom", ON, "blanket"),
    _floor("bedroom", "basket_for_clothes", 9.6, 4.9),
    *_objects("bathroom_counter", ON, "toothbrush tooth_paste soap hairbrush facial_cleanser towel"),
    *_objects("bathroom_cabinet", INSIDE, "painkillers razor deodorant", level=1),
    *_objects("bathroom_cabinet", INSIDE, "perfume hairdryer toilet_paper", level=0),
    *_objects("shower", INSIDE, "shampoo conditioner", level=1),
    *_objects("washing_machine", ON, "laundry_detergent", level=1),
    # The HOMER+ apartment's objects, where its households start them unless that is too full for the robot to
    # reach in (their cupboard holds also the cup, the oats, the coffee and its filters, the peanut butter, the
    # juice and the frying pan, their kitchen cabinet the washcloth, their crowded bathroom counter the toothbrush
    # holder); declared last so that the objects above keep their start poses.
    *_objects("cupboard", INSIDE, "dry_pasta", level=0),
    *_objects("dishwasher", INSIDE, "cup", level=1),
    *_objects("bookshelf_dining_room", ON, "coffee_filter juice", level=2),
    *_objects("bookshelf_dining_room", ON, "food_oatmeal ground_coffee food_peanut_butter", level=0),
    *_objects("kitchen_counter_right", ON, "fryingpan"),
    *_objects("fridge", INSIDE, "food_chicken", level=2),
    *_objects("kitchen_cabinet", INSIDE, "cleaning_solution", level=0),
    *_objects("sink_dining_room", INSIDE, "washcloth"),
    *_objects("tvstand_home_office", ON, "radio", level=2),
    *_objects("bathroom_shelf", ON, "toothbrush_holder", level=2),
    *_objects("bathroom_cabinet", INSIDE, "shaving_cream", level=1),
    _floor("outside", "groceries", -0.7, 3.2),
    # Objects HOMER's activity scripts name beyond its graph and HOMER+.
    *_objects("fridge", INSIDE, "food_egg", level=2),
    *_objects("stove", ON, "sauce_pan"),
    *_objects("kitchen_cabinet", ON, "paper_towel", level=2),
    *_objects("oven", ON, "chef_knife dishrack"),  # the counters are full: the one free top at counter height
    *_objects("filing_cabinet", INSIDE, "note_pad pencil", level=0),
    *_objects("bathroom_cabinet", INSIDE, "face_soap", level=2),  # the shower's corner shelf holds the bottles
    *_objects("dresser", ON, "comb", level=3),
    *_objects("bathroom_cabinet", INSIDE, "mouthwash", level=2),
    *_objects("dresser", INSIDE, "clothes_underwear", level=0),
    *_objects("sofa_bedroom", ON, "pajamas"),
    *_objects("drying_rack", ON, "clothes_skirt clothes_scarf clothes_gloves clothes_hat", level=1),
    *_objects("table_home_office", ON, "instrument_violin"),
    *_objects("bookshelf_bedroom", ON, "bookmark", level=2),
)


@cache
def default_layout() -> Layout:
    """The apartment every dataset and scenario uses."""
    return Layout(ROOMS, WALLS, FURNITURE, OBJECTS)
