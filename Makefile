# Two commands do all the set-up: `make demo` and `make test` create .venv and install.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed-stamp
OUT ?= out

.PHONY: install demo test test-all bench clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e ".[test]"
	touch $(STAMP)

install: $(STAMP)

demo: $(STAMP)
	$(BIN)/python -m imrl_jax.demo --out $(OUT)/demo
	rm -rf $(OUT)/demo/evolve
	$(BIN)/python -m imrl_jax.evolve --cond LE-LS --seeds 2 --preset small --out $(OUT)/demo/evolve

test: $(STAMP)
	$(BIN)/python -m pytest -q

test-all: $(STAMP)
	$(BIN)/python -m pytest -q -m ""

bench: $(STAMP)
	$(BIN)/python -m imrl_jax.bench --json $(OUT)/bench.json

clean:
	rm -rf $(VENV) $(OUT) .pytest_cache
