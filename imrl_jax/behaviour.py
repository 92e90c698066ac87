"""Behaviour of one individual (section 3 of the paper, MODEL.md claim 7): paths, retina views, what experts follow.

Everything here records per-step data of a single individual with
:func:`imrl_jax.lifetime.simulate` and is meant for pictures and small analyses, not for
evolution (which keeps only reductions). A :class:`Trajectory` holds, for each step, the
pose at which the expert was chosen (what the retina saw), the pose after the step, the
expert in control and the events; :func:`colour_shares` turns it into "what each expert
follows": the share of its control steps on which the retina's central receptors see red,
green, blue or nothing.
"""

from __future__ import annotations

import functools
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from imrl_jax.arena import Pose, floor_colour
from imrl_jax.config import Config, LearningParams
from imrl_jax.lifetime import (CHILDHOOD, Phase, adult_phase, childhood_task, init_state, lifetime_keys,
                               random_pose, simulate, task_spec)
from imrl_jax.networks import Agent, decode
from imrl_jax.retina import sample_points

#: Names of the columns of :func:`colour_shares`.
SEEN = ("red", "green", "blue", "nothing")
#: A phase in which nothing learns, there is no target and no noise (probes of experts).
PROBE = Phase(experts_learn=False, selector_learns=False, intrinsic=False, has_target=False, noisy=False)
#: Selector bias that makes one expert take control (sigmoid(-40) ~ 4e-18 for the others).
_FORCE = 40.0


class Trajectory(NamedTuple):
    """Per-step record of one individual (leading axis: steps)."""

    seen_pos: np.ndarray  # (T, 2) position the expert was chosen at (what the retina saw)
    seen_heading: np.ndarray  # (T,)
    pos: np.ndarray  # (T, 2) position after the step (after a reset: the start)
    heading: np.ndarray  # (T,)
    k: np.ndarray  # (T,) expert in control
    reached: np.ndarray  # (T,) the step reached the target
    timeout: np.ndarray  # (T,) the step ended a trial by the timeout

    @property
    def breaks(self) -> np.ndarray:
        """(T,) True where the robot was put back at the start after the step."""
        return self.reached | self.timeout

    def as_path(self) -> dict:
        """The dict :func:`imrl_jax.plotting.plot_life` draws (pos, k, breaks)."""
        return {"pos": self.pos, "k": self.k, "breaks": self.breaks}

    def window(self, start: int, stop: int) -> "Trajectory":
        """Steps start .. stop-1."""
        return Trajectory(*(x[start:stop] for x in self))


def _trajectory(start: Pose, record) -> Trajectory:
    """A Trajectory from a start pose and simulate's records (jnp in, numpy out; batched too)."""
    pos, heading = record.pose.pos, record.pose.heading
    seen_pos = jnp.concatenate([start.pos[..., None, :], pos[..., :-1, :]], -2)
    seen_heading = jnp.concatenate([start.heading[..., None], heading[..., :-1]], -1)
    return Trajectory(*(np.asarray(x) for x in (seen_pos, seen_heading, pos, heading, record.k, record.reached,
                                                 record.timeout)))


@functools.partial(jax.jit, static_argnums=(1, 4, 5))
def _childhood(key, config, params, genome, num_steps, phase_steps):
    keys = lifetime_keys(key, config.num_tasks)
    start = random_pose(keys.pose, config)
    state = init_state(config, decode(config, genome), start)
    _, record = simulate(keys.childhood, config, CHILDHOOD, params, childhood_task(config), state, num_steps,
                         phase_steps)
    return start, record


def childhood_trajectory(key: jax.Array, config: Config, params: LearningParams, genome,
                         num_steps: int) -> Trajectory:
    """The first ``num_steps`` steps of the LE-LS childhood that ``live(key, ...)`` lives (same draws)."""
    start, record = _childhood(key, config, params, jnp.asarray(genome), num_steps, config.childhood_steps)
    return _trajectory(start, record)


def _task(key, config, params, agent, index, num_steps):
    task = task_spec(config, index)
    state = init_state(config, agent, task.start)
    _, record = simulate(key, config, adult_phase(config.condition), params, task, state, num_steps,
                         config.task_steps)
    return task.start, record


@functools.partial(jax.jit, static_argnums=(1, 5))
def _one_task(key, config, params, agent, index, num_steps):
    return _task(key, config, params, agent, index, num_steps)


@functools.partial(jax.jit, static_argnums=(1, 4))
def _all_tasks(keys, config, params, adult_agents, num_steps):
    return jax.vmap(lambda k, a, i: _task(k, config, params, a, i, num_steps))(
        keys, adult_agents, jnp.arange(config.num_tasks))


def task_trajectory(key: jax.Array, config: Config, params: LearningParams, agent: Agent, task: int,
                    num_steps: int) -> Trajectory:
    """``num_steps`` steps of task ``task`` (0-based) from ``agent`` (e.g. a task's final weights), as in adulthood."""
    start, record = _one_task(key, config, params, agent, jnp.int32(task), num_steps)
    return _trajectory(start, record)


def task_trajectories(key: jax.Array, config: Config, params: LearningParams, adult_agents: Agent,
                      num_steps: int) -> list[Trajectory]:
    """One path per task from each task's agent (``LifetimeResult.adult_agents``), in one vmapped program."""
    starts, records = _all_tasks(jax.random.split(key, config.num_tasks), config, params, adult_agents, num_steps)
    batch = _trajectory(starts, records)
    return [Trajectory(*(x[i] for x in batch)) for i in range(config.num_tasks)]


def force_expert(agent: Agent, expert) -> Agent:
    """``agent`` with a selector that always gives control to ``expert``."""
    k, n = agent.selector_actor.shape
    bias = jnp.where(jnp.arange(k) == expert, _FORCE, -_FORCE).astype(agent.selector_actor.dtype)
    return agent._replace(selector_actor=jnp.zeros((k, n), agent.selector_actor.dtype).at[:, -1].set(bias))


@functools.partial(jax.jit, static_argnums=(1, 3, 4))
def _probe(key, config, agent, num_starts, num_steps):
    num_experts = agent.selector_actor.shape[0]
    poses = jax.vmap(lambda k: random_pose(k, config))(jax.random.split(key, num_starts))
    params = config.learning_params()

    def run(expert, pose):
        state = init_state(config, force_expert(agent, expert), pose)
        _, record = simulate(key, config, PROBE, params, childhood_task(config), state, num_steps)
        return record

    per_start = jax.vmap(run, (None, 0))
    records = jax.vmap(per_start, (0, None))(jnp.arange(num_experts), poses)
    starts = jax.tree.map(lambda x: jnp.broadcast_to(x, (num_experts,) + x.shape), poses)
    return starts, records


def probe_experts(key: jax.Array, config: Config, agent: Agent, num_starts: int = 8,
                  num_steps: int = 300) -> Trajectory:
    """Each expert alone in control (no learning, no noise) from ``num_starts`` random poses.

    Returns a Trajectory with leading axes (experts, starts, steps); the same start poses
    for every expert.
    """
    starts, records = _probe(key, config, agent, num_starts, num_steps)
    return _trajectory(starts, records)


@functools.partial(jax.jit, static_argnums=0)
def _retina_points(config, pos, heading):
    return jax.vmap(lambda p, h: sample_points(config, Pose(p, h)))(pos, heading)


@functools.partial(jax.jit, static_argnums=0)
def _retina_colours(config, pos, heading):
    return floor_colour(config, _retina_points(config, pos, heading))


def retina_colours(config: Config, pos, heading) -> np.ndarray:
    """Floor colour (RED 0, GREEN 1, BLUE 2, NONE -1) under each retina point: (..., forward rows, lateral)."""
    pos, heading = np.asarray(pos, np.float32), np.asarray(heading, np.float32)
    colours = _retina_colours(config, pos.reshape(-1, 2), heading.reshape(-1))
    return np.asarray(colours).reshape(heading.shape + colours.shape[1:])


def retina_points(config: Config, pos, heading) -> np.ndarray:
    """World positions (..., forward rows, lateral, 2) of the retina points of poses (..., 2), (...)."""
    pos, heading = np.asarray(pos, np.float32), np.asarray(heading, np.float32)
    points = _retina_points(config, pos.reshape(-1, 2), heading.reshape(-1))
    return np.asarray(points).reshape(heading.shape + points.shape[1:])


def colour_reinforcers(config: Config, strength: float = 2.0) -> np.ndarray:
    """An LE-LS genome whose reinforcer k rewards colour k under the central receptors (MODEL.md's hand-made check).

    r_k = 2 sigmoid(strength * (number of central points seeing colour k)) - 1: 0 when the
    colour is not under the middle of the retina. Not evolved: a known input for the tour.
    """
    rows, lateral = len(config.retina_forward), len(config.retina_lateral)
    n = config.num_inputs + 1
    genome = np.zeros((config.num_experts, n), np.float32)
    for k in range(config.num_experts):
        weights = np.zeros((rows, lateral, 3), np.float32)
        weights[:, central_columns(config), k % 3] = strength
        genome[k, :-1] = weights.reshape(-1)
    return genome.reshape(-1)


def central_columns(config: Config) -> list[int]:
    """Indices of the retina's central lateral points (the two nearest the midline)."""
    lateral = np.abs(np.asarray(config.retina_lateral))
    return [int(i) for i in np.flatnonzero(lateral == lateral.min())]


def colour_shares(config: Config, trajectory: Trajectory, num_experts: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """What each expert follows: for each expert, the share of its control steps' central readings that are R, G, B, nothing.

    The readings are those of the central receptors (both rows, the lateral points nearest
    the midline) at the pose where the expert was chosen. Returns ``shares`` (K, 4), rows
    summing to 1 (NaN for an expert that never had control), and ``steps`` (K,) of control.
    Any leading axes of the trajectory are pooled.
    """
    k = np.asarray(trajectory.k).reshape(-1)
    num_experts = int(k.max()) + 1 if num_experts is None else num_experts
    colours = retina_colours(config, trajectory.seen_pos.reshape(-1, 2), trajectory.seen_heading.reshape(-1))
    central = colours[:, :, central_columns(config)].reshape(len(k), -1)  # (T, rows * central)
    seen = np.stack([(central == c).mean(1) for c in (0, 1, 2)] + [(central < 0).mean(1)], -1)  # (T, 4)
    steps = np.bincount(k, minlength=num_experts)[:num_experts]
    shares = np.full((num_experts, len(SEEN)), np.nan)
    for e in range(num_experts):
        if steps[e]:
            shares[e] = seen[k == e].mean(0)
    return shares, steps


def shares_table(shares: np.ndarray, steps: np.ndarray) -> str:
    """:func:`colour_shares` as a plain-text table (one row per expert)."""
    lines = [f"{'expert':>7} {'steps':>7} " + " ".join(f"{name:>8}" for name in SEEN)]
    for e, (row, n) in enumerate(zip(shares, steps)):
        cells = " ".join(f"{v:8.2f}" if np.isfinite(v) else f"{'-':>8}" for v in row)
        lines.append(f"{e + 1:>7} {int(n):>7} {cells}")
    return "\n".join(lines)
