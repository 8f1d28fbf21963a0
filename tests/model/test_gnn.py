"""The graph network: factored layers equal the dense ones, masking, and it learns a deterministic routine."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
import torch

from homer_sim.data.dataset import Dataset, write_day, write_meta
from homer_sim.graph import ON
from model.evaluate import FitSpec, evaluate, fit_tuned, split_days
from model.gnn import GNNConfig, ObjectGraphNet, PairReadout, neighbour_sums
from model.synthetic import Apartment, day_from_events
from model.train import adjacency, keep_freed_memory

NODES = ("kitchen", "office", "table", "desk", "shelf", "mug", "book", "pen")
CATEGORIES = ("room", "room", "furniture", "furniture", "furniture", "object", "object", "object")
HOME = np.array([-1, -1, 0, 1, 0, 4, 3, 3])  # furniture in rooms; mug on the shelf, book and pen on the desk
TOY = Apartment(NODES, CATEGORIES, tuple(c == "object" for c in CATEGORIES), HOME,
                np.where(HOME < 0, 0, ON).astype(np.int8))


@pytest.fixture(autouse=True)
def one_thread() -> None:
    torch.set_num_threads(1)  # tiny graphs: one thread avoids oversubscription when cores are shared


def _model(**config: object) -> ObjectGraphNet:
    torch.manual_seed(0)
    return ObjectGraphNet(GNNConfig(movable=TOY.movable, **config)).eval()


def test_factored_first_layer_equals_a_linear_layer_over_the_one_hot_concatenation() -> None:
    model, n = _model(), len(NODES)
    dense = torch.nn.Linear(2 * n + 1, model.config.hidden)
    with torch.no_grad():
        dense.weight.copy_(torch.cat([model.src.T, model.dst.T, model.edge[:, None]], dim=1))
        dense.bias.copy_(model.bias)
    adj = torch.rand(2, n, n)
    eye = torch.eye(n)
    inputs = torch.cat([eye[:, None].expand(n, n, n), eye[None].expand(n, n, n)], dim=-1)  # [onehot_i, onehot_j]
    inputs = torch.cat([inputs[None].expand(2, -1, -1, -1), adj[..., None]], dim=-1)  # (2, N, N, 2N + 1)
    expected = model.embed(torch.relu(dense(inputs)))
    torch.testing.assert_close(model.pair_features(adj), expected, atol=1e-6, rtol=1e-5)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc's mallopt")
def test_glibc_takes_the_keep_freed_memory_setting() -> None:
    assert keep_freed_memory() is True


def test_neighbour_sums_by_hand() -> None:
    weight = torch.tensor([[[0.0, 1.0], [2.0, 0.0]]])  # pairs (0, 1) weight 1, (1, 0) weight 2
    edge = torch.arange(8, dtype=torch.float32).reshape(1, 2, 2, 2)  # e_ij = [4i + 2j, 4i + 2j + 1]
    sums = neighbour_sums(weight, edge)  # (1, 2, 4): [outgoing (2), incoming (2)]
    assert sums[0, 0].tolist() == [2.0, 3.0, 8.0, 10.0]  # out: 1 * e_01; in: 2 * e_10
    assert sums[0, 1].tolist() == [8.0, 10.0, 2.0, 3.0]


def test_readout_gradients_equal_autograds_own_through_relu_and_the_output_layer() -> None:
    torch.manual_seed(0)
    readout = PairReadout(hidden=4, time_width=2).double()
    hidden = torch.randn(2, 3, 5, 4, dtype=torch.float64, requires_grad=True)
    upstream = torch.randn(2, 3, 5, dtype=torch.float64)
    ours = torch.autograd.grad((readout.activate(hidden.clone()) * upstream).sum(),
                               [hidden, readout.out.weight, readout.out.bias])
    plain = (readout.out(torch.relu(hidden))[..., 0] * upstream).sum()
    expected = torch.autograd.grad(plain, [hidden, readout.out.weight, readout.out.bias])
    assert float(ours[0].abs().max()) > 0.1 and int((ours[0] == 0).sum()) > 0  # ReLU both passes and blocks
    for got, want in zip(ours, expected, strict=True):
        torch.testing.assert_close(got, want.reshape(got.shape), atol=1e-12, rtol=1e-12)


@pytest.mark.parametrize("config", [{}, {"attention": False}, {"time_encoding": "linear"}])
def test_sparse_training_path_equals_dense_path(config: dict) -> None:
    model = _model(**config)
    parent = torch.tensor(np.array([HOME, [-1, -1, 0, 1, 0, 2, 5, 3]]))  # 2nd: mug on the table, book on the mug
    minute = torch.tensor([480.0, 1000.0])
    dense, sparse = model(adjacency(parent, len(NODES)), minute), model.forward_parents(parent, minute)
    assert dense.shape == (2, 3, len(NODES))  # (B, movable, candidates)
    finite = torch.isfinite(dense)
    assert torch.equal(finite, torch.isfinite(sparse))
    torch.testing.assert_close(dense[finite], sparse[finite], atol=1e-5, rtol=1e-5)


def test_candidates_exclude_the_node_itself_and_static_rows_stay() -> None:
    model = _model()
    probs = model.step(adjacency(torch.tensor(HOME[None]), len(NODES)), torch.tensor([600.0]))
    movable = torch.tensor(TOY.movable)
    torch.testing.assert_close(probs[0, movable].sum(-1), torch.ones(3))
    assert torch.all(probs[0, movable][:, movable].diagonal() == 0)  # never its own parent
    torch.testing.assert_close(probs[0, ~movable], adjacency(torch.tensor(HOME[None]), len(NODES))[0, ~movable])


def test_learns_a_deterministic_routine_to_over_95_percent(tmp_path: Path) -> None:
    # Every day the mug goes shelf -> table at 08:00 and back at 09:00; nothing else moves.
    events = [(480.0, "mug", "table"), (540.0, "mug", "shelf")]
    write_meta(tmp_path, TOY.meta(("h",)))
    for split, count in (("train", 8), ("test", 2)):
        for i in range(count):
            write_day(tmp_path, day_from_events(TOY, "h", split, i, events))
    dataset = Dataset(tmp_path)
    fit, val = split_days(dataset.load("h", "train"))
    spec = FitSpec("gnn", tuple(fit), tuple(val), (("max_epochs", 30), ("patience", 30)))  # 15 epochs suffice
    fit_tuned(spec, dataset.meta, 30, spec.path(tmp_path / "checkpoints", "h"), progress=False)
    result = evaluate(tmp_path, ["gnn"], 30, progress=False)  # reuses the cached checkpoint
    gnn = result["methods"]["gnn"]
    assert gnn["used"]["correct"] > 95.0
    assert gnn["unused"]["correct"] > 99.0
