"""The arena and a task as one environment (section 2 "The robot and its environment"; MODEL.md "Acting"), gymnax-style.

    env = make_env(config, has_target=True)              # static: the arena, with or without a target
    params = task_spec(config, index)                     # dynamic: where trials start, the target
    state = env.reset(key, params)                        # the robot at the task's start (or a random pose)
    x = env.observe(state)                                # the retina's 36 values
    state, events = env.step(key, state, action, params)  # turn, move, clamp; walls, reach, timeout

``action`` is the actor's output in [0, 1]^2 (turn, speed). A reach (reward 1) or the
timeout puts the robot back at the task's start; with ``respawn``, a robot on a wall for
``config.wall_respawn_steps`` steps in a row is put at a random pose. :meth:`Environment.transition`
is ``step`` with the random pose's uniform numbers given instead of a key: the lifetime
draws those a block of steps at a time (the same numbers for the same key, whatever the
batch), the GPU kernel uses the same helper functions, and the brax environments, the
hand-written controllers and the baselines' replays all step through it.
"""

from __future__ import annotations

import dataclasses
import math
from typing import NamedTuple

import jax
import jax.numpy as jnp

from imrl_jax.config import Config
from imrl_jax.world.arena import Pose, heading_vector, move, on_wall, spawn_pose, task_arrays, trial_ends
from imrl_jax.world.base import CONTINUOUS, Actions, Events
from imrl_jax.world.retina import observe


class TaskSpec(NamedTuple):
    """The environment's params: where trials start and where the target is (unused without a target)."""

    start: Pose
    target: jnp.ndarray


EnvParams = TaskSpec


class EnvState(NamedTuple):
    """The robot in the arena."""

    pose: Pose
    # (cos, sin) of pose.heading, kept so that the retina's kernels read it rather than compute it
    # again for each of their sample points.
    direction: jnp.ndarray
    trial_step: jnp.ndarray  # steps since the current trial started
    pinned: jnp.ndarray  # steps on a wall in a row (with respawns)


def at(pose: Pose) -> EnvState:
    """The arena's state with the robot at ``pose``, a trial just started (no steps on a wall)."""
    return EnvState(pose, heading_vector(pose.heading), jnp.int32(0), jnp.int32(0))


def random_pose(key: jax.Array, config: Config, dtype=jnp.float32) -> Pose:
    """Uniform position in [r, size - r]^2 and uniform heading (childhood start)."""
    key_pos, key_heading = jax.random.split(key)
    r = config.robot_radius
    pos = jax.random.uniform(key_pos, (2,), dtype, r, config.arena_size - r)
    heading = jax.random.uniform(key_heading, (), dtype, 0.0, 2.0 * math.pi)
    return Pose(pos, heading)


def task_spec(config: Config, index, dtype=jnp.float32) -> TaskSpec:
    """The start pose and target of task ``index`` (an int or a traced index)."""
    starts, targets, _ = task_arrays(config, dtype)
    return TaskSpec(Pose(starts.pos[index], starts.heading[index]), targets[index])


def childhood_task(config: Config, dtype=jnp.float32) -> TaskSpec:
    """A placeholder task for an environment without a target (childhood)."""
    return TaskSpec(Pose(jnp.zeros((2,), dtype), jnp.zeros((), dtype)), jnp.zeros((2,), dtype))


def end_trial(config: Config, task: TaskSpec, pose: Pose, trial_step):
    """Reaching the target (reward 1) or the timeout puts the robot back at the task's start."""
    reached, timeout = trial_ends(config, pose.pos, task.target, trial_step)
    reset = reached | timeout
    pose = jax.tree.map(lambda start, now: jnp.where(reset, start, now), task.start, pose)
    return pose, jnp.where(reset, 0, trial_step), reached, timeout


def respawn(config: Config, pose: Pose, pinned, spawn):
    """A robot on a wall for config.wall_respawn_steps steps in a row is put at the random pose ``spawn``.

    Returns the pose, the steps on a wall and whether it was put back.
    """
    pinned = jnp.where(on_wall(config, pose.pos), pinned + 1, 0)
    respawned = pinned >= config.wall_respawn_steps
    fresh = Pose(*spawn_pose(config, spawn[:2], spawn[2]))
    pose = jax.tree.map(lambda new, now: jnp.where(respawned, new, now), fresh, pose)
    return pose, jnp.where(respawned, 0, pinned), respawned


@dataclasses.dataclass(frozen=True)
class Environment:
    """The arena with the config's geometry: with a task's target and trials, or open (childhood); respawns or not."""

    config: Config
    has_target: bool = True
    respawn: bool = False

    def reset(self, key: jax.Array, params: TaskSpec, dtype=jnp.float32) -> EnvState:
        """The robot at the task's start pose; without a target at a uniform random pose drawn from ``key``."""
        pose = params.start if self.has_target else random_pose(key, self.config, dtype)
        return self.at(pose)

    def at(self, pose: Pose) -> EnvState:
        """The robot at ``pose``, a trial just started."""
        return at(pose)

    def observe(self, state: EnvState) -> jnp.ndarray:
        """The retina's view of the floor ahead (section 2: 6 x 2 points x RGB)."""
        return observe(self.config, state.pose, state.direction)

    def step(self, key: jax.Array, state: EnvState, action: jnp.ndarray, params: TaskSpec) -> tuple[EnvState, Events]:
        """One step: :meth:`transition` with a random pose drawn from ``key`` (used only with respawns)."""
        spawn = jax.random.uniform(key, (3,), state.pose.pos.dtype) if self.respawn else None
        return self.transition(state, action, params, spawn)

    def transition(self, state: EnvState, action: jnp.ndarray, params: TaskSpec, spawn=None) -> tuple[EnvState, Events]:
        """Turn, move, clamp (:func:`~imrl_jax.world.arena.move`); then walls (respawn at the pose ``spawn``, three
        uniform numbers), the target and the timeout (:func:`end_trial`)."""
        pose = move(self.config, state.pose, action)
        pinned, respawned = state.pinned, jnp.bool_(False)
        if self.respawn:
            pose, pinned, respawned = respawn(self.config, pose, pinned, spawn)
        trial_step = state.trial_step + 1
        reached = timeout = jnp.bool_(False)
        if self.has_target:
            pose, trial_step, reached, timeout = end_trial(self.config, params, pose, trial_step)
        return EnvState(pose, heading_vector(pose.heading), trial_step, pinned), Events(reached, timeout, respawned)


def make_env(config: Config, has_target: bool = True, respawn: bool = False) -> Environment:
    """The environment of a phase: adult tasks have a target; childhood has none and may respawn."""
    return Environment(config, has_target, respawn)


@dataclasses.dataclass(frozen=True)
class Arena:
    """The paper's arena as a world (:class:`imrl_jax.world.base.World`): the retina's 36 inputs, the (turn, speed)
    command, the config's task set; its settings are the config's geometry fields."""

    name: str = "arena"
    num_spawn_draws: int = 3  # a random pose's (x, y, heading) as U[0, 1)^3

    def num_inputs(self, config: Config) -> int:
        """The retina's points x 3 receptors."""
        return config.num_inputs

    def actions(self, config: Config) -> Actions:
        """Turn and speed, each in [0, 1]."""
        return Actions(CONTINUOUS, 2)

    def num_tasks(self, config: Config) -> int:
        """The config's task set."""
        return config.num_tasks

    def task(self, config: Config, index, dtype=jnp.float32) -> TaskSpec:
        """Task ``index``'s start pose and target."""
        return task_spec(config, index, dtype)

    def childhood_task(self, config: Config, dtype=jnp.float32) -> TaskSpec:
        """No target (a placeholder of a task's structure)."""
        return childhood_task(config, dtype)

    def max_reaches(self, config: Config, dtype=jnp.float32) -> jnp.ndarray:
        """Each task's theoretical maximum: the straight line at full speed."""
        return task_arrays(config, dtype)[2]

    def make_env(self, config: Config, has_target: bool = True, respawn: bool = False) -> Environment:
        """:func:`make_env`."""
        return make_env(config, has_target, respawn)


#: The paper's arena, the world every config lives in until a config names another.
ARENA = Arena()
