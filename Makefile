# Quick start: `make demo` runs softtip on the shipped example grasp; `make test` runs the tests.
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
	$(BIN)/softtip estimate --example -o $(OUT)/estimates.csv --plot $(OUT)/estimates.png
	@echo "wrote $(OUT)/estimates.csv and $(OUT)/estimates.png"

test: $(BIN)/softtip
	$(BIN)/python -m pytest -q

bench: $(BIN)/softtip
	$(BIN)/python benchmarks/bench_core.py

clean:
	rm -rf $(VENV) $(OUT) .pytest_cache .hypothesis
