"""Tiny shared fixtures: short lifetimes, so the whole suite stays fast on 2 CPU cores."""

import os

# One compilation cache for the suite, shared by the xdist workers and the command lines tests start in
# subprocesses (each of which would compile again what another process already did); set before jax is
# imported so that those subprocesses inherit it. Programs are keyed by their HLO and jax's version.
os.environ.setdefault("JAX_COMPILATION_CACHE_DIR",
                      os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), ".pytest_cache", "jax"))

# XLA's backend optimisations off for the suite and its subprocesses: its programs run for moments after compiling,
# so compiling is most of its time, which they lengthen (the sharding scripts took about 40 % less CPU without them);
# every comparison is between programs compiled alike or within a tolerance, and the whole suite passes with it.
os.environ.setdefault("JAX_DISABLE_MOST_OPTIMIZATIONS", "1")

import jax  # noqa: E402
import pytest  # noqa: E402

from helpers import TINY_RUN, tiny_config


@pytest.fixture
def tiny():
    """A config factory: the paper's model with lifetimes of a few hundred steps."""
    return tiny_config


@pytest.fixture
def x64():
    """Run the test body with 64-bit floats (exact comparisons with the NumPy reference)."""
    # jax.enable_x64 is jax 0.8's name; the declared floor (0.6.2) has the experimental one
    enable = jax.enable_x64 if hasattr(jax, "enable_x64") else __import__("jax.experimental", fromlist=["x"]).enable_x64
    with enable(True):
        yield


@pytest.fixture(scope="session")
def tiny_run(tmp_path_factory):
    """The run directory of ``python -m imrl_jax.evolve`` with TINY_RUN (made once, in this process)."""
    from imrl_jax.commands import evolve

    out = str(tmp_path_factory.mktemp("tiny_run") / "run")
    assert evolve.main([*TINY_RUN, "--out", out]) == 0
    return out
