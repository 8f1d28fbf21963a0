"""The movable household object classes: shape family, bounding box, mass and colour.

This module imports no simulator: it is the plain table that `homer_sim.home.shapes` turns into MuJoCo geoms and
that layouts, the scene graph and the dataset code read. Every body built from a class has its origin at the
CENTER of the class's axis-aligned bounding box, so resting on a surface at height h puts it at
z = h + size[2] / 2. Sizes are full extents in m, masses in kg. Vocabulary follows the HOMER graph, plus
clothes and a few extras.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from homer_sim.errors import unknown_name

FAMILIES = (
    "box",
    "cylinder",
    "sphere",
    "plate",
    "bowl",
    "cup",
    "mug",
    "pot",
    "bin",
    "utensil",
    "cloth",
    "flat",
)
CAVITY_FAMILIES = ("bowl", "cup", "mug", "pot", "bin")
ROUND_FAMILIES = ("cylinder", "sphere", "cup", "bowl")  # families whose upright footprint is a disk
CATEGORIES = ("object", "prop")
MIN_EXTENT = 0.005  # m, smallest allowed bounding-box extent
MAX_FOOTPRINT = 0.45  # m, largest footprint side for ordinary classes
# may be up to 1.0 m long
LONG_CLASSES = ("comforter", "blanket", "instrument_guitar", "instrument_violin", "vacuum_cleaner")
MAX_LONG_SIDE = 1.0  # m


@dataclass(frozen=True)
class ObjectClass:
    """One class of movable object.

    name: HOMER class name, e.g. "bowl".
    family: one of FAMILIES; decides the collision geometry.
    size: full extents (x, y, z) in m of the axis-aligned bounding box in the default resting pose, z up.
    mass: total mass in kg.
    rgba: colour, components in 0..1.
    category: "object" or "prop".
    supports: other objects may rest ON it.
    handle: (length, width, height) in m of a grip feature centred on top of the object, its length along the
        body x, or None (see _HANDLES). It is part of the bounding box: the body under it is size[2] - height
        tall.
    """

    name: str
    family: str
    size: tuple[float, float, float]
    mass: float
    rgba: tuple[float, float, float, float]
    category: str = "object"
    supports: bool = False
    handle: tuple[float, float, float] | None = None

    @property
    def lying(self) -> bool:
        """True for a cylinder lying with its axis along x (its x extent exceeds its y extent)."""
        return self.family == "cylinder" and self.size[0] > self.size[1]

    @property
    def is_round(self) -> bool:
        """Whether it stands on a round footprint (its horizontal extent is its diameter at any yaw)."""
        return self.family in ROUND_FAMILIES and self.size[0] == self.size[1]

    @property
    def is_container(self) -> bool:
        """True for the families with a real, open-topped cavity."""
        return self.family in CAVITY_FAMILIES


# Colours, named once.
_WHITE = (0.92, 0.92, 0.9, 1.0)
_CERAMIC = (0.85, 0.82, 0.75, 1.0)
_GLASS = (0.75, 0.88, 0.92, 0.6)
_STEEL = (0.7, 0.72, 0.75, 1.0)
_WOOD = (0.62, 0.45, 0.28, 1.0)
_DARK = (0.15, 0.15, 0.17, 1.0)
_RED = (0.8, 0.15, 0.12, 1.0)
_GREEN = (0.25, 0.6, 0.25, 1.0)
_BLUE = (0.2, 0.35, 0.75, 1.0)
_YELLOW = (0.92, 0.8, 0.25, 1.0)
_BROWN = (0.45, 0.3, 0.18, 1.0)
_PINK = (0.9, 0.6, 0.7, 1.0)
_CLOTH = (0.55, 0.6, 0.7, 1.0)
_PAPER = (0.95, 0.94, 0.88, 1.0)
_ORANGE = (0.95, 0.55, 0.1, 1.0)

# name, family, (x, y, z) in m, mass in kg, rgba[, category[, supports]]
_ROWS: tuple[tuple, ...] = (
    # kitchen
    ("bowl", "bowl", (0.16, 0.16, 0.07), 0.3, _CERAMIC, "object", True),
    ("plate", "plate", (0.26, 0.26, 0.02), 0.5, _WHITE, "object", True),
    ("mug", "mug", (0.12, 0.085, 0.10), 0.35, _BLUE),
    ("coffee_cup", "cup", (0.085, 0.085, 0.09), 0.2, _WHITE),
    ("drinking_glass", "cup", (0.075, 0.075, 0.12), 0.25, _GLASS),
    ("wine_glass", "cup", (0.08, 0.08, 0.18), 0.2, _GLASS),
    ("spoon", "utensil", (0.17, 0.035, 0.015), 0.04, _STEEL),
    ("fork", "utensil", (0.19, 0.03, 0.015), 0.045, _STEEL),
    ("knife", "utensil", (0.22, 0.025, 0.012), 0.06, _STEEL),
    ("cookingpot", "pot", (0.30, 0.22, 0.14), 1.5, _STEEL, "object", True),
    ("cutting_board", "box", (0.36, 0.24, 0.02), 0.8, _WOOD, "object", True),
    ("food_cereal", "box", (0.19, 0.07, 0.28), 0.4, _YELLOW),
    ("milk", "box", (0.07, 0.07, 0.20), 1.0, _WHITE),
    ("food_bread", "box", (0.25, 0.11, 0.11), 0.5, _BROWN),
    ("food_cheese", "box", (0.12, 0.08, 0.05), 0.25, _YELLOW),
    ("food_vegetable", "box", (0.15, 0.10, 0.08), 0.4, _GREEN),
    ("food_rice", "box", (0.16, 0.06, 0.22), 1.0, _PAPER),
    ("food_donut", "cylinder", (0.09, 0.09, 0.035), 0.07, _PINK),
    ("oil", "cylinder", (0.07, 0.07, 0.28), 0.9, _YELLOW),
    ("wine", "cylinder", (0.075, 0.075, 0.30), 1.2, (0.35, 0.05, 0.1, 1.0)),
    ("food_butter", "box", (0.11, 0.07, 0.04), 0.25, _YELLOW),
    ("food_jam", "cylinder", (0.07, 0.07, 0.10), 0.45, _RED),
    ("food_apple", "sphere", (0.08, 0.08, 0.08), 0.18, _RED),
    ("coffee", "cylinder", (0.10, 0.10, 0.15), 0.5, _BROWN),
    ("tea", "box", (0.13, 0.075, 0.07), 0.1, _GREEN),
    ("cloth_napkin", "cloth", (0.15, 0.15, 0.01), 0.03, _WHITE),
    ("kitchentowel", "cloth", (0.25, 0.15, 0.02), 0.08, _CLOTH),
    ("dish_soap", "cylinder", (0.065, 0.065, 0.20), 0.5, _GREEN),
    ("sponge", "box", (0.11, 0.07, 0.035), 0.02, _YELLOW),
    ("disinfectant_wipes", "cylinder", (0.085, 0.085, 0.17), 0.4, _BLUE),
    ("trashbag", "cylinder", (0.22, 0.22, 0.28), 1.5, _DARK),
    ("knifeblock", "box", (0.12, 0.10, 0.22), 1.2, _WOOD, "prop"),
    ("trashcan", "bin", (0.28, 0.28, 0.30), 1.2, _STEEL, "prop", True),
    ("cup", "cup", (0.08, 0.08, 0.095), 0.22, _CERAMIC),
    ("fryingpan", "pot", (0.28, 0.20, 0.05), 0.8, _DARK),
    ("coffee_filter", "box", (0.12, 0.06, 0.10), 0.1, _PAPER),
    ("ground_coffee", "box", (0.09, 0.06, 0.16), 0.25, _BROWN),
    ("dry_pasta", "box", (0.18, 0.06, 0.22), 0.5, _YELLOW),
    ("food_oatmeal", "cylinder", (0.10, 0.10, 0.18), 0.5, _PAPER),
    ("food_peanut_butter", "cylinder", (0.08, 0.08, 0.11), 0.45, _BROWN),
    ("food_chicken", "box", (0.18, 0.12, 0.06), 0.6, _PINK),
    ("juice", "box", (0.075, 0.075, 0.24), 1.0, _ORANGE),
    ("cleaning_solution", "cylinder", (0.08, 0.08, 0.26), 0.8, _GREEN),
    ("washcloth", "cloth", (0.15, 0.10, 0.02), 0.05, _WHITE),
    ("groceries", "box", (0.36, 0.20, 0.30), 2.0, _PAPER),
    # classes HOMER's activity scripts name beyond its graph and HOMER+
    ("food_egg", "box", (0.15, 0.09, 0.07), 0.3, _PAPER),  # a carton of six
    ("sauce_pan", "pot", (0.26, 0.16, 0.10), 0.9, _STEEL),
    ("chef_knife", "utensil", (0.30, 0.045, 0.02), 0.2, _STEEL),
    ("paper_towel", "cylinder", (0.12, 0.12, 0.28), 0.3, _WHITE),
    ("dishrack", "bin", (0.36, 0.27, 0.10), 1.0, _STEEL, "prop", True),
    # bathroom
    ("toothbrush", "utensil", (0.19, 0.02, 0.02), 0.02, _BLUE),
    ("tooth_paste", "box", (0.19, 0.045, 0.035), 0.12, _WHITE),
    ("towel", "cloth", (0.30, 0.20, 0.05), 0.4, _CLOTH),
    ("shampoo", "cylinder", (0.06, 0.06, 0.20), 0.4, _BLUE),
    ("conditioner", "cylinder", (0.06, 0.06, 0.19), 0.4, _PINK),
    ("facial_cleanser", "cylinder", (0.045, 0.045, 0.15), 0.15, _WHITE),
    ("deodorant", "cylinder", (0.05, 0.05, 0.15), 0.15, _DARK),
    ("perfume", "box", (0.07, 0.04, 0.10), 0.2, _GLASS),
    ("hairbrush", "box", (0.23, 0.06, 0.04), 0.1, _DARK),
    ("hairdryer", "box", (0.24, 0.09, 0.20), 0.6, _DARK),
    ("painkillers", "cylinder", (0.04, 0.04, 0.08), 0.05, _WHITE),
    ("soap", "box", (0.09, 0.06, 0.03), 0.1, _PINK),
    ("toilet_paper", "cylinder", (0.11, 0.11, 0.10), 0.12, _WHITE),
    ("razor", "utensil", (0.15, 0.04, 0.02), 0.04, _BLUE),
    ("laundry_detergent", "box", (0.25, 0.15, 0.28), 3.0, _BLUE),
    ("shaving_cream", "cylinder", (0.055, 0.055, 0.17), 0.3, _WHITE),
    ("toothbrush_holder", "box", (0.22, 0.10, 0.03), 0.25, _WHITE, "object", True),
    ("mouthwash", "cylinder", (0.08, 0.08, 0.22), 0.6, _GREEN),
    ("face_soap", "box", (0.09, 0.06, 0.035), 0.12, _WHITE),
    ("comb", "utensil", (0.18, 0.03, 0.01), 0.02, _DARK),
    # bedroom
    ("clothes_jacket", "cloth", (0.40, 0.30, 0.08), 1.0, _DARK),
    ("clothes_pants", "cloth", (0.35, 0.28, 0.05), 0.5, _BLUE),
    ("clothes_dress", "cloth", (0.35, 0.28, 0.04), 0.3, _RED),
    ("clothes_shirt", "cloth", (0.30, 0.22, 0.04), 0.25, _WHITE),
    ("clothes_socks", "cloth", (0.12, 0.08, 0.04), 0.06, _DARK),
    ("shoes", "box", (0.30, 0.22, 0.12), 0.9, _BROWN),
    ("alarm_clock", "box", (0.12, 0.06, 0.09), 0.25, _RED),
    ("spectacles", "box", (0.14, 0.05, 0.04), 0.03, _DARK),
    ("comforter", "cloth", (0.70, 0.45, 0.18), 2.5, _WHITE),
    ("blanket", "cloth", (0.60, 0.40, 0.10), 1.2, _CLOTH),
    ("pillow", "cloth", (0.45, 0.32, 0.12), 0.6, _WHITE),
    ("basket_for_clothes", "bin", (0.44, 0.44, 0.32), 0.8, _WOOD, "object", True),
    ("bag", "box", (0.35, 0.15, 0.30), 0.8, _BROWN),
    ("wallet", "box", (0.11, 0.09, 0.02), 0.1, _BROWN),
    ("slippers", "box", (0.28, 0.20, 0.06), 0.4, _PINK),
    ("clothes_gloves", "cloth", (0.22, 0.12, 0.03), 0.1, _DARK),
    ("clothes_hat", "cloth", (0.20, 0.14, 0.06), 0.1, _RED),  # a folded knit hat
    ("clothes_scarf", "cloth", (0.30, 0.12, 0.04), 0.2, _BLUE),
    ("clothes_skirt", "cloth", (0.28, 0.14, 0.04), 0.3, _PINK),
    ("clothes_underwear", "cloth", (0.14, 0.10, 0.03), 0.05, _WHITE),
    ("pajamas", "cloth", (0.32, 0.24, 0.05), 0.4, _CLOTH),
    # office and living
    ("book", "box", (0.23, 0.15, 0.03), 0.5, _RED),
    ("notebook", "box", (0.21, 0.15, 0.012), 0.2, _BLUE),
    ("note_pad", "box", (0.15, 0.10, 0.015), 0.1, _YELLOW),
    ("pencil", "utensil", (0.18, 0.012, 0.012), 0.01, _YELLOW),
    ("bookmark", "flat", (0.15, 0.045, 0.005), 0.005, _RED),
    ("pen", "utensil", (0.14, 0.012, 0.012), 0.01, _BLUE),
    ("highlighter", "utensil", (0.12, 0.018, 0.018), 0.015, _YELLOW),
    ("headset", "box", (0.19, 0.17, 0.08), 0.3, _DARK),
    ("keyboard", "box", (0.44, 0.13, 0.03), 0.7, _DARK),
    ("mouse", "box", (0.11, 0.06, 0.035), 0.09, _DARK),
    ("laptop", "box", (0.33, 0.23, 0.02), 1.5, _STEEL),
    ("cellphone", "box", (0.15, 0.075, 0.008), 0.18, _DARK),
    ("charger", "box", (0.06, 0.045, 0.03), 0.08, _WHITE),
    ("remote_control", "box", (0.18, 0.05, 0.025), 0.12, _DARK),
    ("cd", "flat", (0.142, 0.125, 0.01), 0.08, _GLASS),
    ("cd_player", "box", (0.30, 0.25, 0.08), 2.5, _DARK),
    ("radio", "box", (0.24, 0.10, 0.14), 1.3, _DARK),
    ("deck_of_cards", "box", (0.09, 0.065, 0.02), 0.1, _RED),
    ("chessboard", "box", (0.40, 0.20, 0.05), 1.0, _WOOD),
    ("instrument_guitar", "box", (1.0, 0.38, 0.10), 2.5, _WOOD),
    ("instrument_violin", "box", (0.62, 0.24, 0.11), 1.5, _DARK),  # in its case
    ("keys", "box", (0.08, 0.03, 0.015), 0.06, _STEEL),
    ("mail", "flat", (0.23, 0.11, 0.005), 0.03, _PAPER),
    ("magazine", "flat", (0.28, 0.21, 0.006), 0.25, _PAPER),
    ("newspaper", "flat", (0.30, 0.22, 0.01), 0.3, _PAPER),
    ("candle", "cylinder", (0.07, 0.07, 0.10), 0.3, _WHITE),
    ("vacuum_cleaner", "cylinder", (0.28, 0.28, 0.33), 5.0, _RED),
    ("umbrella", "cylinder", (0.30, 0.05, 0.05), 0.35, _DARK),
    ("water_bottle", "cylinder", (0.07, 0.07, 0.24), 0.8, _GLASS),
)

# Grip features, (length, width, height) in m: carry handles (bag, grocery bag, detergent jug, vacuum cleaner,
# CD player, violin case), a trash bag's tie, a headset's band, and on folded cloth the fold a gripper pinches up
# (cloth is rigid here, like every object). A robot takes these objects by the feature: their bodies are wider than
# its grasp.
_HANDLES: dict[str, tuple[float, float, float]] = {
    "bag": (0.14, 0.025, 0.06),
    "groceries": (0.14, 0.025, 0.06),
    "laundry_detergent": (0.10, 0.03, 0.05),
    "vacuum_cleaner": (0.14, 0.03, 0.06),
    "cd_player": (0.18, 0.025, 0.035),
    "trashbag": (0.04, 0.04, 0.07),
    "headset": (0.15, 0.03, 0.035),
    "towel": (0.22, 0.03, 0.025),
    "clothes_shirt": (0.22, 0.03, 0.02),
    "clothes_pants": (0.26, 0.03, 0.025),
    "clothes_dress": (0.26, 0.03, 0.02),
    "clothes_jacket": (0.30, 0.04, 0.035),
    "pajamas": (0.24, 0.03, 0.02),
    "instrument_violin": (0.14, 0.025, 0.04),  # the case's handle
    "blanket": (0.40, 0.04, 0.04),
    "comforter": (0.50, 0.05, 0.06),
}


def _check(cls: ObjectClass) -> ObjectClass:
    """Assert the invariants of one table row (family, sizes, footprint, cylinder axes); return it."""
    sx, sy, sz = cls.size
    assert cls.family in FAMILIES and cls.category in CATEGORIES, cls
    assert min(cls.size) >= MIN_EXTENT and cls.mass > 0, cls
    limit = MAX_LONG_SIDE if cls.name in LONG_CLASSES else MAX_FOOTPRINT
    assert max(sx, sy) <= limit + 1e-9 and min(sx, sy) <= MAX_FOOTPRINT + 1e-9, cls
    if cls.family == "cylinder":
        assert sx == sy or sy == sz, f"{cls.name}: upright needs x == y, lying needs y == z"
    if cls.family == "sphere":
        assert sx == sy == sz, cls
    if cls.handle is not None:
        length, width, height = cls.handle
        assert length <= sx and width <= sy and MIN_EXTENT <= height < sz and not cls.supports, cls
    return cls


def _build(rows: tuple[tuple, ...]) -> dict[str, ObjectClass]:
    """The catalog dict from the table rows, checked; names are unique."""
    catalog: dict[str, ObjectClass] = {}
    for row in rows:
        cls = _check(replace(ObjectClass(*row), handle=_HANDLES.get(row[0])))
        assert cls.name not in catalog, cls.name
        catalog[cls.name] = cls
    assert set(_HANDLES) <= set(catalog), set(_HANDLES) - set(catalog)
    return catalog


CATALOG: dict[str, ObjectClass] = _build(_ROWS)


def object_class(name: str) -> ObjectClass:
    """The class called `name`; raises UnknownNameError naming the closest classes for an unknown name."""
    try:
        return CATALOG[name]
    except KeyError:
        raise unknown_name("object class", name, CATALOG) from None


def rest_height(cls: ObjectClass) -> float:
    """Body-origin height in m above the supporting surface when `cls` rests in its default pose."""
    return cls.size[2] / 2.0
