"""The studies in the order their results are needed, one after another: one command for every sitting.

    python -m experiments.queue --list     # each study's stages left and its estimated hours, nothing run
    python -m experiments.queue            # run (or go on with) each study in turn

Each study is its own resumable command on the shared stage runner (``reproduce.run_stages``),
run as a subprocess; a finished study passes in seconds, an interrupted one goes on where it
stopped, and a failed one stops the queue with its exit code. The order answers whole questions
early: the selector's time-scale and tasks never met in evolution (together one issue, about a
third of the claims study's cost), then the claims map's screen (it decides which rule set
reproduces the paper, and the future work needs it), that rule set at full scale (the
reproduction's ``faithful`` variant: ``make reproduce``), claim 8's runs, the search strategies,
and last the paper's future work.
"""

from __future__ import annotations

import argparse
import importlib
import os
import subprocess
import sys
from typing import NamedTuple

from experiments.reproduce import cost_left, stage_done

class Study(NamedTuple):
    """One entry of the queue: a module under experiments/, its document, and its command line's options."""

    module: str
    document: str
    argv: tuple[str, ...] = ()  # (): the module's default stages (its ``all_stages``)


#: The studies, in order.
STUDIES = (Study("timescale", "docs/TIMESCALE.md"), Study("novel_tasks", "docs/NOVEL_TASKS.md"),
           Study("claims_study", "docs/CLAIMS.md", ("--only", "screen")),
           Study("reproduce", "docs/REPRODUCTION.md", ("--scale", "paper")),
           Study("claims_study", "docs/CLAIMS.md", ("--only", "experts")),
           Study("search", "docs/SEARCH.md"), Study("future_work", "docs/FUTURE_WORK.md"))
#: Lane-steps per second of the estimates: the claims study's paper-length evolutions on 2 cores, as its
#: manifest measured them (7 evolutions, 7.9 h, 2026-12-03; learning tests ran at about the same rate).
RATE = 2.9e6


def remaining(module: str, rate: float = RATE, argv: tuple[str, ...] = ()) -> tuple[int, int, float]:
    """Stages left, stages in all, and the hours what is left costs at ``rate`` lane-steps a second (a started stage counts its part left)."""
    study = importlib.import_module(f"experiments.{module}")
    stages, scale = study.stages_for(list(argv)) if argv else study.all_stages()
    left = [s for s in stages if not stage_done(s, scale)]
    return len(left), len(stages), sum(cost_left(s, scale) for s in stages) / rate / 3600


def main(argv=None) -> int:
    """The command line: list what is left, or run each study in turn."""
    p = argparse.ArgumentParser(prog="python -m experiments.queue", description=__doc__.split("\n\n")[0])
    p.add_argument("--list", action="store_true", help="each study's stages left and estimated hours; run nothing")
    args = p.parse_args(argv)
    if args.list:
        total = 0.0
        for study in STUDIES:
            left, count, hours = remaining(study.module, argv=study.argv)
            total += hours
            name = " ".join((study.module, *study.argv[1:2]))
            print(f"{name:>21}: {left:>2} of {count:>2} stages left, about {hours:5.1f} h ({study.document})")
        print(f"{'in all':>21}: about {total:.0f} h at {RATE / 1e6:.1f} million lane-steps a second (the claims "
              f"study's evolutions on 2 cores)")
        return 0
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(p for p in (root, os.environ.get("PYTHONPATH")) if p)}
    for study in STUDIES:
        module = " ".join((study.module, *study.argv))
        print(f"\n=== study {module}", flush=True)
        try:
            code = subprocess.run([sys.executable, "-m", f"experiments.{study.module}", *study.argv],
                                  env=env).returncode
        except KeyboardInterrupt:  # the study has stopped at the same signal and kept what it finished
            print(f"\ninterrupted in study {module}: run the same command again to go on", file=sys.stderr)
            return 130
        if code:
            print(f"error: study {module} stopped with exit code {code}; run the same command again to go on",
                  file=sys.stderr)
            return code
    return 0


if __name__ == "__main__":
    sys.exit(main())
