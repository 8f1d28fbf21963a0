"""The robot's predictor for a household of a dataset: the method (by default the best on validation days in the
validation table, `model.selection`), fitted on the training days, tuned on their validation days for the paper's
objective (reported) and for the assistance objective (the threshold the robot acts on), cached as `homer evaluate`
caches it. The demo, the `day_household_*` runs and `homer assist-eval` all take it from here."""

from __future__ import annotations

from pathlib import Path
from typing import NamedTuple

TUNINGS = ("paper", "assist")  # tunings of the robot's predictor, in order; it acts on the last (assistance)


class Fitted(NamedTuple):
    """A household's tuned predictor, its checkpoint info (tunings) and whether it was fitted or tuned just now."""

    predictor: object
    info: dict
    fresh: bool


def predictor_for(dataset, household: str, method: str | None, window_min: int, checkpoints: Path,
                  progress: bool = False) -> Fitted:
    """The household's predictor fitted on its training days (all but the last tenth, which are its validation
    days; a cross-validated method such as analogs on all of them, see `model.evaluate`) and tuned on the
    validation days at `window_min`, cached under `checkpoints` as `homer evaluate` caches
    it (fitted on the first call, loaded after), with its checkpoint info. method None: the best validated method
    of the validation table (`model.selection`). Tuned for the paper's objective (reported) and then for the
    assistance objective (the robot's own loop replayed on the validation days, `model.metrics.robot_counts`),
    whose threshold and act_steps the predictor keeps: the robot's (see `thresholds`)."""
    from model.evaluate import FitSpec, fit_task, household_split, run_fit
    from model.selection import default_method

    fit, val, _, _ = household_split(dataset, household, None)
    spec = FitSpec(method or default_method(), tuple(fit), tuple(val))
    result = run_fit(None, fit_task(spec.method, spec, dataset.meta, window_min,
                                    spec.path(Path(checkpoints), household), TUNINGS, progress=progress))
    result.save()
    return Fitted(result.predictor, result.info, result.changed)


def method_source(method: str | None) -> str:
    """How the predictor's method was chosen: named by the caller, or the validation table's best."""
    from model.selection import TABLE

    return "as asked" if method else f"best on validation days in {TABLE.parent.name}/{TABLE.name}"


def thresholds(info: dict, window_min: int) -> dict[str, float]:
    """{target: the threshold tuned on validation days for it} of a checkpoint's info, for TUNINGS."""
    return {t: float(info["tunings"][f"{t}@{window_min}"]["params"]["threshold"]) for t in TUNINGS}
