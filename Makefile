# The two commands of the README.  Each creates .venv and installs snowjax on first use.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed-stamp

.PHONY: reproduce test test-all lint bench robustness clean

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test,docs,mjx]'
	touch $(STAMP)

reproduce: $(STAMP)
	$(BIN)/snowjax reproduce $(ARGS)

LINTED := snowjax tests benchmarks examples notebooks docs/hooks

# Lint, format and type checks first (seconds), then the suite on two workers: XLA:CPU runs
# each compiled solve on one thread.  --dist loadscope keeps a test file on one worker, so
# its module fixtures (simulations, the reproduce run) are computed once, not once per
# worker (fresh clone of 0b4868e: 18 min 10 s of tests against 19 min 25 s without).
test: lint
	$(BIN)/python -m pytest -q -n 2 --dist loadscope -m "not slow" $(ARGS)

lint: $(STAMP)
	$(BIN)/ruff check $(LINTED)
	$(BIN)/ruff format --check $(LINTED)
	$(BIN)/pyright snowjax

test-all: $(STAMP)
	$(BIN)/python -m pytest -q $(ARGS)

bench: $(STAMP)
	$(BIN)/python benchmarks/run.py $(ARGS)
	$(BIN)/python benchmarks/mjx.py $(ARGS)
	$(BIN)/python benchmarks/ruts.py $(ARGS)

robustness: $(STAMP)
	$(BIN)/python benchmarks/robustness.py $(ARGS)

clean:
	rm -rf $(VENV) build dist *.egg-info .pytest_cache
