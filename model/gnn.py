"""The paper's graph network: pair embeddings, attention from the input graph, all-pairs aggregation, logits.

For B graphs of N nodes, with H the hidden width (20), M the movable nodes and D the time code width:
1. Pair embedding e_ij = MLP([onehot_i, onehot_j, a_ij]), Shape (B, N, N, H). The first linear layer over the
   concatenation equals src[i] + dst[j] + a_ij * edge + bias, so no (2N + 1)-wide one-hot input is ever built.
2. Round 1 (input graph): per node, the sums of e over its outgoing (i -> k) and incoming (l -> i) edges weighted
   by the adjacency a; pair (i, j) sees i's outgoing, i's incoming, j's incoming and j's outgoing sums. An MLP of
   [e_ij, sums of i, sums of j, time] gives one unbounded attention weight per pair (Shape (B, N, N)).
3. Round 2 (all pairs): the same sums weighted by the attention; an MLP (with the time code) gives a logit per
   pair. Log-softmax over each movable node's candidate parents (every other node): Shape (B, M, N).
Each MLP has one hidden layer of width H with ReLU. A linear layer over [pair part, node-i part, node-j part,
time] is computed as the sum of the parts, each broadcast over the pair grid.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import torch
from torch import nn

from model.predictor import ModelError, candidate_mask
from model.time_encoding import encode_time, time_dim


@dataclass(frozen=True)
class GNNConfig:
    """Everything that rebuilds the network and reproduces its training (stored in every checkpoint).

    movable: one flag per node, in dataset order. learning_rate for Adam; batch_size in grid transitions;
    max_epochs and patience (epochs without a better validation loss) bound training; seed fixes torch and numpy.
    """

    movable: tuple[bool, ...]
    hidden: int = 20
    attention: bool = True
    time_encoding: str = "periodic"
    learning_rate: float = 1e-3
    batch_size: int = 32
    max_epochs: int = 60
    patience: int = 4
    seed: int = 0

    @property
    def n_nodes(self) -> int:
        return len(self.movable)

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, raw: dict) -> GNNConfig:
        known = set(cls.__dataclass_fields__)
        unknown = sorted(set(raw) - known)
        if unknown:
            raise ModelError(f"unknown GNN config keys {unknown}; known: {', '.join(sorted(known))}")
        return cls(**{**raw, "movable": tuple(bool(m) for m in raw["movable"])})


def _uniform_(params: list[torch.Tensor], fan_in: int) -> None:
    """Initialise parts of one linear layer as torch does the whole layer: U(-1/sqrt(fan_in), 1/sqrt(fan_in))."""
    bound = 1.0 / math.sqrt(fan_in)
    with torch.no_grad():
        for p in params:
            p.uniform_(-bound, bound)


def neighbour_sums(weight: torch.Tensor, edge: torch.Tensor) -> torch.Tensor:
    """Per node, the weighted sums of its outgoing and incoming pair features.

    weight: Shape (B, N, N), weight of pair (i, j). edge: Shape (B, N, N, H).
    Returns: Shape (B, N, 2H) = [sum_k w_ik e_ik, sum_l w_li e_li].
    """
    weighted = weight[..., None] * edge  # one (B, N, N, H) product summed both ways: the incoming einsum ran as
    return torch.cat([weighted.sum(2), weighted.sum(1)], dim=-1)  # a loop of small copies over a transposed view


class _ReluMatvec(torch.autograd.Function):
    """relu(hidden) @ weight + bias over the last axis, hidden (..., H), weight (H,), bias () -> (...).

    Autograd's own backward hands ReLU a broadcast (stride 0) gradient, grad (...) times weight (H,), and ReLU's
    backward over that ran at a tenth of memory speed (43% of a training step). Here the gradient is made
    contiguous first.
    """

    @staticmethod
    def forward(ctx, hidden: torch.Tensor, weight: torch.Tensor, bias: torch.Tensor) -> torch.Tensor:
        active = torch.relu(hidden)
        ctx.save_for_backward(active, weight)
        return active @ weight + bias

    @staticmethod
    def backward(ctx, grad: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        active, weight = ctx.saved_tensors
        grad_hidden = torch.ops.aten.threshold_backward(grad[..., None] * weight, active, 0.0)
        grad_weight = active.reshape(-1, weight.shape[0]).T @ grad.reshape(-1)
        return grad_hidden, grad_weight, grad.sum()


class PairReadout(nn.Module):
    """MLP over [e_ij, sums of i, sums of j, time code] -> one value per pair, its first layer factored by part."""

    def __init__(self, hidden: int, time_width: int) -> None:
        super().__init__()
        self.pair = nn.Linear(hidden, hidden)
        self.origin = nn.Linear(2 * hidden, hidden, bias=False)
        self.target = nn.Linear(2 * hidden, hidden, bias=False)
        self.time = nn.Linear(time_width, hidden, bias=False)
        self.out = nn.Linear(hidden, 1)
        first = [self.pair.weight, self.pair.bias, self.origin.weight, self.target.weight, self.time.weight]
        _uniform_(first, 5 * hidden + time_width)

    def hidden(self, pair: torch.Tensor, sums_i: torch.Tensor, sums_j: torch.Tensor, code: torch.Tensor
               ) -> torch.Tensor:
        """Pre-activation (B, R, N, H) from the pair term (B or 1, R, N, H), sums_i (B, R, 2H), sums_j (B, N, 2H)."""
        origin = self.origin(sums_i) + self.time(code)[:, None]
        hidden = pair + origin[:, :, None]
        hidden += self.target(sums_j)[:, None]  # in place: one (B, R, N, H) tensor instead of two
        return hidden

    def activate(self, hidden: torch.Tensor) -> torch.Tensor:
        """Output layer over ReLU(hidden): (B, R, N, H) -> (B, R, N); a mat-vec, far faster than Linear(H, 1)."""
        return _ReluMatvec.apply(hidden, self.out.weight[0], self.out.bias[0])

    def forward(self, edge: torch.Tensor, sums_i: torch.Tensor, sums_j: torch.Tensor, code: torch.Tensor
                ) -> torch.Tensor:
        """edge (B, R, N, H) for R origin rows; sums_i (B, R, 2H); sums_j (B, N, 2H); code (B, D) -> (B, R, N)."""
        return self.activate(self.hidden(self.pair(edge), sums_i, sums_j, code))


class ObjectGraphNet(nn.Module):
    """Per movable node, log-probabilities over candidate parents at the next step."""

    def __init__(self, config: GNNConfig) -> None:
        super().__init__()
        self.config = config
        n, h = config.n_nodes, config.hidden
        self.src, self.dst = nn.Parameter(torch.empty(n, h)), nn.Parameter(torch.empty(n, h))
        self.edge, self.bias = nn.Parameter(torch.empty(h)), nn.Parameter(torch.empty(h))
        _uniform_([self.src, self.dst, self.edge, self.bias], 2 * n + 1)
        self.embed = nn.Linear(h, h)
        width = time_dim(config.time_encoding)
        self.attend = PairReadout(h, width) if config.attention else None
        self.readout = PairReadout(h, width)
        movable = torch.tensor(config.movable, dtype=torch.bool)
        self.register_buffer("rows", torch.nonzero(movable).flatten(), persistent=False)
        self.register_buffer("mask", torch.from_numpy(candidate_mask(movable.numpy()))[movable], persistent=False)

    def pair_features(self, adjacency: torch.Tensor) -> torch.Tensor:
        """adjacency (B, N, N), a_ij = P(parent of i is j) -> pair features (B, N, N, H)."""
        hidden = self.src[:, None] + self.dst[None] + adjacency[..., None] * self.edge + self.bias
        return self.embed(torch.relu(hidden))

    def _log_softmax(self, logits: torch.Tensor) -> torch.Tensor:
        return torch.log_softmax(logits.masked_fill(~self.mask, float("-inf")), dim=-1)

    def forward(self, adjacency: torch.Tensor, minute: torch.Tensor) -> torch.Tensor:
        """adjacency (B, N, N) float, minute (B,) routine minute of the predicted step -> log-probs (B, M, N)."""
        code = encode_time(minute, self.config.time_encoding)
        edge = self.pair_features(adjacency)
        if self.attend is not None:
            sums = neighbour_sums(adjacency, edge)
            weight = self.attend(edge, sums, sums, code)
        else:
            weight = torch.ones_like(adjacency)
        sums = neighbour_sums(weight, edge)
        return self._log_softmax(self.readout(edge[:, self.rows], sums[:, self.rows], sums, code))

    def forward_parents(self, parent: torch.Tensor, minute: torch.Tensor) -> torch.Tensor:
        """The same as forward(one-hot adjacency of `parent`), computed sparsely (training fast path).

        parent: (B, N) long, -1 for rooms. With a one-hot input, e_ij equals the input-independent e0_ij except
        at the N edges (i, parent_i), so the pair terms are shared by the batch plus corrections at the edges.
        """
        code = encode_time(minute, self.config.time_encoding)
        edges = _Edges(parent)
        base = self.embed(torch.relu(self.src[:, None] + self.dst[None] + self.bias))  # (N, N, H)
        on_edge = self.embed(torch.relu(self.src + self.dst[edges.target] + self.edge + self.bias))  # (B, N, H)
        delta = (on_edge - base[edges.node, edges.target]) * edges.valid[..., None]
        if self.attend is not None:
            sums = torch.cat([on_edge * edges.valid[..., None], edges.to_parents(on_edge)], dim=-1)
            weight = self._pair_mlp(self.attend, base, delta, edges, sums, sums, code, None)
            outgoing = torch.einsum("bik,ikh->bih", weight, base) + edges.at_edges(weight)[..., None] * delta
            incoming = torch.einsum("bli,lih->bih", weight, base) + edges.to_parents(
                edges.at_edges(weight)[..., None] * delta)
        else:
            outgoing = base.sum(1)[None] + delta
            incoming = base.sum(0)[None] + edges.to_parents(delta)
        sums = torch.cat([outgoing, incoming], dim=-1)
        logits = self._pair_mlp(self.readout, base, delta, edges, sums[:, self.rows], sums, code, self.rows)
        return self._log_softmax(logits)

    @staticmethod
    def _pair_mlp(mlp: PairReadout, base: torch.Tensor, delta: torch.Tensor, edges: _Edges, sums_i: torch.Tensor,
                  sums_j: torch.Tensor, code: torch.Tensor, rows: torch.Tensor | None) -> torch.Tensor:
        """`mlp` over pairs whose features are `base` plus `delta` at the edges; rows selects origin nodes."""
        pair = mlp.pair(base if rows is None else base[rows])[None]
        hidden = mlp.hidden(pair, sums_i, sums_j, code)
        b, i, j, value = edges.flat(nn.functional.linear(delta, mlp.pair.weight), rows)
        hidden.index_put_((b, i, j), value, accumulate=True)
        return mlp.activate(hidden)

    @torch.no_grad()
    def step(self, probs: torch.Tensor, minute: torch.Tensor) -> torch.Tensor:
        """probs (B, N, N) -> next step's probs (B, N, N): movable rows replaced, the others kept."""
        out = probs.clone()
        out[:, self.rows] = self(probs, minute).exp()
        return out


class _Edges:
    """Index helpers for the N edges (i, parent_i) of B one-hot graphs. parent: (B, N) long, -1 for rooms."""

    def __init__(self, parent: torch.Tensor) -> None:
        self.batch, n = parent.shape
        self.valid = (parent >= 0).to(torch.float32)
        self.target = parent.clamp(min=0)
        self.node = torch.arange(n)[None].expand(self.batch, n)
        self._flat = torch.nonzero(parent >= 0, as_tuple=True)

    def at_edges(self, pair_values: torch.Tensor) -> torch.Tensor:
        """(B, N, N) -> (B, N): the value at (i, parent_i), zero for rooms."""
        return pair_values.gather(-1, self.target[..., None]).squeeze(-1) * self.valid

    def to_parents(self, values: torch.Tensor) -> torch.Tensor:
        """(B, N, H) per child -> (B, N, H) summed into each child's parent (rooms' rows contribute nothing)."""
        values = values * self.valid[..., None]
        return torch.zeros_like(values).scatter_add(1, self.target[..., None].expand_as(values), values)

    def flat(self, values: torch.Tensor, rows: torch.Tensor | None) -> tuple[torch.Tensor, ...]:
        """Indices (b, row, parent) and values (K, H) of the valid edges, rows renumbered into `rows` if given."""
        b, i = self._flat
        value = values[b, i]
        if rows is None:
            return b, i, self.target[b, i], value
        position = torch.full((self.node.shape[1],), -1, dtype=torch.long)
        position[rows] = torch.arange(len(rows))
        keep = position[i] >= 0
        return b[keep], position[i[keep]], self.target[b[keep], i[keep]], value[keep]
