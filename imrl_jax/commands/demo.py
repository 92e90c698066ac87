"""A short CPU example of the model: the six tasks solved, and one random individual's life (section 2).

    python -m imrl_jax.demo --out out/demo [--condition LE-LS] [--seed 0] [--overwrite]

Draws what solving the tasks looks like (a hand-written composition of three colour
followers, :mod:`imrl_jax.analysis.controllers`: not evolved, a reference) beside one random
individual of the condition, as evolution starts from it, living at reduced length (the
``small`` preset: 15,000 childhood steps, 5,000 steps per task). Prints the individual's
fitness and per-task performance and writes ``trajectories.png`` (paths coloured by the
expert in control) and ``summary.json``.
"""

from __future__ import annotations

import json
import os
import sys
import time

import jax
import numpy as np

from imrl_jax.runs import cli
from imrl_jax.runs.cli import HelpFormatter, Parser, add_task_set, apply_task_set, check_out, exit_codes
from imrl_jax.config import CONDITIONS, PRESETS, Config, make_config
from imrl_jax.runs.rundir import check_outputs_dir, check_writable, write_atomic

PATH_STEPS = 400  # steps of each task path drawn after the lifetime
CHILDHOOD_PATH_STEPS = 2000
FOLLOWS = ("follows red", "follows green", "follows blue")


OUTPUTS = ("trajectories.png", "summary.json")


def run(config: Config, out_dir: str, seed: int = 0, overwrite: bool = False) -> dict:
    """Drive the composition, live one random individual, write the figure and summary into ``out_dir``; return the summary.

    ``out_dir`` is new, empty, or (with ``overwrite``) a demo's output.
    """
    from imrl_jax.analysis import behaviour, controllers
    from imrl_jax.agent.lifetime import live
    from imrl_jax.analysis.arena_figures import plot_paths
    from imrl_jax.analysis.plotting import save

    check_writable(out_dir)
    check_outputs_dir(out_dir, OUTPUTS, "demo output", overwrite)
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

    # Paths: the first childhood steps (the same draws as the life), then each task from the
    # weights the selector had at the end of that task.
    childhood = None
    if config.spec.has_childhood:
        childhood = behaviour.childhood_trajectory(key_life, config, params, genome, CHILDHOOD_PATH_STEPS)
    paths = behaviour.task_trajectories(key_paths, config, params, result.adult_agents, PATH_STEPS)
    solved = controllers.trajectories(config, PATH_STEPS)
    trips = np.asarray(config.steps_per_trip())
    solved_performance = [float(t.reached.sum() * n / PATH_STEPS) for t, n in zip(solved, trips)]

    scale = f"childhood {config.childhood_steps:,} steps, " if config.spec.has_childhood else ""
    rows = [
        dict(name="The tasks solved: a hand-written composition of three colour followers (not evolved), "
                  "one colour per edge of the route",
             tasks=[dict(t.as_path(), label=f"perf {p:.2f}") for t, p in zip(solved, solved_performance)],
             experts=list(FOLLOWS[:config.num_experts])),
        dict(name=f"A random {config.condition} individual (what evolution starts from), fitness {fitness:.3f}: "
                  f"its selector switches expert almost every step",
             childhood=childhood.as_path() if childhood is not None else None,
             tasks=[dict(t.as_path(), label=f"perf {float(p):.2f}") for t, p in zip(paths, result.performance)]),
    ]
    title = (f"Paths coloured by the expert in control, {PATH_STEPS} steps per task (the robot restarts at the "
             f"start after each reach or timeout);\nthe random individual after its life at reduced scale "
             f"({scale}{config.task_steps:,} steps per task)")
    figure = save(plot_paths(config, rows, title), os.path.join(out_dir, "trajectories.png"))
    summary = {
        "condition": config.condition,
        "seed": seed,
        "childhood_steps": config.childhood_steps if config.spec.has_childhood else 0,
        "task_steps": config.task_steps,
        "fitness": fitness,
        "performance": [float(p) for p in result.performance],
        "reaches": [int(r) for r in result.reaches],
        "timeouts": [int(t) for t in result.timeouts],
        "composition_performance": solved_performance,
        "seconds_with_compile": seconds,
        "figure": figure,
    }
    write_atomic(os.path.join(out_dir, "summary.json"), json.dumps(summary, indent=2).encode())
    return summary


def parser() -> Parser:
    """The demo command line's parser."""
    p = Parser(prog="python -m imrl_jax.demo", description=__doc__.split("\n")[0], formatter_class=HelpFormatter)
    p.add_argument("--out", default="out/demo", help="output directory")
    p.add_argument("--condition", default="LE-LS", choices=CONDITIONS, help="condition of the random individual")
    p.add_argument("--seed", type=int, default=0, help="random seed of the individual and its life")
    p.add_argument("--preset", default="small", choices=sorted(PRESETS),
                   help="config preset (small: reduced scale, about a minute on a CPU)")
    add_task_set(p, "the tasks", default="paper")
    p.add_argument("--overwrite", action="store_true", help="replace the outputs of an earlier demo in --out")
    return p


@exit_codes
def main(argv=None) -> int:
    args = parser().parse_args(argv)
    check_out(args.out)
    config = apply_task_set(make_config(args.preset, condition=args.condition), args)
    cli.check_key("--seed", args.seed)
    check_writable(args.out)
    check_outputs_dir(args.out, OUTPUTS, "demo output", args.overwrite)
    return cli.execute(cli.Call(lambda: report(config, args), config=config, out=args.out))


def report(config: Config, args) -> int:
    """Run the demo the command line checked and print what it found."""
    summary = run(config, args.out, args.seed, args.overwrite)
    print(f"{config.condition} individual (seed {args.seed}), reduced scale: childhood "
          f"{summary['childhood_steps']:,} steps, {config.task_steps:,} steps per task")
    for i, (p, r) in enumerate(zip(summary["performance"], summary["reaches"])):
        print(f"  task {i + 1}: {r:4d} reaches, performance {p:.3f}")
    print(f"fitness {summary['fitness']:.3f}  ({summary['seconds_with_compile']:.1f} s with compilation)")
    print("the hand-written colour followers, for comparison: performance "
          + " ".join(f"{p:.2f}" for p in summary["composition_performance"]))
    print(f"wrote {summary['figure']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
