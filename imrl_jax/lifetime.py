"""Lifetimes of section 2 and MODEL.md "Acting", "Learning", "Life": childhood and adulthood.

One :func:`step` implements a control cycle for every phase; a static :class:`Phase` says
which networks learn and from which reward. A phase is a ``lax.scan`` over bins of a scan
over steps, returning only per-bin counts, so memory does not grow with its length.
:func:`live` is one individual's whole life: LE-LS childhood as one continuous scan, then
the tasks vmapped from the same frozen experts. :func:`simulate` records a per-step
trajectory of one individual, for plots and for the reference tests.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import jax
import jax.numpy as jnp

from imrl_jax.arena import Pose, heading_vector, move, task_arrays
from imrl_jax.config import Config, LearningParams
from imrl_jax.learning import (accumulate, actor_features, ascend, ascend_row, pick_row, selector_features,
                               td_error)
from imrl_jax.networks import Agent, act, decode, evaluate_both, reinforce, with_bias, zero_agent
from imrl_jax.retina import observe


class Phase(NamedTuple):
    """Static description of a phase: who learns, from what, and whether there is a target."""

    experts_learn: bool
    selector_learns: bool
    intrinsic: bool  # rewards: own reinforcer for experts, expert surprise for the selector
    has_target: bool
    noisy: bool  # actions get Gaussian noise annealed linearly to 0 over the phase
    respawn: bool = False  # a robot on a wall for config.wall_respawn_steps steps gets a random pose
    progress: bool = False  # childhood selector: surprise minus the expert's running mean surprise


CHILDHOOD = Phase(experts_learn=True, selector_learns=True, intrinsic=True, has_target=False, noisy=True)
ADULT_LEARNING_SELECTOR = Phase(False, True, False, True, False)
ADULT_EVOLVED_SELECTOR = Phase(False, False, False, True, False)
ADULT_SINGLE_EXPERT = Phase(True, False, False, True, True)


def childhood_phase(config: Config) -> Phase:
    """The childhood phase with the config's options (docs/CHILDHOOD.md; the paper's by default)."""
    return CHILDHOOD._replace(respawn=config.childhood_walls == "respawn",
                              progress=config.childhood_selector_reward == "progress")


def phase_params(phase: Phase, params: LearningParams) -> LearningParams:
    """The learning values a phase uses: childhood (intrinsic rewards) has its own."""
    return params.in_childhood() if phase.intrinsic else params


def adult_phase(condition: str) -> Phase:
    """The adulthood phase of a condition (MODEL.md "Conditions")."""
    return {"LE-LS": ADULT_LEARNING_SELECTOR, "EE-LS": ADULT_LEARNING_SELECTOR,
            "EE-ES": ADULT_EVOLVED_SELECTOR, "SLE": ADULT_SINGLE_EXPERT}[condition]


class Draws(NamedTuple):
    """The random numbers of one step: expert choice u ~ U[0, 1), action noise z ~ N(0, I2),
    and (phases with respawns only) a random pose's (x, y, heading) as U[0, 1)^3."""

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
    pose: Pose
    # (cos, sin) of pose.heading. Carried, so that the retina's kernels read it rather
    # than compute it again for each of their sample points.
    direction: jnp.ndarray
    xbs: jnp.ndarray  # (2, n+1): x~_t in row t % 2 (written by the step), x~_{t-1} in the other
    prev: Previous
    trial_step: jnp.ndarray  # steps since the current trial started
    t: jnp.ndarray  # step within the phase
    block: Draws  # the random numbers of the current block of steps
    pinned: jnp.ndarray  # steps on a wall in a row (childhood with respawns)
    baseline: jnp.ndarray  # (K,): each expert's running mean surprise (childhood "progress" reward)


class TaskSpec(NamedTuple):
    """Where a phase starts trials and where its target is (unused without a target)."""

    start: Pose
    target: jnp.ndarray


class StepRecord(NamedTuple):
    """What one step produced: the pose after it, the expert in control, its events."""

    pose: Pose
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


class LifetimeResult(NamedTuple):
    """What one life returns: fitness, per-task reaches and binned curves, final weights."""

    fitness: jnp.ndarray  # (): mean task performance
    performance: jnp.ndarray  # (tasks,): reaches / theoretical maximum
    reaches: jnp.ndarray  # (tasks,)
    timeouts: jnp.ndarray  # (tasks,)
    reward_curve: jnp.ndarray  # (tasks, bins): reaches per bin
    adult_selections: jnp.ndarray  # (tasks, bins, K)
    childhood_selections: jnp.ndarray  # (bins, K): zeros without childhood
    agent: Agent  # after childhood (the experts adulthood starts from)
    adult_agents: Agent  # (tasks, ...): the weights at the end of each task


class LifetimeKeys(NamedTuple):
    """The keys of one life, one per consumer."""

    pose: jax.Array  # childhood start pose
    childhood: jax.Array
    tasks: jax.Array  # (tasks,)


def draw_block(key: jax.Array, block, block_steps: int, noisy: bool = True, spawn: bool = False) -> Draws:
    """The draws of steps block*B .. block*B + B-1 of a phase whose key is ``key``.

    Random numbers are made ``block_steps`` at a time (one vectorised call instead of
    one per step). Phases without action noise get zeros for z; the expert-choice
    numbers are the same either way, and so are both with or without ``spawn`` draws.
    """
    key_block = jax.random.fold_in(key, block)
    key_u, key_z = jax.random.split(key_block)
    u = jax.random.uniform(key_u, (block_steps,))
    z = jax.random.normal(key_z, (block_steps, 2)) if noisy else jnp.zeros((block_steps, 2), u.dtype)
    spawned = jax.random.uniform(jax.random.fold_in(key_block, 2), (block_steps, 3)) if spawn else None
    return Draws(u, z, spawned)


def draw_many(key: jax.Array, num_steps: int, block_steps: int, spawn: bool = False) -> Draws:
    """The draws of steps 0 .. num_steps-1 (for the reference and tests)."""
    num_blocks = -(-num_steps // block_steps)
    blocks = jax.vmap(draw_block, (None, 0, None, None, None))(key, jnp.arange(num_blocks), block_steps, True,
                                                               spawn)
    return jax.tree.map(lambda x: x.reshape((-1,) + x.shape[2:])[:num_steps], blocks)


def select(u, selection):
    """Expert k with probability s_k / sum(s): the first k with u * sum(s) < cumsum(s)[k]."""
    cumulative = jnp.cumsum(selection)
    return jnp.sum(cumulative[:-1] <= u * cumulative[-1]).astype(jnp.int32)


def lifetime_keys(key: jax.Array, num_tasks: int) -> LifetimeKeys:
    """Split a life's key once per consumer."""
    key_pose, key_child, key_adult = jax.random.split(key, 3)
    return LifetimeKeys(key_pose, key_child, jax.random.split(key_adult, num_tasks))


def random_pose(key: jax.Array, config: Config, dtype=jnp.float32) -> Pose:
    """Uniform position in [r, size - r]^2 and uniform heading (childhood start)."""
    key_pos, key_heading = jax.random.split(key)
    r = config.robot_radius
    pos = jax.random.uniform(key_pos, (2,), dtype, r, config.arena_size - r)
    heading = jax.random.uniform(key_heading, (), dtype, 0.0, 2.0 * math.pi)
    return Pose(pos, heading)


def init_state(config: Config, agent: Agent, pose: Pose) -> State:
    """A phase's first carry: zero traces, nothing to learn from, step 0."""
    dtype = agent.actor.dtype
    k, n = agent.selector_actor.shape
    zeros = lambda *shape: jnp.zeros(shape, dtype)  # noqa: E731
    return State(
        agent=agent,
        traces=Traces(zeros(2, n), zeros(n), zeros(k, n), zeros(n), jnp.bool_(False), jnp.bool_(False)),
        pose=pose,
        direction=heading_vector(pose.heading),
        xbs=zeros(2, n),
        prev=Previous(jnp.int32(0), zeros(2), zeros(2), zeros(k), jnp.bool_(False), jnp.bool_(False)),
        trial_step=jnp.int32(0),
        t=jnp.int32(0),
        block=Draws(zeros(config.draw_block), zeros(config.draw_block, 2)),
        pinned=jnp.int32(0),
        baseline=zeros(k),
    )


def for_phase(config: Config, phase: Phase, state: State) -> State:
    """``state`` whose carried draws have the phase's structure (respawn draws only where used)."""
    if phase.respawn and state.block.spawn is None:
        return state._replace(block=state.block._replace(spawn=jnp.zeros((config.draw_block, 3),
                                                                          state.block.u.dtype)))
    if not phase.respawn and state.block.spawn is not None:
        return state._replace(block=state.block._replace(spawn=None))
    return state


def _set_row(matrix, k, row):
    """matrix with row k replaced."""
    return jax.lax.dynamic_update_index_in_dim(matrix, row, k, 0)


def _row(matrix, k):
    """Row k of matrix."""
    return jax.lax.dynamic_index_in_dim(matrix, k, 0, keepdims=False)


def _turns(values, now):
    """(values[1 - now], values[now]): the evaluations of x~_{t-1} and x~_t from those of xbs's rows."""
    return _row(values, 1 - now), _row(values, now)


def step(config: Config, phase: Phase, params: LearningParams, task: TaskSpec, phase_steps: int,
         key: jax.Array, state: State) -> tuple[State, StepRecord]:
    """One control cycle (MODEL.md "Acting, each time step t of a phase")."""
    agent, traces, prev = state.agent, state.traces, state.prev
    # t is the same for every lane (it is not batched under vmap), so this cond really
    # skips the draw on the steps between blocks.
    offset = state.t % config.draw_block
    block = jax.lax.cond(offset == 0,
                         lambda: draw_block(key, state.t // config.draw_block, config.draw_block, phase.noisy,
                                            phase.respawn),
                         lambda: state.block)
    draws = jax.tree.map(lambda x: x[offset], block)
    params = phase_params(phase, params)
    gamma, lam = params.gamma, params.trace_lambda

    # 1-2: observe, choose the expert.
    # x~_t and x~_{t-1} take turns in the rows of xbs, so that no step copies one into the
    # other. x~_t overwrites x~_{t-2}, which nothing reads, so XLA writes it in place; and
    # computed here from the carried pose, not at the end of the previous step, its kernels
    # read the pose instead of computing the move again for every sample point.
    now = state.t % 2
    xbs = _set_row(state.xbs, now, with_bias(observe(config, state.pose, state.direction)))
    xb, prev_xb = _row(xbs, now), _row(xbs, 1 - now)
    selection = act(agent.selector_actor, xb)
    k = select(draws.u, selection) if selection.shape[0] > 1 else jnp.int32(0)
    same = k == prev.k
    # A transition cut by the timeout (or a phase start) is not learned and ends the traces.
    ends = prev.terminal | ~prev.valid
    extrinsic = prev.terminal.astype(xb.dtype)  # the only extrinsic reward: 1 on reaching the target

    # 3: learn from the transition t-1 -> t.
    surprise = jnp.zeros((), xb.dtype)
    if phase.experts_learn:
        learn = prev.valid & same
        kp = prev.k
        held = jax.nn.one_hot(kp, agent.evaluator.shape[0], dtype=xb.dtype)  # the expert that held control
        # Every reinforcer, and every evaluator, at once: a matrix-vector product is one
        # fast kernel (see evaluate_both), where taking row kp first is a slow gather.
        reward = reinforce(agent.reinforcer, xb)[kp] if phase.intrinsic else extrinsic
        value_before, value_now = (agent.evaluator @ prev_xb)[kp], (agent.evaluator @ xb)[kp]
        surprise = td_error(reward, value_before, value_now, gamma, prev.terminal)
        delta = jnp.where(learn, surprise, 0.0)
        trace_v = accumulate(traces.evaluator, prev_xb, gamma, lam, learn, traces.experts_ended)
        trace_w = accumulate(traces.actor, actor_features(prev.action, prev.output, prev_xb),
                             gamma, lam, learn, traces.experts_ended)
        agent = agent._replace(evaluator=ascend_row(agent.evaluator, held, trace_v, delta, params.eta_evaluator),
                               actor=ascend_row(agent.actor, held, trace_w, delta, params.eta_actor))
        # The expert losing control (or the trial ending) drops its traces.
        traces = traces._replace(evaluator=trace_v, actor=trace_w, experts_ended=~same | ends)
    baseline = state.baseline
    if phase.selector_learns:
        if phase.intrinsic:  # childhood: the surprise of the expert that kept control
            learn, reward = prev.valid & same, surprise
            if phase.progress:
                # Learning progress, roughly: the surprise beyond what this expert usually
                # gets, b_k <- b_k + rho (delta_k - b_k) on the steps it learns, so that an
                # expert whose reinforcer merely pays more everywhere is not favoured.
                held = jax.nn.one_hot(prev.k, baseline.shape[0], dtype=xb.dtype) * learn
                before = jnp.sum(held * baseline)
                reward = surprise - before
                baseline = baseline + params.progress_rate * held * (surprise - baseline)
        else:
            # k >= 0 always holds; it orders this update after the choice of k, which reads
            # the same selector weights, so that XLA can update them in place, not in a copy.
            learn, reward = prev.valid & (k >= 0), extrinsic
        u_weights, s_weights = agent.selector_critic, agent.selector_actor
        delta = td_error(reward, *_turns(evaluate_both(u_weights, xbs), now), gamma, prev.terminal)
        delta = jnp.where(learn, delta, 0.0)
        trace_u = accumulate(traces.selector_critic, prev_xb, gamma, lam, learn, traces.selector_ended)
        trace_s = accumulate(traces.selector_actor, selector_features(prev.k, prev.selection, prev_xb),
                             gamma, lam, learn, traces.selector_ended)
        agent = agent._replace(
            selector_critic=ascend(u_weights, trace_u, delta, params.eta_selector_critic),
            selector_actor=ascend(s_weights, trace_s, delta, params.eta_selector_actor))
        traces = traces._replace(selector_critic=trace_u, selector_actor=trace_s, selector_ended=ends)

    # 4: act.
    output = act(pick_row(agent.actor, k), xb)
    if phase.noisy:
        sigma = params.noise_std * jnp.maximum(1.0 - state.t.astype(xb.dtype) / phase_steps, 0.0)
        action = jnp.clip(output + sigma * draws.z, 0.0, 1.0)
    else:
        action = output

    # 5: move; reaching the target or the timeout starts a new trial.
    pose = move(config, state.pose, action)
    trial_step = state.trial_step + 1
    pinned, respawned = state.pinned, jnp.bool_(False)
    if phase.respawn:
        # On a wall: the clamp holds the centre at the border. After wall_respawn_steps such
        # steps in a row the robot is put at a random pose; like a timeout, nothing learns
        # from that transition.
        r, size = config.robot_radius, config.arena_size
        on_wall = jnp.any((pose.pos <= r) | (pose.pos >= size - r))
        pinned = jnp.where(on_wall, pinned + 1, 0)
        respawned = pinned >= config.wall_respawn_steps
        spawn = Pose(r + (size - 2.0 * r) * draws.spawn[:2], 2.0 * math.pi * draws.spawn[2])
        pose = jax.tree.map(lambda fresh, now: jnp.where(respawned, fresh, now), spawn, pose)
        pinned = jnp.where(respawned, 0, pinned)
    if phase.has_target:
        reached = jnp.sum((pose.pos - task.target) ** 2) <= config.target_radius ** 2
        timeout = ~reached & (trial_step >= config.trial_timeout)
        reset = reached | timeout
        pose = jax.tree.map(lambda start, now: jnp.where(reset, start, now), task.start, pose)
        trial_step = jnp.where(reset, 0, trial_step)
    else:
        reached = timeout = jnp.bool_(False)

    prev = Previous(k, action, output, selection, ~(timeout | respawned), reached)
    state = State(agent, traces, pose, heading_vector(pose.heading), xbs, prev, trial_step, state.t + 1, block,
                  pinned, baseline)
    return state, StepRecord(pose, k, reached, timeout, respawned)


def run_phase(key: jax.Array, config: Config, phase: Phase, params: LearningParams, task: TaskSpec,
              state: State, num_steps: int, phase_steps: int | None = None,
              num_bins: int | None = None) -> tuple[State, Curves]:
    """Run ``num_steps`` steps of a phase as a scan over bins of steps (``config.num_bins`` by default).

    A phase may run in pieces: give each piece the whole phase's length as ``phase_steps``
    (the noise anneals to 0 over it, then stays 0) and the carried state; the pieces together are the same
    computation as one call. With ``config.step_kernel == "pallas"`` each bin is one
    kernel (:func:`imrl_jax.kernel.run_phase`).
    """
    if config.step_kernel == "pallas":
        from imrl_jax import kernel  # imports this module

        return kernel.run_phase(key, config, phase, params, task, state, num_steps, phase_steps, num_bins)
    phase_steps = num_steps if phase_steps is None else phase_steps
    num_bins = config.num_bins if num_bins is None else num_bins
    bin_steps = num_steps // num_bins
    state = for_phase(config, phase, state)
    num_experts = state.agent.selector_actor.shape[0]

    def one_step(carry, _):
        state, counts = carry
        state, record = step(config, phase, params, task, phase_steps, key, state)
        counts = Curves(counts.reaches + record.reached, counts.timeouts + record.timeout,
                        counts.selections + jax.nn.one_hot(record.k, num_experts, dtype=jnp.int32),
                        None if counts.respawns is None else counts.respawns + record.respawned)
        return (state, counts), None

    def one_bin(state, _):
        counts = Curves(jnp.int32(0), jnp.int32(0), jnp.zeros((num_experts,), jnp.int32),
                        jnp.int32(0) if phase.respawn else None)
        (state, counts), _ = jax.lax.scan(one_step, (state, counts), None, length=bin_steps,
                                          unroll=config.scan_unroll)
        return state, counts

    return jax.lax.scan(one_bin, state, None, length=num_bins)


def simulate(key: jax.Array, config: Config, phase: Phase, params: LearningParams, task: TaskSpec,
             state: State, num_steps: int, phase_steps: int | None = None) -> tuple[State, StepRecord]:
    """Run ``num_steps`` steps of one individual and record every step (plots, tests only)."""
    phase_steps = num_steps if phase_steps is None else phase_steps
    state = for_phase(config, phase, state)

    def one_step(state, _):
        return step(config, phase, params, task, phase_steps, key, state)

    return jax.lax.scan(one_step, state, None, length=num_steps)


def task_spec(config: Config, index, dtype=jnp.float32) -> TaskSpec:
    """The start pose and target of task ``index`` (an int or a traced index)."""
    starts, targets, _ = task_arrays(config, dtype)
    return TaskSpec(Pose(starts.pos[index], starts.heading[index]), targets[index])


def childhood_task(config: Config, dtype=jnp.float32) -> TaskSpec:
    """A placeholder task for childhood, which has no target."""
    return TaskSpec(Pose(jnp.zeros((2,), dtype), jnp.zeros((), dtype)), jnp.zeros((2,), dtype))


def adult_agent(config: Config, agent: Agent) -> Agent:
    """The agent a task starts with: selector reset to 0 (SLE: its expert too, paper)."""
    fresh = zero_agent(config, agent.actor.dtype)
    if config.condition == "SLE":
        return fresh
    if config.condition == "EE-ES":
        return agent  # nothing learns; the selector is evolved
    return agent._replace(selector_actor=fresh.selector_actor, selector_critic=fresh.selector_critic)


def grow_up(keys: LifetimeKeys, config: Config, params: LearningParams, genome: jnp.ndarray):
    """The experts adulthood starts from: the decoded genome after its childhood (LE-LS only).

    Returns the agent and the childhood's selections per bin (zeros without childhood).
    """
    agent = decode(config, genome)
    dtype = agent.actor.dtype
    childhood_selections = jnp.zeros((config.num_bins, agent.selector_actor.shape[0]), jnp.int32)
    if config.condition == "LE-LS":
        state = init_state(config, agent, random_pose(keys.pose, config, dtype))
        state, curves = run_phase(keys.childhood, config, childhood_phase(config), params, childhood_task(config, dtype),
                                  state, config.childhood_steps)
        agent, childhood_selections = state.agent, curves.selections
    return agent, childhood_selections


def task_start(config: Config, agent: Agent, index) -> State:
    """The first carry of task ``index`` for the experts ``agent`` (selector reset as the condition says)."""
    return init_state(config, adult_agent(config, agent), task_spec(config, index, agent.actor.dtype).start)


def live(key: jax.Array, config: Config, params: LearningParams, genome: jnp.ndarray) -> LifetimeResult:
    """One individual's whole life: childhood (LE-LS), then every task from the same experts."""
    keys = lifetime_keys(key, config.num_tasks)
    agent, childhood_selections = grow_up(keys, config, params, genome)
    dtype = agent.actor.dtype

    phase = adult_phase(config.condition)

    def live_task(task_key, index):
        state, curves = run_phase(task_key, config, phase, params, task_spec(config, index, dtype),
                                  task_start(config, agent, index), config.task_steps,
                                  phase_steps=config.adult_noise_steps)
        return state.agent, curves

    adult_agents, curves = jax.vmap(live_task)(keys.tasks, jnp.arange(config.num_tasks))
    _, _, best = task_arrays(config, dtype)
    reaches = curves.reaches.sum(-1)
    performance = reaches / best
    return LifetimeResult(
        fitness=performance.mean(),
        performance=performance,
        reaches=reaches,
        timeouts=curves.timeouts.sum(-1),
        reward_curve=curves.reaches,
        adult_selections=curves.selections,
        childhood_selections=childhood_selections,
        agent=agent,
        adult_agents=adult_agents,
    )


def make_evaluate(config: Config):
    """A jitted ``evaluate(key, params, genomes) -> LifetimeResult`` over a batch of individuals."""

    def evaluate_population(key, params, genomes):
        keys = jax.random.split(key, genomes.shape[0])
        return jax.vmap(lambda k, g: live(k, config, params, g))(keys, genomes)

    return jax.jit(evaluate_population)
