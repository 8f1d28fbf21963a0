"""Method names, importable without torch (the CLI's help text and argument checks use them)."""

from __future__ import annotations

GNN_METHODS = ("gnn", "gnn_no_attention", "gnn_linear_time")
BASELINE_METHODS = ("fremen", "fremen_prior", "static_semantic", "last_seen", "markov")
OUR_METHODS = ("analogs",)
METHODS = (*GNN_METHODS, *BASELINE_METHODS, *OUR_METHODS)
DEFAULT_METHODS = ("gnn", "fremen", "fremen_prior", "static_semantic", "last_seen", "markov", "analogs")
