# Quick start: `make demo` reproduces the papers' experiments on the simulator and runs
# softtip on the shipped example grasp; `make test` runs the tests.
# Both create ./.venv on first use.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
OUT ?= demo-output

.PHONY: demo test bench clean

$(BIN)/softtip: pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet -e '.[test]'
	touch $@

demo: $(BIN)/softtip
	mkdir -p $(OUT)
	$(BIN)/softtip reproduce --out $(OUT)/reproduction
	$(BIN)/softtip estimate --example -o $(OUT)/estimates.csv --plot $(OUT)/estimates.png
	@echo "wrote $(OUT)/reproduction/ (figures, summary.md) and $(OUT)/estimates.csv, .png"

test: $(BIN)/softtip
	$(BIN)/python -m pytest -q

bench: $(BIN)/softtip
	$(BIN)/python benchmarks/bench_core.py
	$(BIN)/python benchmarks/bench_sim.py
	$(BIN)/python benchmarks/bench_live.py

clean:
	rm -rf $(VENV) $(OUT) .pytest_cache .hypothesis
