"""Benchmark of the lifetime: lane-steps per second of JAX and of the NumPy reference.

    python -m imrl_jax.bench [--lanes 300] [--task-steps 2000] [--repeats 3] [--json PATH]

One lane is one individual on one task. The JAX side lives ``lanes / 6`` LE-LS individuals
(a childhood of 1.5 x task steps, as in the paper's 150,000 : 100,000, then six tasks),
so adulthood runs ``lanes`` lanes at once; every step an individual lives counts as one
lane-step. The reference lives one individual of the same config step by step. Both are
timed in the same run; the JAX figure is the median of ``repeats`` runs after compilation.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import sys
import time

import jax
import numpy as np

from imrl_jax.config import make_config
from imrl_jax.lifetime import draw_many, lifetime_keys, make_evaluate, random_pose


def bench_jax(config, num_individuals: int, repeats: int) -> dict:
    """Median lane-steps per second of ``make_evaluate`` on a population."""
    evaluate = make_evaluate(config)
    params = config.learning_params()
    genomes = jax.random.uniform(jax.random.key(1), (num_individuals, config.num_genes), minval=-1, maxval=1)
    start = time.perf_counter()
    jax.block_until_ready(evaluate(jax.random.key(0), params, genomes))
    compile_s = time.perf_counter() - start
    times = []
    for r in range(repeats):
        start = time.perf_counter()
        jax.block_until_ready(evaluate(jax.random.key(r + 1), params, genomes))
        times.append(time.perf_counter() - start)
    seconds = statistics.median(times)
    lane_steps = num_individuals * config.lifetime_steps
    return {"seconds": seconds, "compile_and_first_run_s": compile_s, "lane_steps": lane_steps,
            "lane_steps_per_s": lane_steps / seconds}


def bench_reference(config) -> dict:
    """Steps per second of the NumPy reference living one individual of ``config``."""
    from imrl_jax import reference

    key = jax.random.key(2)
    keys = lifetime_keys(key, config.num_tasks)
    genome = np.asarray(jax.random.uniform(key, (config.num_genes,), minval=-1, maxval=1), np.float64)
    pose = random_pose(keys.pose, config)
    child = draw_many(keys.childhood, config.childhood_steps)
    tasks = jax.vmap(draw_many, (0, None))(keys.tasks, config.task_steps)
    start_pose = (*np.asarray(pose.pos, np.float64), float(pose.heading))
    start = time.perf_counter()
    reference.live(config, genome, start_pose, np.asarray(child.u, np.float64), np.asarray(child.z, np.float64),
                   np.asarray(tasks.u, np.float64), np.asarray(tasks.z, np.float64))
    seconds = time.perf_counter() - start
    return {"seconds": seconds, "lane_steps": config.lifetime_steps,
            "lane_steps_per_s": config.lifetime_steps / seconds}


def run(lanes: int, task_steps: int, repeats: int) -> dict:
    """Measure both sides on the same work; return a JSON-friendly result."""
    config = make_config("paper", condition="LE-LS", task_steps=task_steps,
                         childhood_steps=task_steps * 3 // 2, num_bins=10)
    num_individuals = max(1, lanes // config.num_tasks)
    jax_result = bench_jax(config, num_individuals, repeats)
    reference_result = bench_reference(config)
    device = jax.devices()[0]
    return {
        "backend": jax.default_backend(),
        "device": getattr(device, "device_kind", str(device)),
        "cpu_count": os.cpu_count(),
        "machine": platform.machine(),
        "jax_version": jax.__version__,
        "condition": config.condition,
        "lanes": num_individuals * config.num_tasks,
        "individuals": num_individuals,
        "childhood_steps": config.childhood_steps,
        "task_steps": config.task_steps,
        "jax": jax_result,
        "reference": reference_result,
        "speedup": jax_result["lane_steps_per_s"] / reference_result["lane_steps_per_s"],
    }


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m imrl_jax.bench", description=__doc__.split("\n")[0])
    parser.add_argument("--lanes", type=int, default=300, help="adult lanes (individuals x 6 tasks)")
    parser.add_argument("--task-steps", type=int, default=2000, help="steps per task (childhood 1.5x)")
    parser.add_argument("--repeats", type=int, default=3, help="timed JAX runs after compilation")
    parser.add_argument("--json", help="also write the result to this JSON file")
    args = parser.parse_args(argv)
    for name in ("lanes", "task_steps", "repeats"):
        if getattr(args, name) < 1:
            print(f"error: --{name.replace('_', '-')} must be at least 1", file=sys.stderr)
            return 2
    if args.task_steps % 10:
        print("error: --task-steps must be a multiple of 10", file=sys.stderr)
        return 2
    result = run(args.lanes, args.task_steps, args.repeats)
    j, r = result["jax"], result["reference"]
    print(f"backend {result['backend']} ({result['device']}, {result['cpu_count']} cpus), jax {result['jax_version']}")
    print(f"LE-LS lifetime: childhood {result['childhood_steps']:,} + 6 x {result['task_steps']:,} steps, "
          f"{result['individuals']} individuals = {result['lanes']} adult lanes")
    print(f"  jax        {j['lane_steps_per_s']:>14,.0f} lane-steps/s  (median of {args.repeats}, "
          f"{j['seconds']:.3f} s; compile + first run {j['compile_and_first_run_s']:.1f} s)")
    print(f"  reference  {r['lane_steps_per_s']:>14,.0f} lane-steps/s  (one individual, {r['seconds']:.1f} s)")
    print(f"  speed-up   {result['speedup']:>14,.0f} x")
    if args.json:
        os.makedirs(os.path.dirname(os.path.abspath(args.json)), exist_ok=True)
        with open(args.json, "w") as f:
            json.dump(result, f, indent=2)
    return 0


if __name__ == "__main__":
    sys.exit(main())
