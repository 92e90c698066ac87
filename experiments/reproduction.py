"""The paper's Fig. 3 and its seven claims at two scales: each condition under each variant of the learning rules.

    python -m experiments run reproduction          # make reproduce: the paper's sizes
    python -m experiments run reproduction-cpu      # make reproduce-cpu: 1 h 44 min on 2 CPU cores (measured)
    python -m experiments report reproduction       # docs/REPRODUCTION.md and docs/reproduction/
    python -m experiments report reproduction-cpu   # docs/REPRODUCTION_CPU.md and docs/reproduction_cpu/

A variant is a preset of ``imrl_jax.config``: ``skills`` (the rules docs/CHILDHOOD.md chose),
``paper`` (the rules as written), ``faithful`` (the rules as written but for the adult selector's
unstated values, SLE's noise over the whole test: the claims map's ``paper-selector-sle-test``,
docs/CLAIMS.md) and ``extension`` (MODEL.md's learning extensions). Its rows are the paper's
conditions under it, evolved (LE-LS, EE-LS, EE-ES) and learning-tested (and SLE, tested from
scratch); each run is found by its key (``imrl_jax.runs.runspec``), so rows that live the same lives
share one run: EE-ES learns nothing (one run for every variant), faithful's EE-LS is skills'.
The report (``experiments.report``) draws Fig. 1 and Fig. 3, relives the best individuals and
judges the seven claims.

Scales (``experiments.harness.study.SCALES``; what ``cpu`` shrinks is the whole difference): the paper's, with the
variants skills, paper and faithful; ``cpu``, paper and extension with 5 seeds x 40 generations, lives, tests and
their steady state a fifth of the paper's, 2 tests per best individual. Each document opens with its sizes beside the
paper's.
"""

from __future__ import annotations

import dataclasses
import functools
import os
import sys

from experiments.harness.study import REPRODUCTION, RESULTS, SCALES
from experiments.harness.table import Row, Table, dispatch, studies_of
from imrl_jax import conditions


def variant_rows(variant: str, sle_noise_steps: int | None = None) -> tuple[Row, ...]:
    """A variant's rows (``VARIANT CONDITION``): the paper's conditions under its preset, SLE's noise annealed over
    ``sle_noise_steps`` (None: one adult task's length; 0: the whole test)."""
    return tuple(Row(f"{variant} {c}", c, variant, () if conditions.get(c).evolved or sle_noise_steps is None else
                     (f"sle_noise_steps={sle_noise_steps}",)) for c in conditions.PAPER)


@dataclasses.dataclass(frozen=True)
class ReproductionTable(Table):
    """Fig. 3 at one scale: its variants' rows; its report, the document, figures and claims of experiments.report."""

    scale_name: str = "paper"
    whole_test: tuple[str, ...] = ()  # the variants whose claim 5 is read at the test's length (SLE's noise over it)

    @property
    def variants(self) -> list[str]:
        """The variants (the rows' presets), in order."""
        return list(dict.fromkeys(row.preset for row in self.rows))

    def data(self) -> dict:
        """What the report reads: each variant's finished evolutions and tests, the variant whose folder holds each
        run (where it lies in none, the first variant that has it), the stages left, the manifest of their commands."""
        from experiments.claims_study import reproduction_variant
        from experiments.harness.loading import read_evolution, read_json, read_test
        from experiments.harness.reproduce import stage_done
        from imrl_jax.config import PRESETS

        stages, scale = self.all_stages()
        manifest = dict(read_json(os.path.join(self.out, "manifest.json")) or {}, scale=self.scale_name, sizes=scale)
        data = dict(results=self.out, manifest=manifest, variants=self.variants, evolutions={}, tests={}, owners={},
                    missing=[s.name for s in stages if not stage_done(s, scale)])
        first = {}
        for row, evolved, tested in zip(self.rows, self.evolutions().values(), self.tests().values()):
            at, folder = (row.preset, row.condition), evolved or tested
            first.setdefault(folder, row.preset)
            holder = reproduction_variant(folder, self.out)  # the committed layout: OUT/VARIANT/evolve/CONDITION
            data["owners"][at] = holder if holder in PRESETS else first[folder]
            if evolved and (run := read_evolution(evolved)) is not None:
                data["evolutions"][at] = run
            if (test := read_test(tested)) is not None:
                data["tests"][at] = test
        return data

    def report(self, behaviour: bool = True, baselines: str | None = None) -> int:
        """The document, its figures and the claims (``behaviour``: relive and probe the best individuals)."""
        from experiments.report import BASELINES, run

        written = run(self, behaviour=behaviour, baselines_dir=baselines or BASELINES)
        print(f"wrote {written['doc']} and the figures and summaries in {os.path.dirname(written['arena'])}")
        return 0


#: make reproduce: the paper's sizes; faithful's SLE explores over the whole test, as the claims map's row does.
PAPER_TABLE = ReproductionTable(
    "reproduction", "docs/REPRODUCTION.md", 4, scale=SCALES["paper"], out=REPRODUCTION, whole_test=("faithful",),
    rows=variant_rows("skills") + variant_rows("paper") + variant_rows("faithful", 0))
#: make reproduce-cpu: its SLE tests were made before SLE's noise was annealed over one task (their config's 0:
#: over the whole test), and are found as such; claim 5 still reads them as the report did then.
CPU_TABLE = ReproductionTable(
    "reproduction-cpu", "docs/REPRODUCTION_CPU.md", 8, scale=SCALES["cpu"], out=os.path.join(RESULTS, "cpu"),
    scale_name="cpu", rows=variant_rows("paper", 0) + variant_rows("extension", 0))
#: The module's tables by the name its command line takes first (``paper`` when none is given).
TABLES = {"paper": PAPER_TABLE, "cpu": CPU_TABLE}


#: The studies of this module (python -m experiments finds them).
STUDIES = studies_of("reproduction", TABLES)
main = functools.partial(dispatch, TABLES)


if __name__ == "__main__":
    sys.exit(main())
