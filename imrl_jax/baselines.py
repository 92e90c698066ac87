"""``python -m imrl_jax.baselines``: modern deep RL from brax.training on the six tasks (docs/BASELINES.md).

    python -m imrl_jax.baselines --agent ppo --steps 1000000 --seeds 5 --out runs/ppo
    python -m imrl_jax.baselines --agent es --steps 10000000 --seeds 3 --tasks 3,6 --out runs/es

Each task is learned from scratch by brax's PPO or ES on the arena's brax environments
(:mod:`imrl_jax.brax_env`), with ``--steps`` control cycles of experience per task and
seed: the paper's learning tests give each agent 1,000,000 (section 3, Fig. 3b). The
measure is the paper's task performance, reaches / theoretical maximum (MODEL.md
"Tasks"), of the policy replayed from the task's start pose by the project's own
kinematics (:func:`rollout`): the policy as it acts, sampling its actions (as the paper's
learners are measured while they act; brax's default evaluation), and its mode
("deterministic"). Writes to ``--out``: ``runs.csv`` (one row per task and seed: final
performance, seconds, steps per second), ``curves.csv`` (performance at each
evaluation), ``learning_curve.png`` and ``summary.json`` (per task and overall, the
settings, the command and the git commit).
"""

from __future__ import annotations

import argparse
import dataclasses
import functools
import math
import json
import os
import sys
import time
from typing import Callable, NamedTuple, Sequence

import jax
import jax.numpy as jnp
import numpy as np

from imrl_jax.cli import (HelpFormatter, Parser, UsageError, add_task_set, apply_task_set, check_out, parse_sets,
                          exit_codes)
from imrl_jax.config import Config, ConfigError
from imrl_jax.env import make_env
from imrl_jax.progress import Progress


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
    environment (:meth:`imrl_jax.env.Environment.transition`), not by the brax environment's
    step: reaching the target or the timeout puts the robot back at the start, and the replay
    goes on. ``env`` gives the task and the observation.
    """
    from imrl_jax.brax_env import robot_action

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

    from imrl_jax.brax_env import TaskEnv, wrap_for_training

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

    from imrl_jax.brax_env import TaskEnv, wrap_for_training

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


# ----------------------------------------------------------------------------- the run

OUTPUTS = ("runs.csv", "curves.csv", "learning_curve.png", "summary.json")
#: The packages whose versions summary.json records.
VERSIONS = ("jax", "brax", "flax", "optax")


def run(b: Baseline, out_dir: str, config: Config | None = None, quiet: bool = False, command: str = "") -> dict:
    """Train ``b.agent`` on every task and seed of ``b``, write the outputs to ``out_dir``; return the summary."""
    from imrl_jax import brax_env  # noqa: F401  (brax, its environments, the jax shim)
    from imrl_jax.checkpoint import git_commit, package_versions
    from imrl_jax.plotting import save
    from imrl_jax.rundir import csv_bytes, write_atomic

    config = Config() if config is None else config
    if max(b.tasks) > config.num_tasks:
        raise ConfigError(f"tasks: task {max(b.tasks)} is not in the task set (tasks 1 to {config.num_tasks})")
    agent = AGENTS[b.agent]
    jobs = [(task, seed) for task in b.tasks for seed in b.seed_list]
    progress = Progress(len(jobs), quiet=quiet, unit="run")
    total = steps_trained(b)
    rounded = (f" (brax trains whole {agent.update} of "
               f"{steps_per_update(b):,} cycles: {b.steps:,} asked)") if total != b.steps else ""
    progress.note(f"{b.agent.upper()} baseline: {len(b.tasks)} task(s) x {b.seeds} seed(s), {total:,} cycles "
                     f"each{rounded}, {len(jobs) * total:,} in all")
    rows, curves = [], []
    started = time.perf_counter()
    for task, seed in jobs:
        def report(current, task=task, seed=seed):
            if not quiet and current.steps[-1]:
                rate = f", {np.median(current.sps):,.0f} steps/s" if current.sps else ""
                progress.message(f"  task {task} seed {seed}: {current.steps[-1]:,} / {b.steps:,} cycles, "
                                 f"performance {current.stochastic[-1]:.3f}{rate}")

        trained = agent.train(b, config, task, seed, report)
        sto, det = final_performance(trained)
        sps = float(np.median(trained.sps)) if trained.sps else float("nan")
        rows.append(dict(agent=b.agent, task=task, seed=seed, steps=trained.steps[-1], performance=round(sto, 5),
                         performance_deterministic=round(det, 5), seconds=round(trained.seconds, 1),
                         steps_per_s=round(sps)))
        curves += [dict(agent=b.agent, task=task, seed=seed, step=s, performance=round(p, 5),
                        performance_deterministic="" if np.isnan(d) else round(d, 5))
                   for s, p, d in zip(trained.steps, trained.stochastic, trained.deterministic)]
        progress.update(len(rows), 0.0, 0.0, sps,
                        scores=f"task {task} seed {seed}: performance {sto:.3f} (deterministic {det:.3f})")
    summary = summarise(b, config, rows, curves)
    settings = {name: list(v) if isinstance(v, tuple) else v for name, v in dataclasses.asdict(b).items()}
    summary.update(seconds=round(time.perf_counter() - started, 1), command=command, git_commit=git_commit(),
                   versions=package_versions(VERSIONS), backend=jax.default_backend(), settings=settings,
                   task_set=[dataclasses.asdict(t) for t in config.tasks])
    os.makedirs(out_dir, exist_ok=True)
    write_atomic(os.path.join(out_dir, "runs.csv"), csv_bytes(rows))
    write_atomic(os.path.join(out_dir, "curves.csv"), csv_bytes(curves))
    save(plot_learning_curve(b, curves), os.path.join(out_dir, "learning_curve.png"))
    write_atomic(os.path.join(out_dir, "summary.json"), json.dumps(summary, indent=2).encode())  # last: marks completion
    return summary


def summarise(b: Baseline, config: Config, rows: list[dict], curves: list[dict]) -> dict:
    """Per task and overall: mean and sd over seeds of the final performance (acting, and deterministic)."""
    per_task = {}
    for task in b.tasks:
        acting = np.asarray([r["performance"] for r in rows if r["task"] == task])
        mode = np.asarray([r["performance_deterministic"] for r in rows if r["task"] == task])
        per_task[str(task)] = dict(mean=float(acting.mean()), sd=float(acting.std()),
                                   deterministic_mean=float(mode.mean()))
    per_seed = [np.mean([r["performance"] for r in rows if r["seed"] == s]) for s in b.seed_list]
    sps = [r["steps_per_s"] for r in rows if np.isfinite(r["steps_per_s"])]
    return dict(agent=b.agent, steps=b.steps, steps_trained=steps_trained(b), seeds=b.seed_list, tasks=list(b.tasks),
                performance_mean=float(np.mean(per_seed)), performance_sd_over_seeds=float(np.std(per_seed)),
                performance_deterministic_mean=float(np.mean([r["performance_deterministic"] for r in rows])),
                per_task=per_task, steps_per_s_median=float(np.median(sps)) if sps else None,
                steps_per_update=steps_per_update(b),
                measure=f"reaches / theoretical maximum of the trained policy acting (sampled actions), "
                        f"{b.eval_lanes} replays x {b.eval_steps:,} cycles from the task's start by the project's "
                        f"own step; performance_deterministic: the same with the policy's mode")


def plot_learning_curve(b: Baseline, curves: list[dict]):
    """Performance against cycles of experience per task, the mean over seeds (learning_curve.png)."""
    from imrl_jax.plotting import plot_baseline

    # brax trains whole updates: the last point lies past b.steps
    return plot_baseline(curves, b.tasks, steps_trained(b),
                         f"{b.agent.upper()} from brax.training: {b.seeds} seed(s), mean over seeds")


# ----------------------------------------------------------------------------- command line


def _ints(text: str) -> tuple[int, ...]:
    return tuple(int(part) for part in text.split(",") if part.strip())


def parser() -> argparse.ArgumentParser:
    p = Parser(prog="python -m imrl_jax.baselines",
               description="Modern deep RL baselines from brax.training (PPO, ES) on the six tasks, measured as the "
                           "paper measures its agents.",
               formatter_class=HelpFormatter)
    defaults = Baseline()
    p.add_argument("--agent", default=defaults.agent, help=f"one of {', '.join(AGENTS)}")
    p.add_argument("--steps", type=int, default=defaults.steps, help="control cycles of experience per task and seed")
    p.add_argument("--seeds", type=int, default=defaults.seeds, help="seeds per task")
    p.add_argument("--first-seed", type=int, default=defaults.first_seed, help="the first seed")
    p.add_argument("--tasks", help="tasks to learn, e.g. 3,6 (default: every task of the task set)")
    add_task_set(p, "whose tasks --tasks numbers", default="paper")
    p.add_argument("--evals", type=int, default=defaults.num_evals, help="evaluations per run, the untrained one included")
    p.add_argument("--eval-steps", type=int, default=defaults.eval_steps, help="cycles of each evaluation replay")
    p.add_argument("--hidden", default=",".join(map(str, defaults.hidden)), help="hidden layer sizes")
    p.add_argument("--set", action="append", metavar="FIELD=VALUE",
                   help="set a scalar Baseline field, e.g. --set learning_rate=0.001 (repeatable)")
    p.add_argument("--out", required=True, help="output directory")
    p.add_argument("--quiet", action="store_true", help="no progress lines (for logs)")
    p.add_argument("--overwrite", action="store_true", help="replace the outputs of an earlier baseline run in --out")
    return p


@exit_codes
def main(argv: Sequence[str] | None = None) -> int:
    command = "python -m imrl_jax.baselines " + " ".join(sys.argv[1:] if argv is None else argv)
    args = parser().parse_args(argv)
    check_out(args.out)
    config = apply_task_set(Config(), args)
    try:
        hidden = _ints(args.hidden)
        tasks = tuple(range(1, config.num_tasks + 1)) if args.tasks is None else _ints(args.tasks)
    except ValueError:
        raise UsageError(f"--tasks/--hidden: expected comma-separated integers (got {args.tasks!r}, "
                         f"{args.hidden!r})") from None
    settings = Baseline(**{**parse_sets(args.set, Baseline), "agent": args.agent, "steps": args.steps,
                           "seeds": args.seeds, "first_seed": args.first_seed, "tasks": tasks,
                           "num_evals": args.evals, "eval_steps": args.eval_steps, "hidden": hidden})
    from imrl_jax.rundir import check_outputs_dir, check_writable

    check_writable(args.out)
    check_outputs_dir(args.out, OUTPUTS, "baseline run", args.overwrite)
    try:
        from imrl_jax import brax_env  # noqa: F401
    except ImportError as error:
        raise UsageError(str(error)) from None
    summary = run(settings, args.out, config=config, quiet=args.quiet, command=command)
    print(f"{summary['agent'].upper()}, {summary['steps']:,} cycles per task: performance "
          f"{summary['performance_mean']:.4f} (mean over tasks and seeds; sd over seeds "
          f"{summary['performance_sd_over_seeds']:.4f}); outputs in {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
