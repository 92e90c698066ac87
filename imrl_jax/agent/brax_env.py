"""The arena as brax environments: section 2's six tasks and childhood's open floor (MODEL.md "Robot", "Tasks").

    import imrl_jax.agent.brax_env                      # registers imrl-task1 .. imrl-task6, imrl-childhood
    env = brax.envs.get_environment("imrl-task3")

Every environment steps the project's own environment (:mod:`imrl_jax.world.env`: the pose
moves, a trial ends and the retina observes exactly as in a life), so the geometry has one copy. The action
is 2 values in [-1, 1] (what brax's agents emit), mapped to the robot's actor outputs
a = clip((u + 1) / 2, 0, 1), which then turn and move the robot exactly as an actor's
outputs do (:func:`robot_action`; :meth:`TaskEnv.drive` takes the outputs themselves).

A task's episode is one trial, as in adulthood: reaching the target gives reward 1, ends
the episode as a terminal and puts the robot back at the start; ``trial_timeout`` (200)
steps without reaching it end the episode as a truncation (``info['truncation']``: no
bootstrap and, in brax's PPO, nothing learned from that transition, as in the paper's
rules). With ``trial_episodes=False`` the robot is put back the same way but the episode
goes on, so that an episode of N steps counts the reaches of N steps of a task (what
brax's ES scores). Brax's own training wrapper would count a timeout as a terminal:
train with ``wrap_env_fn=wrap_for_training``.

Importing this module has two effects, both needed to train on these environments with
brax: it registers them with ``brax.envs.register_environment``, and on a jax without
``jax.device_put_replicated`` (removed in jax 0.10; brax 0.14's PPO still calls it) it
installs :func:`device_put_replicated`, made from public jax APIs.
"""

from __future__ import annotations

import functools
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np



def _import_quietly(name: str):
    """Import a module, dropping the lines mujoco's optional GPU backend prints when it is absent ("Failed to import warp")."""
    import contextlib
    import importlib
    import io
    import sys

    printed = io.StringIO()
    try:
        with contextlib.redirect_stdout(printed):
            return importlib.import_module(name)
    finally:
        kept = [line for line in printed.getvalue().splitlines(keepends=True)
                if not line.startswith(("Failed to import warp:", "Failed to import mujoco_warp:"))]
        sys.stdout.write("".join(kept))


try:
    _import_quietly("brax.envs")  # brax imports mujoco.mjx, whose warp backend is a GPU extra
    import brax.envs
    from brax.envs.base import Env, State, Wrapper
    from brax.envs.wrappers.training import AutoResetWrapper, EpisodeWrapper, VmapWrapper
except ImportError as error:  # the core package runs without the extra
    raise ImportError("imrl_jax.agent.brax_env needs brax: pip install -e '.[brax]' (docs/BASELINES.md)") from error

from imrl_jax.world.arena import Pose
from imrl_jax.config import Config
from imrl_jax.world.env import childhood_task, make_env, random_pose, task_spec
from imrl_jax.agent.networks import reinforce, with_bias

#: Names under which :func:`register` puts the environments (task k is ``imrl-task{k}``).
TASK_NAME = "imrl-task{}"
CHILDHOOD_NAME = "imrl-childhood"


class Robot(NamedTuple):
    """The environment's ``pipeline_state``: the pose and the steps since the trial started."""

    pose: Pose
    trial_step: jnp.ndarray  # int32


def robot_action(action: jnp.ndarray) -> jnp.ndarray:
    """Brax's action u in [-1, 1]^2 as the robot's actor outputs a = clip((u + 1) / 2, 0, 1)."""
    return jnp.clip(0.5 * (action + 1.0), 0.0, 1.0)


def typed_key(rng: jax.Array) -> jax.Array:
    """A typed key from brax's legacy uint32 key (a typed key is returned as it is)."""
    if jax.dtypes.issubdtype(rng.dtype, jax.dtypes.prng_key):
        return rng
    return jax.random.wrap_key_data(rng)


class _ArenaEnv(Env):
    """What both kinds of environment share: the config, the observation, the action."""

    has_target = True

    def __init__(self, config: Config | None = None):
        self.config = Config() if config is None else config
        self.arena = make_env(self.config, has_target=self.has_target)

    def _retina(self, pose: Pose) -> jnp.ndarray:
        return self.arena.observe(self.arena.at(pose))

    def _move(self, robot: Robot, outputs: jnp.ndarray, task):
        """The robot after one step of :meth:`imrl_jax.world.env.Environment.transition`, and its events."""
        moved, events = self.arena.transition(self.arena.at(robot.pose)._replace(trial_step=robot.trial_step),
                                              outputs, task)
        return Robot(moved.pose, moved.trial_step), events

    @property
    def action_size(self) -> int:
        return 2

    @property
    def backend(self) -> str:
        return "imrl_jax"  # no physics pipeline: the arena's own kinematics


class TaskEnv(_ArenaEnv):
    """Task ``task`` (1-6) of MODEL.md's table: a trial per episode, reward 1 at the target."""

    def __init__(self, task: int = 1, config: Config | None = None, task_id: bool = False,
                 trial_episodes: bool = True):
        super().__init__(config)
        if not 1 <= task <= self.config.num_tasks:
            raise ValueError(f"task: must be 1 to {self.config.num_tasks} (got {task!r})")
        self.task = task
        self.task_id = task_id
        self.trial_episodes = trial_episodes
        self.spec = task_spec(self.config, task - 1)

    def observation(self, pose: Pose) -> jnp.ndarray:
        """The retina's 36 values, then (with ``task_id``) the task as one-hot over the tasks."""
        x = self._retina(pose)
        if self.task_id:
            x = jnp.concatenate([x, jax.nn.one_hot(self.task - 1, self.config.num_tasks, dtype=x.dtype)])
        return x

    @property
    def observation_size(self) -> int:
        return self.config.num_inputs + (self.config.num_tasks if self.task_id else 0)

    def reset(self, rng: jax.Array) -> State:
        """The robot at the task's start pose (the key is not used: the start is fixed)."""
        del rng
        robot = Robot(self.spec.start, jnp.int32(0))
        zero = jnp.zeros((), jnp.float32)
        return State(robot, self.observation(robot.pose), zero, zero, metrics=dict(reaches=zero, timeouts=zero),
                     info=dict(truncation=zero, trial_truncation=zero))

    def step(self, state: State, action: jax.Array) -> State:
        """One control cycle with brax's action in [-1, 1]^2 (:func:`robot_action`)."""
        return self.drive(state, robot_action(action))

    def drive(self, state: State, outputs: jax.Array) -> State:
        """One control cycle with the robot's actor outputs in [0, 1]^2, as :func:`imrl_jax.agent.lifetime.step` moves."""
        robot, events = self._move(state.pipeline_state, outputs, self.spec)
        pose, reached, timeout = robot.pose, events.reached, events.timeout
        reward = reached.astype(jnp.float32)
        ended = (reached | timeout) if self.trial_episodes else jnp.bool_(False)
        truncated = (timeout if self.trial_episodes else jnp.bool_(False)).astype(jnp.float32)
        # brax's EpisodeWrapper rewrites 'truncation' from its own step count; the copy
        # lets wrap_for_training keep the trial's timeout as a truncation.
        info = {**state.info, "truncation": truncated, "trial_truncation": truncated}
        return state.replace(pipeline_state=robot, obs=self.observation(pose), reward=reward,
                             done=ended.astype(jnp.float32),
                             metrics={**state.metrics, "reaches": reward, "timeouts": timeout.astype(jnp.float32)},
                             info=info)


class ChildhoodEnv(_ArenaEnv):
    """Childhood's open floor: no target, no trials, a uniform random start pose (MODEL.md "Life").

    The reward is 0, or with ``reinforcer`` (37 weights) the paper's internal reward
    2 sigmoid(w.x~) - 1 of the view after the step. Walls clamp, as in the ``paper`` preset.
    """

    has_target = False

    def __init__(self, config: Config | None = None, reinforcer=None):
        super().__init__(config)
        if self.config.childhood_walls != "clamp":
            raise ValueError(f"childhood_walls: the childhood environment has clamping walls only "
                             f"(got {self.config.childhood_walls!r})")
        n = self.config.num_inputs + 1
        if reinforcer is not None and np.shape(reinforcer) != (n,):
            raise ValueError(f"reinforcer: expected {n} weights, got shape {np.shape(reinforcer)}")
        self.reinforcer = None if reinforcer is None else jnp.asarray(reinforcer, jnp.float32)

    @property
    def observation_size(self) -> int:
        return self.config.num_inputs

    def _reward(self, x: jnp.ndarray) -> jnp.ndarray:
        if self.reinforcer is None:
            return jnp.zeros((), jnp.float32)
        return reinforce(self.reinforcer, with_bias(x))

    def reset(self, rng: jax.Array) -> State:
        """A uniform random pose, as a childhood starts (:func:`imrl_jax.world.env.random_pose`)."""
        robot = Robot(random_pose(typed_key(rng), self.config), jnp.int32(0))
        zero = jnp.zeros((), jnp.float32)
        return State(robot, self._retina(robot.pose), zero, zero, info=dict(truncation=zero))

    def step(self, state: State, action: jax.Array) -> State:
        """One control cycle with brax's action in [-1, 1]^2 (:func:`robot_action`)."""
        robot, _ = self._move(state.pipeline_state, robot_action(action), childhood_task(self.config))
        x = self._retina(robot.pose)
        return state.replace(pipeline_state=robot, obs=x, reward=self._reward(x))


class TrialTruncation(Wrapper):
    """Keeps a trial's timeout a truncation after brax's EpisodeWrapper has rewritten 'truncation'."""

    def step(self, state: State, action: jax.Array) -> State:
        state = self.env.step(state, action)
        trial = state.info.get("trial_truncation")
        if trial is not None:
            state.info["truncation"] = jnp.maximum(state.info["truncation"], trial)
        return state


def wrap_for_training(env: Env, episode_length: int | None = None, action_repeat: int = 1,
                      randomization_fn=None) -> Wrapper:
    """brax's training wrappers (vmap, episode length, auto-reset) with trial timeouts kept as truncations.

    The signature of ``brax.envs.training.wrap``: pass it as ``wrap_env_fn`` to brax's
    ``ppo.train`` and ``es.train``. ``episode_length`` defaults to the trial timeout.
    """
    if randomization_fn is not None:
        raise ValueError("randomization_fn: the arena has no physics system to randomise")
    if action_repeat != 1:
        raise ValueError(f"action_repeat: must be 1, a trial ends inside a repeated action (got {action_repeat})")
    length = env.unwrapped.config.trial_timeout if episode_length is None else episode_length
    return AutoResetWrapper(TrialTruncation(EpisodeWrapper(VmapWrapper(env), length, action_repeat)))


#: The axis brax.training's agents pmap their training step over (``_PMAP_AXIS_NAME`` there).
BRAX_PMAP_AXIS = "i"


def device_put_replicated(x, devices):
    """``x`` (a pytree) stacked once per device along a new leading axis, one slice on each device.

    What ``jax.device_put_replicated`` did before jax 0.10 removed it, from public APIs. The
    copies are made by an identity ``jax.pmap`` over ``devices`` and brax's axis name, so
    that they are laid out as brax's pmapped training step returns its state: it takes
    them back as its next input, and any other layout would make it compile a second time.
    """
    devices = list(devices)
    stacked = jax.tree.map(lambda leaf: jnp.stack([jnp.asarray(leaf)] * len(devices)), x)
    return jax.pmap(lambda tree: tree, axis_name=BRAX_PMAP_AXIS, devices=devices)(stacked)


def install_jax_compat() -> bool:
    """Put :func:`device_put_replicated` on ``jax`` where it is missing; whether it was put there."""
    if hasattr(jax, "device_put_replicated"):
        return False
    jax.device_put_replicated = device_put_replicated
    return True


def register() -> None:
    """Register ``imrl-task1`` .. ``imrl-task6`` and ``imrl-childhood`` with brax (keyword options pass through)."""
    for task in range(1, Config().num_tasks + 1):
        brax.envs.register_environment(TASK_NAME.format(task), functools.partial(TaskEnv, task))
    brax.envs.register_environment(CHILDHOOD_NAME, ChildhoodEnv)


# Importing this module is how a brax user asks for these environments (see the docstring).
register()
install_jax_compat()
