"""The control cycle of section 2 (MODEL.md "Acting", "Learning") as one GPU kernel per bin of steps.

:func:`run_phase` computes what :func:`imrl_jax.agent.lifetime.run_phase` computes, with the
same signature and results, but each bin of steps of a lane is one Pallas (Triton) kernel
whose loop keeps the lane's weights, traces and pose in registers. On a GPU the XLA
program runs each step as dozens of small kernels, one after the other, so a step costs
their launches whatever the number of lanes; here a step is one iteration of a warp's
loop. The random numbers are the same stream as the XLA program's, drawn by XLA for a
bin at a time and read by the kernel.

Every model of the condition table lives on it in the arena: evolved evaluators (``Phase.evaluation``), an
evolved number of experts (the expression mask), evolved learning values and childhood length (per lane),
two reinforcer units, and the selector's options (``Config.selector_period``, docs/TIMESCALE.md). What a
model adds that the paper's does not is an input or a carried vector only where the model has it, so the
paper's kernels are the same program as before.

Selected with ``Config.step_kernel = "pallas"``. Off a GPU the kernel runs in Pallas's
interpreter (slow; for tests): float64 lives then agree with the XLA program to rounding.
Each lane is one kernel instance; ``vmap`` (over tasks, individuals and seeds) makes the
grid. Vectors are padded to powers of two (Triton's rule): experts K to Kp, x~ (n+1) to N
(:mod:`imrl_jax.agent.kernel_layout`).
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from imrl_jax.agent import learning
from imrl_jax.world.arena import advance, floor_colour_xy, on_wall, spawn_pose, trial_ends, turn
from imrl_jax.config import Config, ConfigError, LearningParams
from imrl_jax.agent.kernel_layout import (NUM_FLOATS, OPTION_DISCOUNT, OPTION_LEARNED, OPTION_REWARD,
                                          OPTION_STEPS, OPTION_TRACE_DISCOUNT, T_SLOT, Fixed, Packed, pow2, fixed,
                                          num_points, pack, retina_layout, unpack)
from imrl_jax.agent.learning import ascend, ascend_row, selector_features, td_error, unit_features
from imrl_jax.agent.networks import explore, internal_reward, pick, select
from imrl_jax.conditions import Phase
from imrl_jax.world.env import TaskSpec
from imrl_jax.agent.state import Curves, Draws, State, bin_steps, childhood_phase, draw_block, phase_params, spawn_draws
from imrl_jax.agent.timescale import Option


def round_even(x):
    """Round half to even, from floor (which Triton has; it has no round-half-even)."""
    # x - floor(x) is exact in floating point, so the tie test is exact.
    low = jnp.floor(x)
    frac = x - low
    odd = low - 2.0 * jnp.floor(0.5 * low)
    return jnp.where(frac > 0.5, low + 1.0, jnp.where(frac < 0.5, low, low + odd))


def observe_points(config: Config, pose, offsets, colours, bias):
    """x~ in the colour-major columns of ``kernel_retina="points"`` (:func:`kernel_layout.columns`): each retina
    point's floor colour computed once (P points, a power of two), copied to each of the four blocks of P
    columns and compared with the column's colour (the bias's block sees none). What ``observe`` computes, with
    the point's work done once instead of once per colour and padding column."""
    x, y, c, s = pose
    forward, lateral = offsets
    width, big_n = forward.shape[0], colours.shape[0]
    colour = floor_colour_xy(config, x + forward * c - lateral * s, y + forward * s + lateral * c, round_even)
    wide = jnp.broadcast_to(colour.astype(colours.dtype)[None, :], (big_n // width, width)).reshape(big_n)
    return (wide == colours).astype(colours.dtype) + bias


def _dot_rows(matrix, vector):
    """matrix @ vector, for a (rows, N) matrix."""
    return jnp.sum(matrix * vector[None, :], axis=1)


class _Carry(NamedTuple):
    """The kernel loop's carry: one lane's state, in registers, and the bin's counts."""

    weights: tuple  # the five (Kp, N) weight matrices, in Packed.weights order
    critic: jnp.ndarray
    traces: tuple  # the four (N,) traces, in Packed.traces order
    selector_trace: jnp.ndarray
    prev_xb: jnp.ndarray
    before_xb: jnp.ndarray
    selection: jnp.ndarray
    floats: tuple  # x, y, heading, cos, sin, a0, a1, o0, o1
    ints: tuple  # k, valid, terminal, trial_step, t, experts_ended, selector_ended, pinned (int32)
    baseline: jnp.ndarray  # (Kp,)
    reaches: jnp.ndarray
    timeouts: jnp.ndarray
    respawns: jnp.ndarray
    selections: jnp.ndarray  # (Kp,) int32
    option: Option | None = None  # the option that runs (its flag an int32: 0/1), or None without options


class _Model(NamedTuple):
    """What a lane's model adds to the paper's, static: it decides which inputs the kernel reads."""

    options: bool = False  # the selector chooses options (Config.selector_options)
    expressed: bool = False  # an expression mask (an evolved number of experts)
    second_reinforcer: bool = False  # two reinforcer units per expert
    childhood_length: bool = False  # an evolved childhood length (learning and noise stop at it)


#: The kernel's inputs, in order; a None field of Packed or Fixed is not passed.
_INPUTS = ("layout", "params", "task", "u", "z", "spawn") + Fixed._fields + tuple(f"in_{f}" for f in Packed._fields)


def _make_kernel(config: Config, phase: Phase, phase_steps: int, num_steps: int, num_experts: int, model: _Model,
                 inputs: tuple[str, ...], outputs: tuple[str, ...]):
    """The kernel body: ``num_steps`` steps of one lane (refs: the ``inputs``, then the ``outputs``, by name).

    The step is lifetime.step's control cycle on the lane's registers; the rules it applies
    are the XLA program's functions (networks, learning, timescale, arena), written so that Triton
    lowers them (no gather, no scatter: rows are read and written through one-hot masks).
    """

    def kernel(*refs):
        ref = dict(zip(inputs + outputs, refs))
        weights_ref, params_ref, task_ref, u_ref, z_ref, spawn_ref = (
            ref["in_weights"], ref["params"], ref["task"], ref["u"], ref["z"], ref["spawn"])
        layout_ref, selection_ref = ref["layout"], ref["in_selection"]
        dtype = weights_ref.dtype
        p = LearningParams(*(params_ref[j] for j in range(len(LearningParams._fields))))
        gamma, lam = p.gamma, p.trace_lambda
        progress_rate = p.progress_rate
        # An evolved childhood's length: the entry after the learning values.
        length = params_ref[len(LearningParams._fields)] if model.childhood_length else None
        start_x, start_y, start_heading, target_x, target_y = (task_ref[j] for j in range(5))
        start_cos, start_sin = jnp.cos(start_heading), jnp.sin(start_heading)
        forward, lateral, colours, bias = (layout_ref[j] for j in range(4))
        if config.kernel_retina == "points":  # each point's offsets: the first P columns
            width = pow2(num_points(config))
            point_forward, point_lateral = layout_ref[0, :width], layout_ref[1, :width]
        expressed = ref["expressed"][...] if model.expressed else None
        second_reinforcer = ref["second_reinforcer"][...] if model.second_reinforcer else None
        kp = selection_ref.shape[0]
        rows = jax.lax.broadcasted_iota(jnp.int32, (kp,), 0)
        expert_rows = rows < num_experts
        zero = jnp.zeros((), dtype)

        def observe(x, y, c, s):
            if config.kernel_retina == "points":
                return observe_points(config, (x, y, c, s), (point_forward, point_lateral), colours, bias)
            colour = floor_colour_xy(config, x + forward * c - lateral * s, y + forward * s + lateral * c,
                                     round_even)
            return (colour.astype(dtype) == colours).astype(dtype) + bias

        def seen(xb, colour):
            """1 where some retina point of x~ sees ``colour`` (timescale.colours_seen's entry)."""
            return jnp.max(jnp.where(colours == colour, xb, 0.0))

        def reinforcement(reinforcer, xb, k):
            """The expert k's internal reward (networks.internal_rewards): one unit's, or two units' mean."""
            reward = internal_reward(pick(_dot_rows(reinforcer, xb), k))
            if second_reinforcer is None:
                return reward
            return 0.5 * (reward + internal_reward(pick(_dot_rows(second_reinforcer, xb), k)))

        def accumulate(trace, phi, discount, learn, ended):
            return learning.accumulate(trace, phi, discount, lam, learn, ended)

        def one_step(i, carry: _Carry) -> _Carry:
            reinforcer, actor0, actor1, evaluator, selector = carry.weights
            trace_actor0, trace_actor1, trace_evaluator, trace_critic = carry.traces
            x, y, heading, c, s, a0, a1, o0, o1 = carry.floats
            prev_k, valid, terminal, trial_step, t, experts_ended, selector_ended, pinned = carry.ints
            valid, terminal = valid != 0, terminal != 0
            critic, selector_trace, prev_xb = carry.critic, carry.selector_trace, carry.prev_xb
            baseline = carry.baseline
            eta_actor, eta_evaluator = p.eta_actor, p.eta_evaluator
            eta_selector_actor, eta_selector_critic = p.eta_selector_actor, p.eta_selector_critic
            noise_std = p.noise_std
            if length is not None:  # state.learning_until: after the evolved childhood, no learning and no noise
                learning = t.astype(dtype) < length
                eta_actor, eta_evaluator, eta_selector_actor, eta_selector_critic, noise_std = (
                    jnp.where(learning, v, 0.0)
                    for v in (eta_actor, eta_evaluator, eta_selector_actor, eta_selector_critic, noise_std))

            # 1-2: observe, choose the expert (where the option ends, if the selector has options).
            xb = observe(x, y, c, s)
            selection = jnp.where(expert_rows, jax.nn.sigmoid(_dot_rows(selector, xb)), 0.0)
            if expressed is not None:  # networks.expressed_only: an unexpressed expert is never chosen
                selection = selection * expressed
            # One expert: k is 0, computed from the carry (Triton's lowering cannot return a constant from the loop).
            k = select(u_ref[i], selection, num_experts) if num_experts > 1 else jnp.minimum(prev_k, 0)
            option = carry.option
            if model.options:  # timescale.ends: a trial's end, the period, or (colour) a colour come into view
                choose = terminal | ~valid | (option.steps + 1 >= config.selector_period)
                if config.selector_termination == "colour":
                    for colour in range(3):
                        choose = choose | (seen(xb, colour) > seen(prev_xb, colour))
                k = jnp.where(choose, k, prev_k)
            same = k == prev_k
            ends = terminal | ~valid
            extrinsic = terminal.astype(dtype)
            held = rows == prev_k

            # 3: learn from the transition t-1 -> t.
            surprise = zero
            if phase.experts_learn:
                learn = valid & same
                if phase.evaluation:  # learning.learn_experts: the change of the innate evaluation alone
                    reward, discount = zero, gamma if phase.evaluation == "discounted" else 1.0
                else:
                    reward = reinforcement(reinforcer, xb, prev_k) if phase.intrinsic else extrinsic
                    discount = gamma
                value_before = pick(_dot_rows(evaluator, prev_xb), prev_k)
                value_now = pick(_dot_rows(evaluator, xb), prev_k)
                surprise = td_error(reward, value_before, value_now, discount, terminal)
                delta = jnp.where(learn, surprise, 0.0)
                ended = experts_ended != 0
                learns_value = not phase.evaluation  # an evolved evaluation is innate: it does not learn
                if learns_value:
                    trace_evaluator = accumulate(trace_evaluator, prev_xb, gamma, learn, ended)
                trace_actor0 = accumulate(trace_actor0, unit_features(a0, o0, prev_xb), gamma, learn, ended)
                trace_actor1 = accumulate(trace_actor1, unit_features(a1, o1, prev_xb), gamma, learn, ended)
                row = held.astype(dtype)
                if learns_value:
                    evaluator = ascend_row(evaluator, row, trace_evaluator, delta, eta_evaluator)
                actor0 = ascend_row(actor0, row, trace_actor0, delta, eta_actor)
                actor1 = ascend_row(actor1, row, trace_actor1, delta, eta_actor)
                experts_ended = (~same | ends).astype(jnp.int32)
            if phase.selector_learns:
                if phase.intrinsic:
                    learn, reward = valid & same, surprise
                    if phase.progress:  # lifetime.step: surprise minus the expert's running mean
                        mine = held.astype(dtype) * learn.astype(dtype)
                        reward = surprise - jnp.sum(mine * baseline)
                        baseline = baseline + progress_rate * mine * (surprise - baseline)
                else:
                    learn, reward = valid, extrinsic
                if model.options:  # learning.learn_selector_over_option: semi-Markov TD when the option ends
                    if phase.intrinsic:
                        reward = jnp.where(learn, reward, 0.0)
                        worth = (option.learned != 0) | learn
                    else:
                        worth = valid | ~valid  # True, computed (Triton's loop cannot return a constant)
                    total, discount = option.reward + option.discount * reward, option.discount * gamma
                    learn = choose & valid & worth
                    delta = (total + jnp.where(terminal, 0.0, discount * jnp.sum(critic * xb))
                             - jnp.sum(critic * option.start_xb))
                    delta = jnp.where(learn, delta, 0.0)
                    ended = selector_ended != 0
                    trace_critic = accumulate(trace_critic, option.start_xb, option.trace_discount, learn, ended)
                    phi = selector_features(prev_k, option.selection, option.start_xb)
                    selector_trace = accumulate(selector_trace, phi, option.trace_discount, learn, ended)
                    selector_ended = jnp.where(choose, ends.astype(jnp.int32), selector_ended)
                    option = option._replace(reward=total, discount=discount, learned=worth.astype(jnp.int32),
                                             trace_discount=jnp.where(learn, discount, option.trace_discount))
                else:
                    value_before = jnp.sum(critic * prev_xb)
                    value_now = jnp.sum(critic * xb)
                    delta = td_error(reward, value_before, value_now, gamma, terminal)
                    delta = jnp.where(learn, delta, 0.0)
                    ended = selector_ended != 0
                    trace_critic = accumulate(trace_critic, prev_xb, gamma, learn, ended)
                    phi = selector_features(prev_k, carry.selection, prev_xb)
                    selector_trace = accumulate(selector_trace, phi, gamma, learn, ended)
                critic = ascend(critic, trace_critic, delta, eta_selector_critic)
                selector = ascend(selector, selector_trace, delta, eta_selector_actor)
                if not model.options:
                    selector_ended = ends.astype(jnp.int32)
            if model.options:  # timescale.next_option: a new option where the selector chose, else one step longer
                option = Option(start_xb=jnp.where(choose, xb, option.start_xb),
                                selection=jnp.where(choose, selection, option.selection),
                                reward=jnp.where(choose, 0.0, option.reward),
                                discount=jnp.where(choose, 1.0, option.discount),
                                learned=jnp.where(choose, 0, option.learned),
                                steps=jnp.where(choose, 0, option.steps + 1),
                                trace_discount=option.trace_discount)

            # 4: act.
            out0 = jax.nn.sigmoid(pick(_dot_rows(actor0, xb), k))
            out1 = jax.nn.sigmoid(pick(_dot_rows(actor1, xb), k))
            if phase.noisy:
                act0 = explore(out0, z_ref[0, i], noise_std, t, phase_steps)
                act1 = explore(out1, z_ref[1, i], noise_std, t, phase_steps)
            else:
                act0, act1 = out0, out1

            # 5: move; walls (respawn), then reaching the target or the timeout starts a new trial.
            heading = turn(config, heading, act0)
            c, s = jnp.cos(heading), jnp.sin(heading)
            x, y = advance(config, (x, y), (c, s), act1)
            trial_step = trial_step + 1
            if phase.respawn:
                pinned = jnp.where(on_wall(config, (x, y)), pinned + 1, 0)
                respawned = pinned >= config.wall_respawn_steps
                (spawn_x, spawn_y), spawn_heading = spawn_pose(config, (spawn_ref[0, i], spawn_ref[1, i]),
                                                               spawn_ref[2, i])
                x, y = jnp.where(respawned, spawn_x, x), jnp.where(respawned, spawn_y, y)
                heading = jnp.where(respawned, spawn_heading, heading)
                c, s = jnp.where(respawned, jnp.cos(heading), c), jnp.where(respawned, jnp.sin(heading), s)
                pinned = jnp.where(respawned, 0, pinned)
            else:
                respawned = trial_step < 0  # False, computed (see below)
            if phase.has_target:
                reached, timeout = trial_ends(config, (x, y), (target_x, target_y), trial_step)
                reset = reached | timeout
                x, y = jnp.where(reset, start_x, x), jnp.where(reset, start_y, y)
                heading = jnp.where(reset, start_heading, heading)
                c, s = jnp.where(reset, start_cos, c), jnp.where(reset, start_sin, s)
                trial_step = jnp.where(reset, 0, trial_step)
            else:
                # False, but computed: Triton's lowering cannot return a constant from the loop.
                reached = timeout = trial_step < 0

            return _Carry(
                weights=(reinforcer, actor0, actor1, evaluator, selector),
                critic=critic,
                traces=(trace_actor0, trace_actor1, trace_evaluator, trace_critic),
                selector_trace=selector_trace,
                prev_xb=xb,
                before_xb=prev_xb,
                selection=selection,
                floats=(x, y, heading, c, s, act0, act1, out0, out1),
                ints=(k, (~(timeout | respawned)).astype(jnp.int32), reached.astype(jnp.int32), trial_step, t + 1,
                      experts_ended, selector_ended, pinned),
                baseline=baseline,
                reaches=carry.reaches + reached.astype(jnp.int32),
                timeouts=carry.timeouts + timeout.astype(jnp.int32),
                respawns=carry.respawns + respawned.astype(jnp.int32),
                selections=carry.selections + (rows == k).astype(jnp.int32),
                option=option,
            )

        traces_ref, floats_ref, ints_ref, xbs_ref = ref["in_traces"], ref["in_floats"], ref["in_ints"], ref["in_xbs"]
        option = None
        if model.options:
            of, oi = ref["in_option_floats"], ref["in_option_ints"]
            option = Option(start_xb=ref["in_option_xb"][...], selection=ref["in_option_selection"][...],
                            reward=of[OPTION_REWARD], discount=of[OPTION_DISCOUNT], learned=oi[OPTION_LEARNED],
                            steps=oi[OPTION_STEPS], trace_discount=of[OPTION_TRACE_DISCOUNT])
        carry = _Carry(
            weights=tuple(weights_ref[j] for j in range(5)),
            critic=ref["in_critic"][...],
            traces=tuple(traces_ref[j] for j in range(4)),
            selector_trace=ref["in_selector_trace"][...],
            prev_xb=xbs_ref[0],
            before_xb=xbs_ref[1],
            selection=selection_ref[...],
            floats=tuple(floats_ref[j] for j in range(9)),
            ints=tuple(ints_ref[j] for j in range(8)),
            baseline=ref["in_baseline"][...],
            reaches=jnp.int32(0),
            timeouts=jnp.int32(0),
            respawns=jnp.int32(0),
            selections=jnp.zeros((kp,), jnp.int32),
            option=option,
        )
        carry = jax.lax.fori_loop(0, num_steps, one_step, carry)
        for j in range(5):
            ref["out_weights"][j] = carry.weights[j]
        ref["out_critic"][...] = carry.critic
        for j in range(4):
            ref["out_traces"][j] = carry.traces[j]
        ref["out_selector_trace"][...] = carry.selector_trace
        ref["out_xbs"][0] = carry.prev_xb
        ref["out_xbs"][1] = carry.before_xb
        ref["out_selection"][...] = carry.selection
        for j, value in enumerate(carry.floats):
            ref["out_floats"][j] = value
        for j in range(9, NUM_FLOATS):
            ref["out_floats"][j] = zero
        for j, value in enumerate(carry.ints):
            ref["out_ints"][j] = value
        ref["out_baseline"][...] = carry.baseline
        if model.options:
            option = carry.option
            ref["out_option_xb"][...] = option.start_xb
            ref["out_option_selection"][...] = option.selection
            for j, value in ((OPTION_REWARD, option.reward), (OPTION_DISCOUNT, option.discount),
                             (OPTION_TRACE_DISCOUNT, option.trace_discount), (3, zero)):
                ref["out_option_floats"][j] = value
            ref["out_option_ints"][OPTION_LEARNED] = option.learned
            ref["out_option_ints"][OPTION_STEPS] = option.steps
        ref["counts"][0] = carry.reaches
        ref["counts"][1] = carry.timeouts
        ref["counts"][2] = carry.respawns
        ref["selections"][...] = carry.selections

    return kernel


def _interpret() -> bool:
    """Run the kernel in Pallas's interpreter off a GPU (Triton kernels need one)."""
    return jax.default_backend() != "gpu"


def run_bin(config: Config, phase: Phase, params: LearningParams, task: TaskSpec, phase_steps: int,
            draws: Draws, packed: Packed, num_experts: int, interpret: bool | None = None,
            lane: Fixed = Fixed(), childhood_length=None):
    """Steps ``len(draws.u)`` of one lane from ``packed``: the new state and (reaches, timeouts), selections.

    ``lane``: what the lane reads beyond the paper's model (:func:`fixed`); ``childhood_length``: the step at
    which an evolved childhood stops learning and exploring (None: it does not).
    """
    from jax.experimental import pallas as pl
    from jax.experimental.pallas import triton as pltriton

    dtype = packed.weights.dtype
    num_steps = draws.u.shape[0]
    values = list(params) + ([] if childhood_length is None else [childhood_length])
    params_vector = jnp.stack([jnp.asarray(p, dtype) for p in values])
    task_vector = jnp.stack([task.start.pos[0], task.start.pos[1], task.start.heading,
                             task.target[0], task.target[1]]).astype(dtype)
    kp = packed.selection.shape[0]
    model = _Model(options=packed.option_xb is not None, expressed=lane.expressed is not None,
                   second_reinforcer=lane.second_reinforcer is not None,
                   childhood_length=childhood_length is not None)
    # Without noise the kernel reads no z: a stand-in spares the lanes x steps zeros.
    z = draws.z.T.astype(dtype) if phase.noisy else jnp.zeros((2, 1), dtype)
    spawn = draws.spawn.T.astype(dtype) if phase.respawn else jnp.zeros((3, 1), dtype)
    given = dict(layout=retina_layout(config, dtype), params=params_vector, task=task_vector, u=draws.u.astype(dtype),
                 z=z, spawn=spawn, **lane._asdict(), **{f"in_{f}": v for f, v in packed._asdict().items()})
    inputs = tuple(name for name in _INPUTS if given[name] is not None)
    state_fields = tuple(f for f, v in packed._asdict().items() if v is not None)
    outputs = tuple(f"out_{f}" for f in state_fields) + ("counts", "selections")
    out_shape = (*(jax.ShapeDtypeStruct(getattr(packed, f).shape, getattr(packed, f).dtype) for f in state_fields),
                 jax.ShapeDtypeStruct((3,), jnp.int32), jax.ShapeDtypeStruct((kp,), jnp.int32))
    call = pl.pallas_call(
        _make_kernel(config, phase, phase_steps, num_steps, num_experts, model, inputs, outputs),
        out_shape=out_shape,
        interpret=_interpret() if interpret is None else interpret,
        # One warp per lane: every reduction stays within the warp.
        compiler_params=pltriton.CompilerParams(num_warps=1, num_stages=1),
        name="imrl_steps",
    )
    *state, counts, selections = call(*(given[name] for name in inputs))
    return Packed(**dict(zip(state_fields, state))), counts, selections


def draw_range(key: jax.Array, start, num_steps: int, block_steps: int, noisy: bool, spawn: int = 0) -> Draws:
    """The draws of steps start .. start + num_steps - 1 of a phase (the XLA program's stream)."""
    num_blocks = -(-num_steps // block_steps) + 1
    first = start // block_steps
    blocks = jax.vmap(lambda b: draw_block(key, first + b, block_steps, noisy, spawn))(jnp.arange(num_blocks))
    flat = jax.tree.map(lambda x: x.reshape((-1,) + x.shape[2:]), blocks)
    offset = start - first * block_steps
    return jax.tree.map(lambda x: jax.lax.dynamic_slice_in_dim(x, offset, num_steps), flat)


#: The fields of a Phase the kernel implements; a phase that sets any other (a later rule) is refused.
SUPPORTED = ("experts_learn", "selector_learns", "intrinsic", "has_target", "noisy", "respawn", "progress",
             "evaluation")


def check_supported(phase: Phase) -> None:
    """Refuse a phase whose rules the kernel does not implement (ConfigError naming the field)."""
    default = Phase(*(False,) * 5)
    for name in Phase._fields:
        if name not in SUPPORTED and getattr(phase, name) != getattr(default, name):
            raise ConfigError(f"step_kernel: the pallas kernel does not implement the phase option {name}="
                              f"{getattr(phase, name)!r}; use step_kernel=xla")


def unsupported(config: Config) -> str | None:
    """Why the kernel cannot live ``config``'s condition (one line), or None when it can."""
    if config.world != "arena":  # the kernel's loop is the arena's step
        return (f"step_kernel: the pallas kernel does not implement world {config.world} (the arena's only); use "
                f"step_kernel=xla")
    try:
        if config.spec.has_childhood:
            check_supported(childhood_phase(config))
        check_supported(config.spec.adult)
    except ConfigError as error:
        return str(error)
    return None


def run_phase(key: jax.Array, config: Config, phase: Phase, params: LearningParams, task: TaskSpec,
              state: State, num_steps: int, phase_steps: int | None = None,
              num_bins: int | None = None, interpret: bool | None = None) -> tuple[State, Curves]:
    """:func:`imrl_jax.agent.lifetime.run_phase`, each bin one kernel call (``interpret``: default off a GPU)."""
    if config.world != "arena":
        raise ConfigError(unsupported(config), "step_kernel")
    check_supported(phase)
    phase_steps = num_steps if phase_steps is None else phase_steps
    num_bins = config.num_bins if num_bins is None else num_bins
    steps_per_bin = bin_steps(num_steps, num_bins)
    num_experts = state.agent.selector_actor.shape[0]
    # As lifetime.step: an individual with learning values of its own learns with them; an evolved childhood's
    # length stops its learning and noise.
    params = phase_params(phase, params if state.agent.params is None else state.agent.params)
    length = state.agent.childhood_length if phase.intrinsic else None
    lane = fixed(state.agent, config)

    def one_bin(packed, _):
        draws = draw_range(key, packed.ints[T_SLOT], steps_per_bin, config.draw_block, phase.noisy,
                           spawn_draws(config, phase))
        packed, counts, selections = run_bin(config, phase, params, task, phase_steps, draws, packed, num_experts,
                                             interpret, lane, length)
        return packed, Curves(counts[0], counts[1], selections[:num_experts], counts[2] if phase.respawn else None)

    packed, curves = jax.lax.scan(one_bin, pack(state, config), None, length=num_bins)
    # The block of the last step, as the XLA program leaves it.
    block = draw_block(key, (packed.ints[T_SLOT] - 1) // config.draw_block, config.draw_block, phase.noisy,
                       spawn_draws(config, phase))
    return unpack(packed, state, block, config), curves
