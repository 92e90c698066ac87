"""Lifetimes of section 2 and MODEL.md "Acting", "Learning", "Life": childhood and adulthood.

One :func:`step` implements a control cycle for every phase (the learning rules are
:func:`imrl_jax.agent.learning.learn_experts` and :func:`~imrl_jax.agent.learning.learn_selector`; the
carried types live in :mod:`imrl_jax.agent.state`); a static :class:`Phase` says which networks
learn and from which reward. A phase is a ``lax.scan`` over bins of a scan
over steps, returning only per-bin counts, so memory does not grow with its length.
:func:`live` is one individual's whole life: LE-LS childhood as one continuous scan, then
the tasks vmapped from the same frozen experts. :func:`simulate` records a per-step
trajectory of one individual, for plots and for the reference tests.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from imrl_jax.world.arena import Pose
from imrl_jax.conditions import Phase
from imrl_jax.config import Config, LearningParams
from imrl_jax.agent import kernel_choice
from imrl_jax.genome import EVOLVED_FIELDS
from imrl_jax.world.env import TaskSpec, childhood_task, random_pose, task_spec  # noqa: F401 (lifetime's names for them)
from imrl_jax.world.base import DISCRETE
from imrl_jax.world.worlds import world_of
from imrl_jax.agent.learning import learn_experts, learn_selector, learn_selector_over_option, pick_row, take_row
from imrl_jax.agent.networks import Agent, act, decode, explore, expressed_only, select, with_bias, zero_agent
from imrl_jax.agent.state import (Curves, Draws, Previous, State, StepRecord, bin_steps, childhood_phase, draw_block,
                                  draw_many, for_phase, init_state, learning_until, phase_params, spawn_draws)
from imrl_jax.agent.timescale import ends, next_option


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


def lifetime_keys(key: jax.Array, num_tasks: int) -> LifetimeKeys:
    """Split a life's key once per consumer."""
    key_pose, key_child, key_adult = jax.random.split(key, 3)
    return LifetimeKeys(key_pose, key_child, jax.random.split(key_adult, num_tasks))


def _set_row(matrix, k, row):
    """matrix with row k replaced."""
    return jax.lax.dynamic_update_index_in_dim(matrix, row, k, 0)


def _draws(config: Config, phase: Phase, key: jax.Array, state: State) -> tuple[Draws, Draws]:
    """The carried block of draws (a new one every config.draw_block steps) and this step's draws."""
    # t is the same for every lane (it is not batched under vmap), so this cond really
    # skips the draw on the steps between blocks.
    offset = state.t % config.draw_block
    block = jax.lax.cond(offset == 0,
                         lambda: draw_block(key, state.t // config.draw_block, config.draw_block, phase.noisy,
                                            spawn_draws(config, phase)),
                         lambda: state.block)
    return block, jax.tree.map(lambda x: x[offset], block)


def _action(phase: Phase, params: LearningParams, output, z, t, phase_steps: int):
    """The action: :func:`~imrl_jax.agent.networks.explore` in noisy phases, else o_t.

    T is the phase's length, or a shorter noise horizon (``Config.sle_noise_steps``).
    """
    return explore(output, z, params.noise_std, t, phase_steps) if phase.noisy else output


def choose_action(phase: Phase, output, z):
    """A discrete world's action: drawn with probability o_a / sum(o) where the phase explores (the paper's rule for
    its one discrete choice, the selector's; the draw's uniform is Phi(z_0) of the step's action noise), else the
    largest o_a. Learned as the selector is: e_W <- gamma lambda e_W + ((e_a - o) o (1 - o)) x~^T."""
    if not phase.noisy:
        return jnp.argmax(output).astype(jnp.int32)
    return select(jax.scipy.special.ndtr(z[0]), output)


def step(key: jax.Array, config: Config, phase: Phase, params: LearningParams, task: TaskSpec, phase_steps: int,
         state: State) -> tuple[State, StepRecord]:
    """One control cycle (MODEL.md "Acting, each time step t of a phase"): observe, choose, learn, act, move.

    ``key`` is the phase's key: the step takes its random numbers from the block of draws it
    makes from it every ``config.draw_block`` steps.
    """
    world = world_of(config)
    env = world.make_env(config, phase.has_target, phase.respawn)
    robot = state.world
    block, draws = _draws(config, phase, key, state)
    # An individual with learning values of its own (evolved learning parameters) learns with them.
    params = phase_params(phase, params if state.agent.params is None else state.agent.params)
    if phase.intrinsic and state.agent.childhood_length is not None:  # an evolved childhood length
        params = learning_until(params, state.t < state.agent.childhood_length)
    agent, traces, prev, baseline = state.agent, state.traces, state.prev, state.baseline

    # 1-2: observe x_t, choose the expert k_t with probability s_k / sum(s).
    # x~_t and x~_{t-1} take turns in the rows of xbs, so that no step copies one into the
    # other. x~_t overwrites x~_{t-2}, which nothing reads, so XLA writes it in place; and
    # computed here from the carried pose, not at the end of the previous step, its kernels
    # read the pose instead of computing the move again for every sample point.
    now = state.t % 2
    # In the agent's float type: a world may observe in another (XLand's float32 in a float64 life).
    xbs = _set_row(state.xbs, now, with_bias(env.observe(robot).astype(state.xbs.dtype)))
    xb, prev_xb = take_row(xbs, now), take_row(xbs, 1 - now)
    selection = expressed_only(agent, act(agent.selector_actor, xb))
    k = select(draws.u, selection) if selection.shape[0] > 1 else jnp.int32(0)
    option = state.option
    if option is not None:  # a selector on its own time-scale: it chooses only where the option ends
        choose = ends(config, option, prev, xb, prev_xb)
        k = jnp.where(choose, k, prev.k)
    same = k == prev.k

    # 3: learn from the transition t-1 -> t.
    surprise = jnp.zeros((), xb.dtype)
    if phase.experts_learn:
        agent, traces, surprise = learn_experts(phase, params, agent, traces, prev, xb, prev_xb, same)
    if phase.selector_learns and option is not None:
        agent, traces, baseline, option = learn_selector_over_option(phase, params, agent, traces, prev, option, xb,
                                                                     choose, same, surprise, baseline)
    elif phase.selector_learns:
        agent, traces, baseline = learn_selector(phase, params, agent, traces, prev, xbs, now, k, same, surprise,
                                                 baseline)
    if option is not None:
        option = next_option(option, choose, xb, selection)

    # 4: act: the expert in control's output, with noise where the phase has it (a discrete world: one action).
    output = act(pick_row(agent.actor, k), xb)
    if world.actions(config).kind == DISCRETE:
        index = choose_action(phase, output, draws.z)
        action, command = jax.nn.one_hot(index, output.shape[0], dtype=output.dtype), index
    else:
        action = command = _action(phase, params, output, draws.z, state.t, phase_steps)

    # 5: the world's step (the arena's: turn, move, clamp; then walls (respawn), the target and the timeout).
    robot, events = env.transition(robot, command, task, draws.spawn)
    prev = Previous(k, action, output, selection, ~(events.timeout | events.respawned), events.reached)
    state = State(agent, traces, robot, xbs, prev, state.t + 1, block, baseline, option)
    return state, StepRecord(robot, k, events.reached, events.timeout, events.respawned)


def run_phase(key: jax.Array, config: Config, phase: Phase, params: LearningParams, task: TaskSpec,
              state: State, num_steps: int, phase_steps: int | None = None,
              num_bins: int | None = None) -> tuple[State, Curves]:
    """Run ``num_steps`` steps of a phase as a scan over bins of steps (``config.num_bins`` by default).

    A phase may run in pieces: give each piece the whole phase's length as ``phase_steps``
    (the noise anneals to 0 over it, then stays 0) and the carried state; the pieces together are the same
    computation as one call. With ``config.step_kernel == "pallas"`` (or "auto" resolved to it,
    :mod:`imrl_jax.agent.kernel_choice`) each bin is one kernel (:func:`imrl_jax.agent.kernel.run_phase`).
    """
    if kernel_choice.chosen(config) == "pallas":  # an explicit choice as it is; "auto" resolved
        from imrl_jax.agent import kernel  # imports this module

        return kernel.run_phase(key, config, phase, params, task, state, num_steps, phase_steps, num_bins)
    phase_steps = num_steps if phase_steps is None else phase_steps
    num_bins = config.num_bins if num_bins is None else num_bins
    steps_per_bin = bin_steps(num_steps, num_bins)
    state = for_phase(config, phase, state)
    num_experts = state.agent.selector_actor.shape[0]

    def one_step(carry, _):
        state, counts = carry
        state, record = step(key, config, phase, params, task, phase_steps, state)
        counts = Curves(counts.reaches + record.reached, counts.timeouts + record.timeout,
                        counts.selections + jax.nn.one_hot(record.k, num_experts, dtype=jnp.int32),
                        None if counts.respawns is None else counts.respawns + record.respawned)
        return (state, counts), None

    def one_bin(state, _):
        counts = Curves(jnp.int32(0), jnp.int32(0), jnp.zeros((num_experts,), jnp.int32),
                        jnp.int32(0) if phase.respawn else None)
        (state, counts), _ = jax.lax.scan(one_step, (state, counts), None, length=steps_per_bin,
                                          unroll=config.scan_unroll)
        return state, counts

    return jax.lax.scan(one_bin, state, None, length=num_bins)


def simulate(key: jax.Array, config: Config, phase: Phase, params: LearningParams, task: TaskSpec,
             state: State, num_steps: int, phase_steps: int | None = None) -> tuple[State, StepRecord]:
    """Run ``num_steps`` steps of one individual and record every step (plots, tests only)."""
    phase_steps = num_steps if phase_steps is None else phase_steps
    state = for_phase(config, phase, state)

    def one_step(state, _):
        return step(key, config, phase, params, task, phase_steps, state)

    return jax.lax.scan(one_step, state, None, length=num_steps)


def adult_agent(config: Config, agent: Agent) -> Agent:
    """The agent a task starts with: the networks the condition resets set back to their start
    (LE-LS, EE-LS: the selector; SLE: everything; EE-ES: nothing)."""
    reset = config.spec.reset
    if not reset:
        return agent
    fresh = zero_agent(config, agent.actor.dtype)
    return agent._replace(**{network: getattr(fresh, network) for network in reset})


def with_params(agent, params: LearningParams):
    """An agent whose genome carries learning values (LE-LS-P) takes the rest of them from ``params``, not from the
    config it was decoded with: a life's dynamic values are its arguments (a sweep's points, a learning test)."""
    if agent.params is None:
        return agent
    evolved = {f: getattr(agent.params, f) for f in EVOLVED_FIELDS if f in LearningParams._fields}
    return agent._replace(params=jax.tree.map(lambda p, a: jnp.asarray(p, a.dtype), params, agent.params)._replace(
        **evolved))


def grow_up(keys: LifetimeKeys, config: Config, params: LearningParams, genome: jnp.ndarray):
    """The experts adulthood starts from: the decoded genome after its childhood (conditions that have one).

    Returns the agent and the childhood's selections per bin (zeros without childhood).
    """
    agent = with_params(decode(config, genome), params)
    dtype = agent.actor.dtype
    childhood_selections = jnp.zeros((config.num_bins, agent.selector_actor.shape[0]), jnp.int32)
    if config.spec.has_childhood:
        world, phase = world_of(config), childhood_phase(config)
        task = world.childhood_task(config, dtype)
        start = world.make_env(config, phase.has_target, phase.respawn).reset(keys.pose, task, dtype)
        state, curves = run_phase(keys.childhood, config, phase, params, task, init_state(config, agent, start),
                                  config.childhood_steps)
        agent, childhood_selections = state.agent, curves.selections
    return agent, childhood_selections


def task_start(config: Config, agent: Agent, index) -> State:
    """The first carry of task ``index`` for the experts ``agent`` (selector reset as the condition says)."""
    world, dtype = world_of(config), agent.actor.dtype
    start = world.make_env(config).reset(None, world.task(config, index, dtype), dtype)
    return init_state(config, adult_agent(config, agent), start)


def live(key: jax.Array, config: Config, params: LearningParams, genome: jnp.ndarray) -> LifetimeResult:
    """One individual's whole life: childhood (LE-LS), then every task from the same experts."""
    keys = lifetime_keys(key, config.num_tasks)
    agent, childhood_selections = grow_up(keys, config, params, genome)
    dtype = agent.actor.dtype

    phase = config.spec.adult

    def live_task(task_key, index):
        state, curves = run_phase(task_key, config, phase, params, world_of(config).task(config, index, dtype),
                                  task_start(config, agent, index), config.task_steps,
                                  phase_steps=config.adult_noise_steps)
        return state.agent, curves

    adult_agents, curves = jax.vmap(live_task)(keys.tasks, jnp.arange(config.num_tasks))
    best = world_of(config).max_reaches(config, dtype)
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


class LifeDraws(NamedTuple):
    """Every random number :func:`live` uses, drawn whole (for the NumPy reference)."""

    pose: Pose  # the childhood's start
    childhood: Draws  # (childhood_steps, ...)
    tasks: Draws  # (tasks, task_steps, ...)


def life_draws(key: jax.Array, config: Config, dtype=jnp.float32) -> LifeDraws:
    """The draws ``live(key, config, ...)`` makes, step by step (for :func:`imrl_jax.agent.reference.live`)."""
    keys = lifetime_keys(key, config.num_tasks)
    spawn = spawn_draws(config, childhood_phase(config)) if config.spec.has_childhood else 0
    child = draw_many(keys.childhood, config.childhood_steps, config.draw_block, spawn=spawn)
    tasks = jax.vmap(draw_many, (0, None, None))(keys.tasks, config.task_steps, config.draw_block)
    return LifeDraws(random_pose(keys.pose, config, dtype), child, tasks)


def make_evaluate(config: Config):
    """A jitted ``evaluate(key, params, genomes) -> LifetimeResult`` over a batch of individuals."""

    def evaluate_population(key, params, genomes):
        keys = jax.random.split(key, genomes.shape[0])
        return jax.vmap(lambda k, g: live(k, config, params, g))(keys, genomes)

    return jax.jit(evaluate_population)
