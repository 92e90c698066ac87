"""The perceptrons of section 2 and MODEL.md "Networks": reinforcers, actors, evaluators, selector.

Every perceptron reads the retina with a bias input, x~ = [x, 1]. Weights are grouped in
an :class:`Agent` pytree; :func:`decode` turns a genome into the weights a condition evolves.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import jax
import jax.numpy as jnp

from imrl_jax.config import Config, LearningParams
from imrl_jax.genome import express, get_part, parameter_values  # noqa: F401 (networks' names for them)


class Agent(NamedTuple):
    """All weights of one individual: K experts and the selector (leading axis K = experts)."""

    reinforcer: jnp.ndarray  # (K, n+1): r_k = 2 sigmoid(w.x~) - 1
    actor: jnp.ndarray  # (K, 2, n+1): o = sigmoid(W x~)
    evaluator: jnp.ndarray  # (K, n+1): V_k = v.x~
    selector_actor: jnp.ndarray  # (K, n+1): s = sigmoid(S x~)
    selector_critic: jnp.ndarray  # (n+1,): U = u.x~
    # (K,) 1 for an expressed expert, 0 for one that is not (an evolved number of experts); None: all are.
    expressed: jnp.ndarray | None = None
    # The individual's own learning values (evolved learning parameters); None: the phase's params.
    params: LearningParams | None = None
    # () steps of childhood it learns and explores for (an evolved childhood length); None: all of them.
    childhood_length: jnp.ndarray | None = None
    # (K, n+1) a second reinforcer unit per expert (LE-LS-2R): r_k = (r1 + r2) / 2; None: one unit.
    second_reinforcer: jnp.ndarray | None = None


def with_bias(x: jnp.ndarray) -> jnp.ndarray:
    """x~ = [x, 1]."""
    return jnp.concatenate([x, jnp.ones((1,), x.dtype)])


def internal_reward(activation: jnp.ndarray) -> jnp.ndarray:
    """A reinforcer's reward in [-1, 1] from its activation w.x~: 2 sigmoid(w.x~) - 1."""
    return 2.0 * jax.nn.sigmoid(activation) - 1.0


def reinforce(w: jnp.ndarray, xb: jnp.ndarray) -> jnp.ndarray:
    """Internal reward in [-1, 1]: 2 sigmoid(w.x~) - 1."""
    return internal_reward(w @ xb)


def internal_rewards(agent: Agent, xb: jnp.ndarray) -> jnp.ndarray:
    """Every expert's internal reward r_k = 2 sigmoid(w_k.x~) - 1; with two units, their mean (r1 + r2) / 2."""
    rewards = reinforce(agent.reinforcer, xb)
    if agent.second_reinforcer is None:
        return rewards
    return 0.5 * (rewards + reinforce(agent.second_reinforcer, xb))


def pick(values: jnp.ndarray, k) -> jnp.ndarray:
    """values[k] (k may be traced), as a masked sum: the GPU kernel's Triton has no gather."""
    return jnp.sum(jnp.where(jax.lax.broadcasted_iota(jnp.int32, values.shape, 0) == k, values, 0.0))


def expressed_only(agent: Agent, selection: jnp.ndarray) -> jnp.ndarray:
    """The selector's outputs with those of unexpressed experts set to 0: they are never chosen, so never learn."""
    return selection if agent.expressed is None else selection * agent.expressed


def select(u, selection: jnp.ndarray, num_experts: int | None = None) -> jnp.ndarray:
    """Expert k with probability s_k / sum(s): the first k with u * sum(s) < cumsum(s)[k].

    ``u`` is a uniform draw in [0, 1); only the first ``num_experts`` entries of
    ``selection`` count (the GPU kernel pads it with zeros).
    """
    num_experts = selection.shape[0] if num_experts is None else num_experts
    partial = [pick(selection, j) for j in range(num_experts)]
    total = partial[0]
    for j in range(1, num_experts):
        total = total + partial[j]
    threshold = u * total
    cumulative, k = jnp.zeros((), selection.dtype), jnp.int32(0)
    for j in range(num_experts - 1):
        cumulative = cumulative + partial[j]
        k = k + (cumulative <= threshold).astype(jnp.int32)
    return k


def explore(output, z, noise_std, t, phase_steps: int):
    """a_t = clip(o_t + sigma_t z, 0, 1), sigma_t = noise_std max(1 - t / T, 0) (the paper's annealed noise)."""
    sigma = noise_std * jnp.maximum(1.0 - t.astype(output.dtype) / phase_steps, 0.0)
    return jnp.clip(output + sigma * z, 0.0, 1.0)


def act(weights: jnp.ndarray, xb: jnp.ndarray) -> jnp.ndarray:
    """Sigmoid outputs of an actor (2 units) or of the selector (K units)."""
    return jax.nn.sigmoid(weights @ xb)


def evaluate_both(v: jnp.ndarray, xbs: jnp.ndarray) -> jnp.ndarray:
    """The selector critic's evaluations u.x~ of both rows of xbs, as one product.

    One product instead of two vector products: XLA's CPU backend runs a batch of
    matrix-vector products as one fast dot, but a batch of vector products as a slow
    multiply-reduce.
    """
    return xbs @ v


def zero_agent(config: Config, dtype=jnp.float32) -> Agent:
    """An agent before evolution and learning: weights 0 (MODEL.md), except (in the arena) the actors' speed
    unit's bias, ``config.initial_speed_bias`` (0 by default; docs/CHILDHOOD.md)."""
    k, n, units = config.num_lane_experts, config.num_inputs + 1, config.num_actor_units
    actor = jnp.zeros((k, units, n), dtype)
    if config.world == "arena":  # the speed unit's bias: a discrete world's actions start alike
        actor = actor.at[:, 1, -1].set(config.initial_speed_bias)
    agent = Agent(
        reinforcer=jnp.zeros((k, n), dtype),
        actor=actor,
        evaluator=jnp.zeros((k, n), dtype),
        selector_actor=jnp.zeros((k, n), dtype),
        selector_critic=jnp.zeros((n,), dtype),
    )
    for name in config.spec.genome:  # the fields a genome part adds (e.g. expression: all expressed)
        part = get_part(name)
        if part.start is not None:
            agent = agent._replace(**part.start(config, dtype))
    return agent


def trait_names(config: Config) -> tuple[str, ...]:
    """The evolved values a condition's genomes carry besides weights (recorded per generation by ``evolve``)."""
    return tuple(name for part in config.spec.genome for name in get_part(part).trait_names(config))


def traits(config: Config, genome: jnp.ndarray) -> jnp.ndarray:
    """The values of :func:`trait_names` for one genome (the learning values its genes decode to; how many experts it
    expresses, and 1 in the ``share_k_experts`` entry of that number): a population's mean of those is the share."""
    agent = decode(config, genome)
    values = [value for part in config.spec.genome for value in get_part(part).trait_values(config, agent)]
    return jnp.stack([jnp.asarray(v, genome.dtype) for v in values]) if values else jnp.zeros((0,), genome.dtype)


def decode(config: Config, genome: jnp.ndarray) -> Agent:
    """The weights a genome encodes (MODEL.md "Conditions"); the rest start as :func:`zero_agent`.

    The genome lists the networks of ``config.spec.genome`` one after the other (LE-LS: the K
    reinforcers; EE-LS: the K actors; EE-ES: the K actors, then the selector actor; SLE: nothing).
    """
    if genome.shape != (config.num_genes,):
        raise ValueError(f"genome: expected shape ({config.num_genes},) for {config.condition}, "
                         f"got {genome.shape}")
    agent, start = zero_agent(config, genome.dtype), 0
    for name in config.spec.genome:  # each part puts its genes in place (genome.PARTS)
        part = get_part(name)
        shape = part.shape(config.num_lane_experts, config.num_inputs + 1, config.num_actor_units)
        size = math.prod(shape)
        agent = part.decode(config, agent, genome[start:start + size].reshape(shape))
        start += size
    return agent


def encode(config: Config, agent: Agent) -> jnp.ndarray:
    """Inverse of :func:`decode`: the genome of the evolved parts of an agent."""
    parts = []
    for name in config.spec.genome:
        part = get_part(name)
        if part.encode is None:
            raise ValueError(f"encode: {part.what} are not encoded back into genes")
        parts.append(part.encode(agent).reshape(-1))
    return jnp.concatenate(parts) if parts else jnp.zeros((0,), agent.actor.dtype)
