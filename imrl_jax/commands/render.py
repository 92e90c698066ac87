"""``python -m imrl_jax.render``: a life of the best individual of an evolution on one task, drawn (section 3, Fig. 1).

    python -m imrl_jax.render RUN_DIR --task K --out FILE.gif [--steps 300] [--every 2] [--fps 20]
    python -m imrl_jax.render RUN_DIR --task K --out FILE.png [--steps 300]     (a still: another world's run)

RUN_DIR is a run directory of ``python -m imrl_jax.evolve`` (``config.json`` and
``final_population.npz``). The individual is the fittest of all seeds in the last
evaluated generation. It lives the very life that earned its fitness (the run's keys),
which trains its experts in childhood (LE-LS) and its selector on every task; then it
drives task K (1 to the world's number of tasks) from the weights it ended that task with, for ``--steps`` steps,
recorded with :func:`imrl_jax.agent.lifetime.simulate`. The world the run lived in (``config.json``'s ``world``)
chooses the drawing, in one table (:data:`DRAWERS`): the arena's animation shows the arena with the
task, the path coloured by the expert in control, the robot with its retina patch, a
zoom on the robot and the retina's 2 x 6 view (``.gif``, ``.mp4``); XLand's
(:mod:`imrl_jax.analysis.xland_figures`) shows the room as the world's state has it (an opened door, a picked key),
the agent as a triangle pointing its way, its path coloured by the expert in control, its 3 x 3 view and the expert
at every step, as a still of the whole path (``.png``) or animated (``.gif``, ``.mp4``). ``.gif`` is written with
Pillow; ``.mp4`` needs ffmpeg on PATH.

Bad input (a missing or incomplete run directory, a task out of range, an unknown
extension or one the run's world is not drawn in, ``--every`` or ``--fps`` for a still, an output that exists,
without ``--overwrite``) gets a one-line error and exit
code 2, and nothing is written. Only FILE is ever written (through a temporary file in
its directory, renamed when complete).
"""

from __future__ import annotations

import argparse
import importlib
import os
import shutil
import sys
import time
from typing import NamedTuple

import numpy as np

from imrl_jax.runs.cli import HelpFormatter, Parser, UsageError, add_register, exit_codes, register
from imrl_jax.runs import cli
from imrl_jax.runs.rundir import check_writable, load_run

FORMATS = (".gif", ".mp4", ".png")
#: Formats that hold one picture (no frames: ``--every`` and ``--fps`` make no sense there).
STILLS = (".png",)
#: ``--every`` and ``--fps`` when not given.
DEFAULT_EVERY, DEFAULT_FPS = 2, 20


class Drawer(NamedTuple):
    """How a life in one world is recorded and drawn: ``"module:function"`` names, imported when used."""

    formats: tuple[str, ...]
    # (key, config, params, agent, task (0-based), steps) -> the recorded steps (with ``reached``)
    record: str
    # (config, life, path, task=, every=, fps=, title=, expressed=) -> frames written
    draw: str


#: Each world's drawing by its name (``config.world``): the one place render tells the worlds apart.
DRAWERS = {
    "arena": Drawer((".gif", ".mp4"), "imrl_jax.analysis.behaviour:task_trajectory",
                    "imrl_jax.analysis.arena_figures:write_animation"),
    "xland": Drawer((".png", ".gif", ".mp4"), "imrl_jax.analysis.xland_figures:task_life",
                    "imrl_jax.analysis.xland_figures:write_life"),
}


def _function(name: str):
    module, attribute = name.split(":")
    return getattr(importlib.import_module(module), attribute)


def drawer(world: str, ext: str) -> Drawer:
    """The drawing of a life in ``world`` as a file of extension ``ext``; raises UsageError if there is none."""
    if world not in DRAWERS:
        raise UsageError(f"run_dir: render draws no life in world {world!r} (it draws: {', '.join(DRAWERS)})")
    found = DRAWERS[world]
    if ext not in found.formats:
        raise UsageError(f"--out: a life in world {world} is drawn as {' or '.join(found.formats)}, not {ext}")
    return found


class Best(NamedTuple):
    """The fittest individual of a run's last evaluated generation and where it came from."""

    config: object  # Config
    genome: np.ndarray
    seed: int
    index: int  # in its seed's population
    generation: int  # 0-based generation it was evaluated in
    fitness: float


def best_individual(run_dir: str) -> Best:
    """The fittest individual over all seeds of the last evaluated generation of a run."""
    run = load_run(run_dir)
    s, i = np.unravel_index(int(np.argmax(run.fitness)), run.fitness.shape)
    return Best(run.config, run.evaluated[s, i], run.seeds[s], int(i), run.generation - 1, float(run.fitness[s, i]))


def check_output(out_path: str, overwrite: bool = False) -> str:
    """The output's extension after checking the path can be written; raises UsageError."""
    ext = os.path.splitext(out_path)[1].lower()
    if ext not in FORMATS:
        raise UsageError(f"--out: unknown extension {ext or '(none)'!r} (use {' or '.join(FORMATS)})")
    if ext == ".mp4" and shutil.which("ffmpeg") is None:
        raise UsageError("--out: writing .mp4 needs ffmpeg on PATH (not found); write a .gif instead")
    if os.path.isdir(out_path):
        raise UsageError(f"--out: {out_path} is a directory")
    if os.path.exists(out_path) and not overwrite:
        raise UsageError(f"--out: {out_path} exists (pass --overwrite to replace it)")
    check_writable(os.path.dirname(os.path.abspath(out_path)))
    return ext


#: The most steps an animation follows, frames it draws (each is a matplotlib figure) and frames per second.
MAX_STEPS = 100_000
MAX_FRAMES = 5_000
MAX_FPS = 100


def check_sizes(steps: int, every: int, fps: int, still: bool = False) -> None:
    """Refuse sizes that would run for hours or overflow (raises UsageError naming the option and its limit); a
    still has no frames to count."""
    if steps < 1 or every < 1 or fps < 1:
        raise UsageError("--steps, --every and --fps must be at least 1")
    for flag, value, limit in (("--steps", steps, MAX_STEPS), ("--every", every, MAX_STEPS), ("--fps", fps, MAX_FPS)):
        if value > limit:
            raise UsageError(f"{flag}: {value:,} is above the limit of {limit:,}")
    frames = -(-steps // every)
    if frames > MAX_FRAMES and not still:
        raise UsageError(f"--steps / --every: {frames:,} frames is above the limit of {MAX_FRAMES:,} (raise --every)")


class Plan(NamedTuple):
    """An animation checked and ready to draw: nothing written yet (``imrl_jax.runs.cli``)."""

    run_dir: str
    task: int  # 1-based
    out_path: str
    steps: int
    every: int
    fps: int
    best: Best

    def execute(self) -> int:
        """Draw the picture into ``out_path`` (through a temporary file renamed when complete) and say so."""
        summary = animate(self)
        shown = ("a still" if os.path.splitext(summary["out"])[1].lower() in STILLS else
                 f"{summary['frames']} frames")
        print(f"wrote {summary['out']}: {shown} of task {summary['task']} "
              f"(best individual: seed {summary['seed']}, generation {summary['generation']}, fitness "
              f"{summary['fitness']:.3f}, relived {summary['relived_fitness']:.3f}; "
              f"{summary['reaches_in_animation']} reaches shown) in {summary['seconds']:.1f} s")
        return 0


def plan(run_dir: str, task: int, out_path: str, steps: int = 300, every: int | None = None, fps: int | None = None,
         overwrite: bool = False) -> Plan:
    """Every check of a drawing (sizes, output, the run, its world, the task), nothing written; raises UsageError.
    ``every`` and ``fps`` (None: not given) are an animation's: refused for a still."""
    still = os.path.splitext(out_path)[1].lower() in STILLS
    for flag, value in (("--every", every), ("--fps", fps)):
        if still and value is not None:
            raise UsageError(f"{flag}: {os.path.basename(out_path)} is a still, it has no frames (leave {flag} out, "
                             f"or write a .gif)")
    every, fps = DEFAULT_EVERY if every is None else every, DEFAULT_FPS if fps is None else fps
    check_sizes(steps, every, fps, still)
    ext = check_output(out_path, overwrite)
    best = best_individual(run_dir)
    drawer(best.config.world, ext)
    if not 1 <= task <= best.config.num_tasks:
        raise UsageError(f"--task: must be in 1..{best.config.num_tasks} (got {task})")
    return Plan(run_dir, task, out_path, steps, every, fps, best)


def run(run_dir: str, task: int, out_path: str, steps: int = 300, every: int | None = None, fps: int | None = None,
        overwrite: bool = False) -> dict:
    """Draw the best individual of ``run_dir`` on task ``task`` (1-based) into ``out_path``; return a summary."""
    return animate(plan(run_dir, task, out_path, steps, every, fps, overwrite))


def animate(checked: Plan) -> dict:
    """The drawing of a checked plan, written; its summary."""
    run_dir, task, out_path, steps, every, fps, best = checked
    config = best.config
    drawing = drawer(config.world, os.path.splitext(out_path)[1].lower())

    import jax
    import jax.numpy as jnp

    from imrl_jax.agent.lifetime import live
    from imrl_jax.evolution import search

    start = time.perf_counter()
    params = config.learning_params()
    key = search.life_key(config, best.seed, best.generation, best.index)
    result = jax.jit(live, static_argnums=1)(key, config, params, jnp.asarray(best.genome, jnp.float32))
    agent = jax.tree.map(lambda x: x[task - 1], result.adult_agents)
    trajectory = _function(drawing.record)(jax.random.fold_in(key, task), config, params, agent, task - 1, steps)

    title = (f"{config.condition}, best individual of {os.path.basename(os.path.normpath(run_dir))} "
             f"(seed {best.seed}, generation {best.generation}, fitness {best.fitness:.3f})\n"
             f"task {task}: {steps} steps after its {config.task_steps:,}-step learning period")
    directory = os.path.dirname(os.path.abspath(out_path))
    os.makedirs(directory, exist_ok=True)
    base, ext = os.path.splitext(os.path.basename(out_path))
    tmp = os.path.join(directory, f".{base}.tmp-{os.getpid()}{ext}")
    try:
        frames = _function(drawing.draw)(config, trajectory, tmp, task=task - 1, every=every, fps=fps, title=title,
                                         expressed=agent.expressed)
        os.replace(tmp, out_path)
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)
    return {"out": out_path, "frames": frames, "task": task, "seed": best.seed, "index": best.index,
            "generation": best.generation, "fitness": best.fitness, "relived_fitness": float(result.fitness),
            "task_performance": float(result.performance[task - 1]),
            "reaches_in_animation": int(trajectory.reached.sum()), "seconds": time.perf_counter() - start}


def parser() -> argparse.ArgumentParser:
    p = Parser(prog="python -m imrl_jax.render",
               description="Draw (animate, or for a run in another world than the arena also a still) the best "
                           "individual of an evolve run on one task.",
               formatter_class=HelpFormatter)
    p.add_argument("run_dir", metavar="RUN_DIR", help="run directory of python -m imrl_jax.evolve")
    p.add_argument("--task", type=int, required=True, help="task to show, 1 to the world's number of tasks (6)")
    p.add_argument("--out", required=True,
                   help="animation file, .gif (or .mp4 with ffmpeg on PATH); or, for a run in another world than the "
                        "arena, a still .png")
    p.add_argument("--steps", type=int, default=300, help=f"steps of the task to show (at most {MAX_STEPS:,})")
    p.add_argument("--every", type=int,
                   help=f"one frame every this many steps (at most {MAX_FRAMES:,} frames in all; default "
                        f"{DEFAULT_EVERY}; an animation's only)")
    p.add_argument("--fps", type=int, help=f"frames per second (at most {MAX_FPS}; default {DEFAULT_FPS}; an "
                                           f"animation's only)")
    p.add_argument("--overwrite", action="store_true", help="replace --out if it exists")
    add_register(p)
    return p


@exit_codes
def main(argv=None) -> int:
    args = parser().parse_args(argv)
    register(args.register)
    return cli.execute(plan(args.run_dir, args.task, args.out, args.steps, args.every, args.fps, args.overwrite))


if __name__ == "__main__":
    sys.exit(main())
