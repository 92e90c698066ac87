"""The GPU kernel's layout of a lane (section 2, MODEL.md "Acting"): a phase's state packed, and back.

Triton's blocks have power-of-two shapes, and a kernel reads and writes whole arrays: the state of
:mod:`imrl_jax.agent.state` (weights, traces, pose, the last two observations, what the previous step left)
becomes a few arrays of a lane, experts K padded to Kp rows and x~'s n + 1 entries to N columns, and
the scalars gathered into one float and one int vector. :func:`retina_layout` says, for each column,
which retina point and colour it holds.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from imrl_jax.agent.networks import Agent
from imrl_jax.agent.state import Draws, Previous, State, Traces
from imrl_jax.agent.timescale import Option
from imrl_jax.config import Config
from imrl_jax.world.env import EnvState

# Slots of the per-lane scalar vectors.
_X, _Y, _HEADING, _COS, _SIN, _A0, _A1, _O0, _O1 = range(9)  # floats
_K, _VALID, _TERMINAL, _TRIAL_STEP, T_SLOT, _EXPERTS_ENDED, _SELECTOR_ENDED, _PINNED = range(8)  # int32
NUM_FLOATS, _NUM_INTS = 16, 8
# Slots of an option's scalars (the selector's options only).
OPTION_REWARD, OPTION_DISCOUNT, OPTION_TRACE_DISCOUNT = range(3)  # floats, 4 slots
OPTION_LEARNED, OPTION_STEPS = range(2)  # int32
# Rows of the packed weights and traces.
_REINFORCER, _ACTOR0, _ACTOR1, _EVALUATOR, _SELECTOR = range(5)
_TRACE_ACTOR0, _TRACE_ACTOR1, _TRACE_EVALUATOR, _TRACE_CRITIC = range(4)


class Packed(NamedTuple):
    """One lane's phase state in the kernel's padded layout (K -> Kp rows, n+1 -> N columns).

    The option's fields are None unless the selector has options (``Config.selector_options``).
    """

    weights: jnp.ndarray  # (5, Kp, N): reinforcer, actor unit 0, actor unit 1, evaluator, selector actor
    critic: jnp.ndarray  # (N,): selector critic
    traces: jnp.ndarray  # (4, N): actor unit 0, actor unit 1, evaluator, selector critic
    selector_trace: jnp.ndarray  # (Kp, N)
    xbs: jnp.ndarray  # (2, N): x~_{t-1}, x~_{t-2}
    selection: jnp.ndarray  # (Kp,): s_{t-1} (0 in padded rows)
    floats: jnp.ndarray  # (16,): pose, (cos, sin), a_{t-1}, o_{t-1}
    ints: jnp.ndarray  # (8,): k, valid, terminal, trial step, t, ended flags, steps on a wall
    baseline: jnp.ndarray  # (Kp,): each expert's running mean surprise (0 in padded rows)
    option_xb: jnp.ndarray | None = None  # (N,): x~ at the option's choice
    option_selection: jnp.ndarray | None = None  # (Kp,): s at the choice
    option_floats: jnp.ndarray | None = None  # (4,): its reward so far, gamma^tau, the last learned option's gamma^tau
    option_ints: jnp.ndarray | None = None  # (2,): it learned (0/1), its transitions so far


class Fixed(NamedTuple):
    """What a lane reads but never changes, beyond the paper's model (None where the model lacks it)."""

    expressed: jnp.ndarray | None = None  # (Kp,): 1 for an expressed expert (an evolved number of experts)
    second_reinforcer: jnp.ndarray | None = None  # (Kp, N): the second reinforcer units (LE-LS-2R)


def pow2(n: int) -> int:
    """The least power of two at least n (Triton's block sizes)."""
    return 1 << max(0, (n - 1).bit_length())


def _pad(x, shape):
    return jnp.pad(x, [(0, s - d) for s, d in zip(shape, x.shape)])


def num_points(config: Config) -> int:
    """The retina's points (each sees three colours: x~ holds 3 entries a point, then the bias)."""
    return config.num_inputs // 3


def columns(config: Config) -> np.ndarray:
    """(N,): the entry of x~ (bias included) that each of the kernel's columns holds; -1 for a padding column.

    ``kernel_retina="entries"``: x~'s own order (entry 3 p + c for colour c of point p), padded to N =
    2^ceil(log2(n + 1)). ``"points"``: colour-major, column c P + p for colour c of point p (P the points padded
    to a power of two), the bias in column 3 P, N = 4 P: x~ is then the points' colours compared with each block's
    colour (:func:`imrl_jax.agent.kernel.observe_points`), and a permutation changes no product.
    """
    n = config.num_inputs
    if config.kernel_retina == "entries":
        cols = np.full(pow2(n + 1), -1)
        cols[:n + 1] = np.arange(n + 1)
        return cols
    points, width = num_points(config), pow2(num_points(config))
    cols = np.full(4 * width, -1)
    for colour in range(3):
        cols[colour * width:colour * width + points] = 3 * np.arange(points) + colour
    cols[3 * width] = n
    return cols


def _to_columns(x, cols: np.ndarray):
    """``x``'s last axis (x~'s entries) in the kernel's columns, padding 0 (x~'s own order: padded only)."""
    if np.array_equal(cols[:x.shape[-1]], np.arange(x.shape[-1])):
        return _pad(x, x.shape[:-1] + (cols.shape[0],))
    padded = jnp.concatenate([x, jnp.zeros(x.shape[:-1] + (1,), x.dtype)], axis=-1)  # entry -1: the zero
    return padded[..., np.where(cols >= 0, cols, x.shape[-1])]


def _from_columns(x, cols: np.ndarray, num_entries: int):
    """The entries of x~ from the kernel's columns (the last axis)."""
    where = np.argsort(np.where(cols >= 0, cols, cols.shape[0] + num_entries))[:num_entries]
    return x[..., :num_entries] if np.array_equal(where, np.arange(num_entries)) else x[..., where]


def pack(state: State, config: Config) -> Packed:
    """The kernel's layout of a phase state."""
    agent, traces, prev = state.agent, state.traces, state.prev
    k, n = agent.selector_actor.shape
    kp, cols = pow2(k), columns(config)
    rows = lambda m: _pad(_to_columns(m, cols), (kp, cols.shape[0]))  # noqa: E731
    vec = lambda v: _to_columns(v, cols)  # noqa: E731
    dtype = agent.actor.dtype
    now = state.t % 2
    xbs = jnp.stack([state.xbs[1 - now], state.xbs[now]])  # x~_{t-1}, x~_{t-2}
    robot = state.world  # the arena's EnvState: the kernel lives the arena only
    floats = jnp.stack([robot.pose.pos[0], robot.pose.pos[1], robot.pose.heading, *robot.direction,
                        *prev.action, *prev.output]).astype(dtype)
    ints = jnp.stack([prev.k, prev.valid, prev.terminal, robot.trial_step, state.t, traces.experts_ended,
                      traces.selector_ended, robot.pinned]).astype(jnp.int32)
    option = {}
    if state.option is not None:
        o = state.option
        option = dict(option_xb=vec(o.start_xb), option_selection=_pad(o.selection, (kp,)),
                      option_floats=_pad(jnp.stack([o.reward, o.discount, o.trace_discount]).astype(dtype), (4,)),
                      option_ints=jnp.stack([o.learned, o.steps]).astype(jnp.int32))
    return Packed(
        weights=jnp.stack([rows(agent.reinforcer), rows(agent.actor[:, 0]), rows(agent.actor[:, 1]),
                           rows(agent.evaluator), rows(agent.selector_actor)]),
        critic=vec(agent.selector_critic),
        traces=jnp.stack([vec(traces.actor[0]), vec(traces.actor[1]), vec(traces.evaluator),
                          vec(traces.selector_critic)]),
        selector_trace=rows(traces.selector_actor),
        xbs=jax.vmap(vec)(xbs),
        selection=_pad(prev.selection, (kp,)),
        floats=_pad(floats, (NUM_FLOATS,)),
        ints=_pad(ints, (_NUM_INTS,)),
        baseline=_pad(state.baseline, (kp,)),
        **option,
    )


def fixed(agent: Agent, config: Config) -> Fixed:
    """The kernel's layout of what ``agent`` holds beyond the paper's networks and never changes."""
    kp, cols = pow2(agent.selector_actor.shape[0]), columns(config)
    second = agent.second_reinforcer
    return Fixed(
        expressed=None if agent.expressed is None else _pad(agent.expressed, (kp,)),
        second_reinforcer=None if second is None else _pad(_to_columns(second, cols), (kp, cols.shape[0])),
    )


def unpack(packed: Packed, like: State, block: Draws, config: Config) -> State:
    """The phase state that ``packed`` holds (``like`` gives the shapes and what the lane never changes; ``block``
    the current draws)."""
    k, n = like.agent.selector_actor.shape
    cols = columns(config)
    entries = lambda x: _from_columns(x, cols, n)  # noqa: E731
    w, f, i = packed.weights, packed.floats, packed.ints
    t = i[T_SLOT]
    now = t % 2
    # x~_t goes in row t % 2: at step t the last observation x~_{t-1} sits in row 1 - t % 2.
    xbs = entries(jnp.where(now == 0, packed.xbs[::-1], packed.xbs))
    agent = like.agent._replace(  # expression, learning values, childhood length, second reinforcers: as they were
        reinforcer=entries(w[_REINFORCER, :k]),
        actor=jnp.stack([entries(w[_ACTOR0, :k]), entries(w[_ACTOR1, :k])], axis=1),
        evaluator=entries(w[_EVALUATOR, :k]),
        selector_actor=entries(w[_SELECTOR, :k]),
        selector_critic=entries(packed.critic),
    )
    traces = Traces(
        actor=entries(packed.traces[jnp.array([_TRACE_ACTOR0, _TRACE_ACTOR1])]),
        evaluator=entries(packed.traces[_TRACE_EVALUATOR]),
        selector_actor=entries(packed.selector_trace[:k]),
        selector_critic=entries(packed.traces[_TRACE_CRITIC]),
        experts_ended=i[_EXPERTS_ENDED] != 0,
        selector_ended=i[_SELECTOR_ENDED] != 0,
    )
    prev = Previous(k=i[_K], action=f[jnp.array([_A0, _A1])], output=f[jnp.array([_O0, _O1])],
                    selection=packed.selection[:k], valid=i[_VALID] != 0, terminal=i[_TERMINAL] != 0)
    pose = like.world.pose._replace(pos=f[jnp.array([_X, _Y])], heading=f[_HEADING])
    robot = EnvState(pose, f[jnp.array([_COS, _SIN])], i[_TRIAL_STEP], i[_PINNED])
    option = None
    if like.option is not None:
        of, oi = packed.option_floats, packed.option_ints
        option = Option(start_xb=entries(packed.option_xb), selection=packed.option_selection[:k],
                        reward=of[OPTION_REWARD], discount=of[OPTION_DISCOUNT],
                        learned=oi[OPTION_LEARNED] != 0, steps=oi[OPTION_STEPS],
                        trace_discount=of[OPTION_TRACE_DISCOUNT])
    return State(agent, traces, robot, xbs, prev, t, block, packed.baseline[:k], option)


def retina_layout(config: Config, dtype=jnp.float32) -> jnp.ndarray:
    """(4, N): for each of the kernel's columns, its point's forward and lateral offset (``"points"``: in the
    first P columns, one a point), its colour (3: none, so a padding column never sees one), its bias (1 in the
    bias's column)."""
    forward, lateral = np.meshgrid(config.retina_forward, config.retina_lateral, indexing="ij")
    n, cols = config.num_inputs, columns(config)
    layout = np.zeros((4, cols.shape[0]))
    holds = (cols >= 0) & (cols < n)
    point = np.where(holds, cols // 3, 0)
    if config.kernel_retina == "entries":
        layout[0] = np.where(holds, forward.ravel()[point], 0.0)
        layout[1] = np.where(holds, lateral.ravel()[point], 0.0)
    else:
        layout[0, :num_points(config)] = forward.ravel()
        layout[1, :num_points(config)] = lateral.ravel()
    layout[2] = np.where(holds, cols % 3, 3.0)
    layout[3] = cols == n
    return jnp.asarray(layout, dtype)
