"""A study as a table over shared runs: each row names what its evolution computes, and the run is found by its key.

A row is a condition under a preset and ``--set`` overrides (docs/STUDIES.md). Its evolution's
spec is exactly what the evolve command builds from its command line (``evolve.build_config``), so
its key (``imrl_jax.runspec``) finds the run wherever a study already made it under the results
folder, and a new one goes to ``results/runs/KEY/evolve``: nothing is shared by hand. A row's
learning test sits beside its evolution (the last ``evolve`` of the path replaced by ``test``).
"""

from __future__ import annotations

import dataclasses
import os

from experiments.executor import add_options, from_options
from experiments.reproduce import (Stage, evolution_cost, evolve_command, load_manifest, run_stages, test_command,
                                   test_cost)
from experiments.study import Study
from imrl_jax import runspec

#: Where every study's runs are looked for by key.
RESULTS = os.path.join("experiments", "results")


@dataclasses.dataclass(frozen=True)
class Row:
    """A row: a condition under a preset and overrides, evolved and then (``test``) learning-tested."""

    name: str
    condition: str
    preset: str
    sets: tuple[str, ...] = ()
    test: bool = True


def evolution_spec(row: Row, scale: dict) -> runspec.RunSpec:
    """What the row's evolve command computes: the config and seeds it builds from its own command line."""
    from imrl_jax import evolve

    command = evolve_command(scale, row.preset, row.condition, os.devnull, sets=row.sets)
    config, seeds = evolve.build_config(evolve.parser().parse_args(command[3:]))
    return runspec.RunSpec.make(config, seeds)


def learning_test_dir(evolved: str) -> str:
    """A learning test's folder beside its evolution's: the last ``evolve`` of the path replaced by ``test``."""
    parts = os.path.normpath(evolved).split(os.sep)
    at = len(parts) - 1 - parts[::-1].index("evolve")
    return os.sep.join(parts[:at] + ["test"] + parts[at + 1:])


@dataclasses.dataclass(frozen=True)
class Table:
    """A study of rows at one scale: its stages, their commands and its command line."""

    name: str
    document: str
    order: float
    rows: tuple[Row, ...]
    scale: dict = dataclasses.field(hash=False)
    out: str  # its manifest and logs (its runs lie wherever their keys find them under ``results``)
    results: str = RESULTS

    def evolutions(self) -> dict[str, str]:
        """Each row's evolution folder: the run its key finds under ``results``, or ``results/runs/KEY/evolve``."""
        known = runspec.index(self.results) if os.path.isdir(self.results) else {}
        return {row.name: runspec.locate(self.results, evolution_spec(row, self.scale), known)[0]
                for row in self.rows}

    def all_stages(self) -> tuple[list[Stage], dict]:
        """Every stage, in order (each evolution, then its test), and the scale; a run two rows share is one stage."""
        stages, evolving = [], {}
        for row, evolved in zip(self.rows, self.evolutions().values()):
            if evolved not in evolving:
                evolving[evolved] = f"evolve {row.name}"
                stages.append(Stage(evolving[evolved], "evolve", row.name, row.condition, evolved,
                                    evolution_cost(self.scale, row.condition)))
            if row.test:
                stages.append(Stage(f"learning test {row.name}", "test", row.name, row.condition,
                                    learning_test_dir(evolved), test_cost(self.scale, row.condition),
                                    needs=(evolving[evolved],)))
        return stages, self.scale

    def stage_command(self, stage: Stage) -> tuple[list[str], None]:
        """A stage's command line: the row's evolution, or the learning test of the run it found."""
        row = next(r for r in self.rows if r.name == stage.variant)
        if stage.kind == "evolve":
            return evolve_command(self.scale, row.preset, row.condition, stage.out_dir, sets=row.sets), None
        evolved = self.evolutions()[row.name]
        return test_command(self.scale, row.preset, row.condition, evolved, stage.out_dir, sets=row.sets), None

    def main(self, argv=None) -> int:
        """The study's command line: run (or go on with) its stages."""
        import argparse

        p = argparse.ArgumentParser(prog=f"python -m experiments run {self.name}")
        add_options(p)
        args = p.parse_args(argv)
        stages, scale = self.all_stages()
        manifest, manifest_path = load_manifest(self.out, study=self.name, sizes=scale)
        return run_stages(stages, scale, manifest, manifest_path, self.stage_command, **from_options(args, self.out))

    def study(self, module: str) -> Study:
        """Its entry for ``python -m experiments`` (its report is to come with its measures)."""
        return Study(self.name, module, self.document, self.order, report_argv=None)
