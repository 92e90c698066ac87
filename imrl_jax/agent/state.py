"""The state a phase carries from step to step, and what it records (section 2, MODEL.md "Acting").

A phase (:class:`Phase`: who learns, from which reward, with or without a target) runs a
scan whose carry is a :class:`State`: the agent's weights, the eligibility traces, the world's
state (the arena's: the robot's pose), the observations of the last two steps, what the previous step left for learning
(:class:`Previous`), and the random numbers of the current block of steps (:class:`Draws`).
Every step records a :class:`StepRecord`; a phase returns per-bin :class:`Curves`. Both the
XLA step (``lifetime.step``) and the GPU kernel (``kernel.py``) use these types.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp

from imrl_jax.conditions import CHILDHOOD, Phase
from imrl_jax.config import Config, ConfigError, LearningParams
from imrl_jax.agent.networks import Agent
from imrl_jax.agent.timescale import Option, init_option
from imrl_jax.world.worlds import world_of


def bin_steps(num_steps: int, num_bins: int) -> int:
    """Steps per bin of a phase of ``num_steps`` steps; a count the bins do not divide is refused, not cut."""
    if num_bins < 1 or num_steps % num_bins:
        raise ConfigError(f"num_steps, num_bins: {num_steps} steps cannot be split into {num_bins} equal bins "
                          f"(steps must be a multiple of the bins)")
    return num_steps // num_bins


def childhood_phase(config: Config) -> Phase:
    """The condition's childhood phase (LE-LS's by default) with the config's options (docs/CHILDHOOD.md)."""
    phase = config.spec.childhood if config.spec.has_childhood else CHILDHOOD
    return phase._replace(respawn=config.childhood_walls == "respawn",
                          progress=config.childhood_selector_reward == "progress")


def phase_params(phase: Phase, params: LearningParams) -> LearningParams:
    """The learning values a phase uses: childhood (intrinsic rewards) has its own."""
    return params.in_childhood() if phase.intrinsic else params


def learning_until(params: LearningParams, learning) -> LearningParams:
    """The values with every learning rate and the noise 0 where ``learning`` is false (the end of an evolved
    childhood: the weights stay as they are, w + 0 = w, and the actions are the actors' outputs)."""
    off = lambda v: jnp.where(learning, v, jnp.zeros_like(v))  # noqa: E731
    return params._replace(eta_actor=off(params.eta_actor), eta_evaluator=off(params.eta_evaluator),
                           eta_selector_actor=off(params.eta_selector_actor),
                           eta_selector_critic=off(params.eta_selector_critic), noise_std=off(params.noise_std))


class Draws(NamedTuple):
    """The random numbers of one step: expert choice u ~ U[0, 1), action noise z ~ N(0, I2),
    and (phases with respawns only) the world's ``num_spawn_draws`` U[0, 1) numbers of a random start (the arena's:
    a pose's x, y, heading)."""

    u: jnp.ndarray
    z: jnp.ndarray
    spawn: jnp.ndarray | None = None


class Traces(NamedTuple):
    """Eligibility traces. Only the expert in control has a non-zero trace, so one suffices.

    A trace that ends is not zeroed at once: its flag makes the next step read it as 0.
    Zeroing it there would take one more pass over it, after the update that reads it.
    """

    actor: jnp.ndarray  # (2, n+1)
    evaluator: jnp.ndarray  # (n+1,)
    selector_actor: jnp.ndarray  # (K, n+1)
    selector_critic: jnp.ndarray  # (n+1,)
    experts_ended: jnp.ndarray  # (): the expert traces ended last step (read as 0)
    selector_ended: jnp.ndarray  # (): the selector traces ended last step (read as 0)


class Previous(NamedTuple):
    """What step t-1 left for learning its transition at step t."""

    k: jnp.ndarray  # expert in control
    action: jnp.ndarray  # a_{t-1}, executed (noisy) action
    output: jnp.ndarray  # o_{t-1}, actor output
    selection: jnp.ndarray  # s_{t-1}, selector outputs used for the choice
    valid: jnp.ndarray  # False at a phase start and after a timeout: nothing to learn
    terminal: jnp.ndarray  # the transition reached the target: reward 1, no bootstrap


class State(NamedTuple):
    """Scan carry of a phase."""

    agent: Agent
    traces: Traces
    world: Any  # the world's state (the arena's ``env.EnvState``: pose, direction, trial step, steps on a wall)
    xbs: jnp.ndarray  # (2, n+1): x~_t in row t % 2 (written by the step), x~_{t-1} in the other
    prev: Previous
    t: jnp.ndarray  # step within the phase
    block: Draws  # the random numbers of the current block of steps
    baseline: jnp.ndarray  # (K,): each expert's running mean surprise (childhood "progress" reward)
    option: Option | None = None  # the selector's running choice (a selector on its own time-scale only)


class StepRecord(NamedTuple):
    """What one step produced: the world's state after it (the arena's: the pose), the expert in control, its
    events."""

    world: Any
    k: jnp.ndarray
    reached: jnp.ndarray
    timeout: jnp.ndarray
    respawned: jnp.ndarray  # put at a random pose after too long on a wall


class Curves(NamedTuple):
    """Per-bin counts of a phase."""

    reaches: jnp.ndarray  # (bins,)
    timeouts: jnp.ndarray  # (bins,)
    selections: jnp.ndarray  # (bins, K): steps each expert was in control
    respawns: jnp.ndarray | None = None  # (bins,): random poses after a wall (phases with respawns only)


def draw_block(key: jax.Array, block, block_steps: int, noisy: bool = True, spawn: int = 0) -> Draws:
    """The draws of steps block*B .. block*B + B-1 of a phase whose key is ``key``.

    Random numbers are made ``block_steps`` at a time (one vectorised call instead of
    one per step). Phases without action noise get zeros for z; the expert-choice
    numbers are the same either way, and so are both with or without ``spawn`` draws (a random start's
    ``spawn`` numbers a step, 0: none).
    """
    if isinstance(spawn, bool):  # a count, not a flag: True would draw one number where a start needs several
        raise TypeError("draw_block: spawn is the number of draws of a random start (World.num_spawn_draws), or 0")
    key_block = jax.random.fold_in(key, block)
    key_u, key_z = jax.random.split(key_block)
    u = jax.random.uniform(key_u, (block_steps,))
    z = jax.random.normal(key_z, (block_steps, 2)) if noisy else jnp.zeros((block_steps, 2), u.dtype)
    spawned = jax.random.uniform(jax.random.fold_in(key_block, 2), (block_steps, spawn)) if spawn else None
    return Draws(u, z, spawned)


def draw_many(key: jax.Array, num_steps: int, block_steps: int, spawn: int = 0) -> Draws:
    """The draws of steps 0 .. num_steps-1 (for the reference and tests)."""
    num_blocks = -(-num_steps // block_steps)
    blocks = jax.vmap(draw_block, (None, 0, None, None, None))(key, jnp.arange(num_blocks), block_steps, True,
                                                               spawn)
    return jax.tree.map(lambda x: x.reshape((-1,) + x.shape[2:])[:num_steps], blocks)


def init_state(config: Config, agent: Agent, world) -> State:
    """A phase's first carry in the world's state ``world``: zero traces, nothing to learn from, step 0."""
    dtype = agent.actor.dtype
    k, n = agent.selector_actor.shape
    units = agent.actor.shape[1]  # the arena's (turn, speed), or a discrete world's actions
    zeros = lambda *shape: jnp.zeros(shape, dtype)  # noqa: E731
    return State(
        agent=agent,
        traces=Traces(zeros(units, n), zeros(n), zeros(k, n), zeros(n), jnp.bool_(False), jnp.bool_(False)),
        world=world,
        xbs=zeros(2, n),
        prev=Previous(jnp.int32(0), zeros(units), zeros(units), zeros(k), jnp.bool_(False), jnp.bool_(False)),
        t=jnp.int32(0),
        block=Draws(zeros(config.draw_block), zeros(config.draw_block, 2)),
        baseline=zeros(k),
        option=init_option(k, n, dtype) if config.selector_options else None,
    )


def spawn_draws(config: Config, phase: Phase) -> int:
    """The uniform numbers a step of ``phase`` draws for a random start: the world's, in phases with respawns."""
    return world_of(config).num_spawn_draws if phase.respawn else 0


def for_phase(config: Config, phase: Phase, state: State) -> State:
    """``state`` whose carried draws have the phase's structure (a world's respawn draws only where used)."""
    if phase.respawn and state.block.spawn is None:
        spawn = jnp.zeros((config.draw_block, spawn_draws(config, phase)), state.block.u.dtype)
        return state._replace(block=state.block._replace(spawn=spawn))
    if not phase.respawn and state.block.spawn is not None:
        return state._replace(block=state.block._replace(spawn=None))
    return state
