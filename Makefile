# The two commands of the README.  Each creates .venv and installs snowjax on first use.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed-stamp

.PHONY: reproduce test test-slow test-all lint bench robustness clean

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test,docs,mjx,rl]'
	touch $(STAMP)

reproduce: $(STAMP)
	$(BIN)/snowjax reproduce $(ARGS)

LINTED := snowjax tests benchmarks examples notebooks docs/hooks

# Lint, format and type checks first (seconds), then the suite on two workers: XLA:CPU runs
# each compiled solve on one thread.  --dist loadscope keeps a test file on one worker, so
# its module fixtures (simulations, the reproduce run) are computed once, not once per
# worker.  `make test` is the fast tier; `make test-slow` runs the rest (the notebooks,
# the long simulations, the guide's examples); CI runs both (.ci/run).
PYTEST := $(BIN)/python -m pytest -q -n 2 --dist loadscope

test: lint
	$(PYTEST) -m "not slow" $(ARGS)

test-slow: $(STAMP)
	$(PYTEST) -m slow $(ARGS)

lint: $(STAMP)
	$(BIN)/ruff check $(LINTED)
	$(BIN)/ruff format --check $(LINTED)
	$(BIN)/pyright snowjax

test-all: test test-slow

bench: $(STAMP)
	$(BIN)/python benchmarks/run.py $(ARGS)
	$(BIN)/python benchmarks/accuracy.py $(ARGS)
	$(BIN)/python benchmarks/mjx.py $(ARGS)
	$(BIN)/python benchmarks/ruts.py $(ARGS)

robustness: $(STAMP)
	$(BIN)/python benchmarks/robustness.py $(ARGS)

clean:
	rm -rf $(VENV) build dist *.egg-info .pytest_cache
