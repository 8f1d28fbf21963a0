"""Training the graph network: shuffled mini-batches, Adam, cross-entropy on the next step's parent, early stopping.

`GNNPredictor` puts the network behind the common predictor interface.
"""

from __future__ import annotations

import copy
import ctypes
import functools
import logging
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np
import torch
from tqdm import tqdm

from homer_sim.data.dataset import GRID_MIN, DatasetMeta, Day
from model.gnn import GNNConfig, ObjectGraphNet
from model.predictor import THRESHOLDS, Predictor, Rollout, Transitions, transitions

log = logging.getLogger(__name__)
TORCH_THREADS = 2
# Graphs per forward pass during rollouts: per graph and step, one thread, B = 4 costs 3.0 ms and B = 64 6.0 ms.
ROLLOUT_CHUNK = 4


@functools.cache
def keep_freed_memory() -> bool:
    """Let glibc keep freed memory for reuse instead of returning it to the kernel (once per process).

    A training step allocates and frees pair tensors of tens of MB. By default glibc serves each with a fresh
    mmap and unmaps it on free, so every step page-faults its whole working set in again: ReLU ran at 4 GB/s.
    With allocations kept in the heap (no mmap, no trimming, 64 MB of top pad) one thread went from 140 to 78 ms
    a batch on household_a. Returns whether the setting took (Linux with glibc only).
    """
    if not sys.platform.startswith("linux"):
        return False
    try:
        mallopt = ctypes.CDLL("libc.so.6").mallopt
    except (OSError, AttributeError):
        return False
    m_trim_threshold, m_top_pad, m_mmap_max = -1, -2, -4
    return all(mallopt(option, value) == 1 for option, value in
               ((m_mmap_max, 0), (m_trim_threshold, 2**31 - 1), (m_top_pad, 64 << 20)))


def adjacency(parent: torch.Tensor, n_nodes: int) -> torch.Tensor:
    """Parent indices (B, N) long, -1 for rooms -> one-hot adjacency (B, N, N) float32 with zero rows for rooms."""
    out = torch.zeros(*parent.shape, n_nodes)
    out.scatter_(-1, parent.clamp(min=0)[..., None], 1.0)
    return out * (parent >= 0)[..., None]


def batch_loss(model: ObjectGraphNet, parent: torch.Tensor, minute: torch.Tensor, target: torch.Tensor
               ) -> torch.Tensor:
    """Mean cross-entropy of the movable nodes' next parents. parent, target (B, N) long; minute (B,)."""
    log_probs = model.forward_parents(parent, minute)
    picked = log_probs.gather(-1, target[:, model.rows][..., None]).squeeze(-1)
    return -picked.mean()


@torch.no_grad()
def mean_loss(model: ObjectGraphNet, data: Transitions, batch_size: int = 128) -> float:
    """Mean cross-entropy over all transitions in `data` (evaluation mode, no gradients)."""
    model.eval()
    total = 0.0
    for start in range(0, len(data), batch_size):
        chunk = slice(start, start + batch_size)
        loss = batch_loss(model, torch.from_numpy(data.parent[chunk]), torch.from_numpy(data.minute_next[chunk]),
                          torch.from_numpy(data.target[chunk]))
        total += float(loss) * len(data.minute_next[chunk])
    return total / max(len(data), 1)


@dataclass(frozen=True)
class TrainReport:
    epochs: int
    best_epoch: int
    best_val_loss: float
    wall_s: float
    history: tuple[tuple[float, float], ...]  # (train loss, validation loss) per epoch


def train(model: ObjectGraphNet, fit: Transitions, val: Transitions, progress: bool = True) -> TrainReport:
    """Train in place until the validation loss has not improved for `patience` epochs; keep the best weights."""
    config, started = model.config, time.perf_counter()
    keep_freed_memory()
    torch.set_num_threads(min(TORCH_THREADS, torch.get_num_threads()))
    torch.manual_seed(config.seed)
    rng = np.random.default_rng(config.seed)
    optimizer = torch.optim.Adam(model.parameters(), lr=config.learning_rate)
    best_loss, best_epoch, best_state, history = mean_loss(model, val), 0, copy.deepcopy(model.state_dict()), []
    bar = tqdm(range(1, config.max_epochs + 1), desc="train gnn", unit="epoch", disable=not progress, leave=False)
    for epoch in bar:
        model.train()
        order, total = rng.permutation(len(fit)), 0.0
        for start in range(0, len(order), config.batch_size):
            idx = order[start:start + config.batch_size]
            loss = batch_loss(model, torch.from_numpy(fit.parent[idx]), torch.from_numpy(fit.minute_next[idx]),
                              torch.from_numpy(fit.target[idx]))
            optimizer.zero_grad()
            loss.backward()
            optimizer.step()
            total += float(loss.detach()) * len(idx)
        val_loss = mean_loss(model, val)
        history.append((total / len(fit), val_loss))
        bar.set_postfix(train=f"{history[-1][0]:.4f}", val=f"{val_loss:.4f}")
        log.info("epoch %d of at most %d: train loss %.5f, validation loss %.5f (%.0f s so far)", epoch,
                 config.max_epochs, history[-1][0], val_loss, time.perf_counter() - started)
        if val_loss < best_loss:
            best_loss, best_epoch, best_state = val_loss, epoch, copy.deepcopy(model.state_dict())
        elif epoch - best_epoch >= config.patience:
            break
    model.load_state_dict(best_state)
    model.eval()
    report = TrainReport(len(history), best_epoch, best_loss, time.perf_counter() - started, tuple(history))
    log.info("trained %d epochs (best %d, val loss %.5f) in %.1f s", report.epochs, best_epoch, best_loss,
             report.wall_s)
    return report


class GNNPredictor(Predictor):
    """The graph network behind the predictor interface; `threshold` is its tunable confidence gate."""

    method = "gnn"
    grid = {"threshold": THRESHOLDS}

    def __init__(self, meta: DatasetMeta, config: GNNConfig | None = None, progress: bool = True,
                 **params: float) -> None:
        super().__init__(meta, **params)
        self.config = config if config is not None else GNNConfig(movable=tuple(meta.movable))
        if self.config.movable != tuple(meta.movable):
            self.config = replace(self.config, movable=tuple(meta.movable))
        torch.manual_seed(self.config.seed)
        self.model = ObjectGraphNet(self.config).eval()
        self.progress = progress
        self.report: TrainReport | None = None

    def fit(self, fit_days: Sequence[Day], val_days: Sequence[Day]) -> None:
        """Train on `fit_days` (continuing from the current weights), early stopping on `val_days`."""
        self.report = train(self.model, transitions(fit_days), transitions(val_days or fit_days), self.progress)

    def step(self, probs: np.ndarray, minute: np.ndarray) -> np.ndarray:
        with torch.no_grad():
            out = self.model.step(torch.from_numpy(np.asarray(probs, dtype=np.float32)),
                                  torch.as_tensor(minute, dtype=torch.float32))
        return out.numpy()

    @torch.no_grad()
    def rollout(self, parent: np.ndarray, minute: np.ndarray, steps: int) -> Rollout:
        """As Predictor.rollout, in torch and in chunks of ROLLOUT_CHUNK graphs."""
        keep_freed_memory()
        torch.set_num_threads(min(TORCH_THREADS, torch.get_num_threads()))
        parent_t = torch.as_tensor(np.array(parent, dtype=np.int64))  # a copy: Ray hands tasks read-only arrays
        minute_t = torch.as_tensor(np.array(minute, dtype=np.float32))
        chunks = []
        for start in range(0, len(parent_t), ROLLOUT_CHUNK):
            chunk = slice(start, start + ROLLOUT_CHUNK)
            probs, observed, per_step = adjacency(parent_t[chunk], self.n_nodes), parent_t[chunk].clamp(min=0), []
            for s in range(1, steps + 1):
                probs = self.model.step(probs, minute_t[chunk] + GRID_MIN * s)
                masked = probs.scatter(-1, observed[..., None], -1.0)
                best, other = probs.max(dim=-1), masked.max(dim=-1)
                per_step.append(tuple(t.numpy() for t in (best.indices, best.values, other.indices,
                                                          other.values.clamp(min=0.0))))
            chunks.append(per_step)
        merged = [tuple(np.concatenate([c[s][k] for c in chunks]) for k in range(4)) for s in range(steps)]
        return self._finish(parent, merged)

    def state(self) -> dict[str, np.ndarray]:
        return {k: v.detach().numpy().copy() for k, v in self.model.state_dict().items()}

    def load_state(self, arrays: dict[str, np.ndarray]) -> None:
        self.model.load_state_dict({k: torch.as_tensor(v) for k, v in arrays.items()})
        self.model.eval()
