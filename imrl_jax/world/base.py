"""A world behind a small interface (section 2's arena is one; gymnax's ``reset``/``step`` in the paper's terms).

What the agent needs of a world, and all it may use of one:

- what it observes: a feature vector of a fixed size (:meth:`World.num_inputs`), read by every perceptron with a
  bias input;
- how it acts (:meth:`World.actions`): ``Actions(CONTINUOUS, 2)`` is the arena's command in [0, 1]^2 (turn,
  speed), each actor unit a sigmoid; ``Actions(DISCRETE, n)`` is one of n actions, the actor a softmax over n units;
- its tasks: :meth:`World.num_tasks`, a task's params (:meth:`World.task`, an index that may be traced), the most
  reaches a task allows in a test of ``config.task_steps`` steps (:meth:`World.max_reaches`, performance's
  denominator), and childhood's params (:meth:`World.childhood_task`: no task reward);
- an environment per phase (:meth:`World.make_env`: with a task's target and trials, or open as in childhood;
  with respawns or not) whose state is any pytree of arrays: :meth:`Env.observe`, and :meth:`Env.transition`,
  the step with the random numbers it needs (``World.num_spawn_draws`` uniforms) given rather than drawn, so
  that a lifetime draws them a block of steps at a time. A reach is the task's reward 1 and ends the trial; the
  timeout ends it too; both put the agent back at the task's start.

A world's own settings are a frozen dataclass it holds (the arena's are ``Config``'s geometry fields).
"""

from __future__ import annotations

from typing import Any, NamedTuple, Protocol

import jax
import jax.numpy as jnp

CONTINUOUS = "continuous"
DISCRETE = "discrete"


class Actions(NamedTuple):
    """How an agent acts in a world: ``size`` outputs in [0, 1] (continuous) or one of ``size`` actions (discrete)."""

    kind: str
    size: int


class Events(NamedTuple):
    """What one step of an environment produced."""

    reached: jnp.ndarray  # the task's goal was reached (reward 1): the trial starts again
    timeout: jnp.ndarray  # the trial's steps were used up: the trial starts again
    respawned: jnp.ndarray  # put at a random start after being stuck (childhood with respawns)


class Env(Protocol):
    """One phase's environment: a world with a task (or open, in childhood); its state is a pytree of arrays."""

    def reset(self, key: jax.Array, params: Any, dtype=jnp.float32) -> Any:
        """The state at a trial's start: the task's start, or (open, childhood) a random one drawn from ``key``."""

    def observe(self, state: Any) -> jnp.ndarray:
        """The agent's view: ``World.num_inputs`` numbers (float)."""

    def transition(self, state: Any, action: jnp.ndarray, params: Any, spawn=None) -> tuple[Any, Events]:
        """One step under ``action`` (a float vector, or an int32 action index), ``spawn`` the step's
        ``num_spawn_draws`` uniform numbers (used only with respawns)."""


class World(Protocol):
    """A world: what is observed, how one acts, the tasks, and an environment for each phase."""

    name: str
    #: Uniform numbers a step of an environment with respawns draws (0: it never respawns).
    num_spawn_draws: int

    def num_inputs(self, config) -> int:
        """The size of an observation."""

    def actions(self, config) -> Actions:
        """How an agent acts."""

    def num_tasks(self, config) -> int:
        """The tasks of a life."""

    def task(self, config, index, dtype=jnp.float32) -> Any:
        """Task ``index``'s params (a pytree; ``index`` may be traced)."""

    def childhood_task(self, config, dtype=jnp.float32) -> Any:
        """The params of childhood: no task, no reward (the same structure as a task's)."""

    def max_reaches(self, config, dtype=jnp.float32) -> jnp.ndarray:
        """(tasks,): the most reaches each task allows in ``config.task_steps`` steps."""

    def make_env(self, config, has_target: bool = True, respawn: bool = False) -> Env:
        """The environment of a phase: adult tasks have a target; childhood has none and may respawn."""
