# Two commands do all the set-up: `make demo` and `make test` create .venv and install.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed-stamp
OUT ?= out

.PHONY: install demo test test-all test-min bench gpu-check reproduce reproduce-cpu clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e ".[test,brax,evosax,slurm,worlds]"
	touch $(STAMP)

install: $(STAMP)

demo: $(STAMP)
	rm -rf $(OUT)/demo/evolve
	$(BIN)/python -m imrl_jax.demo --out $(OUT)/demo --overwrite
	$(BIN)/python -m imrl_jax.evolve --cond LE-LS --seeds 2 --preset small --out $(OUT)/demo/evolve

test: $(STAMP)
	$(BIN)/python -m pytest -q -n 2 --durations=10

test-all: $(STAMP)
	$(BIN)/python -m pytest -q -m ""

# The default suite against the declared floors of the core dependencies (tests/floors.txt), in
# its own environment; the optional extras (brax, evosax) need newer jax and are not installed.
test-min:
	$(PYTHON) -m venv .venv-min
	.venv-min/bin/python -m pip install --quiet --upgrade pip
	.venv-min/bin/python -m pip install --quiet -c tests/floors.txt -e ".[test]"
	.venv-min/bin/python -m pytest -q -n 2 -p no:cacheprovider --durations=5

bench: $(STAMP)
	$(BIN)/python -m imrl_jax.bench --json $(OUT)/bench.json

# The GPU check (docs/PERFORMANCE.md, "On a GPU: measured"): run by the Python that has JAX with CUDA,
# from the source tree (nothing is installed or downloaded); `--dry` runs it at tiny sizes anywhere.
gpu-check:
	PYTHONPATH=. $(PYTHON) -m imrl_jax.gpu_check --out $(OUT)/gpu_check

# The paper's Fig. 3 and claims under each variant of the learning rules (experiments/reproduction.py), then
# the report. Resumable: run the same target again after an interruption.
reproduce: $(STAMP)
	$(BIN)/python -m experiments run reproduction && $(BIN)/python -m experiments report reproduction

reproduce-cpu: $(STAMP)
	$(BIN)/python -m experiments run reproduction-cpu && $(BIN)/python -m experiments report reproduction-cpu

clean:
	rm -rf $(VENV) .venv-min $(OUT) .pytest_cache
