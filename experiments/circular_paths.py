"""Claim 4 and the arena (docs/CLAIMS.md): what a stereotyped circular path can score on MODEL.md's six tasks.

    python -m experiments.circular_paths --out experiments/results/claims/circles

The paper explains EE-ES's fitness by "a stereotyped behavior such that the robot follows a circular
path at maximum speed which includes most of the target positions". This measures the simplest one:
a robot that ignores its retina and repeats one action (turn, speed) from each task's start, trial
after trial (``controllers.constant_performance``), for every action of a grid. A measure stage of
the claims study, done when ``result.json`` is written.
"""

from __future__ import annotations

import os
import sys

import numpy as np

from experiments.harness.measures import check_counts, check_out_dir, write_measure
from experiments.harness.study import MEASURED, RESULTS
from imrl_jax.runs import cli
from imrl_jax.runs.cli import HelpFormatter, Parser, UsageError, exit_codes

OUT = os.path.join(RESULTS, "claims", "circles")
#: The action grid: turn in [0, 1] (0.5 straight; 0 and 1 the 30 deg turns; steps of 0.06 deg), speed up to full.
TURNS = np.linspace(0.0, 1.0, 1001)
SPEEDS = np.linspace(0.5, 1.0, 6)
#: Steps per task: 20,000 (about 300-670 trips of the theoretical maximum; a constant action's
#: reaches repeat exactly trial after trial, so a longer task changes only the rounding).
TASK_STEPS = 20_000
#: MODEL.md's pairs (0-based): the tasks of a pair look alike up to their first junction.
PAIRS = ((0, 1), (2, 3), (4, 5))


def actions() -> np.ndarray:
    """(turns x speeds, 2) every action of the grid, turn-major."""
    return np.stack([values.ravel() for values in np.meshgrid(TURNS, SPEEDS, indexing="ij")], axis=1)


def summarise(grid: np.ndarray, performance: np.ndarray, pairs=PAIRS) -> dict:
    """The numbers the document quotes, from each action's (actions, tasks) performance."""
    def action(k: int) -> dict:
        """The turn and speed of the grid's ``k``-th action."""
        return dict(turn=float(grid[k, 0]), speed=float(grid[k, 1]))

    best = int(performance.mean(1).argmax())
    per_task = [dict(task=t + 1, performance=float(column.max()), **action(column.argmax()))
                for t, column in enumerate(performance.T)]
    per_pair = []
    for i, j in pairs:  # one action for both tasks of a pair: what it scores on the two together
        k = int((performance[:, i] + performance[:, j]).argmax())
        per_pair.append(dict(tasks=[i + 1, j + 1], performance=[float(performance[k, i]), float(performance[k, j])],
                             turn=float(grid[k, 0])))
    # One action per pair (a controller that tells the pairs apart by their first colour, but not the
    # tasks of a pair): the mean over the six tasks of each pair's best action.
    return dict(one_action=dict(performance=float(performance.mean(1)[best]), **action(best),
                                per_task=[float(v) for v in performance[best]]), per_task=per_task, per_pair=per_pair,
                one_action_per_pair=float(sum(sum(p["performance"]) for p in per_pair) / performance.shape[1]))


def figure(grid: np.ndarray, performance: np.ndarray, path: str) -> str:
    """Performance per task against the turn, at full speed; the mean over tasks in black."""
    from imrl_jax.analysis.plotting import new_figure, save, style_axis

    full = np.isclose(grid[:, 1], 1.0)
    fig = new_figure(6.4, 3.6)
    ax = fig.add_subplot()
    turn_deg = (grid[full, 0] - 0.5) * 60.0  # degrees per step, positive = left
    for t in range(performance.shape[1]):
        ax.plot(turn_deg, performance[full, t], lw=1.0, label=f"task {t + 1}")
    ax.plot(turn_deg, performance[full].mean(1), color="black", lw=2.0, label="mean of the six")
    ax.set(xlim=(-4, 4), ylim=(0, 1))
    style_axis(ax, "one constant action from each task's start, at full speed", "turn per step (deg, + left)",
               "task performance")
    ax.legend(fontsize=7, loc="upper right")
    fig.tight_layout()
    return save(fig, path)


def measure(out_dir: str = OUT, task_steps: int = TASK_STEPS) -> dict:
    """Every action of the grid on the six tasks; writes circles.png, circles.csv, then result.json (done)."""
    from imrl_jax.analysis import controllers
    from imrl_jax.config import make_config

    config, grid = make_config("paper"), actions()
    performance = np.asarray(controllers.constant_performance(config, grid, task_steps), float)
    figure(grid, performance, os.path.join(out_dir, "circles.png"))
    summary = summarise(grid, performance)
    rows = [dict(turn=f"{turn:.3f}", speed=f"{speed:.2f}", **{f"task_{t + 1}": f"{v:.4f}" for t, v in enumerate(row)},
                 mean=f"{row.mean():.4f}") for (turn, speed), row in zip(grid, performance)]
    write_measure(out_dir, "circles", rows, f"python -m experiments.circular_paths --out {out_dir} --task-steps "
                  f"{task_steps}", task_steps=task_steps, actions=len(grid), **summary)
    return summary


def parser() -> Parser:
    """The measure's command line."""
    p = Parser(prog="python -m experiments.circular_paths", description=__doc__.split("\n\n")[0],
               formatter_class=HelpFormatter)
    p.add_argument("--out", required=True, help="its folder (the claims study's stage gives its own)")
    p.add_argument("--task-steps", type=int, default=TASK_STEPS, help="steps per task")
    return p


def check_grid_memory(task_steps: int) -> None:
    """Refuse (one line) a grid whose steps' records cannot fit: each lane keeps a reach flag per step until summed."""
    from imrl_jax.evolution import devices
    from imrl_jax.config import make_config

    lanes = len(TURNS) * len(SPEEDS) * make_config("paper").num_tasks
    needed, have = devices.BASE_BYTES + 2 * lanes * task_steps, devices.available_memory()  # 2: XLA's copies
    if have is not None and needed > have:
        raise UsageError(f"memory: {lanes:,} lanes of {task_steps:,} steps need about {needed / 2**30:.1f} GiB but "
                         f"this machine has {have / 2**30:.1f} GiB available; use fewer --task-steps")


def plan(argv) -> cli.Call:
    """Parse and check: the call that measures the grid (nothing written before it)."""
    args = parser().parse_args(argv)
    check_counts(args, dict(task_steps=cli.MAX_STEPS))
    check_grid_memory(args.task_steps)
    check_out_dir(args.out, ("circles.png", "circles.csv", MEASURED), "circular-path measure")
    return cli.Call(lambda: report(args), out=args.out, task_steps=args.task_steps)


def report(args) -> int:
    """Measure and say what it found."""
    summary = measure(args.out, args.task_steps)
    print(f"one action for all six tasks: {summary['one_action']['performance']:.3f}; one per pair: "
          f"{summary['one_action_per_pair']:.3f}; wrote {args.out}")
    return 0


@exit_codes
def main(argv=None) -> int:
    """The measure's command line: the grid at ``--task-steps`` steps per task into ``--out``."""
    return cli.execute(plan(argv))


if __name__ == "__main__":
    sys.exit(main())
