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

import numpy as np

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

    def measure(self) -> list[dict]:
        """Each row's evolution (final best fitness, its spread and plateau, once finished) and learning test."""
        from experiments.claims import final_best, plateau_generation
        from experiments.loading import read_evolution, read_test

        measured = []
        for row, evolved in zip(self.rows, self.evolutions().values()):
            run, test = read_evolution(evolved), read_test(learning_test_dir(evolved))
            entry = dict(row=row.name, condition=row.condition, preset=row.preset, dir=evolved, generations=0)
            if run is not None:
                best = run["best"][~np.isnan(run["best"]).any(1)]  # the generations every seed has finished
                entry.update(generations=len(best), seeds=int(best.shape[1]), best=best)
                if len(best) >= self.scale["generations"]:
                    final = final_best(best)
                    entry.update(final_mean=float(final.mean()), final_sd=float(final.std()),
                                 plateau=plateau_generation(best.mean(1)))
            if test is not None:
                entry.update(steady_mean=float(test["steady"]["steady_mean"]),
                             steady_sd=float(test["steady"]["steady_sd"]), test_runs=len(test["steady"]["steady_per_run"]))
            measured.append(entry)
        return measured

    def table(self, measured: list[dict]) -> str:
        """The rows as markdown: what ran, the final best fitness, the plateau and the steady state."""
        lines = ["| row | condition | preset | seeds | generations | final best fitness | plateau generation | "
                 "steady state |", "|---|---|---|---|---|---|---|---|"]
        for m in measured:
            final = (f"{m['final_mean']:.3f} +- {m['final_sd']:.3f}" if "final_mean" in m else
                     "running" if m["generations"] else "not started")
            steady = (f"{m['steady_mean']:.3f} +- {m['steady_sd']:.3f} ({m['test_runs']} runs)" if "steady_mean" in m
                      else "-")
            lines.append(f"| {m['row']} | {m['condition']} | {m['preset']} | {m.get('seeds', '-')} | "
                         f"{m['generations']} of {self.scale['generations']} | {final} | {m.get('plateau', '-')} | "
                         f"{steady} |")
        return "\n".join(lines)

    def figure(self, measured: list[dict], path: str) -> str:
        """Each row's best fitness per generation (mean over seeds, +-1 sd): solid under skills, dashed otherwise."""
        from imrl_jax.plotting import CONDITION_STYLES, new_figure, save, style_axis

        fig = new_figure(6.4, 3.8)
        ax = fig.add_subplot()
        for m in (m for m in measured if m["generations"]):
            style = {**CONDITION_STYLES.get(m["condition"], {}), "ls": "-" if m["preset"] == "skills" else "--"}
            x, mean, sd = np.arange(m["generations"]), m["best"].mean(1), m["best"].std(1)
            ax.plot(x, mean, label=f"{m['row']} ({m['seeds']} seeds{'' if 'final_mean' in m else ', running'})",
                    **style)
            ax.fill_between(x, mean - sd, mean + sd, color=style.get("color", "0.5"), alpha=0.12, lw=0)
        ax.set_ylim(bottom=0)
        style_axis(ax, f"{self.name}: best fitness per generation", "generation",
                   "best fitness (best of a generation's lives)")
        ax.legend(fontsize=7)
        fig.tight_layout()
        return save(fig, path)

    def report(self) -> int:
        """Measure what has finished; write the table into the document (between its markers) and the figure."""
        from experiments.claims_study import write_table

        measured = self.measure()
        os.makedirs(self.out, exist_ok=True)
        drawn = self.figure(measured, os.path.join(self.out, f"{self.name}.png"))
        write_table(self.document, self.table(measured), f"<!-- {self.name} table: python -m experiments report "
                    f"{self.name} -->", f"<!-- end of {self.name} table -->")
        print(f"{len(measured)} rows ({sum('final_mean' in m for m in measured)} finished); wrote {drawn} and the "
              f"table of {self.document}")
        return 0

    def main(self, argv=None) -> int:
        """The study's command line: run (or go on with) its stages, or ``--report``."""
        import argparse

        p = argparse.ArgumentParser(prog=f"python -m experiments run {self.name}")
        p.add_argument("--report", action="store_true", help="the table and figure of what has finished (runs nothing)")
        add_options(p)
        args = p.parse_args(argv)
        if args.report:
            return self.report()
        stages, scale = self.all_stages()
        manifest, manifest_path = load_manifest(self.out, study=self.name, sizes=scale)
        return run_stages(stages, scale, manifest, manifest_path, self.stage_command, **from_options(args, self.out))

    def study(self, module: str) -> Study:
        """Its entry for ``python -m experiments``."""
        return Study(self.name, module, self.document, self.order)
