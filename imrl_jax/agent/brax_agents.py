"""brax.training's agents on the six tasks: a baseline's settings, PPO and ES training and their measure (BASELINES.md).

Each task is learned from scratch by brax's PPO or ES on the arena's brax environments
(:mod:`imrl_jax.agent.brax_env`, imported only when an agent trains). The measure is the paper's task
performance, reaches / theoretical maximum (MODEL.md "Tasks"), of the policy replayed from the
task's start pose by the project's own kinematics (:func:`rollout`): the policy as it acts,
sampling its actions, and its mode ("deterministic").
"""

from __future__ import annotations

import dataclasses
import functools
import math
import time
from typing import Callable, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from imrl_jax.config import Config, ConfigError
from imrl_jax.world.env import make_env


@dataclasses.dataclass(frozen=True)
class Baseline:
    """Static settings of a baseline run: the agent, its budget, its evaluation and its hyperparameters."""

    agent: str = "ppo"
    steps: int = 1_000_000  # control cycles of experience per task and seed (the paper's learning test)
    seeds: int = 3
    first_seed: int = 0
    tasks: tuple[int, ...] = (1, 2, 3, 4, 5, 6)
    num_evals: int = 11  # evaluations of the policy, the untrained one included
    eval_lanes: int = 8  # independent replays of each evaluation
    eval_steps: int = 5_000  # control cycles of each replay
    hidden: tuple[int, ...] = (64, 64)  # hidden layers of the policy (and of PPO's value network)
    discounting: float = 0.99  # the paper's gamma
    # PPO: steps per update = batch_size * num_minibatches * unroll_length (10,240)
    num_envs: int = 64
    unroll_length: int = 20
    batch_size: int = 64
    num_minibatches: int = 8
    updates_per_batch: int = 4
    learning_rate: float = 1e-3
    entropy_cost: float = 1e-2
    # ES: a generation is 2 * population episodes of episode_length cycles
    population: int = 32
    episode_length: int = 500
    perturbation_std: float = 0.1
    es_learning_rate: float = 0.02

    def __post_init__(self):
        _validate(self)

    @property
    def seed_list(self) -> list[int]:
        return list(range(self.first_seed, self.first_seed + self.seeds))


def _validate(b: Baseline) -> None:
    def fail(field: str, why: str):
        raise ConfigError(f"{field}: {why} (got {getattr(b, field)!r})")

    if b.agent not in AGENTS:  # (defined below the training functions it names)
        fail("agent", f"must be one of {', '.join(AGENTS)}")
    for name in ("steps", "seeds", "num_evals", "eval_lanes", "eval_steps", "num_envs", "unroll_length",
                 "batch_size", "num_minibatches", "updates_per_batch", "population", "episode_length"):
        value = getattr(b, name)
        if not isinstance(value, int) or isinstance(value, bool) or value < 1:
            fail(name, "must be a positive integer")
    if b.first_seed < 0:
        fail("first_seed", "must be 0 or more")
    if b.num_evals < 2:
        fail("num_evals", "must be at least 2 (the untrained policy and the trained one)")
    if not b.tasks or len(set(b.tasks)) != len(b.tasks) or not all(t >= 1 for t in b.tasks):
        fail("tasks", "must be distinct task numbers from 1 (of the task set)")
    if not b.hidden or any(h < 1 for h in b.hidden):
        fail("hidden", "must be positive layer sizes")
    if (b.batch_size * b.num_minibatches) % b.num_envs:
        fail("num_envs", f"must divide batch_size * num_minibatches = {b.batch_size * b.num_minibatches}")
    for name in ("learning_rate", "entropy_cost", "perturbation_std", "es_learning_rate"):
        if not np.isfinite(getattr(b, name)) or getattr(b, name) < 0:
            fail(name, "must be a finite number >= 0")
    if not 0.0 <= b.discounting <= 1.0:
        fail("discounting", "must be in [0, 1]")


def steps_per_update(b: Baseline) -> int:
    """Control cycles between two policy updates (PPO: one batch of unrolls; ES: one generation)."""
    return AGENTS[b.agent].steps_per_update(b)


def steps_trained(b: Baseline) -> int:
    """Control cycles brax trains for ``b.steps`` asked: whole updates, rounded up as its trainers do.

    PPO: ``num_evals - 1`` epochs of ceil(steps / ((num_evals - 1) x update)) updates each;
    ES: generations until the count reaches ``steps`` (one epoch).
    """
    update, epochs = steps_per_update(b), AGENTS[b.agent].epochs(b)
    return epochs * math.ceil(b.steps / (epochs * update)) * update


# ----------------------------------------------------------------------------- measuring


def rollout(key: jax.Array, env, policy, num_lanes: int, num_steps: int) -> jnp.ndarray:
    """Reaches of ``policy`` (brax's ``policy(obs, key)``) in ``num_lanes`` replays of ``num_steps`` cycles.

    Each replay starts at the task's start pose and is driven by the project's own
    environment (:meth:`imrl_jax.world.env.Environment.transition`), not by the brax environment's
    step: reaching the target or the timeout puts the robot back at the start, and the replay
    goes on. ``env`` gives the task and the observation.
    """
    from imrl_jax.agent.brax_env import robot_action

    arena, spec = make_env(env.config), env.spec
    advance = jax.vmap(lambda robot, outputs: arena.transition(robot, outputs, spec))

    def one_step(carry, step_key):
        robots, reaches = carry
        action, _ = policy(jax.vmap(env.observation)(robots.pose), step_key)
        robots, events = advance(robots, robot_action(action))
        return (robots, reaches + events.reached), None

    robots = jax.vmap(lambda _: arena.at(spec.start))(jnp.arange(num_lanes))
    (_, reaches), _ = jax.lax.scan(one_step, (robots, jnp.zeros((num_lanes,), jnp.int32)),
                                   jax.random.split(key, num_steps))
    return reaches


def performance(config: Config, task: int, reaches, num_steps: int):
    """Reaches in ``num_steps`` cycles of task ``task`` (1-6) / the theoretical maximum (MODEL.md)."""
    return np.asarray(reaches, float) * config.steps_per_trip()[task - 1] / num_steps


def make_evaluate(b: Baseline, env, make_policy):
    """Jitted ``evaluate(key, params) -> (stochastic, deterministic)`` task performance of brax policy params."""

    def evaluate(key, params):
        modes = []
        for deterministic in (False, True):
            reaches = rollout(key, env, make_policy(params, deterministic=deterministic), b.eval_lanes, b.eval_steps)
            modes.append(reaches.sum() * env.config.steps_per_trip()[env.task - 1] / (b.eval_lanes * b.eval_steps))
        return tuple(modes)

    return jax.jit(evaluate)


# ----------------------------------------------------------------------------- training


class Run:
    """What one (task, seed) training gives: the evaluations, the final policy, the time."""

    def __init__(self):
        self.steps: list[int] = []
        self.stochastic: list[float] = []  # the policy as it acts (sampled actions)
        self.deterministic: list[float] = []  # its mode (NaN where not measured)
        self.sps: list[float] = []
        self.losses: dict[str, float] = {}  # PPO's last reported losses
        self.make_policy = None
        self.params = None
        self.seconds = 0.0


def train_ppo(b: Baseline, config: Config, task: int, seed: int, report=None) -> Run:
    """brax's PPO on task ``task`` for ``b.steps`` cycles, evaluated ``b.num_evals`` times."""
    from brax.training.agents.ppo import networks as ppo_networks
    from brax.training.agents.ppo import train as ppo

    from imrl_jax.agent.brax_env import TaskEnv, wrap_for_training

    env = TaskEnv(task, config)
    run, evaluate = Run(), None
    key = jax.random.fold_in(jax.random.key(seed), task)

    def on_params(step, make_policy, params):
        nonlocal evaluate
        evaluate = evaluate or make_evaluate(b, env, make_policy)
        # On the host: the untrained and the trained parameters come laid out over different
        # device meshes, and would each compile the evaluation.
        sto, det = evaluate(jax.random.fold_in(key, len(run.steps)), jax.tree.map(np.asarray, params))
        run.steps.append(int(step))
        run.stochastic.append(float(sto))
        run.deterministic.append(float(det))
        if report is not None:
            report(run)

    def on_metrics(step, metrics):
        if step and "training/sps" in metrics:
            run.sps.append(float(metrics["training/sps"]))
        run.losses = {name[len("training/"):]: float(value) for name, value in metrics.items()
                      if name.startswith("training/") and name.endswith("loss")}

    start = time.perf_counter()
    network = functools.partial(ppo_networks.make_ppo_networks, policy_hidden_layer_sizes=b.hidden,
                                value_hidden_layer_sizes=b.hidden)
    run.make_policy, run.params, _ = ppo.train(
        env, num_timesteps=b.steps, num_envs=b.num_envs, episode_length=config.trial_timeout,
        wrap_env_fn=wrap_for_training, learning_rate=b.learning_rate, entropy_cost=b.entropy_cost,
        discounting=b.discounting, unroll_length=b.unroll_length, batch_size=b.batch_size,
        num_minibatches=b.num_minibatches, num_updates_per_batch=b.updates_per_batch, num_evals=b.num_evals,
        run_evals=False, seed=seed, network_factory=network, progress_fn=on_metrics, policy_params_fn=on_params)
    run.seconds = time.perf_counter() - start
    return run


def train_es(b: Baseline, config: Config, task: int, seed: int, report=None) -> Run:
    """brax's ES on task ``task`` for ``b.steps`` cycles; a fitness is the reaches of one ``episode_length`` episode."""
    from brax.training.agents.es import networks as es_networks
    from brax.training.agents.es import train as es

    from imrl_jax.agent.brax_env import TaskEnv, wrap_for_training

    env = TaskEnv(task, config, trial_episodes=False)  # reaches do not end an episode: it scores them all
    run = Run()

    def on_metrics(step, metrics):
        # brax's ES gives no parameters between evaluations: its own evaluation is used
        # (the policy acting for one episode from the start in each of b.eval_lanes copies
        # of this environment).
        run.steps.append(int(step))
        run.stochastic.append(float(performance(config, task, metrics["eval/episode_reaches"], b.episode_length)))
        run.deterministic.append(float("nan"))
        if "training/sps" in metrics:
            run.sps.append(float(metrics["training/sps"]))
        if report is not None:
            report(run)

    start = time.perf_counter()
    network = functools.partial(es_networks.make_es_networks, hidden_layer_sizes=b.hidden)
    run.make_policy, run.params, _ = es.train(
        env, wrap_env_fn=wrap_for_training, num_timesteps=b.steps, episode_length=b.episode_length,
        population_size=b.population, learning_rate=b.es_learning_rate, perturbation_std=b.perturbation_std,
        num_evals=b.num_evals, num_eval_envs=b.eval_lanes, seed=seed, network_factory=network,
        progress_fn=on_metrics)
    run.seconds = time.perf_counter() - start
    # The final policy is measured as PPO's is: replays by the project's own step.
    sto, det = make_evaluate(b, env, run.make_policy)(jax.random.fold_in(jax.random.key(seed), task), run.params)
    run.final = (float(sto), float(det))
    # The curve ends with the same measure as runs.csv (the earlier points are brax's own evaluation).
    if not run.steps or run.steps[-1] != steps_trained(b):
        run.steps.append(steps_trained(b)), run.stochastic.append(0.0), run.deterministic.append(0.0)
    run.stochastic[-1], run.deterministic[-1] = run.final
    return run


def final_performance(run: Run) -> tuple[float, float]:
    """The trained policy's (stochastic, deterministic) performance."""
    return getattr(run, "final", (run.stochastic[-1], run.deterministic[-1]))


class Agent(NamedTuple):
    """What differs between the agents: how one trains, and the whole updates brax trains it in."""

    train: Callable[..., Run]  # train(b, config, task, seed, report) -> Run
    update: str  # what one update is called
    steps_per_update: Callable[[Baseline], int]  # control cycles between two policy updates
    epochs: Callable[[Baseline], int]  # training epochs, each of whole updates (brax rounds each one up)


#: The agents, by the name ``--agent`` takes.
AGENTS = {
    "ppo": Agent(train_ppo, "updates", lambda b: b.batch_size * b.num_minibatches * b.unroll_length,
                 lambda b: max(b.num_evals - 1, 1)),  # an epoch between two evaluations
    "es": Agent(train_es, "generations", lambda b: 2 * b.population * b.episode_length, lambda b: 1),
}
