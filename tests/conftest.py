"""Tiny shared fixtures: short lifetimes, so the whole suite stays fast on 2 CPU cores."""

import jax
import pytest

from imrl_jax.config import make_config


@pytest.fixture
def tiny():
    """A config factory: the paper's model with lifetimes of a few hundred steps."""

    def make(condition="LE-LS", **overrides):
        sizes = dict(childhood_steps=400, task_steps=200, num_bins=2, population_size=4, num_parents=2)
        return make_config("paper", condition=condition, **{**sizes, **overrides})

    return make


@pytest.fixture
def x64():
    """Run the test body with 64-bit floats (exact comparisons with the NumPy reference)."""
    with jax.enable_x64(True):
        yield


#: A tiny evolve run (2 seeds, 1 generation) for the render and sweep tests (EE-LS: it
#: compiles in half the time of LE-LS, and they share everything these tests use).
TINY_RUN = ["--cond", "EE-LS", "--seeds", "2", "--preset", "small", "--population", "4", "--parents", "2",
            "--generations", "1", "--task-steps", "200", "--childhood-steps", "200", "--bins", "1", "--quiet"]


@pytest.fixture(scope="session")
def tiny_run(tmp_path_factory):
    """The run directory of ``python -m imrl_jax.evolve`` with TINY_RUN (made once, in this process)."""
    from imrl_jax import evolve

    out = str(tmp_path_factory.mktemp("tiny_run") / "run")
    assert evolve.main([*TINY_RUN, "--out", out]) == 0
    return out
