"""A world behind its interface (imrl_jax/world/base.py): the arena is one, and a life reaches it only through it."""

import dataclasses
import inspect

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from imrl_jax.agent import lifetime as L
from imrl_jax.agent import state as S
from imrl_jax.world import base, env as E, worlds


def test_the_arena_is_a_world():
    config = E.Config()
    for name, member in inspect.getmembers(base.World, inspect.isfunction):
        assert callable(getattr(E.ARENA, name)), name
    for name, member in inspect.getmembers(base.Env, inspect.isfunction):
        assert callable(getattr(E.ARENA.make_env(config), name)), name
    assert E.ARENA.num_inputs(config) == 36 and E.ARENA.actions(config) == base.Actions(base.CONTINUOUS, 2)
    assert E.ARENA.num_tasks(config) == 6 and E.ARENA.num_spawn_draws == 3
    np.testing.assert_allclose(E.ARENA.max_reaches(config), config.theoretical_max(), rtol=1e-6)
    assert worlds.world_of(config) is E.ARENA and worlds.WORLDS == {"arena": E.ARENA}


def test_a_respawn_draws_the_world_s_count_of_numbers_and_a_flag_is_refused():
    key = jax.random.key(0)
    assert S.draw_block(key, 0, 8, spawn=3).spawn.shape == (8, 3)
    assert S.draw_block(key, 0, 8).spawn is None
    with pytest.raises(TypeError, match="number of draws"):
        S.draw_block(key, 0, 8, spawn=True)


@dataclasses.dataclass(frozen=True)
class HalfAsHard(E.Arena):
    """The arena, whose tasks allow twice the reaches: the same lives score half."""

    def max_reaches(self, config, dtype=jnp.float32):
        return 2 * super().max_reaches(config, dtype)


@dataclasses.dataclass(frozen=True)
class Blind(E.Arena):
    """The arena seen as nothing: an agent that observes only its world's observe sees zeros."""

    def make_env(self, config, has_target=True, respawn=False):
        return BlindEnv(config, has_target, respawn)


@dataclasses.dataclass(frozen=True)
class BlindEnv(E.Environment):
    def observe(self, state):
        return jnp.zeros_like(super().observe(state))


def test_a_life_reaches_the_world_only_through_it(tiny, monkeypatch):
    """Performance is reaches over the world's max_reaches, and the agent sees only what its env observes."""
    config = tiny("LE-LS", task_steps=300, childhood_steps=300, num_bins=2)
    genome = jax.random.uniform(jax.random.key(1), (config.num_genes,), minval=-1.0, maxval=1.0)
    life = jax.jit(L.live, static_argnums=1)
    key, params = jax.random.key(2), config.learning_params()
    plain = life(key, config, params, genome)
    monkeypatch.setitem(worlds.WORLDS, "arena", HalfAsHard())
    jax.clear_caches()  # the world is read when the life is traced: trace it again
    half = jax.jit(L.live, static_argnums=1)(key, config, params, genome)
    np.testing.assert_array_equal(half.reaches, plain.reaches)
    np.testing.assert_allclose(half.performance, plain.performance / 2, rtol=1e-6)
    monkeypatch.setitem(worlds.WORLDS, "arena", Blind())
    jax.clear_caches()
    blind = jax.jit(L.live, static_argnums=1)(key, config, params, genome)
    # Seeing nothing, every perceptron reads only its bias: the reinforcers pay the same reward everywhere.
    assert not np.array_equal(np.asarray(blind.agent.actor), np.asarray(plain.agent.actor))
    np.testing.assert_array_equal(np.asarray(blind.agent.actor)[..., :-1], 0.0)
