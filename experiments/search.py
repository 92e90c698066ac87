"""Modern evolution strategies beside the paper's GA (docs/SEARCH.md): EE-LS, EE-ES and LE-LS under ``skills``.

    python -m experiments.search                    # run (or go on with) every stage, in order
    python -m experiments.search --only snes        # the rows of some strategies
    python -m experiments.search --list             # the stages and their commands, nothing run

Each row is a search strategy (``python -m imrl_jax.evolve --strategy NAME``) and an evolved
condition of the paper under the ``skills`` preset, evolved at the paper's life lengths
(150,000 + 6 x 100,000 steps) for 5 seeds x 100 generations of 50 lives, then a learning
test of its 5 best x 4 tests (1,000,000 cycles per task). The GA's rows are the finished
paper-scale reproduction's ``skills`` runs (``experiments/results/paper/skills``: 10 seeds,
learning tests of 10 x 10 x 10), not run again: the search is the only difference. The stages
run through the reproduction's resumable stage runner
(:func:`experiments.reproduce.run_stages`): run the same command again after an interruption.
"""

from __future__ import annotations

import argparse
import os
import sys
from typing import NamedTuple

from experiments.claims_study import SCREEN
from experiments.reproduce import (Stage, evolution_cost, evolve_command, load_manifest, run_stages, test_command,
                                   test_cost)

OUT = os.path.join("experiments", "results", "search")
PRESET = "skills"
CONDITIONS = ("EE-LS", "EE-ES", "LE-LS")


class Row(NamedTuple):
    """One row of the study: a strategy, at evosax's defaults, evolving a condition."""

    strategy: str
    condition: str

    @property
    def name(self) -> str:
        """The row's name: its strategy and condition (``--only`` takes it; its stages are named after it)."""
        return f"{self.strategy}-{self.condition}"


#: Sep-CMA-ES (diagonal covariance: 111-333 genes, 50 lives) and SNES (separable natural ES), at evosax's
#: defaults and the paper's initial spread (mean 0, sd 1/sqrt(3) as U[-1, 1]).
ROWS: tuple[Row, ...] = tuple(Row(s, c) for s in ("sep_cma_es", "snes") for c in CONDITIONS)
BY_NAME = {row.name: row for row in ROWS}


def plan(rows, scale: dict = SCREEN, out: str = OUT) -> list[Stage]:
    """The stages of ``rows``, in order: each evolution then its learning test."""
    stages = []
    for row in rows:
        folder = os.path.join(out, row.strategy, row.condition)
        stages.append(Stage(f"evolve {row.name}", "evolve", row.name, row.condition, os.path.join(folder, "evolve"),
                            evolution_cost(scale, row.condition)))
        stages.append(Stage(f"learning test {row.name}", "test", row.name, row.condition, os.path.join(folder, "test"),
                            test_cost(scale, row.condition)))
    return stages


def stage_command(stage: Stage, scale: dict = SCREEN) -> tuple[list[str], None]:
    """A stage's command line: evolve with the row's strategy, or the learning test of its run."""
    row = BY_NAME[stage.variant]
    if stage.kind == "evolve":
        return evolve_command(scale, PRESET, row.condition, stage.out_dir) + ["--strategy", row.strategy], None
    evolved = os.path.join(os.path.dirname(stage.out_dir), "evolve")
    return test_command(scale, PRESET, row.condition, evolved, stage.out_dir), None


def main(argv=None) -> int:
    """The command line: list the chosen rows' stages, or run (or go on with) them."""
    p = argparse.ArgumentParser(prog="python -m experiments.search", description=__doc__.split("\n\n")[0])
    strategies = sorted({row.strategy for row in ROWS})
    p.add_argument("--only", help=f"comma-separated strategies or rows (default: all: {', '.join(strategies)})")
    p.add_argument("--out", default=OUT, help=f"results directory (default: {OUT})")
    p.add_argument("--list", action="store_true", help="print the stages and their commands, run nothing")
    args = p.parse_args(argv)
    wanted = args.only.split(",") if args.only else strategies
    unknown = [w for w in wanted if w not in BY_NAME and w not in strategies]
    if unknown:
        print(f"error: --only: unknown strategy or row {unknown[0]!r} (choose from {', '.join(strategies)} or "
              f"{', '.join(BY_NAME)})", file=sys.stderr)
        return 2
    rows = [row for row in ROWS if row.name in wanted or row.strategy in wanted]
    stages = plan(rows, SCREEN, args.out)
    if args.list:
        for stage in stages:
            print(f"{stage.name}: {' '.join(stage_command(stage, SCREEN)[0][1:])}")
        return 0
    manifest, manifest_path = load_manifest(args.out, study="search", sizes=SCREEN, rows=[r.name for r in rows])
    return run_stages(stages, SCREEN, manifest, manifest_path, lambda stage: stage_command(stage, SCREEN))


if __name__ == "__main__":
    sys.exit(main())
