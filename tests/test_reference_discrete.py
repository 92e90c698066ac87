"""A JAX life in a world of discrete actions (XLand) against the NumPy reference, whole lives in float64.

The reference (imrl_jax/agent/reference_discrete.py) is the arena's reference agent with a body of discrete
actions; the world is its oracle. Given the life's draws, both take the same action at every step of childhood and
of every task, reach the same goals, and end with the same weights (to ~1e-9), with the paper's rules and with
traces and other rates.
"""

import dataclasses
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import EXTENDED

from imrl_jax.agent import lifetime as L
from imrl_jax.world import worlds

pytest.importorskip("xminigrid")  # the worlds extra (not in the minimum environment)

from imrl_jax.agent import reference_discrete as RD  # noqa: E402
from imrl_jax.world import xland  # noqa: E402

#: What the watched world's environments were given: (task index (-1: childhood), step of the phase, action).
HEARD: list = []


def _hear(task, step, action):
    HEARD.append((int(task), int(step), int(action)))


@dataclasses.dataclass(frozen=True)
class WatchedEnv:
    """An environment that reports each action it is given; its state is the world's and the phase's step."""

    inner: Any

    @property
    def respawn(self):
        return self.inner.respawn

    def reset(self, key, params, dtype=jnp.float32):
        return self.inner.reset(key, params[0], dtype), jnp.int32(0)

    def observe(self, state):
        return self.inner.observe(state[0])

    def transition(self, state, action, params, spawn=None):
        jax.debug.callback(_hear, params[1], state[1], action)
        inner, events = self.inner.transition(state[0], action, params[0], spawn)
        return (inner, state[1] + 1), events


@dataclasses.dataclass(frozen=True)
class Watched:
    """XLand whose tasks carry their index and whose environments report their actions (the world unchanged)."""

    inner: Any
    name = "xland"
    num_spawn_draws = 2

    def __getattr__(self, name):  # num_inputs, actions, num_tasks, max_reaches: the world's
        if name == "inner":
            raise AttributeError(name)
        return getattr(self.inner, name)

    def task(self, config, index, dtype=jnp.float32):
        return self.inner.task(config, index, dtype), jnp.asarray(index, jnp.int32)

    def childhood_task(self, config, dtype=jnp.float32):
        return self.inner.childhood_task(config, dtype), jnp.int32(-1)

    def make_env(self, config, has_target=True, respawn=False):
        return WatchedEnv(self.inner.make_env(config, has_target, respawn))


def follower(channel: int, num_weights: int = 56) -> np.ndarray:
    """An actor (5 actions, 56 weights) that follows one colour of the default view: on along it, turning to it on
    either side, turning left where it sees none; it opens a door and picks up a key ahead."""
    forward, right, left, pick_up, toggle = range(5)
    ahead, far, beside_left, beside_right = 4, 1, 6, 8  # cells of the 3 x 3 view, far row first
    cell = lambda index, what: 6 * index + what  # noqa: E731 (3 colours, then blocked, door, key)
    actor = np.zeros((5, num_weights))
    actor[forward, cell(ahead, channel)], actor[forward, cell(far, channel)] = 3.0, 1.0
    actor[left, cell(beside_left, channel)], actor[right, cell(beside_right, channel)] = 2.0, 2.0
    actor[toggle, cell(ahead, 4)], actor[pick_up, cell(ahead, 5)] = 6.0, 6.0
    actor[left, -1] = 0.5
    return actor


def _actions(heard, num_tasks, childhood_steps, task_steps) -> tuple[np.ndarray, np.ndarray]:
    """The JAX life's actions, childhood (steps,) and tasks (tasks, steps), from what its environments heard."""
    child, tasks = np.full(childhood_steps, -1), np.full((num_tasks, task_steps), -1)
    for task, step, action in heard:
        if task < 0:
            child[step] = action
        else:
            tasks[task, step] = action
    return child, tasks


def _close(jax_agent, ref: dict):
    for name in ("reinforcer", "actor", "evaluator", "selector_actor", "selector_critic"):
        np.testing.assert_allclose(np.asarray(getattr(jax_agent, name)), ref[name], rtol=1e-9, atol=1e-12,
                                   err_msg=name)


@pytest.mark.usefixtures("x64")
@pytest.mark.parametrize("condition", ["LE-LS", "EE-LS", pytest.param("SLE", marks=pytest.mark.slow)])
def test_whole_life_in_xland_matches_reference(tiny, monkeypatch, condition):
    """live() in XLand: childhood (LE-LS), key splitting, selector resets, six tasks, reaches and fitness."""
    monkeypatch.setitem(worlds.WORLDS, "xland", Watched(xland.XLand()))
    program = worlds.configure(tiny(condition, childhood_steps=300, task_steps=200, num_bins=1), "xland")
    world = worlds.world_of(program)
    life = jax.jit(lambda *args: L.live(*args), static_argnums=1)  # noqa: E731 (traced anew: the watched world)
    key = jax.random.key(1)
    genome = jax.random.uniform(jax.random.key(0), (program.num_genes,), jnp.float64, -1.0, 1.0)
    if condition == "EE-LS":  # colour followers: some tasks are reached
        genome = jnp.asarray(np.stack([follower(c) for c in range(3)]).reshape(-1))
    # The life's draws and its childhood start, from its keys (each one program: op by op compiles many).
    draws = jax.jit(L.life_draws, static_argnums=(1, 2))(key, program, jnp.float64)
    env = world.make_env(program, False, program.childhood_walls == "respawn")
    start = jax.jit(env.reset, static_argnums=2)(L.lifetime_keys(key, program.num_tasks).pose,
                                                 world.childhood_task(program, jnp.float64), jnp.float64)
    seen = dict(reaches=0, childhood=set(), tasks=set())
    for rules in ({}, EXTENDED):  # dynamic values: one compiled life
        config = program.replace(**rules)
        HEARD.clear()
        result = life(key, program, config.learning_params(), genome)
        jax.effects_barrier()
        child, tasks = _actions(HEARD, program.num_tasks, program.childhood_steps, program.task_steps)
        ref = RD.live_with(config, genome, draws, start)

        if program.spec.has_childhood:
            np.testing.assert_array_equal(child, ref["childhood"]["action"])
        for t in range(program.num_tasks):
            np.testing.assert_array_equal(tasks[t], ref["tasks"][t]["action"], err_msg=f"task {t}")
            _close(jax.tree.map(lambda x: x[t], result.adult_agents), ref["task_weights"][t])
        np.testing.assert_array_equal(np.asarray(result.reaches), ref["reaches"])
        np.testing.assert_array_equal(np.asarray(result.timeouts), ref["timeouts"])
        np.testing.assert_allclose(float(result.fitness), ref["fitness"], rtol=1e-12)
        _close(result.agent, ref["childhood_weights"])
        seen["reaches"] += int(ref["reaches"].sum())
        seen["childhood"] |= set(child.tolist()) if program.spec.has_childhood else set()
        seen["tasks"] |= set(tasks.reshape(-1).tolist())
    # The windows hold what matters: every action drawn in childhood, several taken in the tasks, reaches with EE-LS.
    assert seen["childhood"] == (set(range(5)) if program.spec.has_childhood else set()), seen
    assert len(seen["tasks"]) >= 2 and (condition != "EE-LS" or seen["reaches"] > 0), seen
