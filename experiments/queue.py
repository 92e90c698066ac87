"""The studies in the order their results are needed, one after another: one command for every sitting.

    python -m experiments.queue --list     # each study's stages left and its estimated hours, nothing run
    python -m experiments.queue            # run (or go on with) each study in turn

Each study is its own resumable command on the shared stage runner (``reproduce.run_stages``),
run as a subprocess; a finished study passes in seconds, an interrupted one goes on where it
stopped, and a failed one stops the queue with its exit code. The order answers whole questions
early: the selector's time-scale and tasks never met in evolution (together one issue, about a
third of the claims study's cost), then the claims map (it decides which rule set reproduces the
paper, and the future work needs it), the search strategies, and last the paper's future work.
"""

from __future__ import annotations

import argparse
import importlib
import os
import subprocess
import sys

from experiments.reproduce import stage_done

#: The studies, in order: (module under experiments/, document).
STUDIES = (("timescale", "docs/TIMESCALE.md"), ("novel_tasks", "docs/NOVEL_TASKS.md"),
           ("claims_study", "docs/CLAIMS.md"), ("search", "docs/SEARCH.md"),
           ("future_work", "docs/FUTURE_WORK.md"))
#: Lane-steps per second of the estimates: the claims study's paper-length evolutions on 2 cores.
RATE = 1.9e6


def remaining(module: str, rate: float = RATE) -> tuple[int, int, float]:
    """Stages left, stages in all, and the hours the stages left cost at ``rate`` lane-steps a second."""
    stages, scale = importlib.import_module(f"experiments.{module}").all_stages()
    left = [s for s in stages if not stage_done(s, scale)]
    return len(left), len(stages), sum(s.cost for s in left) / rate / 3600


def main(argv=None) -> int:
    """The command line: list what is left, or run each study in turn."""
    p = argparse.ArgumentParser(prog="python -m experiments.queue", description=__doc__.split("\n\n")[0])
    p.add_argument("--list", action="store_true", help="each study's stages left and estimated hours; run nothing")
    args = p.parse_args(argv)
    if args.list:
        total = 0.0
        for module, document in STUDIES:
            left, count, hours = remaining(module)
            total += hours
            print(f"{module:>13}: {left:>2} of {count:>2} stages left, about {hours:5.1f} h ({document})")
        print(f"{'in all':>13}: about {total:.0f} h at {RATE / 1e6:.1f} million lane-steps a second (the claims "
              f"study's evolutions on 2 cores)")
        return 0
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(p for p in (root, os.environ.get("PYTHONPATH")) if p)}
    for module, _ in STUDIES:
        print(f"\n=== study {module}", flush=True)
        try:
            code = subprocess.run([sys.executable, "-m", f"experiments.{module}"], env=env).returncode
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
