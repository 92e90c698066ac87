"""``python -m experiments list|run|report NAME|all``: every study, found by itself (docs/STUDIES.md).

    python -m experiments list                # each study: stages and hours left, its document, its whole hours on
                                              # this CPU and on a GPU (experiments/harness/gpu_hours.py: docs/gpu speeds)
    python -m experiments list search         # a study's stages and their commands, nothing run
    python -m experiments run all             # run (or go on with) every study in order
    python -m experiments run timescale       # one study
    python -m experiments run search --jobs 2 # its independent stages two at a time (or --executor slurm)
    python -m experiments report all          # every study's tables and figures from what has finished

Each study runs as its own resumable command on the shared stage runner: a finished study passes
in seconds, an interrupted one goes on where it stopped, and a failed one stops ``all`` with its exit
code. ``all`` runs them in the order their results are needed (whole questions early).
"""

from __future__ import annotations

import functools
import os
import subprocess
import sys
from typing import NamedTuple

from experiments.harness import gpu_hours
from experiments.harness.executor import add_options, dying_with_runner, options_argv
from experiments.harness.reproduce import MANIFEST, cost_left, read_manifest, stage_done
from experiments.harness.study import environment, studies
from imrl_jax.runs import cli

#: Lane-steps per second of the estimates: the claims study's paper-length evolutions on 2 cores, as its
#: manifest measured them (7 evolutions, 7.9 h, 2026-12-03; learning tests ran at about the same rate).
RATE = 2.9e6


@functools.lru_cache(maxsize=None)
def _world_factor(world: str) -> float:
    from imrl_jax.runs.progress import world_factor

    return world_factor(world) or 1.0  # a world the benchmark has not measured: the arena's speed


def stage_rate(stage, rate: float = RATE) -> float:
    """The lane-steps per second of ``stage`` on this CPU: ``rate`` in the arena; in another world, ``rate`` times how
    fast the agent lives there against the arena (``bench --world``'s files in docs/bench)."""
    return rate * _world_factor(stage.world)


def remaining(study, rate: float = RATE, planned=None) -> tuple[int, int, float]:
    """Stages left, stages in all, and the hours what is left costs at ``rate`` (a started stage counts its part left;
    a stage in another world at its world's speed); ``planned``: the study's stages and scale, if already planned."""
    stages, scale = planned or study.stages()
    left = [s for s in stages if not stage_done(s, scale)]
    return len(left), len(stages), sum(cost_left(s, scale) / stage_rate(s, rate) for s in stages) / 3600


def listing(chosen, planned) -> list[str]:
    """Each chosen study's stages left and hours; one study's stages and commands (the lines of ``list``)."""
    if len(chosen) == 1:
        study, (stages, scale) = chosen[0], planned[0]
        return [f"{study.name} ({study.document}): python {' '.join(study.command()[1:])}"] + [
            f"  {stage.name}: {'done' if stage_done(stage, scale) else 'to run'} ({stage.out_dir})" for stage in stages]
    lines, total, speed = [], [0.0, 0.0, 0.0], gpu_hours.read_speed()
    for study, plan in zip(chosen, planned):
        left, count, hours = remaining(study, planned=plan)
        whole = sum(s.cost / stage_rate(s) for s in plan[0]) / 3600
        gpu = gpu_hours.study_hours(*plan, speed)
        total = [total[0] + hours, total[1] + whole, total[2] + (gpu or 0.0)]
        lines.append(f"{study.name:>16}: {left:>2} of {count:>2} stages left, about {hours:5.1f} h ({study.document}); "
                     f"whole: {whole:5.1f} h on this CPU" + ("" if gpu is None else f", {gpu:5.2f} h on a GPU"))
    measured = ("no GPU measured (docs/gpu holds no gpu_check.json)" if speed is None else
                f"{total[2]:.1f} h on one {speed.device} ({speed.source}: its generations' speeds, step_kernel=auto)")
    return lines + [f"{'in all':>16}: about {total[0]:.0f} h left at {RATE / 1e6:.1f} million lane-steps a second "
                    f"(the claims study's evolutions on 2 cores; another world's stages at its benchmarked share of "
                    f"that); whole: {total[1]:.0f} h on this CPU, {measured}"]


def run_studies(chosen, report: bool = False, options: tuple[str, ...] = ()) -> int:
    """Run (or report) each chosen study in turn; the first failure or Ctrl-C stops the rest."""
    what = "report" if report else "study"
    for study in chosen:
        if report and study.report_argv is None:
            print(f"\n=== {study.name}: no report of its own (a stage of its run writes it, or none is written yet)",
                  flush=True)
            continue
        print(f"\n=== {what} {study.name}", flush=True)
        # the study's runner dies with this one (a killed command leaves no study, and so no stage, running)
        process = subprocess.Popen(dying_with_runner(study.command(report, options)), env=environment())
        try:
            code = process.wait()
        except KeyboardInterrupt:
            # The study got the same signal (one process group): it stops its stages and keeps what they finished,
            # however long that takes (subprocess.run would kill it a quarter of a second later). A second Ctrl-C
            # does not wait.
            try:
                process.wait()
            except KeyboardInterrupt:
                process.kill()
                process.wait()
            print(f"\ninterrupted in {what} {study.name}: run the same command again to go on", file=sys.stderr)
            return 130
        if code == 2:  # refused: its own line said why, and the same command would be refused again
            print(f"error: {what} {study.name} refused (exit code 2; its error above says why)", file=sys.stderr)
            return code
        if code:
            print(f"error: {what} {study.name} stopped with exit code {code}; run the same command again to go on",
                  file=sys.stderr)
            return code
    return 0


class Listing(NamedTuple):
    """``list``: the lines to print, every study planned."""

    lines: list[str]

    def execute(self) -> int:
        print("\n".join(self.lines))
        return 0


class Running(NamedTuple):
    """``run`` or ``report``: the studies, each planned and checked, and the runner's options for their commands."""

    studies: tuple
    report: bool
    options: tuple[str, ...]

    def execute(self) -> int:
        return run_studies(self.studies, report=self.report, options=self.options)


def parser(found) -> cli.Parser:
    """The command line's parser, with the studies ``found``."""
    p = cli.Parser(prog="python -m experiments", description=__doc__.split("\n\n")[0])
    p.add_argument("action", choices=("list", "run", "report"))
    p.add_argument("study", nargs="?", default="all", help=f"a study or all (default): {', '.join(found)}")
    add_options(p)
    return p


def plan(args, found) -> Listing | Running:
    """What the command will do: the studies chosen, their stages planned, their manifests read and checked, none
    held by another runner (``run``); raises a user error, writes nothing."""
    if args.study != "all" and args.study not in found:
        raise cli.UsageError(f"study: unknown study {args.study[:100]!r} (choose from all, {', '.join(found)})")
    chosen = list(found.values()) if args.study == "all" else [found[args.study]]
    planned = [study.stages() for study in chosen]  # a run of two folders (DuplicateRunError), an unreadable config
    for study in chosen:
        folder = study.folder()
        if folder is not None:
            read_manifest(os.path.join(folder, MANIFEST))
            if args.action == "run":
                from experiments.harness.runner import check_free

                check_free(study.name, folder)
    if args.action == "list":
        return Listing(listing(chosen, planned))
    return Running(tuple(chosen), args.action == "report", tuple(options_argv(args)))


@cli.exit_codes
def main(argv=None) -> int:
    """The command line: list, run or report one study or all of them (parse, plan, ``cli.execute``)."""
    found = studies()
    return cli.execute(plan(parser(found).parse_args(argv), found))


if __name__ == "__main__":
    sys.exit(main())
