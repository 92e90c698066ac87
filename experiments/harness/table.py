"""A study as a table over shared runs: each row names what its evolution computes, and the run is found by its key.

A row is a condition under a preset, ``--set`` overrides and more evolve options (a search strategy)
at the table's sizes or its own (docs/STUDIES.md). Its evolution's spec is exactly what the evolve
command builds from its command line (``evolve.build_config``), so its key (``imrl_jax.runs.runspec``)
finds the run wherever a study already made it under the results folder, and a new one goes to
``results/runs/KEY/evolve``: nothing is shared by hand. A row's learning test sits beside its
evolution (the last ``evolve`` of the path replaced by ``test``); a condition that is not evolved
(SLE, EXT-LS) is only learning-tested from scratch, in ``TABLE_OUT/ROW/test``.
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import json
import os
import sys
from typing import NamedTuple

import numpy as np

from experiments.harness.loading import read_evolution, read_test
from experiments.harness.markdown import head, line, mean_sd
from experiments.harness.reproduce import Stage, evolution_cost, evolve_command, test_command, test_cost
from experiments.harness.study import REPRODUCTION, RESULTS, Study, markers, write_table
from imrl_jax.analysis.claims import final_best, plateau_generation
from imrl_jax import conditions
from imrl_jax.runs import runspec


@dataclasses.dataclass(frozen=True)
class Row:
    """A row: a condition under a preset and overrides, evolved and then (``test``) learning-tested."""

    name: str
    condition: str
    preset: str
    sets: tuple[str, ...] = ()
    test: bool = True
    options: tuple[str, ...] = ()  # more options of its evolve command (``("--strategy", "snes")``)
    scale: dict | None = dataclasses.field(default=None, hash=False)  # its own sizes (None: the table's)

    @property
    def evolved(self) -> bool:
        """Whether its condition is evolved (else it is only learning-tested from scratch)."""
        return conditions.get(self.condition).evolved


def row_option(row: Row, flag: str, default: str) -> str:
    """The value of a row's option ``flag`` (``--world``, ``--strategy``), else ``default``."""
    return dict(zip(row.options[::2], row.options[1::2])).get(flag, default)


def row_world(row: Row) -> str:
    """The world a row's runs live in: its ``--world`` option's, else the arena."""
    return row_option(row, "--world", "arena")


def evolution_command(row: Row, scale: dict, out_dir: str, sweep: tuple[str, ...] = ()) -> list[str]:
    """The row's evolve command into ``out_dir``."""
    command = evolve_command(scale, row.preset, row.condition, out_dir, sets=row.sets, sweep=sweep)
    return command[:-1] + list(row.options) + ["--resume"] if command[-1] == "--resume" else command + list(row.options)


def scratch_test_command(row: Row, scale: dict, out_dir: str) -> list[str]:
    """The learning test from scratch of a row not evolved (its options the test's; SLE's noise the test's own: it
    anneals over the whole test at ``sle_noise_steps=0``)."""
    noise = [s for s in row.sets if s.startswith("sle_noise_steps=")]
    return test_command(scale, row.preset, row.condition, "", out_dir, sets=tuple(s for s in row.sets if s not in noise),
                        sle_noise_steps=int(noise[0].split("=")[1]) if noise else None) + list(row.options)


def scratch_test_key(row: Row, scale: dict) -> str:
    """The key of a row's learning test from scratch (``runspec.test_key``): the config and sizes its command
    builds, by the learning test's own builders."""
    from imrl_jax.runs import cli
    from imrl_jax.commands.learning_test_options import parser, scratch_genomes, tested_config

    args = parser().parse_args(scratch_test_command(row, scale, os.devnull)[3:])
    config, _ = tested_config(args, scratch_genomes(args, cli.parse_sets(args.set))[0], "")
    return runspec.test_key(config, dict(num_runs=args.runs, num_best=args.best, num_tests=args.tests,
                                         steady_steps=args.steady_steps, seed=args.seed))


def evolution_spec(row: Row, scale: dict) -> runspec.RunSpec:
    """What the row's evolve command computes: the config, seeds and search it builds from its own command line."""
    return _evolution_spec(row, json.dumps(scale, sort_keys=True))


@functools.lru_cache(maxsize=None)
def _evolution_spec(row: Row, scale: str) -> runspec.RunSpec:
    # Memoised: a study's plan asks for each row's spec several times (its evolutions, tests, measures, stages).
    from imrl_jax.commands import evolve
    from imrl_jax.evolution.strategies import GA_NAME, GA_RECORD, parse_settings

    args = evolve.parser().parse_args(evolution_command(row, json.loads(scale), os.devnull)[3:])
    config, seeds = evolve.build_config(args)
    # the search as the run records it (strategies.describe), without building the strategy (evosax compiles)
    search = GA_RECORD if (args.strategy or GA_NAME) == GA_NAME else {
        "strategy": args.strategy, "settings": parse_settings(args.strategy_set)}
    return runspec.RunSpec.make(config, seeds, search)


@dataclasses.dataclass(frozen=True)
class Measure:
    """A measure: ``python -m MODULE RUN --out OUT ARGS`` (RUN a row's evolution, the run a Row of the measure's own
    finds by its key (a run another study made, not a row of this table), a folder, or none: ``run=""``); OUT is
    ``out``, or ``TABLE_OUT/measures/NAME``. An argument ``{ROW}`` is the evolution folder of the table's row ROW:
    a measure of several runs names them so, and waits for each (an argument in braces must name an evolved row);
    an argument that is a Row of the measure's own is the run its key finds (another study's runs, read by key).
    Done as its ``kind`` of stage is done: a "measure" when OUT holds result.json, a "test"
    (``imrl_jax.commands.learning_test`` with options of its own, such as another task set) its steady.json, a "baseline"
    (``imrl_jax.commands.baselines``) its summary.json."""

    name: str
    run: "str | Row"  # a row's name, a Row of its own (its run found by key), a run directory, or "" (none)
    args: tuple["str | Row", ...] = ()
    module: str = "imrl_jax.landscape_run"
    cost: float = 0.0  # lane-steps, estimated
    out: str | None = None  # its folder within the table's (None: measures/NAME)
    kind: str = "measure"  # measure, test or baseline: what makes it done (reproduce.stage_done)

    def rows_named(self) -> list[str]:
        """The rows its arguments name as ``{ROW}``."""
        return [a[1:-1] for a in self.args if isinstance(a, str) and len(a) > 2 and a[0] == "{" and a[-1] == "}"]


class Sweep(NamedTuple):
    """Rows whose runs are made in one program: the first row's command with ``--sweep FIELD=V1,V2 --zip``."""

    rows: tuple[Row, ...]
    values: tuple[str, ...]  # FIELD=V1,V2,... in the rows' order (empty for a sweep already begun)


def static_signature(spec: runspec.RunSpec) -> str:
    """What runs made in one program must share: every field but the dynamic ones, the seeds and the search."""
    from imrl_jax.evolution.sweeps import DYNAMIC_FIELDS

    model = {k: v for k, v in spec.config.to_dict().items() if k not in DYNAMIC_FIELDS}
    return runspec.canonical({"model": model, "seeds": list(spec.seeds), "search": spec.search})


def varying_fields(specs: list[runspec.RunSpec]) -> list[str]:
    """The dynamic fields whose values differ between the specs."""
    from imrl_jax.evolution.sweeps import DYNAMIC_FIELDS

    return [f for f in DYNAMIC_FIELDS if f != "eta" and len({getattr(s.config, f) for s in specs}) > 1]


def point_key(base: runspec.RunSpec, spec: runspec.RunSpec, fields: list[str]) -> str:
    """The key of the sweep point of ``base`` with ``spec``'s values of ``fields`` (``spec``'s own key if the two
    differ only there)."""
    changed = base.config.replace(**{f: getattr(spec.config, f) for f in fields})
    return runspec.RunSpec.make(changed, spec.seeds, json.loads(spec.search)).key()


def learning_test_dir(evolved: str) -> str:
    """A learning test's folder beside its evolution's: the last ``evolve`` of the path replaced by ``test``."""
    parts = os.path.normpath(evolved).split(os.sep)
    at = len(parts) - 1 - parts[::-1].index("evolve")
    return os.sep.join(parts[:at] + ["test"] + parts[at + 1:])


@dataclasses.dataclass(frozen=True)
class Table:
    """A study: its rows (runs found by what they compute) and measures, their stages and commands, its command line
    and its report."""

    name: str
    document: str
    order: float
    rows: tuple[Row, ...]
    scale: dict = dataclasses.field(hash=False)
    out: str  # its manifest and logs (its runs lie wherever their keys find them under ``results``)
    results: str = RESULTS
    measures: tuple[Measure, ...] = ()

    def __post_init__(self):
        names = [row.name for row in self.rows] + [m.name for m in self.measures]
        twice = sorted({name for name in names if names.count(name) > 1})
        if twice:  # a row's runs and a stage's command are found by its name
            raise ValueError(f"table {self.name}: two rows or measures are named {twice[0]!r}")
        rows = {r.name: r for r in self.rows}
        for m in self.measures:
            for name in [*m.rows_named(), *([m.run] if isinstance(m.run, str) and m.run in rows else [])]:
                if name not in rows or not rows[name].evolved:
                    raise ValueError(f"table {self.name}: measure {m.name} reads row {name}, which is "
                                     f"{'no row' if name not in rows else 'not evolved'} (a measure reads a run)")

    @property
    def reproduction(self) -> str:
        """The reproduction's runs under this table's results folder (``REPRODUCTION`` for the committed ones)."""
        return os.path.join(self.results, os.path.relpath(REPRODUCTION, RESULTS))

    def measure_folder(self, measure: Measure) -> str:
        """Where a measure writes: its ``out`` within the table's folder (so a table moved elsewhere, as in the
        tests, moves its measures too), or ``OUT/measures/NAME``."""
        return os.path.normpath(os.path.join(self.out, measure.out or os.path.join("measures", measure.name)))

    def measured_run(self, measure: Measure) -> str:
        """The folder a measure reads: its row's run, or its own Row's found by key, or the folder it names."""
        return self.found_run(measure.run) if isinstance(measure.run, Row) else (
            self.evolutions().get(measure.run) or measure.run)

    def found_run(self, row: Row) -> str:
        """The evolution folder a row that is not the table's finds by its key (or where it would be made)."""
        return dataclasses.replace(self, rows=(row,), measures=()).evolutions()[row.name] or ""

    def scale_of(self, row: Row) -> dict:
        """The row's sizes: its own, or the table's."""
        return self.scale if row.scale is None else row.scale

    def evolutions(self) -> dict[str, str | None]:
        """Each row's evolution folder: the run its key finds under ``results``, or where it will be made (a point of
        a sweep, :meth:`sweeps`, or ``results/runs/KEY/evolve``); None for a row whose condition is not evolved."""
        return self.plan()[0]

    def tests(self) -> dict[str, str]:
        """Each row's learning-test folder: beside its evolution; for a row not evolved, the test from scratch its
        key finds under ``results`` (``runspec.test_index``), or ``OUT/ROW/test`` for a new one."""
        known = runspec.test_index(self.results) if os.path.isdir(self.results) else {}
        folders = {}
        for row, evolved in zip(self.rows, self.evolutions().values()):
            if evolved is not None:
                folders[row.name] = learning_test_dir(evolved)
                continue
            key = scratch_test_key(row, self.scale_of(row))
            folders[row.name] = (os.path.join(self.results, known[key]) if key in known else
                                 os.path.join(self.out, row.name, "test"))
        return folders

    def sweeps(self) -> dict[str, Sweep]:
        """The sweeps the rows' new runs are grouped into, by their folder (see :meth:`plan`)."""
        return self.plan()[1]

    def plan(self) -> tuple[dict[str, str], dict[str, "Sweep"]]:
        """Each row's evolution folder, and the sweeps that make several rows' runs in one program.

        Runs not made yet that differ only in dynamic values (:data:`imrl_jax.evolution.sweeps.DYNAMIC_FIELDS`) are one
        sweep (``evolve --sweep``) in ``results/sweeps/HASH/evolve``, HASH of its runs' keys, each run a point
        ``.../evolve/KEY``; a sweep begun is found by its points and goes on as one.
        """
        known = runspec.index(self.results) if os.path.isdir(self.results) else {}
        specs = {row.name: evolution_spec(row, self.scale_of(row)) for row in self.rows if row.evolved}
        dirs, begun, groups = {row.name: None for row in self.rows}, {}, {}
        for row in (r for r in self.rows if r.evolved):
            dirs[row.name], found = runspec.locate(self.results, specs[row.name], known)
            root = os.path.dirname(dirs[row.name])
            if found and os.path.isfile(os.path.join(root, "sweep.json")):
                begun.setdefault(root, []).append(row)
            elif not found and json.loads(specs[row.name].search) == runspec.GA_SEARCH:
                groups.setdefault(static_signature(specs[row.name]), {}).setdefault(specs[row.name].key(), row)
        sweeps = {root: Sweep(tuple(rows), ()) for root, rows in begun.items() if len(rows) > 1}
        for members in groups.values():
            rows = list(members.values())
            fields = varying_fields([specs[r.name] for r in rows])
            if len(rows) < 2 or any(point_key(specs[rows[0].name], specs[r.name], fields) != specs[r.name].key()
                                    for r in rows):
                continue
            root = os.path.join(self.results, "sweeps",
                                hashlib.sha256(",".join(sorted(members)).encode()).hexdigest()[:runspec.KEY_LENGTH],
                                "evolve")
            sweeps[root] = Sweep(tuple(rows), tuple(
                f"{f}={','.join(repr(float(getattr(specs[r.name].config, f))) for r in rows)}" for f in fields))
            for row in self.rows:
                if row.evolved and specs[row.name].key() in members:
                    dirs[row.name] = os.path.join(root, specs[row.name].key())
        return {row.name: dirs[row.name] for row in self.rows}, sweeps

    def all_stages(self) -> tuple[list[Stage], dict]:
        """Every stage, in order (each evolution, then its test), and the scale; a run two rows share is one stage,
        and so is a sweep of several rows' runs."""
        stages, evolving, testing = [], {}, set()
        evolutions, sweeps = self.plan()
        for row, evolved, tested in zip(self.rows, evolutions.values(), self.tests().values()):
            scale = self.scale_of(row)
            if evolved is None:  # tested from scratch: nothing to wait for
                if tested not in testing:
                    testing.add(tested)
                    stages.append(Stage(f"learning test {row.name}", "test", row.name, row.condition, tested,
                                        test_cost(scale, row.condition), runs=scale["seeds"], needs=(),
                                        world=row_world(row)))
                continue
            root = os.path.dirname(evolved)
            if root in sweeps:
                if root not in evolving:
                    members = sweeps[root].rows
                    evolving[root] = f"evolve {'+'.join(r.name for r in members)} (one sweep)"
                    stages.append(Stage(evolving[root], "evolve", row.name, row.condition, root,
                                        sum(evolution_cost(scale, r.condition) for r in members),
                                        generations=scale["generations"], world=row_world(row)))
                evolving[evolved] = evolving[root]
            elif evolved not in evolving:
                evolving[evolved] = f"evolve {row.name}"
                # rows of one run may ask for different lengths (not part of its key): the longest is made
                longest = max(self.scale_of(r)["generations"] for r, e in zip(self.rows, evolutions.values())
                              if e == evolved)
                stages.append(Stage(evolving[evolved], "evolve", row.name, row.condition, evolved,
                                    evolution_cost(scale, row.condition), generations=longest, world=row_world(row)))
            if root in sweeps and all(r.test for r in sweeps[root].rows):  # its points tested in one program too
                if f"test {root}" not in evolving:
                    members = sweeps[root].rows
                    evolving[f"test {root}"] = f"learning test {'+'.join(r.name for r in members)} (one sweep)"
                    stages.append(Stage(evolving[f"test {root}"], "test", row.name, row.condition,
                                        learning_test_dir(root), sum(test_cost(scale, r.condition)
                                                                     for r in members), runs=scale["seeds"],
                                        needs=(evolving[root],), world=row_world(row)))
            elif row.test and tested not in testing:  # a test two rows share is one stage
                testing.add(tested)
                stages.append(Stage(f"learning test {row.name}", "test", row.name, row.condition, tested,
                                    test_cost(scale, row.condition), runs=scale["seeds"], needs=(evolving[evolved],),
                                    world=row_world(row)))
        for measure in self.measures:
            run = self.measured_run(measure)
            row = next((r for r, e in zip(self.rows, evolutions.values()) if e is not None and e == run), None)
            condition = measure.run.condition if isinstance(measure.run, Row) else row.condition if row else ""
            named = [evolving[evolutions[name]] for name in measure.rows_named()]
            lives = row or (measure.run if isinstance(measure.run, Row) else None)  # the run it measures
            stages.append(Stage(f"{measure.kind} {measure.name}", measure.kind, measure.name, condition,
                                self.measure_folder(measure), measure.cost,
                                needs=tuple(dict.fromkeys(([evolving[run]] if row else []) + named)),
                                world=row_world(lives) if lives else "arena"))
        return stages, self.scale

    def stage_command(self, stage: Stage) -> tuple[list[str], None]:
        """A stage's command line: a measure, the row's evolution, or the learning test of the run it found."""
        measure = next((m for m in self.measures if stage.name == f"{m.kind} {m.name}"), None)
        if measure is not None:
            run, evolutions = self.measured_run(measure), self.evolutions()
            named = set(measure.rows_named())
            args = [self.found_run(a) if isinstance(a, Row) else evolutions[a[1:-1]] if a[:1] + a[-1:] == "{}"
                    and a[1:-1] in named else a for a in measure.args]
            return [sys.executable, "-m", measure.module, *([run] if run else []), "--out", stage.out_dir,
                    *args], None
        row = next(r for r in self.rows if r.name == stage.variant)
        scale = self.scale_of(row)
        if stage.kind == "evolve":
            scale = dict(scale, generations=stage.generations or scale["generations"])  # the longest of its rows
            sweep = self.sweeps().get(stage.out_dir)
            if sweep is not None and os.path.isfile(os.path.join(stage.out_dir, "sweep.json")):  # goes on as it began
                return [sys.executable, "-m", "imrl_jax.evolve", "--resume", "--out", stage.out_dir, "--generations",
                        str(scale["generations"])], None
            return evolution_command(row, scale, stage.out_dir, sweep.values if sweep else ()), None
        evolved = self.evolutions()[row.name]
        if evolved is None:
            return scratch_test_command(row, scale, stage.out_dir), None
        if os.path.dirname(evolved) in self.sweeps():  # a sweep's points, tested as one
            evolved = os.path.dirname(evolved)
            if os.path.normpath(stage.out_dir) != os.path.normpath(learning_test_dir(evolved)):
                evolved = self.evolutions()[row.name]  # a row of the sweep tested alone
        return test_command(scale, row.preset, row.condition, evolved, stage.out_dir, sets=row.sets), None

    def measure(self) -> list[dict]:
        """Each row's evolution (final best fitness, its spread and plateau, once finished) and learning test."""
        measured = []
        for row, evolved, tested in zip(self.rows, self.evolutions().values(), self.tests().values()):
            run, test = (None if evolved is None else read_evolution(evolved)), read_test(tested)
            entry = dict(row=row.name, condition=row.condition, preset=row.preset, dir=evolved, generations=0,
                         target=self.scale_of(row)["generations"])
            if run is not None:
                best = run["best"][~np.isnan(run["best"]).any(1)]  # the generations every seed has finished
                entry.update(generations=len(best), seeds=int(best.shape[1]), best=best)
                if len(best) >= self.scale_of(row)["generations"]:
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
        lines = head("row", "condition", "preset", "seeds", "generations", "final best fitness", "plateau generation",
                     "steady state")
        for m in measured:
            final = (mean_sd(m["final_mean"], m["final_sd"]) if "final_mean" in m else
                     "running" if m["generations"] else "not evolved" if m["dir"] is None else "not started")
            steady = (f"{mean_sd(m['steady_mean'], m['steady_sd'])} ({m['test_runs']} runs)" if "steady_mean" in m
                      else "-")
            lines.append(line(m["row"], m["condition"], m["preset"], m.get("seeds", "-"),
                              "-" if m["dir"] is None else f"{m['generations']} of {m['target']}", final,
                              m.get("plateau", "-"), steady))
        return "\n".join(lines)

    def figure(self, measured: list[dict], path: str) -> str:
        """Each row's best fitness per generation (mean over seeds, +-1 sd): its condition's colour, solid under skills,
        dashed otherwise (a row that would look like one drawn before takes a colour of its own)."""
        from imrl_jax.analysis.plotting import CONDITION_STYLES, new_figure, save, style_axis

        fig = new_figure(6.4, 3.8)
        ax = fig.add_subplot()
        drawn, spare = set(), iter(("tab:purple", "tab:cyan", "tab:pink", "tab:olive", "tab:brown", "tab:orange"))
        for m in (m for m in measured if m["generations"]):
            style = {**CONDITION_STYLES.get(m["condition"], {}), "ls": "-" if m["preset"] == "skills" else "--"}
            if (style.get("color"), style["ls"]) in drawn:  # EE-LS-T beside EE-LS: both grey and solid under skills
                style["color"] = next(spare, "0.3")
            drawn.add((style.get("color"), style["ls"]))
            x, mean, sd = np.arange(m["generations"]), m["best"].mean(1), m["best"].std(1)
            ax.plot(x, mean, label=f"{m['row']} ({m['seeds']} seeds{'' if 'final_mean' in m else ', running'})",
                    **style)
            ax.fill_between(x, mean - sd, mean + sd, color=style.get("color", "0.5"), alpha=0.12, lw=0)
        ax.set_ylim(bottom=0)
        style_axis(ax, f"{self.name}: best fitness per generation", "generation",
                   "best fitness (best of a generation's lives)")
        if ax.lines:
            ax.legend(fontsize=7)
        fig.tight_layout()
        return save(fig, path)

    def report(self) -> int:
        """Measure what has finished; write the table into the document (between its markers) and the figure."""
        measured = self.measure()
        os.makedirs(self.out, exist_ok=True)
        drawn = self.figure(measured, os.path.join(self.out, f"{self.name}.png"))
        write_table(self.document, self.table(measured), *markers(f"{self.name} table", self.name))
        print(f"{len(measured)} rows ({sum('final_mean' in m for m in measured)} finished); wrote {drawn} and the "
              f"table of {self.document}")
        return 0

    def main(self, argv=None) -> int:
        """The study's command line: run (or go on with) its stages, or ``--report`` (``experiments.harness.runner``)."""
        from experiments.harness.runner import study_main

        return study_main(argv, self.name, self.out, self.all_stages, self.stage_command, self.report)

    def study(self, module: str) -> Study:
        """Its entry for ``python -m experiments``."""
        return Study(self.name, module, self.document, self.order, out=self.out)


def studies_of(module: str, tables: dict[str, Table]) -> tuple[Study, ...]:
    """The studies of a module of several tables (``TABLES``), each run as ``python -m experiments.MODULE NAME``."""
    return tuple(Study(table.name, module, table.document, table.order, (name,), (name, "--report"), table.out)
                 for name, table in tables.items())


def dispatch(tables: dict[str, Table], argv=None) -> int:
    """``python -m experiments.MODULE [NAME] [--report] [runner options]``: table NAME's command line (the first
    table's when none is named)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    return (tables[argv.pop(0)] if argv and argv[0] in tables else next(iter(tables.values()))).main(argv)
