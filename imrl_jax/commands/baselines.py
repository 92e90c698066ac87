"""``python -m imrl_jax.baselines``: modern deep RL from brax.training on the six tasks (docs/BASELINES.md).

    python -m imrl_jax.baselines --agent ppo --steps 1000000 --seeds 5 --out runs/ppo
    python -m imrl_jax.baselines --agent es --steps 10000000 --seeds 3 --tasks 3,6 --out runs/es

Each task is learned from scratch by brax's PPO or ES (:mod:`imrl_jax.agent.brax_agents`), with
``--steps`` control cycles of experience per task and seed: the paper's learning tests give
each agent 1,000,000 (section 3, Fig. 3b). Writes to ``--out``: ``runs.csv`` (one row per
task and seed: final performance, seconds, steps per second), ``curves.csv`` (performance
at each evaluation), ``learning_curve.png`` and ``summary.json`` (per task and overall, the
settings, the command and the git commit).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import sys
import time
from typing import Sequence

import jax
import numpy as np

from imrl_jax.runs import cli
from imrl_jax.agent.brax_agents import AGENTS, Baseline, final_performance, steps_per_update, steps_trained
from imrl_jax.runs.cli import (HelpFormatter, Parser, UsageError, add_task_set, apply_task_set, check_out, parse_sets,
                          exit_codes)
from imrl_jax.config import Config, ConfigError
from imrl_jax.runs.progress import Progress

#: What a run writes into its --out (summary.json last).
OUTPUTS = ("runs.csv", "curves.csv", "learning_curve.png", "summary.json")
#: The packages whose versions summary.json records.
VERSIONS = ("jax", "brax", "flax", "optax")


def run(b: Baseline, out_dir: str, config: Config | None = None, quiet: bool = False, command: str = "") -> dict:
    """Train ``b.agent`` on every task and seed of ``b``, write the outputs to ``out_dir``; return the summary."""
    from imrl_jax.agent import brax_env  # noqa: F401  (brax, its environments, the jax shim)
    from imrl_jax.runs.checkpoint import git_commit, package_versions
    from imrl_jax.analysis.plotting import save
    from imrl_jax.runs.rundir import csv_bytes, write_atomic

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
    from imrl_jax.analysis.charts import plot_baseline

    # brax trains whole updates: the last point lies past b.steps
    return plot_baseline(curves, b.tasks, steps_trained(b),
                         f"{b.agent.upper()} from brax.training: {b.seeds} seed(s), mean over seeds")


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
    for flag, value, limit in (("--steps", args.steps, cli.MAX_STEPS), ("--seeds", args.seeds, cli.MAX_SEEDS),
                               ("--evals", args.evals, cli.MAX_BINS), ("--eval-steps", args.eval_steps, cli.MAX_STEPS)):
        cli.check_at_most(flag, value, limit)  # before anything is allocated; the lower bounds: Baseline's
    cli.check_key("--first-seed", args.first_seed, cli.MAX_KEY - args.seeds + 1 if args.seeds >= 1 else cli.MAX_KEY)
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
    from imrl_jax.runs.rundir import check_outputs_dir, check_writable

    check_writable(args.out)
    check_outputs_dir(args.out, OUTPUTS, "baseline run", args.overwrite)
    try:
        from imrl_jax.agent import brax_env  # noqa: F401
    except ImportError as error:
        raise UsageError(str(error)) from None
    return cli.execute(cli.Call(lambda: report(settings, args, config, command), settings=settings, out=args.out))


def report(settings: Baseline, args, config: Config, command: str) -> int:
    """Train the baseline the command line checked and print what it measured."""
    summary = run(settings, args.out, config=config, quiet=args.quiet, command=command)
    print(f"{summary['agent'].upper()}, {summary['steps']:,} cycles per task: performance "
          f"{summary['performance_mean']:.4f} (mean over tasks and seeds; sd over seeds "
          f"{summary['performance_sd_over_seeds']:.4f}); outputs in {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
