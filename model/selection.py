"""Which predictor the robot uses by default: the method with the best validation score in a validation table.

The table (TABLE, `model/validation_table.json`) is written by `benchmarks/paper_results.py` from its runs on the
benchmark dataset (`homer generate --households 5 --train-days 50 --test-days 10 --seed 0`): for each method and
household, the tuning objective (`model.metrics.Counts.objective` at 30 minutes, under the 99%-unused rule of
`model.evaluate.tune`) on the household's validation days, never its test days. `best_method` takes the method with
the highest mean over the households every listed method has; nobody names the default in code. The demo, the
`day_household_*` runs and `homer assist-eval` start from `default_method()`.

Importable without torch (the command line's help text reads it).
"""

from __future__ import annotations

import json
from functools import cache
from pathlib import Path

from model.names import METHODS
from model.predictor import ModelError

TABLE = Path(__file__).with_name("validation_table.json")


def load_table(path: str | Path | None = None) -> dict:
    """The validation table at `path` (default TABLE): {"dataset", "window_min", "score", "methods": {method:
    {household: score}}}."""
    path = path or TABLE
    try:
        table = json.loads(Path(path).read_text())
    except (OSError, ValueError) as error:
        raise ModelError(f"{path}: no readable validation table ({error}); write it with "
                         "benchmarks/paper_results.py --report") from None
    if not isinstance(table, dict) or not isinstance(table.get("methods"), dict) or not table["methods"]:
        raise ModelError(f"{path}: a validation table needs a non-empty 'methods' mapping")
    return table


def ranking(table: dict) -> list[tuple[str, float]]:
    """(method, mean validation score) of the table's known methods, best first, over the households that every
    one of them has (ties: the order of METHODS)."""
    rows = {m: scores for m, scores in table["methods"].items() if m in METHODS and scores}
    if not rows:
        raise ModelError(f"the validation table lists no known method ({', '.join(table['methods'])})")
    common = set.intersection(*(set(scores) for scores in rows.values()))
    if not common:
        raise ModelError("the validation table's methods share no household")
    means = {m: sum(float(scores[h]) for h in common) / len(common) for m, scores in rows.items()}
    return sorted(means.items(), key=lambda item: (-item[1], METHODS.index(item[0])))


def validation_score(record: dict, window_min: int) -> float:
    """A run's tuning objective on its validation days at `window_min` (its checkpoint info: under "tunings"
    since tuning version 3, "val_objective" in version 2)."""
    info = record["info"]
    if "tunings" in info:
        return float(info["tunings"][f"paper@{window_min}"]["val_score"])
    return float(info["val_objective"])


def validation_table(records: dict[str, dict], dataset: str, window_min: int) -> dict:
    """The table of `benchmarks/paper_results.py`'s main runs (keys "main/<household>/<method>/<days>", records
    with the fit's checkpoint "info"): {"dataset", "window_min", "score", "methods": {method: {household: score}}}."""
    methods: dict[str, dict[str, float]] = {}
    for key, record in sorted(records.items()):
        kind, house, method, _ = key.split("/")
        if kind == "main":
            methods.setdefault(method, {})[house] = round(validation_score(record, window_min), 4)
    return {"dataset": dataset, "window_min": window_min,
            "score": "used correct % - used wrong % - unused wrong % on validation days (model.evaluate.tune)",
            "methods": methods}


def format_validation(table: dict) -> str:
    """The validation table as markdown, best first (the order of `ranking`): the first row is the default."""
    houses = sorted(set.intersection(*(set(s) for s in table["methods"].values())))
    lines = [f"validation days, window {table['window_min']} min: {table['score']}; the first row is the default "
             "predictor (model/selection.py)", "", "| method | mean | " + " | ".join(houses) + " |",
             "|---" * (len(houses) + 2) + "|"]
    for method, mean in ranking(table):
        scores = table["methods"][method]
        lines.append(f"| {method} | {mean:.2f} | " + " | ".join(f"{scores[h]:.2f}" for h in houses) + " |")
    return "\n".join(lines) + "\n"


def best_method(table: dict) -> str:
    """The method with the highest mean validation score in `table` (see `ranking`)."""
    return ranking(table)[0][0]


def default_method(path: str | Path | None = None) -> str:
    """The best validated method of the table at `path` (default TABLE), read once per process and path."""
    return _best_in(str(path or TABLE))


@cache
def _best_in(path: str) -> str:
    return best_method(load_table(path))
