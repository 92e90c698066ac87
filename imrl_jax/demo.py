"""A short CPU example of the model: one individual's childhood and adulthood (section 2).

    python -m imrl_jax.demo --out out/demo [--condition LE-LS] [--seed 0]

Lives one random individual of the condition at reduced length (the ``small`` preset:
15,000 childhood steps, 5,000 steps per task), prints its fitness and per-task
performance, and writes ``trajectories.png`` (the arena, the first childhood steps and a
path on each task, coloured by the expert in control) and ``summary.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time

import jax
import jax.numpy as jnp
import numpy as np

from imrl_jax.config import CONDITIONS, Config, ConfigError, make_config
from imrl_jax.lifetime import (CHILDHOOD, adult_phase, childhood_task, init_state, lifetime_keys, live,
                               random_pose, simulate, task_spec)
from imrl_jax.networks import decode

PATH_STEPS = 400  # steps of each task path drawn after the lifetime
CHILDHOOD_PATH_STEPS = 2000


def _record(record) -> dict:
    pos = np.asarray(record.pose.pos)
    breaks = np.asarray(record.reached | record.timeout)
    return {"pos": pos, "k": np.asarray(record.k), "breaks": breaks}


def run(config: Config, out_dir: str, seed: int = 0) -> dict:
    """Live one random individual, write the figure and summary into ``out_dir``; return the summary."""
    from imrl_jax.plotting import plot_life

    os.makedirs(out_dir, exist_ok=True)
    key = jax.random.key(seed)
    key_genome, key_life, key_paths = jax.random.split(key, 3)
    genome = jax.random.uniform(key_genome, (config.num_genes,), minval=-config.init_scale,
                                maxval=config.init_scale)
    params = config.learning_params()

    start = time.perf_counter()
    result = jax.jit(live, static_argnums=1)(key_life, config, params, genome)
    fitness = float(result.fitness)
    seconds = time.perf_counter() - start

    # Paths for the figure: the first childhood steps (same key and start pose as the life),
    # then each task from the weights the selector had at the end of that task.
    childhood = None
    if config.condition == "LE-LS":
        keys = lifetime_keys(key_life, config.num_tasks)
        state = init_state(config, decode(config, genome), random_pose(keys.pose, config))
        _, record = jax.jit(simulate, static_argnums=(1, 2, 6, 7))(
            keys.childhood, config, CHILDHOOD, params, childhood_task(config), state,
            CHILDHOOD_PATH_STEPS, config.childhood_steps)
        childhood = _record(record)

    phase = adult_phase(config.condition)

    def task_path(task_key, index, agent):
        task = task_spec(config, index)
        _, record = simulate(task_key, config, phase, params, task, init_state(config, agent, task.start),
                             PATH_STEPS, config.task_steps)
        return record

    records = jax.jit(jax.vmap(task_path))(jax.random.split(key_paths, config.num_tasks),
                                          jnp.arange(config.num_tasks), result.adult_agents)
    tasks = []
    for i in range(config.num_tasks):
        entry = _record(jax.tree.map(lambda x: x[i], records))
        entry["label"] = f"perf {float(result.performance[i]):.2f}"
        tasks.append(entry)

    figure = os.path.join(out_dir, "trajectories.png")
    plot_life(config, childhood, tasks, figure,
              title=f"{config.condition}, one random individual, reduced scale "
                    f"(childhood {config.childhood_steps:,}, {config.task_steps:,} steps/task): "
                    f"fitness {fitness:.3f}")
    summary = {
        "condition": config.condition,
        "seed": seed,
        "childhood_steps": config.childhood_steps if config.condition == "LE-LS" else 0,
        "task_steps": config.task_steps,
        "fitness": fitness,
        "performance": [float(p) for p in result.performance],
        "reaches": [int(r) for r in result.reaches],
        "timeouts": [int(t) for t in result.timeouts],
        "seconds_with_compile": seconds,
        "figure": figure,
    }
    with open(os.path.join(out_dir, "summary.json"), "w") as f:
        json.dump(summary, f, indent=2)
    return summary


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m imrl_jax.demo", description=__doc__.split("\n")[0])
    parser.add_argument("--out", default="out/demo", help="output directory (default: out/demo)")
    parser.add_argument("--condition", default="LE-LS", choices=CONDITIONS, help="condition to live")
    parser.add_argument("--seed", type=int, default=0, help="random seed of the individual and its life")
    parser.add_argument("--preset", default="small", help="config preset (default: small, reduced scale)")
    args = parser.parse_args(argv)
    try:
        config = make_config(args.preset, condition=args.condition)
    except ConfigError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    summary = run(config, args.out, args.seed)
    print(f"{config.condition} individual (seed {args.seed}), reduced scale: childhood "
          f"{summary['childhood_steps']:,} steps, {config.task_steps:,} steps per task")
    for i, (p, r) in enumerate(zip(summary["performance"], summary["reaches"])):
        print(f"  task {i + 1}: {r:4d} reaches, performance {p:.3f}")
    print(f"fitness {summary['fitness']:.3f}  ({summary['seconds_with_compile']:.1f} s with compilation)")
    print(f"wrote {summary['figure']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
