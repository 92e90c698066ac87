"""Why evolving goals is easier than evolving behaviours (docs/GOALS.md): the size-matched controls' first runs.

    python -m experiments run goals          # run (or go on with) every stage, in order
    python -m experiments list goals         # the stages, done or to run

The paper's conditions (LE-LS: 111 reinforcer genes; EE-LS: 222 actor genes) differ in both the size
and the kind of what is evolved. The controls cross the two (MODEL.md "Size-matched controls"):
EE-LS-T evolves behaviours at LE-LS's size, LE-LS-2R goals at EE-LS's size. Each is evolved under
``skills`` and ``faithful`` for 5 seeds x 100 generations of 50 lives at the paper's lengths (150,000 +
6 x 100,000 steps), then its 5 best x 4 tests are learning-tested, as in the future-work study. The
landscape measures (``imrl_jax.landscape``) and the report come with the study's next stages.
"""

from __future__ import annotations

import os
import sys

from experiments.claims_study import SCREEN
from experiments.executor import add_options, from_options
from experiments.reproduce import (Stage, evolution_cost, evolve_command, load_manifest, run_stages, test_command,
                                   test_cost)
from experiments.study import Study

OUT = os.path.join("experiments", "results", "goals")
#: (row, condition, preset): behaviours at goals' size, goals at behaviours' size; skills first, then faithful.
ROWS = (("EE-LS-T", "EE-LS-T", "skills"), ("LE-LS-2R", "LE-LS-2R", "skills"),
        ("EE-LS-T-faithful", "EE-LS-T", "faithful"), ("LE-LS-2R-faithful", "LE-LS-2R", "faithful"))
BY_NAME = {name: (condition, preset) for name, condition, preset in ROWS}


def all_stages(out: str = OUT) -> tuple[list[Stage], dict]:
    """Every stage, in order (each evolution, then its learning test), and their scale."""
    stages = []
    for name, condition, _ in ROWS:
        folder = os.path.join(out, name)
        stages.append(Stage(f"evolve {name}", "evolve", name, condition, os.path.join(folder, "evolve"),
                            evolution_cost(SCREEN, condition)))
        stages.append(Stage(f"learning test {name}", "test", name, condition, os.path.join(folder, "test"),
                            test_cost(SCREEN, condition), needs=(f"evolve {name}",)))  # its own, not the other preset's
    return stages, SCREEN


def stage_command(stage: Stage) -> tuple[list[str], None]:
    """A stage's command line: evolve the row's condition under its preset, or test what it evolved."""
    condition, preset = BY_NAME[stage.variant]
    if stage.kind == "evolve":
        return evolve_command(SCREEN, preset, condition, stage.out_dir), None
    evolved = os.path.join(os.path.dirname(stage.out_dir), "evolve")
    return test_command(SCREEN, preset, condition, evolved, stage.out_dir), None


def main(argv=None) -> int:
    """The command line: run (or go on with) the stages."""
    import argparse

    p = argparse.ArgumentParser(prog="python -m experiments.goals", description=__doc__.split("\n\n")[0])
    p.add_argument("--out", default=OUT, help=f"results directory (default: {OUT})")
    add_options(p)
    args = p.parse_args(argv)
    stages, scale = all_stages(args.out)
    manifest, manifest_path = load_manifest(args.out, study="goals", sizes=scale)
    return run_stages(stages, scale, manifest, manifest_path, stage_command, **from_options(args, args.out))


#: The studies of this module (python -m experiments finds them).
STUDIES = (Study("goals", "goals", "docs/GOALS.md", 9, report_argv=None),)


if __name__ == "__main__":
    sys.exit(main())
