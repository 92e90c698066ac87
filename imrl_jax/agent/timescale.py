"""The selector on its own time-scale (the paper's Discussion; MODEL.md "Selector time-scale"; docs/TIMESCALE.md).

The paper: "the selector, which is supposed to operate at a more abstract level with respect to
experts, should not operate at the same time-scale and with the same input as them." Its selector
chooses an expert at every step. With ``Config.selector_period`` N > 1 it chooses an *option*
instead: the chosen expert keeps control until the option ends,

* after N steps (``selector_termination="period"``), or
* when a colour comes into view that the retina did not see the step before, as at a junction,
  or after N steps at most (``"colour"``),

and always when a trial ends (a reach, a timeout, a respawn; a phase's first step too). The experts
act and learn every step as before; the selector learns once per option, when it ends, by
semi-Markov TD (:func:`imrl_jax.agent.learning.learn_selector_over_option`). An :class:`Option` is what
the step carries of the option that runs.
"""

from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp

from imrl_jax.config import Config


class Option(NamedTuple):
    """The option that runs: where and how it was chosen, and what it has earned so far."""

    start_xb: jnp.ndarray  # (n+1,): x~ at the choice
    selection: jnp.ndarray  # (K,): the selector's outputs s at the choice
    reward: jnp.ndarray  # (): sum_i gamma^i r_{i+1} over its transitions so far
    discount: jnp.ndarray  # (): gamma^tau for its tau transitions so far
    learned: jnp.ndarray  # (): its expert learned from one of them (childhood: the selector's reward exists)
    steps: jnp.ndarray  # (): its transitions before this step's
    trace_discount: jnp.ndarray  # (): gamma^tau of the last option the selector learned from (its traces' decay)


def init_option(num_experts: int, num_weights: int, dtype) -> Option:
    """A phase's first option: nothing chosen yet (the phase's first step always chooses)."""
    zero = jnp.zeros((), dtype)
    return Option(jnp.zeros((num_weights,), dtype), jnp.zeros((num_experts,), dtype), zero, zero + 1.0,
                  jnp.bool_(False), jnp.int32(0), zero + 1.0)


def colours_seen(xb: jnp.ndarray) -> jnp.ndarray:
    """(3,): 1 for each colour some retina point sees in x~ (its last entry is the bias)."""
    return xb[:-1].reshape(-1, 3).max(axis=0)


def ends(config: Config, option: Option, prev, xb: jnp.ndarray, prev_xb: jnp.ndarray) -> jnp.ndarray:
    """Whether the option ends at this step, so that the selector chooses again (see the module docstring)."""
    trial_over = ~prev.valid | prev.terminal
    done = trial_over | (option.steps + 1 >= config.selector_period)
    if config.selector_termination == "colour":
        done = done | jnp.any(colours_seen(xb) > colours_seen(prev_xb))
    return done


def next_option(option: Option, choose: jnp.ndarray, xb: jnp.ndarray, selection: jnp.ndarray) -> Option:
    """The option after this step: a new one where the selector chose (at x~_t, with s_t), else one step longer."""
    fresh = Option(xb, selection, jnp.zeros_like(option.reward), jnp.ones_like(option.discount), jnp.bool_(False),
                   jnp.int32(0), option.trace_discount)
    longer = option._replace(steps=option.steps + 1)
    return Option(*(jnp.where(choose, a, b) for a, b in zip(fresh, longer)))
