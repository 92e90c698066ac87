"""The environment (imrl_jax.world.env): reset, observe and step on hand-computed cases, as the lifetime uses it."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from imrl_jax.world import env as E
from imrl_jax.agent import lifetime as L
from imrl_jax.world.arena import Pose
from imrl_jax.config import ConfigError, make_config
from imrl_jax.world.retina import observe


def _config(**overrides):
    return make_config("paper", condition="EE-LS", **overrides)


def test_reset_and_observe():
    config = _config()
    env, task = E.make_env(config), E.task_spec(config, 2)
    state = env.reset(jax.random.key(0), task)
    np.testing.assert_array_equal(state.pose.pos, task.start.pos)
    assert int(state.trial_step) == 0 and int(state.pinned) == 0
    np.testing.assert_allclose(state.direction, [math.cos(float(task.start.heading)), math.sin(float(task.start.heading))])
    np.testing.assert_array_equal(env.observe(state), observe(config, task.start))
    open_floor = E.make_env(config, has_target=False).reset(jax.random.key(0), E.childhood_task(config))
    np.testing.assert_array_equal(open_floor.pose.pos, L.random_pose(jax.random.key(0), config).pos)


def test_a_step_reaches_the_target_and_restarts_the_trial():
    """11 cm from the target, heading at it, full speed (2 cm): within its 10 cm radius, back to the start."""
    config = _config()
    env, task = E.make_env(config), E.task_spec(config, 0)
    near = env.at(Pose(task.target - jnp.asarray([11.0, 0.0]), jnp.float32(0.0)))._replace(trial_step=jnp.int32(7))
    state, events = env.step(jax.random.key(0), near, jnp.asarray([0.5, 1.0]), task)
    assert bool(events.reached) and not bool(events.timeout) and not bool(events.respawned)
    np.testing.assert_array_equal(state.pose.pos, task.start.pos)
    assert int(state.trial_step) == 0
    # 13 cm away the same step is 2 cm closer and the trial goes on.
    far = env.at(Pose(task.target - jnp.asarray([13.0, 0.0]), jnp.float32(0.0)))
    state, events = env.step(jax.random.key(0), far, jnp.asarray([0.5, 1.0]), task)
    assert not bool(events.reached) and int(state.trial_step) == 1
    np.testing.assert_allclose(state.pose.pos, task.target - jnp.asarray([11.0, 0.0]), atol=1e-4)


def test_the_timeout_restarts_the_trial():
    config = _config()
    env, task = E.make_env(config), E.task_spec(config, 0)
    waiting = env.at(task.start)._replace(trial_step=jnp.int32(config.trial_timeout - 1))
    state, events = env.step(jax.random.key(0), waiting, jnp.asarray([0.5, 0.0]), task)
    assert bool(events.timeout) and int(state.trial_step) == 0


def test_a_robot_pinned_on_a_wall_is_respawned_from_the_key():
    """With respawns, the pose after too long on a wall is the key's uniform pose (as the lifetime's draws give it)."""
    config = _config(wall_respawn_steps=2)
    env = E.make_env(config, has_target=False, respawn=True)
    pinned = env.at(Pose(jnp.asarray([config.robot_radius, 200.0]), jnp.float32(math.pi)))
    task = E.childhood_task(config)
    state, events = env.step(jax.random.key(1), pinned, jnp.asarray([0.5, 1.0]), task)  # into the west wall
    assert not bool(events.respawned) and int(state.pinned) == 1
    key = jax.random.key(2)
    state, events = env.step(key, state, jnp.asarray([0.5, 1.0]), task)
    assert bool(events.respawned) and int(state.pinned) == 0
    u = jax.random.uniform(key, (3,))
    r, size = config.robot_radius, config.arena_size
    np.testing.assert_allclose(state.pose.pos, r + (size - 2 * r) * u[:2], rtol=1e-6)
    np.testing.assert_allclose(state.pose.heading, 2 * math.pi * u[2], rtol=1e-6)


def test_a_step_count_the_bins_do_not_divide_is_refused():
    """10 steps in 3 bins is an error naming both, in the XLA step and the kernel, not 9 steps."""
    config = _config(task_steps=30, num_bins=3)
    task = E.task_spec(config, 0)
    state = L.init_state(config, L.adult_agent(config, L.decode(config, jnp.zeros(config.num_genes))), E.at(task.start))
    from imrl_jax.agent import kernel
    from imrl_jax.conditions import ADULT_LEARNING_SELECTOR

    for run in (L.run_phase, kernel.run_phase):
        with pytest.raises(ConfigError, match="10 steps cannot be split into 3 equal bins"):
            run(jax.random.key(0), config, ADULT_LEARNING_SELECTOR, config.learning_params(), task, state, 10)
