"""The control cycle of section 2 (MODEL.md "Acting", "Learning") as one GPU kernel per bin of steps.

:func:`run_phase` computes what :func:`imrl_jax.agent.lifetime.run_phase` computes, with the
same signature and results, but each bin of steps of a lane is one Pallas (Triton) kernel
whose loop keeps the lane's weights, traces and pose in registers. On a GPU the XLA
program runs each step as dozens of small kernels, one after the other, so a step costs
their launches whatever the number of lanes; here a step is one iteration of a warp's
loop. The random numbers are the same stream as the XLA program's, drawn by XLA for a
bin at a time and read by the kernel.

Selected with ``Config.step_kernel = "pallas"``. Off a GPU the kernel runs in Pallas's
interpreter (slow; for tests): float64 lives then agree with the XLA program to rounding.
Each lane is one kernel instance; ``vmap`` (over tasks, individuals and seeds) makes the
grid. Vectors are padded to powers of two (Triton's rule): experts K to Kp, x~ (n+1) to N.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from imrl_jax.agent import learning
from imrl_jax.world.arena import advance, floor_colour_xy, on_wall, spawn_pose, trial_ends, turn
from imrl_jax.config import Config, ConfigError, LearningParams
from imrl_jax.agent.learning import ascend, ascend_row, selector_features, td_error, unit_features
from imrl_jax.agent.networks import Agent, explore, internal_reward, pick, select
from imrl_jax.conditions import Phase
from imrl_jax.genome import PARTS, GenomePart, get_part
from imrl_jax.world.env import EnvState, TaskSpec
from imrl_jax.agent.state import (Curves, Draws, Previous, State, Traces, bin_steps, childhood_phase, draw_block,
                                  phase_params, spawn_draws)

# Slots of the per-lane scalar vectors.
_X, _Y, _HEADING, _COS, _SIN, _A0, _A1, _O0, _O1 = range(9)  # floats
_K, _VALID, _TERMINAL, _TRIAL_STEP, _T, _EXPERTS_ENDED, _SELECTOR_ENDED, _PINNED = range(8)  # int32
_NUM_FLOATS, _NUM_INTS = 16, 8
# Rows of the packed weights and traces.
_REINFORCER, _ACTOR0, _ACTOR1, _EVALUATOR, _SELECTOR = range(5)
_TRACE_ACTOR0, _TRACE_ACTOR1, _TRACE_EVALUATOR, _TRACE_CRITIC = range(4)


class Packed(NamedTuple):
    """One lane's phase state in the kernel's padded layout (K -> Kp rows, n+1 -> N columns)."""

    weights: jnp.ndarray  # (5, Kp, N): reinforcer, actor unit 0, actor unit 1, evaluator, selector actor
    critic: jnp.ndarray  # (N,): selector critic
    traces: jnp.ndarray  # (4, N): actor unit 0, actor unit 1, evaluator, selector critic
    selector_trace: jnp.ndarray  # (Kp, N)
    xbs: jnp.ndarray  # (2, N): x~_{t-1}, x~_{t-2}
    selection: jnp.ndarray  # (Kp,): s_{t-1} (0 in padded rows)
    floats: jnp.ndarray  # (16,): pose, (cos, sin), a_{t-1}, o_{t-1}
    ints: jnp.ndarray  # (8,): k, valid, terminal, trial step, t, ended flags, steps on a wall
    baseline: jnp.ndarray  # (Kp,): each expert's running mean surprise (0 in padded rows)


def _pow2(n: int) -> int:
    return 1 << max(0, (n - 1).bit_length())


def _pad(x, shape):
    return jnp.pad(x, [(0, s - d) for s, d in zip(shape, x.shape)])


def pack(state: State) -> Packed:
    """The kernel's layout of a phase state."""
    agent, traces, prev = state.agent, state.traces, state.prev
    k, n = agent.selector_actor.shape
    kp, big_n = _pow2(k), _pow2(n)
    rows = lambda m: _pad(m, (kp, big_n))  # noqa: E731
    vec = lambda v: _pad(v, (big_n,))  # noqa: E731
    dtype = agent.actor.dtype
    now = state.t % 2
    xbs = jnp.stack([state.xbs[1 - now], state.xbs[now]])  # x~_{t-1}, x~_{t-2}
    robot = state.world  # the arena's EnvState: the kernel lives the arena only
    floats = jnp.stack([robot.pose.pos[0], robot.pose.pos[1], robot.pose.heading, *robot.direction,
                        *prev.action, *prev.output]).astype(dtype)
    ints = jnp.stack([prev.k, prev.valid, prev.terminal, robot.trial_step, state.t, traces.experts_ended,
                      traces.selector_ended, robot.pinned]).astype(jnp.int32)
    return Packed(
        weights=jnp.stack([rows(agent.reinforcer), rows(agent.actor[:, 0]), rows(agent.actor[:, 1]),
                           rows(agent.evaluator), rows(agent.selector_actor)]),
        critic=vec(agent.selector_critic),
        traces=jnp.stack([vec(traces.actor[0]), vec(traces.actor[1]), vec(traces.evaluator),
                          vec(traces.selector_critic)]),
        selector_trace=rows(traces.selector_actor),
        xbs=jax.vmap(vec)(xbs),
        selection=_pad(prev.selection, (kp,)),
        floats=_pad(floats, (_NUM_FLOATS,)),
        ints=_pad(ints, (_NUM_INTS,)),
        baseline=_pad(state.baseline, (kp,)),
    )


def unpack(packed: Packed, like: State, block: Draws) -> State:
    """The phase state that ``packed`` holds (``like`` gives the shapes; ``block`` the current draws)."""
    k, n = like.agent.selector_actor.shape
    w, f, i = packed.weights, packed.floats, packed.ints
    t = i[_T]
    now = t % 2
    # x~_t goes in row t % 2: at step t the last observation x~_{t-1} sits in row 1 - t % 2.
    xbs = jnp.where(now == 0, packed.xbs[::-1], packed.xbs)[:, :n]
    agent = Agent(
        reinforcer=w[_REINFORCER, :k, :n],
        actor=jnp.stack([w[_ACTOR0, :k, :n], w[_ACTOR1, :k, :n]], axis=1),
        evaluator=w[_EVALUATOR, :k, :n],
        selector_actor=w[_SELECTOR, :k, :n],
        selector_critic=packed.critic[:n],
    )
    traces = Traces(
        actor=packed.traces[jnp.array([_TRACE_ACTOR0, _TRACE_ACTOR1]), :n],
        evaluator=packed.traces[_TRACE_EVALUATOR, :n],
        selector_actor=packed.selector_trace[:k, :n],
        selector_critic=packed.traces[_TRACE_CRITIC, :n],
        experts_ended=i[_EXPERTS_ENDED] != 0,
        selector_ended=i[_SELECTOR_ENDED] != 0,
    )
    prev = Previous(k=i[_K], action=f[jnp.array([_A0, _A1])], output=f[jnp.array([_O0, _O1])],
                    selection=packed.selection[:k], valid=i[_VALID] != 0, terminal=i[_TERMINAL] != 0)
    pose = like.world.pose._replace(pos=f[jnp.array([_X, _Y])], heading=f[_HEADING])
    robot = EnvState(pose, f[jnp.array([_COS, _SIN])], i[_TRIAL_STEP], i[_PINNED])
    return State(agent, traces, robot, xbs, prev, t, block, packed.baseline[:k])


def retina_layout(config: Config, dtype=jnp.float32) -> jnp.ndarray:
    """(4, N): for each entry of x~, its point's forward and lateral offset, its colour (3: none), its bias."""
    forward, lateral = np.meshgrid(config.retina_forward, config.retina_lateral, indexing="ij")
    n = config.num_inputs
    big_n = _pow2(n + 1)
    layout = np.zeros((4, big_n))
    layout[0, :n] = np.repeat(forward.ravel(), 3)
    layout[1, :n] = np.repeat(lateral.ravel(), 3)
    layout[2] = 3.0
    layout[2, :n] = np.tile(np.arange(3.0), n // 3)
    layout[3, n] = 1.0
    return jnp.asarray(layout, dtype)


def round_even(x):
    """Round half to even, from floor (which Triton has; it has no round-half-even)."""
    # x - floor(x) is exact in floating point, so the tie test is exact.
    low = jnp.floor(x)
    frac = x - low
    odd = low - 2.0 * jnp.floor(0.5 * low)
    return jnp.where(frac > 0.5, low + 1.0, jnp.where(frac < 0.5, low, low + odd))


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


def _make_kernel(config: Config, phase: Phase, phase_steps: int, num_steps: int, num_experts: int):
    """The kernel body: ``num_steps`` steps of one lane (refs: inputs, then outputs).

    The step is lifetime.step's control cycle on the lane's registers; the rules it applies
    are the XLA program's functions (networks, learning, arena), written so that Triton
    lowers them (no gather, no scatter: rows are read and written through one-hot masks).
    """

    def kernel(layout_ref, params_ref, task_ref, u_ref, z_ref, spawn_ref, weights_ref, critic_ref, traces_ref,
               selector_trace_ref, xbs_ref, selection_ref, floats_ref, ints_ref, baseline_ref,
               weights_out, critic_out, traces_out, selector_trace_out, xbs_out, selection_out,
               floats_out, ints_out, baseline_out, counts_out, selections_out):
        dtype = weights_ref.dtype
        p = LearningParams(*(params_ref[j] for j in range(len(LearningParams._fields))))
        gamma, lam, noise_std = p.gamma, p.trace_lambda, p.noise_std
        eta_actor, eta_evaluator = p.eta_actor, p.eta_evaluator
        eta_selector_actor, eta_selector_critic = p.eta_selector_actor, p.eta_selector_critic
        progress_rate = p.progress_rate
        start_x, start_y, start_heading, target_x, target_y = (task_ref[j] for j in range(5))
        start_cos, start_sin = jnp.cos(start_heading), jnp.sin(start_heading)
        forward, lateral, colours, bias = (layout_ref[j] for j in range(4))
        kp = selection_ref.shape[0]
        rows = jax.lax.broadcasted_iota(jnp.int32, (kp,), 0)
        expert_rows = rows < num_experts
        zero = jnp.zeros((), dtype)

        def observe(x, y, c, s):
            colour = floor_colour_xy(config, x + forward * c - lateral * s, y + forward * s + lateral * c,
                                     round_even)
            return (colour.astype(dtype) == colours).astype(dtype) + bias

        def accumulate(trace, phi, learn, ended):
            return learning.accumulate(trace, phi, gamma, lam, learn, ended)

        def one_step(i, carry: _Carry) -> _Carry:
            reinforcer, actor0, actor1, evaluator, selector = carry.weights
            trace_actor0, trace_actor1, trace_evaluator, trace_critic = carry.traces
            x, y, heading, c, s, a0, a1, o0, o1 = carry.floats
            prev_k, valid, terminal, trial_step, t, experts_ended, selector_ended, pinned = carry.ints
            valid, terminal = valid != 0, terminal != 0
            critic, selector_trace, prev_xb = carry.critic, carry.selector_trace, carry.prev_xb
            baseline = carry.baseline

            # 1-2: observe, choose the expert.
            xb = observe(x, y, c, s)
            selection = jnp.where(expert_rows, jax.nn.sigmoid(_dot_rows(selector, xb)), 0.0)
            # One expert: k is 0, computed from the carry (Triton's lowering cannot return a constant from the loop).
            k = select(u_ref[i], selection, num_experts) if num_experts > 1 else jnp.minimum(prev_k, 0)
            same = k == prev_k
            ends = terminal | ~valid
            extrinsic = terminal.astype(dtype)
            held = rows == prev_k

            # 3: learn from the transition t-1 -> t.
            surprise = zero
            if phase.experts_learn:
                learn = valid & same
                if phase.intrinsic:
                    reward = internal_reward(pick(_dot_rows(reinforcer, xb), prev_k))
                else:
                    reward = extrinsic
                value_before = pick(_dot_rows(evaluator, prev_xb), prev_k)
                value_now = pick(_dot_rows(evaluator, xb), prev_k)
                surprise = td_error(reward, value_before, value_now, gamma, terminal)
                delta = jnp.where(learn, surprise, 0.0)
                ended = experts_ended != 0
                trace_evaluator = accumulate(trace_evaluator, prev_xb, learn, ended)
                trace_actor0 = accumulate(trace_actor0, unit_features(a0, o0, prev_xb), learn, ended)
                trace_actor1 = accumulate(trace_actor1, unit_features(a1, o1, prev_xb), learn, ended)
                row = held.astype(dtype)
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
                value_before = jnp.sum(critic * prev_xb)
                value_now = jnp.sum(critic * xb)
                delta = td_error(reward, value_before, value_now, gamma, terminal)
                delta = jnp.where(learn, delta, 0.0)
                ended = selector_ended != 0
                trace_critic = accumulate(trace_critic, prev_xb, learn, ended)
                phi = selector_features(prev_k, carry.selection, prev_xb)
                selector_trace = accumulate(selector_trace, phi, learn, ended)
                critic = ascend(critic, trace_critic, delta, eta_selector_critic)
                selector = ascend(selector, selector_trace, delta, eta_selector_actor)
                selector_ended = ends.astype(jnp.int32)

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
            )

        carry = _Carry(
            weights=tuple(weights_ref[j] for j in range(5)),
            critic=critic_ref[...],
            traces=tuple(traces_ref[j] for j in range(4)),
            selector_trace=selector_trace_ref[...],
            prev_xb=xbs_ref[0],
            before_xb=xbs_ref[1],
            selection=selection_ref[...],
            floats=tuple(floats_ref[j] for j in range(9)),
            ints=tuple(ints_ref[j] for j in range(8)),
            baseline=baseline_ref[...],
            reaches=jnp.int32(0),
            timeouts=jnp.int32(0),
            respawns=jnp.int32(0),
            selections=jnp.zeros((kp,), jnp.int32),
        )
        carry = jax.lax.fori_loop(0, num_steps, one_step, carry)
        for j in range(5):
            weights_out[j] = carry.weights[j]
        critic_out[...] = carry.critic
        for j in range(4):
            traces_out[j] = carry.traces[j]
        selector_trace_out[...] = carry.selector_trace
        xbs_out[0] = carry.prev_xb
        xbs_out[1] = carry.before_xb
        selection_out[...] = carry.selection
        for j, value in enumerate(carry.floats):
            floats_out[j] = value
        for j in range(9, _NUM_FLOATS):
            floats_out[j] = zero
        for j, value in enumerate(carry.ints):
            ints_out[j] = value
        baseline_out[...] = carry.baseline
        counts_out[0] = carry.reaches
        counts_out[1] = carry.timeouts
        counts_out[2] = carry.respawns
        selections_out[...] = carry.selections

    return kernel


def _interpret() -> bool:
    """Run the kernel in Pallas's interpreter off a GPU (Triton kernels need one)."""
    return jax.default_backend() != "gpu"


def run_bin(config: Config, phase: Phase, params: LearningParams, task: TaskSpec, phase_steps: int,
            draws: Draws, packed: Packed, num_experts: int, interpret: bool | None = None):
    """Steps ``len(draws.u)`` of one lane from ``packed``: the new state and (reaches, timeouts), selections."""
    from jax.experimental import pallas as pl
    from jax.experimental.pallas import triton as pltriton

    dtype = packed.weights.dtype
    num_steps = draws.u.shape[0]
    params_vector = jnp.stack([jnp.asarray(p, dtype) for p in params])
    task_vector = jnp.stack([task.start.pos[0], task.start.pos[1], task.start.heading,
                             task.target[0], task.target[1]]).astype(dtype)
    kp = packed.selection.shape[0]
    out_shape = (*(jax.ShapeDtypeStruct(x.shape, x.dtype) for x in packed),
                 jax.ShapeDtypeStruct((3,), jnp.int32), jax.ShapeDtypeStruct((kp,), jnp.int32))
    call = pl.pallas_call(
        _make_kernel(config, phase, phase_steps, num_steps, num_experts),
        out_shape=out_shape,
        interpret=_interpret() if interpret is None else interpret,
        # One warp per lane: every reduction stays within the warp.
        compiler_params=pltriton.CompilerParams(num_warps=1, num_stages=1),
        name="imrl_steps",
    )
    # Without noise the kernel reads no z: a stand-in spares the lanes x steps zeros.
    z = draws.z.T.astype(dtype) if phase.noisy else jnp.zeros((2, 1), dtype)
    spawn = draws.spawn.T.astype(dtype) if phase.respawn else jnp.zeros((3, 1), dtype)
    *state, counts, selections = call(retina_layout(config, dtype), params_vector, task_vector,
                                      draws.u.astype(dtype), z, spawn, *packed)
    return Packed(*state), counts, selections


def draw_range(key: jax.Array, start, num_steps: int, block_steps: int, noisy: bool, spawn: int = 0) -> Draws:
    """The draws of steps start .. start + num_steps - 1 of a phase (the XLA program's stream)."""
    num_blocks = -(-num_steps // block_steps) + 1
    first = start // block_steps
    blocks = jax.vmap(lambda b: draw_block(key, first + b, block_steps, noisy, spawn))(jnp.arange(num_blocks))
    flat = jax.tree.map(lambda x: x.reshape((-1,) + x.shape[2:]), blocks)
    offset = start - first * block_steps
    return jax.tree.map(lambda x: jax.lax.dynamic_slice_in_dim(x, offset, num_steps), flat)


#: The fields of a Phase the kernel implements; a phase that sets any other (a later condition's rule) is refused.
SUPPORTED = ("experts_learn", "selector_learns", "intrinsic", "has_target", "noisy", "respawn", "progress")


def check_supported(phase: Phase) -> None:
    """Refuse a phase whose rules the kernel does not implement (ConfigError naming the field)."""
    default = Phase(*(False,) * 5)
    for name in Phase._fields:
        if name not in SUPPORTED and getattr(phase, name) != getattr(default, name):
            raise ConfigError(f"step_kernel: the pallas kernel does not implement the phase option {name}="
                              f"{getattr(phase, name)!r}; use step_kernel=xla")


def refusal(part: GenomePart) -> str:
    """The one line refusing a genome part the kernel does not implement (``GenomePart.kernel`` False)."""
    return f"step_kernel: the pallas kernel does not implement {part.what} (genome part {part.name!r}); use step_kernel=xla"


def check_parts(genome: tuple[str, ...]) -> None:
    """Refuse a genome with a part the kernel does not implement (ConfigError naming it)."""
    for name in genome:
        if not get_part(name).kernel:
            raise ConfigError(refusal(get_part(name)))


def check_agent(agent: Agent) -> None:
    """Refuse an agent holding what only a part the kernel does not implement sets (ConfigError naming it)."""
    for part in PARTS.values():
        if not part.kernel and part.field is not None and getattr(agent, part.field) is not None:
            raise ConfigError(refusal(part))


def unsupported(config: Config) -> str | None:
    """Why the kernel cannot live ``config``'s condition (one line), or None when it can."""
    if config.world != "arena":  # the kernel's loop is the arena's step
        return (f"step_kernel: the pallas kernel does not implement world {config.world} (the arena's only); use "
                f"step_kernel=xla")
    try:
        if config.spec.has_childhood:
            check_supported(childhood_phase(config))
        check_supported(config.spec.adult)
        check_parts(config.spec.genome)
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
    check_parts(config.spec.genome)
    check_agent(state.agent)
    phase_steps = num_steps if phase_steps is None else phase_steps
    num_bins = config.num_bins if num_bins is None else num_bins
    steps_per_bin = bin_steps(num_steps, num_bins)
    num_experts = state.agent.selector_actor.shape[0]
    params = phase_params(phase, params)

    def one_bin(packed, _):
        draws = draw_range(key, packed.ints[_T], steps_per_bin, config.draw_block, phase.noisy,
                           spawn_draws(config, phase))
        packed, counts, selections = run_bin(config, phase, params, task, phase_steps, draws, packed, num_experts,
                                             interpret)
        return packed, Curves(counts[0], counts[1], selections[:num_experts], counts[2] if phase.respawn else None)

    packed, curves = jax.lax.scan(one_bin, pack(state), None, length=num_bins)
    # The block of the last step, as the XLA program leaves it.
    block = draw_block(key, (packed.ints[_T] - 1) // config.draw_block, config.draw_block, phase.noisy,
                       spawn_draws(config, phase))
    return unpack(packed, state, block), curves
