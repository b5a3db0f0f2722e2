# Quick start: `make demo` reproduces the papers' experiments on the simulator and runs
# softtip on the shipped example grasp; `make test` runs the tests.
# Both create ./.venv on first use: `demo` installs softtip alone, `test` adds the test tools
# and every optional extra (numba, ROS bags, Net F/T, the Rerun viewer: about 1.3 GB).
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
OUT ?= demo-output

.PHONY: demo test bench clean

$(BIN)/python:
	@echo "creating $(VENV) with $(PYTHON)"
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip

# one stamp per install set, so that `make demo` never pulls the test extras
$(VENV)/.demo-installed: pyproject.toml | $(BIN)/python
	@echo "installing softtip and numpy, scipy, matplotlib, pyarrow, trimesh, click, tqdm into $(VENV) (a few hundred MB, a minute on first use)"
	$(BIN)/pip install --quiet -e .
	touch $@

$(VENV)/.test-installed: pyproject.toml | $(BIN)/python
	@echo "installing softtip with pytest, pytest-xdist, hypothesis and every extra into $(VENV) (about 1.3 GB, a few minutes on first use)"
	$(BIN)/pip install --quiet -e '.[test]'
	touch $@ $(VENV)/.demo-installed

demo: $(VENV)/.demo-installed
	mkdir -p $(OUT)
	$(BIN)/softtip reproduce --out $(OUT)/reproduction
	$(BIN)/softtip estimate --example -o $(OUT)/estimates.csv --plot $(OUT)/estimates.png
	@echo "wrote $(OUT)/reproduction/ (figures, summary.md) and $(OUT)/estimates.csv, .png"

# one worker per core (pytest-xdist), each test file on one worker so that its module's
# simulations run once
test: $(VENV)/.test-installed
	$(BIN)/python -m pytest -q -n auto --dist loadfile

bench: $(VENV)/.test-installed
	$(BIN)/python benchmarks/bench_core.py
	$(BIN)/python benchmarks/bench_sim.py
	$(BIN)/python benchmarks/bench_live.py

clean:
	rm -rf $(VENV) $(OUT) .pytest_cache .hypothesis
