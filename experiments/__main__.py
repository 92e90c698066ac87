"""``python -m experiments list|run|report NAME|all``: every study, found by itself (docs/STUDIES.md).

    python -m experiments list                # each study: stages left, estimated hours, its document
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

import argparse
import subprocess
import sys

from experiments.executor import add_options, options_argv
from experiments.reproduce import cost_left, stage_done
from experiments.study import environment, studies

#: Lane-steps per second of the estimates: the claims study's paper-length evolutions on 2 cores, as its
#: manifest measured them (7 evolutions, 7.9 h, 2026-12-03; learning tests ran at about the same rate).
RATE = 2.9e6


def remaining(study, rate: float = RATE) -> tuple[int, int, float]:
    """Stages left, stages in all, and the hours what is left costs at ``rate`` (a started stage counts its part left)."""
    stages, scale = study.stages()
    left = [s for s in stages if not stage_done(s, scale)]
    return len(left), len(stages), sum(cost_left(s, scale) for s in stages) / rate / 3600


def list_studies(chosen) -> int:
    """Each chosen study's stages left and hours; one study's stages and commands."""
    if len(chosen) == 1:
        study = chosen[0]
        stages, scale = study.stages()
        print(f"{study.name} ({study.document}): python {' '.join(study.command()[1:])}")
        for stage in stages:
            print(f"  {stage.name}: {'done' if stage_done(stage, scale) else 'to run'} ({stage.out_dir})")
        return 0
    total = 0.0
    for study in chosen:
        left, count, hours = remaining(study)
        total += hours
        print(f"{study.name:>16}: {left:>2} of {count:>2} stages left, about {hours:5.1f} h ({study.document})")
    print(f"{'in all':>16}: about {total:.0f} h at {RATE / 1e6:.1f} million lane-steps a second (the claims "
          f"study's evolutions on 2 cores)")
    return 0


def run_studies(chosen, report: bool = False, options: tuple[str, ...] = ()) -> int:
    """Run (or report) each chosen study in turn; the first failure or Ctrl-C stops the rest."""
    what = "report" if report else "study"
    for study in chosen:
        if report and study.report_argv is None:
            print(f"\n=== {study.name}: no report of its own (a stage of its run writes it, or none is written yet)",
                  flush=True)
            continue
        print(f"\n=== {what} {study.name}", flush=True)
        process = subprocess.Popen(study.command(report, options), env=environment())
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
        if code:
            print(f"error: {what} {study.name} stopped with exit code {code}; run the same command again to go on",
                  file=sys.stderr)
            return code
    return 0


def main(argv=None) -> int:
    """The command line: list, run or report one study or all of them."""
    found = studies()
    p = argparse.ArgumentParser(prog="python -m experiments", description=__doc__.split("\n\n")[0])
    p.add_argument("action", choices=("list", "run", "report"))
    p.add_argument("study", nargs="?", default="all", help=f"a study or all (default): {', '.join(found)}")
    add_options(p)
    args = p.parse_args(argv)
    if args.study != "all" and args.study not in found:
        print(f"error: study: unknown study {args.study!r} (choose from all, {', '.join(found)})", file=sys.stderr)
        return 2
    chosen = list(found.values()) if args.study == "all" else [found[args.study]]
    if args.action == "list":
        from imrl_jax.rundir import RunDirError

        try:
            return list_studies(chosen)
        except RunDirError as error:  # two folders of one run (runspec.DuplicateRunError), an unreadable config.json
            print(f"error: {error}", file=sys.stderr)
            return 2
    return run_studies(chosen, report=args.action == "report", options=tuple(options_argv(args)))


if __name__ == "__main__":
    sys.exit(main())
