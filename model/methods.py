"""Method names, construction, and checkpoints that rebuild any fitted predictor from the file alone.

A checkpoint is a dict of plain values and tensors (loaded with torch.load(..., weights_only=True)):
{"format", "method", "params", "nodes", "categories", "movable", "config" (graph networks), "arrays",
"info"}. `info` holds provenance (household, days, tuning window, training report).
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import torch

from homer_sim.data.dataset import DatasetMeta
from homer_sim.errors import unknown_name
from model.analogs import Analogs
from model.baselines import FreMEn, FreMEnPrior, LastSeen, StaticSemantic
from model.gnn import GNNConfig
from model.markov import TimedMarkov
from model.names import DEFAULT_METHODS, METHODS
from model.predictor import ModelError, Predictor
from model.train import GNNPredictor

CHECKPOINT_FORMAT = 1
GNN_VARIANTS = {"gnn": {}, "gnn_no_attention": {"attention": False}, "gnn_linear_time": {"time_encoding": "linear"}}
BASELINES: dict[str, Callable[[DatasetMeta], Predictor]] = {
    "fremen": FreMEn, "fremen_prior": FreMEnPrior, "static_semantic": StaticSemantic, "last_seen": LastSeen,
    "markov": TimedMarkov, "analogs": Analogs,
}
assert METHODS == (*GNN_VARIANTS, *BASELINES)
__all__ = ["DEFAULT_METHODS", "METHODS", "check_method", "load_predictor", "make_predictor", "save_predictor"]


def check_method(method: str) -> str:
    """The method name, or an error listing the known ones."""
    if method not in METHODS:
        raise unknown_name("method", method, METHODS, limit=len(METHODS))
    return method


def make_predictor(method: str, meta: DatasetMeta, progress: bool = True, **config: object) -> Predictor:
    """A fresh predictor for `method`; `config` overrides GNNConfig fields of the graph-network variants."""
    check_method(method)
    if method in GNN_VARIANTS:
        fields = {**GNN_VARIANTS[method], **config, "movable": tuple(meta.movable)}
        predictor: Predictor = GNNPredictor(meta, GNNConfig.from_dict(fields), progress=progress)
    else:
        if config:
            raise ModelError(f"{method} takes no network config; got {sorted(config)}")
        predictor = BASELINES[method](meta)
    predictor.method = method
    return predictor


def save_predictor(path: str | Path, predictor: Predictor, info: dict | None = None) -> Path:
    """Write a checkpoint (temporary file, then rename)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    config = predictor.config.to_dict() if isinstance(predictor, GNNPredictor) else None
    # the arrays are copied: those of a predictor that came back from a Ray task are read-only
    blob = {"format": CHECKPOINT_FORMAT, "method": predictor.method, "params": dict(predictor.params),
            "nodes": list(predictor.meta.nodes), "categories": list(predictor.meta.categories),
            "movable": [bool(m) for m in predictor.meta.movable], "config": config,
            "arrays": {k: torch.as_tensor(np.array(v, order="C")) for k, v in predictor.state().items()},
            "info": info or {}}
    tmp = path.with_name(path.name + ".tmp")
    torch.save(blob, tmp)
    tmp.replace(path)
    return path


def load_predictor(path: str | Path, meta: DatasetMeta | None = None, progress: bool = True
                   ) -> tuple[Predictor, dict]:
    """Rebuild a fitted predictor and return it with the checkpoint's info; checks nodes against `meta`."""
    try:
        blob = torch.load(Path(path), map_location="cpu", weights_only=True)
    except FileNotFoundError:
        raise ModelError(f"{path}: no such checkpoint") from None
    except Exception as error:  # noqa: BLE001 (torch raises UnpicklingError, RuntimeError, EOFError, ... alike)
        reason = (str(error).strip().splitlines() or [""])[0][:200]
        raise ModelError(f"{path}: not a readable checkpoint, corrupted or holding code that weights-only loading "
                         f"refuses to run ({type(error).__name__}: {reason})") from None
    if not isinstance(blob, dict) or blob.get("format") != CHECKPOINT_FORMAT:
        raise ModelError(f"{path}: checkpoint format {blob.get('format') if isinstance(blob, dict) else None!r}; "
                         f"this homer-sim reads {CHECKPOINT_FORMAT}")
    if meta is None:
        meta = DatasetMeta(tuple(blob["nodes"]), tuple(blob["categories"]), tuple(blob["movable"]), ())
    elif list(meta.nodes) != blob["nodes"] or [bool(m) for m in meta.movable] != blob["movable"]:
        raise ModelError(f"{path}: checkpoint nodes differ from the dataset's ({len(blob['nodes'])} vs "
                         f"{len(meta.nodes)} nodes); retrain on this dataset")
    config = {k: v for k, v in (blob["config"] or {}).items() if k != "movable"}
    predictor = make_predictor(blob["method"], meta, progress=progress, **config)
    predictor.load_state({k: v.numpy() for k, v in blob["arrays"].items()})
    predictor.set_params(**blob["params"])
    return predictor, dict(blob["info"])
