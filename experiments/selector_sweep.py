"""Which learning-extension values make the adult selector learn (MODEL.md "Learning extensions").

EE-LS without evolution: the three experts are fixed perceptron colour-followers
(:func:`imrl_jax.controllers.perceptron_followers`) and only the selector learns, once per
task, for a whole adult task (100,000 steps). The sweep is a full grid over the eligibility
trace lambda and the selector's actor and critic learning rates; every point lives the same
lanes with the same keys. The winner (highest mean task performance over the whole task,
since an evolved individual is scored on the whole task) becomes the ``extension`` preset.

    python experiments/selector_sweep.py --out experiments/results/selector_sweep

Writes ``sweep.csv`` (one row per point), ``sweep.json`` (the winner, the paper's point,
the command and the git commit) and ``sweep.png``.
"""

from __future__ import annotations

import argparse
import csv
import itertools
import json
import os
import sys
import time

import numpy as np


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", default="experiments/results/selector_sweep")
    p.add_argument("--task-steps", type=int, default=100_000)
    p.add_argument("--seeds", type=int, default=3, help="lanes per task and point (different keys)")
    p.add_argument("--lambdas", default="0,0.5,0.9,0.95,0.98")
    p.add_argument("--selector-actor-rates", default="0.01,0.1,0.3,1")
    p.add_argument("--selector-critic-rates", default="0.001,0.003,0.01")
    p.add_argument("--turn-gain", type=float, default=0.1)
    args = p.parse_args(argv)

    import jax
    import jax.numpy as jnp

    from imrl_jax import sweeps
    from imrl_jax.checkpoint import git_commit
    from imrl_jax.config import make_config
    from imrl_jax.controllers import perceptron_followers
    from imrl_jax.plotting import new_figure, save

    floats = lambda text: [float(v) for v in text.split(",")]  # noqa: E731
    grid = list(itertools.product(floats(args.lambdas), floats(args.selector_actor_rates),
                                  floats(args.selector_critic_rates)))
    config = make_config("paper", condition="EE-LS", task_steps=args.task_steps, num_bins=10)
    sweep = sweeps.from_settings(config, [dict(trace_lambda=lam, eta_selector_actor=sa, eta_selector_critic=sc)
                                          for lam, sa, sc in grid])
    genome = perceptron_followers(config, args.turn_gain).reshape(-1)
    genomes = jnp.broadcast_to(genome, (args.seeds,) + genome.shape)
    lanes = len(grid) * args.seeds * config.num_tasks
    print(f"{len(grid)} points x {args.seeds} seeds x {config.num_tasks} tasks = {lanes} lanes of "
          f"{args.task_steps} steps", flush=True)
    start = time.perf_counter()
    result = sweeps.make_lifetime_sweep(config)(jax.random.key(0), genomes, sweep.points)
    performance = np.asarray(result.performance)  # (V, seeds, tasks)
    last = sweeps.normalised_curve(config, np.asarray(result.reward_curve))[..., -1]  # (V, seeds, tasks)
    seconds = time.perf_counter() - start
    print(f"done in {seconds:.0f} s ({lanes * args.task_steps / seconds / 1e6:.2f} M lane-steps/s)")

    os.makedirs(args.out, exist_ok=True)
    rows = []
    for i, (lam, sa, sc) in enumerate(grid):
        rows.append(dict(trace_lambda=lam, eta_selector_actor=sa, eta_selector_critic=sc,
                         performance=float(performance[i].mean()), performance_sd=float(performance[i].mean(1).std()),
                         last_tenth=float(last[i].mean()), worst_task=float(performance[i].mean(0).min()),
                         **{f"task_{t + 1}": float(performance[i, :, t].mean()) for t in range(config.num_tasks)}))
    with open(os.path.join(args.out, "sweep.csv"), "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows({k: (f"{v:.4f}" if isinstance(v, float) else v) for k, v in r.items()} for r in rows)
    best = max(rows, key=lambda r: r["performance"])
    paper = next((r for r in rows if (r["trace_lambda"], r["eta_selector_actor"], r["eta_selector_critic"])
                  == (0.0, 0.01, 0.01)), None)  # the paper's rules, when the grid holds them
    summary = dict(best=best, paper=paper, task_steps=args.task_steps, seeds=args.seeds, turn_gain=args.turn_gain,
                   seconds=round(seconds, 1), backend=jax.default_backend(),
                   command="python experiments/selector_sweep.py " + " ".join(argv if argv is not None else sys.argv[1:]),
                   git_commit=git_commit())
    with open(os.path.join(args.out, "sweep.json"), "w") as f:
        json.dump(summary, f, indent=2)

    # One panel per lambda: performance over (selector actor rate, selector critic rate).
    lambdas, actor_rates, critic_rates = (sorted(set(v)) for v in zip(*grid))
    fig = new_figure(3.0 * len(lambdas), 3.0)
    axes = fig.subplots(1, len(lambdas), squeeze=False)[0]
    for ax, lam in zip(axes, lambdas):
        image = np.full((len(actor_rates), len(critic_rates)), np.nan)
        for r in rows:
            if r["trace_lambda"] == lam:
                image[actor_rates.index(r["eta_selector_actor"]), critic_rates.index(r["eta_selector_critic"])] = \
                    r["performance"]
        ax.imshow(image, vmin=0, vmax=1, cmap="viridis", origin="lower")
        for (a, c), v in np.ndenumerate(image):
            ax.text(c, a, f"{v:.2f}", ha="center", va="center", color="w" if v < 0.5 else "k", fontsize=8)
        ax.set_xticks(range(len(critic_rates)), [f"{v:g}" for v in critic_rates])
        ax.set_yticks(range(len(actor_rates)), [f"{v:g}" for v in actor_rates])
        ax.set_xlabel("selector critic rate")
        ax.set_title(f"lambda = {lam:g}")
    axes[0].set_ylabel("selector actor rate")
    fig.suptitle(f"EE-LS selector over fixed colour-followers: task performance over {args.task_steps:,} steps")
    save(fig, os.path.join(args.out, "sweep.png"))
    print(f"best: lambda={best['trace_lambda']:g} selector actor={best['eta_selector_actor']:g} "
          f"critic={best['eta_selector_critic']:g}: {best['performance']:.3f} (last tenth {best['last_tenth']:.3f})")
    if paper:
        print(f"paper's rules: {paper['performance']:.3f} (last tenth {paper['last_tenth']:.3f})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
