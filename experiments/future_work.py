"""The paper's future work as conditions (docs/FUTURE_WORK.md): evolutions and learning tests of the new rows.

    python -m experiments.future_work               # run (or go on with) every stage, in order
    python -m experiments.future_work --only EV-LS,EXT-LS
    python -m experiments.future_work --list        # the stages and their commands, nothing run

Each row of :data:`RUNS` is a condition of the table (``imrl_jax.conditions``) under a preset
and ``--set`` overrides, evolved (5 seeds x 100 generations at the paper's life lengths, then
a learning test of its 5 best x 4 tests) or, for a condition that is not evolved, tested from
scratch (5 runs x 5 x 4). The paper's four conditions under the same rules come from the
finished paper-scale reproduction (``experiments/results/paper``). The stages run through
the reproduction's resumable stage runner (:func:`experiments.reproduce.run_stages`): run the
same command again after an interruption.
"""

from __future__ import annotations

import argparse
import os
import sys
from typing import NamedTuple

from experiments.claims_study import SCREEN
from experiments.reproduce import (Stage, evolution_cost, evolve_command, load_manifest, run_stages, test_command,
                                   test_cost)
from imrl_jax import conditions

OUT = os.path.join("experiments", "results", "future_work")


class Run(NamedTuple):
    """One row of the study: a condition under a preset and overrides."""

    name: str
    condition: str
    preset: str
    sets: tuple[str, ...]
    about: str


RUNS: tuple[Run, ...] = (
    Run("EV-LS", "EV-LS", "skills", (), "(a) evolved evaluators, gamma V(x_t) - V(x_{t-1})"),
    Run("EV-LS-diff", "EV-LS-diff", "skills", (), "(a) evolved evaluators, V(x_t) - V(x_{t-1})"),
    Run("EXT-LS", "EXT-LS", "skills", (), "(b) the hierarchy on the task's reward only, SLE's noise over 100,000 cycles"),
    Run("EXT-LS-whole", "EXT-LS", "skills", ("sle_noise_steps=0",), "(b), the noise over the whole test"),
    Run("LE-LS-P", "LE-LS-P", "skills", (), "(c) evolved learning parameters"),
    Run("LE-LS-PC", "LE-LS-PC", "skills", (), "(c) evolved learning parameters and childhood length"),
    Run("LE-LS-N6", "LE-LS-N", "skills", ("num_experts=6",), "(d) up to 6 experts, each expressed by a gene"),
    Run("LE-LS-6", "LE-LS", "skills", ("num_experts=6",), "(d)'s comparison: 6 experts, all expressed"),
)
BY_NAME = {run.name: run for run in RUNS}


def plan(names, scale: dict = SCREEN, out: str = OUT) -> list[Stage]:
    """The stages of the rows ``names``, in order: each evolution then its learning test."""
    stages = []
    for name in names:
        run = BY_NAME[name]
        if conditions.get(run.condition).evolved:
            stages.append(Stage(f"evolve {name}", "evolve", name, run.condition,
                                os.path.join(out, name, "evolve"), evolution_cost(scale, run.condition)))
        stages.append(Stage(f"learning test {name}", "test", name, run.condition, os.path.join(out, name, "test"),
                            test_cost(scale, run.condition)))
    return stages


def stage_command(stage: Stage, scale: dict = SCREEN, out: str = OUT) -> tuple[list[str], None]:
    """A stage's command line: the package's evolve or learning_test with the row's preset and overrides."""
    run = BY_NAME[stage.variant]
    if stage.kind == "evolve":
        return evolve_command(scale, run.preset, run.condition, stage.out_dir, sets=run.sets), None
    evolved_dir = os.path.join(out, run.name, "evolve")
    noise = [s for s in run.sets if s.startswith("sle_noise_steps=")]
    sets = tuple(s for s in run.sets if s not in noise)
    return test_command(scale, run.preset, run.condition, evolved_dir, stage.out_dir, sets=sets,
                        sle_noise_steps=int(noise[0].split("=")[1]) if noise else None), None


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m experiments.future_work", description=__doc__.split("\n\n")[0])
    p.add_argument("--only", help=f"comma-separated rows, in order (default: all: {', '.join(BY_NAME)})")
    p.add_argument("--out", default=OUT, help=f"results directory (default: {OUT})")
    p.add_argument("--list", action="store_true", help="print the stages and their commands, run nothing")
    args = p.parse_args(argv)
    names = args.only.split(",") if args.only else list(BY_NAME)
    unknown = [n for n in names if n not in BY_NAME]
    if unknown:
        print(f"error: --only: unknown row {unknown[0]!r} (choose from {', '.join(BY_NAME)})", file=sys.stderr)
        return 2
    stages = plan(names, SCREEN, args.out)
    if args.list:
        for stage in stages:
            print(f"{stage.name}: {' '.join(stage_command(stage, SCREEN, args.out)[0][1:])}")
        return 0
    manifest, manifest_path = load_manifest(args.out, study="future_work", sizes=SCREEN, rows=names)
    return run_stages(stages, SCREEN, manifest, manifest_path, lambda stage: stage_command(stage, SCREEN, args.out))


if __name__ == "__main__":
    sys.exit(main())
