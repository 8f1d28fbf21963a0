# Two entry points for a fresh machine: `make demo` (the main job) and `make test` (the test suite).
# Both create .venv and install the pinned CPU build of torch first, so no CUDA packages are pulled in.
# `make test` also installs the cluster extra (Ray), so that the Ray tests run; `make demo` stays without it.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin

.PHONY: demo test lint bench install install-cluster

$(BIN)/homer: pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet "torch==2.13.0"
	$(BIN)/pip install --quiet -e ".[test]"
	touch $(BIN)/homer

$(VENV)/.cluster: $(BIN)/homer
	$(BIN)/pip install --quiet -e ".[test,cluster]"
	touch $(VENV)/.cluster

install: $(BIN)/homer

install-cluster: $(VENV)/.cluster

demo: install
	$(BIN)/homer demo breakfast --rrd breakfast.rrd

test: install-cluster
	$(BIN)/python -m pytest -q

lint: install
	$(BIN)/ruff check .

bench: install
	$(BIN)/python benchmarks/bench_physics.py
	$(BIN)/python benchmarks/bench_scene_graph.py
