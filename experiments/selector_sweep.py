"""Which learning-extension values make the adult selector learn (MODEL.md "Learning extensions").

    python -m experiments list|run selector-sweep     # its one stage, done once its result.json is written
    python -m experiments.selector_sweep --out experiments/results/selector_sweep sweep [--lambdas 0 ...]   # by hand

EE-LS without evolution: the three experts are fixed perceptron colour-followers
(:func:`imrl_jax.analysis.controllers.perceptron_followers`) and only the selector learns, once per
task, for a whole adult task (100,000 steps). The sweep is a full grid over the eligibility
trace lambda and the selector's actor and critic learning rates; every point lives the same
lanes with the same keys. The winner (highest mean task performance over the whole task,
since an evolved individual is scored on the whole task) becomes the ``extension`` preset.
It writes ``sweep.csv`` (one row per point), ``sweep.png``, ``sweep.json`` (the winner, the
paper's point, the command and the git commit) and last the same summary as ``result.json``,
which tells the runner the sweep is done.
"""

from __future__ import annotations

import argparse
import dataclasses
import itertools
import json
import math
import os
import sys
import time

import numpy as np

from experiments.harness.measures import check_counts, check_out_dir
from experiments.harness.study import MEASURED, RESULTS
from experiments.harness.table import Measure, Table
from imrl_jax.runs import cli

OUT = os.path.join(RESULTS, "selector_sweep")
#: The grid's axes (the command line's defaults): trace decay, selector actor rate, selector critic rate.
GRID = dict(lambdas="0,0.5,0.9,0.95,0.98", selector_actor_rates="0.01,0.1,0.3,1",
            selector_critic_rates="0.001,0.003,0.01")
#: The LearningParams fields of the grid's axes, in its order.
FIELDS = ("trace_lambda", "eta_selector_actor", "eta_selector_critic")
#: Its sizes: lanes per task and point, and the task's length.
SIZES = dict(seeds=3, task_steps=100_000)


def floats(text: str) -> list[float]:
    """A comma-separated list of numbers (a grid axis)."""
    try:
        return [float(v) for v in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a comma-separated list of numbers: {text!r}") from None


def parser() -> cli.Parser:
    """The sweep's command line."""
    p = cli.Parser(prog="python -m experiments.selector_sweep", description=__doc__.split("\n\n")[0],
                   formatter_class=cli.HelpFormatter)
    p.add_argument("sweep", choices=("sweep",))
    p.add_argument("--out", required=True, help="its folder (the study's stage gives its own)")
    p.add_argument("--task-steps", type=int, default=SIZES["task_steps"])
    p.add_argument("--seeds", type=int, default=SIZES["seeds"], help="lanes per task and point (different keys)")
    for name, default in GRID.items():
        p.add_argument(f"--{name.replace('_', '-')}", type=floats, default=default)
    p.add_argument("--turn-gain", type=float, default=0.1, help="the followers' turn weight per cm of offset")
    return p


#: What the sweep's folder may hold: its outputs, and the study runner's manifest and logs (the stage's folder is the
#: study's own).
OUTPUTS = ("sweep.csv", "sweep.png", "sweep.json", MEASURED, "manifest.json", "logs")
#: The followers' turn weight: past it a colour a few cm off turns the robot fully (tanh saturated).
MAX_TURN_GAIN = 100.0


def plan(argv: list[str]) -> cli.Call:
    """Parse and check every value, the grid's points, the memory and --out: the call that sweeps (nothing written)."""
    from imrl_jax.evolution import devices
    from imrl_jax.config import ConfigError, make_config

    args = parser().parse_args(argv)
    check_counts(args, dict(task_steps=cli.MAX_STEPS, seeds=cli.MAX_SEEDS))
    if not math.isfinite(args.turn_gain) or abs(args.turn_gain) > MAX_TURN_GAIN:
        raise cli.UsageError(f"--turn-gain: {args.turn_gain} is not a number in [-{MAX_TURN_GAIN:g}, "
                             f"{MAX_TURN_GAIN:g}]")
    config = make_config("paper", condition="EE-LS", task_steps=args.task_steps, num_bins=10)
    for name, field in zip(GRID, FIELDS):
        flag = f"--{name.replace('_', '-')}"
        for value in getattr(args, name):
            try:  # the config's bounds of the field: a NaN, a rate out of range
                config.replace(**{field: value})
            except ConfigError as error:
                raise cli.UsageError(f"{flag}: {error}") from None
        if len(set(getattr(args, name))) != len(getattr(args, name)):
            raise cli.UsageError(f"{flag}: a value given twice ({','.join(map(str, getattr(args, name)))})")
    grid = [dict(zip(FIELDS, point)) for point in itertools.product(*(getattr(args, name) for name in GRID))]
    lanes = len(grid) * args.seeds * config.num_tasks
    cli.check_at_most("lanes (points x --seeds x tasks)", lanes, cli.MAX_LANES)
    devices.check_memory(config, lanes, f"a sweep of {len(grid)} points x {args.seeds} seeds x {config.num_tasks} "
                         f"tasks")
    check_out_dir(args.out, OUTPUTS, "selector sweep")
    return cli.Call(lambda: sweep(args, argv, grid), out=args.out, grid=grid, lanes=lanes)


def sweep(args, argv: list[str], grid: list[dict]) -> int:
    """Live every point of the checked grid; write sweep.csv, sweep.png, sweep.json and result.json last."""
    import jax
    import jax.numpy as jnp

    from imrl_jax.evolution import sweeps
    from imrl_jax.runs.checkpoint import git_commit
    from imrl_jax.config import make_config
    from imrl_jax.analysis.controllers import perceptron_followers
    from imrl_jax.runs.rundir import csv_bytes, make_dir, write_atomic

    config = make_config("paper", condition="EE-LS", task_steps=args.task_steps, num_bins=10)
    genome = perceptron_followers(config, args.turn_gain).reshape(-1)
    lanes = len(grid) * args.seeds * config.num_tasks
    print(f"{len(grid)} points x {args.seeds} seeds x {config.num_tasks} tasks = {lanes} lanes of "
          f"{args.task_steps} steps", flush=True)
    genomes = jnp.broadcast_to(genome, (args.seeds,) + genome.shape)
    start = time.perf_counter()
    result = sweeps.make_lifetime_sweep(config)(jax.random.key(0), genomes, sweeps.from_settings(config, grid).points)
    performance = np.asarray(result.performance)  # (V, seeds, tasks)
    last = sweeps.normalised_curve(config, np.asarray(result.reward_curve))[..., -1]  # (V, seeds, tasks)
    seconds = time.perf_counter() - start
    print(f"done in {seconds:.0f} s ({lanes * args.task_steps / seconds / 1e6:.2f} M lane-steps/s)")

    make_dir(args.out)
    rows = [dict(point, performance=float(performance[i].mean()), performance_sd=float(performance[i].mean(1).std()),
                 last_tenth=float(last[i].mean()), worst_task=float(performance[i].mean(0).min()),
                 **{f"task_{t + 1}": float(performance[i, :, t].mean()) for t in range(config.num_tasks)})
            for i, point in enumerate(grid)]
    write_atomic(os.path.join(args.out, "sweep.csv"),  # LF lines, as the committed sweep.csv
                 csv_bytes([{k: (f"{v:.4f}" if isinstance(v, float) else v) for k, v in r.items()} for r in rows]))
    figure(rows, os.path.join(args.out, "sweep.png"), args.task_steps)
    best = max(rows, key=lambda r: r["performance"])
    # the paper's rules, when the grid holds them
    paper = next((r for r in rows if tuple(r[k] for k in FIELDS) == (0.0, 0.01, 0.01)), None)
    summary = dict(best=best, paper=paper, task_steps=args.task_steps, seeds=args.seeds, turn_gain=args.turn_gain,
                   seconds=round(seconds, 1), backend=jax.default_backend(),
                   command="python -m experiments.selector_sweep " + " ".join(argv), git_commit=git_commit())
    for name in ("sweep.json", MEASURED):  # result.json last: the stage is done
        write_atomic(os.path.join(args.out, name), json.dumps(summary, indent=2).encode())
    print(f"best: lambda={best['trace_lambda']:g} selector actor={best['eta_selector_actor']:g} "
          f"critic={best['eta_selector_critic']:g}: {best['performance']:.3f} (last tenth {best['last_tenth']:.3f})")
    if paper:
        print(f"paper's rules: {paper['performance']:.3f} (last tenth {paper['last_tenth']:.3f})")
    return 0


def figure(rows: list[dict], path: str, task_steps: int) -> str:
    """One panel per lambda: task performance over (selector actor rate, selector critic rate)."""
    from imrl_jax.analysis.plotting import new_figure, save

    lambdas, actor_rates, critic_rates = (sorted({r[k] for r in rows}) for k in FIELDS)
    fig = new_figure(3.0 * len(lambdas), 3.2)
    axes = fig.subplots(1, len(lambdas), squeeze=False)[0]
    for ax, lam in zip(axes, lambdas):
        image = np.full((len(actor_rates), len(critic_rates)), np.nan)
        for r in (r for r in rows if r["trace_lambda"] == lam):
            image[actor_rates.index(r["eta_selector_actor"]), critic_rates.index(r["eta_selector_critic"])] = \
                r["performance"]
        ax.imshow(image, vmin=0, vmax=1, cmap="viridis", origin="lower", aspect="auto")
        for (a, c), v in np.ndenumerate(image):
            ax.text(c, a, f"{v:.2f}", ha="center", va="center", color="w" if v < 0.5 else "k", fontsize=8)
        ax.set_xticks(range(len(critic_rates)), [f"{v:g}" for v in critic_rates])
        ax.set_yticks(range(len(actor_rates)), [f"{v:g}" for v in actor_rates])
        ax.set_xlabel("selector critic rate")
        ax.set_title(f"lambda = {lam:g}")
    axes[0].set_ylabel("selector actor rate")
    fig.suptitle(f"EE-LS selector over fixed colour-followers: task performance over {task_steps:,} steps")
    fig.tight_layout(rect=(0, 0, 1, 0.92))  # the panels' titles below the figure's
    return save(fig, path)


#: The study: one measure of no run, done once its committed folder holds result.json.
SWEEP = Table("selector-sweep", os.path.join("docs", "MODEL.md"), 0.5, rows=(), scale=SIZES, out=OUT, measures=(
    Measure("sweep", "", ("sweep",), "experiments.selector_sweep",
            float(5 * 4 * 3 * SIZES["seeds"] * 6 * SIZES["task_steps"]), "."),))
all_stages = SWEEP.all_stages


def main(argv=None) -> int:
    """The sweep (``sweep``), or the study's run of it on the stage runner."""
    argv = sys.argv[1:] if argv is None else list(argv)
    return measure_main(argv) if "sweep" in argv else SWEEP.main(argv)


@cli.exit_codes
def measure_main(argv: list[str]) -> int:
    """The sweep's command line: parse, plan, execute."""
    return cli.execute(plan(argv))


#: The studies of this module (python -m experiments finds them); its stage draws its figure, so no report of its own.
STUDIES = (dataclasses.replace(SWEEP.study(__name__.rsplit(".", 1)[-1]), report_argv=None),)

if __name__ == "__main__":
    sys.exit(main())
