"""Plain NumPy reference of a life in a world of discrete actions (MODEL.md "Discrete actions"); slow, for tests.

The agent is :func:`imrl_jax.agent.reference.run_phase`'s, step for step and in float64: the same expert choice,
learning rules, traces and selector. What differs is its body, :class:`Discrete`: each expert's actor has a
sigmoid unit per action; where the phase explores, action a is drawn with probability o_a / sum(o) by the
selector's rule (``reference._choose_expert``) with the uniform Phi(z_0) of the step's first noise number, else
it is the largest o_a; the action is kept as the one-hot e_a, so the actor learns ((e_a - o) o (1 - o)) x~.

The world is not the agent: it is the oracle here. Each step calls the world's own JAX environment
(``Env.observe``, ``Env.transition``, one step at a time, its observation read as float64), so this checks the
agent's rules in the world, not the world. :func:`live` is one whole life (childhood, then each task from the same
experts), :func:`live_with` the life ``lifetime.live(key, ...)`` lives, given its draws and its childhood start.
"""

from __future__ import annotations

import functools
import math

import jax
import jax.numpy as jnp
import numpy as np

from imrl_jax.agent.reference import PHASES, _choose_expert, _copy_weights, run_phase, start_life, task_weights
from imrl_jax.conditions import Phase
from imrl_jax.world.worlds import world_of


@functools.lru_cache(maxsize=32)
def _compiled(env):
    """The environment's observe and transition, each compiled once (an env is a frozen, hashable dataclass)."""
    return jax.jit(env.observe), jax.jit(env.transition)


def normal_cdf(z: float) -> float:
    """Phi(z) = erfc(-z / sqrt 2) / 2, the uniform of a step's action draw."""
    return 0.5 * math.erfc(-z / math.sqrt(2.0))


class Discrete:
    """The agent in a world of discrete actions, as :func:`~imrl_jax.agent.reference.run_phase`'s body: it
    observes, draws or picks an action from the actor's outputs, and lets the world's environment step."""

    def __init__(self, config, phase, state, task, spawn=None):
        self.env = world_of(config).make_env(config, phase.has_target, phase.intrinsic and
                                             config.childhood_walls == "respawn")
        self.observe_world, self.transition = _compiled(self.env)
        self.state, self.task = state, task
        self.spawn = None if spawn is None or not self.env.respawn else np.asarray(spawn, np.float64)
        self.actions, self.states = [], []  # each step's action index, and the world's state after it

    def observe(self):
        return np.asarray(self.observe_world(self.state), dtype=np.float64)

    def act(self, o, explores, t, z):
        """e_a: a drawn with probability o_a / sum(o) (uniform Phi(z_0)) where the phase explores, else argmax o."""
        index = _choose_expert(o, normal_cdf(float(z[0]))) if explores else int(np.argmax(o))
        self.actions.append(index)
        return np.eye(len(o))[index]

    def step(self, a, t):
        """The world's transition under the action just chosen: (reached, timeout, respawned)."""
        spawn = None if self.spawn is None else self.spawn[t]
        self.state, events = self.transition(self.state, np.int32(self.actions[-1]), self.task, spawn)
        self.states.append(self.state)
        return tuple(bool(flag) for flag in jax.device_get(events))

    def record(self) -> dict:
        states = jax.tree.map(lambda *leaves: np.stack([np.asarray(x) for x in leaves]), *self.states)
        return {"action": np.asarray(self.actions, np.int64), "world": states}


def run_phase_discrete(config, phase, weights, state, u, z, task=None, phase_steps=None, spawn=None,
                       learning_steps=None) -> dict:
    """:func:`~imrl_jax.agent.reference.run_phase` in config's world from its state ``state``; ``task`` the world's
    task params (childhood's without a target), ``spawn`` (T, World.num_spawn_draws) with respawns. Returns what
    it returns, with each step's action index and the world's state after each step."""
    phase = phase if isinstance(phase, Phase) else PHASES[phase]
    body = Discrete(config, phase, state, task, spawn)
    return run_phase(config, phase, weights, None, u, z, phase_steps=phase_steps, learning_steps=learning_steps,
                     body=body)


def live(config, genome, start, childhood_u, childhood_z, task_u, task_z, childhood_spawn=None) -> dict:
    """One whole life of config.condition in config's world (MODEL.md "Life"), as reference.live in the arena.

    start: the world's state at childhood's start (a condition with a childhood). childhood_u (childhood_steps,),
    childhood_z (childhood_steps, 2), childhood_spawn (childhood_steps, World.num_spawn_draws) with respawns;
    task_u (tasks, task_steps), task_z (tasks, task_steps, 2): the draws of each task. Returns reference.live's
    numbers, the timeouts, and each phase's own record ("childhood": None without one; "tasks"): its actions.
    """
    config, grown, options = start_life(config, genome)  # evolved values: the config; a childhood's length
    spec, world, dtype = config.spec, world_of(config), jnp.float64
    child = None
    if spec.has_childhood:
        child = run_phase_discrete(config, spec.childhood, grown, start, childhood_u, childhood_z,
                                   world.childhood_task(config, dtype), config.childhood_steps, childhood_spawn,
                                   **options)
        grown = child["weights"]

    reaches = np.zeros(config.num_tasks, dtype=np.int64)
    timeouts = np.zeros(config.num_tasks, dtype=np.int64)
    phases = []
    for i in range(config.num_tasks):
        task = world.task(config, i, dtype)
        result = run_phase_discrete(config, spec.adult, task_weights(config, grown),
                                    world.make_env(config).reset(None, task, dtype), task_u[i], task_z[i], task,
                                    config.adult_noise_steps)
        reaches[i], timeouts[i] = result["reaches"], int(result["timeout"].sum())
        phases.append(result)

    performance = reaches / np.asarray(world.max_reaches(config, dtype), dtype=np.float64)
    return {"reaches": reaches, "timeouts": timeouts, "performance": performance,
            "fitness": float(performance.mean()), "childhood_weights": _copy_weights(grown),
            "task_weights": [result["weights"] for result in phases], "childhood": child, "tasks": phases}


def live_with(config, genome, draws, start) -> dict:
    """:func:`live` with the draws of a JAX life (``lifetime.life_draws``: its pose is the arena's, unused) and the
    world's childhood start (the state ``Env.reset`` draws from the life's pose key)."""
    child, tasks = draws.childhood, draws.tasks
    spawn = None if child.spawn is None else np.asarray(child.spawn, np.float64)
    return live(config, np.asarray(genome, np.float64), start, np.asarray(child.u, np.float64),
                np.asarray(child.z, np.float64), np.asarray(tasks.u, np.float64), np.asarray(tasks.z, np.float64),
                childhood_spawn=spawn)
