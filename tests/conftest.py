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
