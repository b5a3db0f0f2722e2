# Quick start: `make demo` runs softtip on the shipped example grasp and plots it (seconds);
# `make test` runs the tests. `make reproduce` is the full reproduction of the papers'
# experiments on the simulator (52 simulated grasps, about a minute of CPU time);
# `make docs` builds the documentation site into docs/_build/html, warnings as errors.
# All create ./.venv on first use: `demo` and `reproduce` install softtip alone, `test` adds
# the test and docs tools and every optional extra (ROS bags, Net F/T, the Rerun
# viewer: about 1.3 GB), `docs` the docs tools.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
OUT ?= demo-output

.PHONY: demo reproduce test docs bench clean

$(BIN)/python:
	@echo "creating $(VENV) with $(PYTHON)"
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip

# one stamp per install set, so that `make demo` never pulls the test extras
$(VENV)/.demo-installed: pyproject.toml | $(BIN)/python
	@echo "installing softtip and numpy, scipy, numba, matplotlib, pyarrow, trimesh, click, tqdm into $(VENV) (a few hundred MB, a minute on first use)"
	$(BIN)/pip install --quiet -e .
	touch $@

$(VENV)/.test-installed: pyproject.toml | $(BIN)/python
	@echo "installing softtip with pytest, pytest-xdist, hypothesis, the docs tools and every extra into $(VENV) (about 1.3 GB, a few minutes on first use)"
	$(BIN)/pip install --quiet -e '.[test,docs]'
	touch $@ $(VENV)/.demo-installed $(VENV)/.docs-installed

$(VENV)/.docs-installed: pyproject.toml | $(BIN)/python
	@echo "installing softtip with Sphinx, numpydoc, sphinx-gallery, myst-parser and furo into $(VENV)"
	$(BIN)/pip install --quiet -e '.[docs]'
	touch $@ $(VENV)/.demo-installed

demo: $(VENV)/.demo-installed
	mkdir -p $(OUT)
	$(BIN)/softtip estimate --example -o $(OUT)/estimates.csv --plot $(OUT)/estimates.png
	@echo "wrote $(OUT)/estimates.csv and $(OUT)/estimates.png; the papers' experiments: make reproduce"

reproduce: $(VENV)/.demo-installed
	mkdir -p $(OUT)
	$(BIN)/softtip reproduce --out $(OUT)/reproduction
	@echo "wrote $(OUT)/reproduction/ (figures, summary.md)"

# the site, warnings as errors; the gallery's examples run (cached while unchanged)
docs: $(VENV)/.docs-installed
	$(BIN)/python -m sphinx -W --keep-going -b html docs docs/_build/html
	@echo "open docs/_build/html/index.html"

# one worker per core (pytest-xdist), each test file on one worker so that its module's
# simulations run once
test: $(VENV)/.test-installed
	$(BIN)/python -m pytest -q -n auto --dist loadfile

bench: $(VENV)/.test-installed
	$(BIN)/python benchmarks/bench_core.py
	$(BIN)/python benchmarks/bench_sim.py
	$(BIN)/python benchmarks/bench_live.py

clean:
	rm -rf $(VENV) $(OUT) .pytest_cache .hypothesis docs/_build docs/auto_examples dist
