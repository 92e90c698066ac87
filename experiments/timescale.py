"""A selector on its own time-scale (docs/TIMESCALE.md): the composition ceiling per option, then evolutions.

    python -m experiments list|run|report timescale   # its stages; run (or go on with) them; its tables and figure
    python -m experiments.timescale --out DIR ceiling|rates|confirm [--lives N]   # one measurement by hand

Three measurements of EE-LS individuals whose experts are ideal colour followers, the selector learning as
in adulthood: ``ceiling`` (each of :data:`OPTIONS` under each of :data:`RULES`), ``rates`` (the selector's
trace decay and rates swept per option, :data:`RATE_GRID`) and ``confirm`` (each option's best point in
fresh lives). Then the rows they call for (:func:`evolution_groups`), found by their keys.
"""

from __future__ import annotations

import dataclasses
import itertools
import os
import sys

import jax
import jax.numpy as jnp
import numpy as np

from experiments import claims_study
from experiments.harness.figures import _band
from experiments.harness.loading import read_evolution, read_json, read_test, write_json
from experiments.harness.markdown import head, line, mean_sd
from experiments.rule_sets import BY_NAME
from experiments.harness.measures import write_measure  # atomic: a kill leaves a measurement not done
from experiments.harness.study import MEASURED, REPRODUCTION, RESULTS, SCREEN, Study, markers, write_table
from experiments.harness.table import Measure, Row, Table
from imrl_jax.analysis.claims import CLAIMS
from imrl_jax.runs import cli
from imrl_jax.evolution import sweeps
from imrl_jax.runs.cli import Parser, UsageError, exit_codes
from imrl_jax.config import ADULT_SELECTOR, make_config
from imrl_jax.analysis.controllers import composition_ceiling, perceptron_followers
from imrl_jax.analysis.plotting import new_figure, save, style_axis, wrap_title

OUT = os.path.join(RESULTS, "timescale")
DOCUMENT = os.path.join("docs", "TIMESCALE.md")
#: The selector's options: name -> Config fields. "per-step" is the paper's selector.
OPTIONS = {"per-step": dict(selector_period=1), **{f"period-{p}": dict(selector_period=p) for p in (5, 10, 20, 40)},
           **{f"colour-{p}": dict(selector_period=p, selector_termination="colour") for p in (20, 60)}}
#: Adult learning rules of the ceiling: the paper's one-step rules, skills' adult selector (traces, rates), and a
#: selector that does not learn: what choosing at random (s = 0.5 for every expert) is worth, per option.
RULES = dict(paper={}, skills=dict(ADULT_SELECTOR), random=dict(eta_selector_actor=0.0, eta_selector_critic=0.0))
RULE_LABELS = dict(paper="paper's one-step selector rules", skills="skills' adult selector (traces, rates)",
                   random="selector does not learn (random choices)")
#: A ceiling at least this high means composition pays under those rules: above what one colour follower
#: gets on the paper's tasks (it can solve at most one task of each pair) and half the hand-written composition.
COMPOSES = 0.5
#: The ceiling's size: lives per (option, rules), and its task length (the paper's).
LIVES, TASK_STEPS = 8, 100_000
#: Stage 2: the selector's rates and trace decay swept for these options (skills' values were chosen for a
#: per-step selector, which learns once a step; an option's selector learns once an option).
RATE_OPTIONS = ("per-step", "period-5", "period-10", "colour-20", "colour-60")
RATE_GRID = dict(trace_lambda=(0.0, 0.9, 0.98), eta_selector_actor=(0.01, 0.1, 0.3, 1.0, 3.0, 10.0),
                 eta_selector_critic=(0.001, 0.01, 0.1))
RATE_LIVES = 3
#: The conditions evolved with an option (under the paper's rules EE-ES too: it has a selector and no childhood).
EVOLVED = ("LE-LS", "EE-LS")
#: The per-step selector the evolutions are compared with: the reproduction's run of this rule set (10 x 100).
BASELINE = "skills"
#: Where the report's tables go in docs/TIMESCALE.md.
REPORT_START, REPORT_END = markers("timescale evolutions", "timescale")


def read_measure(out: str, name: str) -> list[dict] | None:
    """The rows the measurement ``name`` ("ceiling", "rates", "confirm") wrote under ``out`` (None before it ran)."""
    return (read_json(os.path.join(out, name, MEASURED)) or {}).get("rows")


def best_rates(rows: list[dict], option: str, trace_lambda: float | None = None) -> dict:
    """The swept row of ``option`` with the highest mean fitness (at ``trace_lambda`` only, if given)."""
    mine = [r for r in rows if r["option"] == option and (trace_lambda is None or r["trace_lambda"] == trace_lambda)]
    if not mine:
        raise UsageError(f"rates: no swept point of option {option}" + (f" at trace_lambda {trace_lambda}"
                                                                         if trace_lambda is not None else ""))
    return max(mine, key=lambda r: r["fitness"])


def evolution_groups(out: str = OUT) -> tuple[Row, ...]:
    """The rows the measures call for, "PRESET+OPTION CONDITION" (none before they ran).

    Under ``skills``: LE-LS and EE-LS with the option (other than per-step) whose best point of the rate
    sweep scores highest in the confirmation's fresh lives, at that point's rates. Under ``paper``: LE-LS,
    EE-LS and EE-ES with the option of the highest ceiling under the paper's own rules, if that ceiling
    reaches :data:`COMPOSES`.
    """
    ceiling, confirmed = read_measure(out, "ceiling"), read_measure(out, "confirm")
    if ceiling is None or confirmed is None:
        return ()
    best = max((r for r in confirmed if r["option"] != "per-step"), key=lambda r: r["fitness"])
    paper = max((r for r in ceiling if r["rules"] == "paper" and r["option"] != "per-step"), key=lambda r: r["fitness"])
    groups = [(f"skills+{best['option']}", {**OPTIONS[best["option"]], **{f: best[f] for f in RATE_GRID}}, EVOLVED)]
    if paper["fitness"] >= COMPOSES:
        groups.append((f"paper+{paper['option']}", OPTIONS[paper["option"]], EVOLVED + ("EE-ES",)))
    return tuple(Row(f"{variant} {c}", c, variant.split("+")[0], tuple(f"{k}={v}" for k, v in fields.items()))
                 for variant, fields, conditions in groups for c in conditions)


@dataclasses.dataclass(frozen=True)
class TimescaleTable(Table):
    """The study: its measurements, then the rows they call for, compared with the per-step selector's runs."""

    reproduction: str = REPRODUCTION  # the per-step runs compared with, and the EE-ES and SLE an option borrows
    summary: dict | None = dataclasses.field(default=None, hash=False)  # the reproduction report's probes

    def all_stages(self):
        """The measurements (the confirmation waits for the rate sweep), then the rows' evolutions and tests."""
        stages, scale = super().all_stages()
        ordered = [s for s in stages if s.kind == "measure"] + [s for s in stages if s.kind != "measure"]
        return [s._replace(needs=("measure rates",)) if s.name == "measure confirm" else s for s in ordered], scale

    def variants(self) -> dict[str, list[Row]]:
        """The rows of each option ("PRESET+OPTION"), in order."""
        return {variant: list(rows) for variant, rows in itertools.groupby(self.rows, lambda r: r.name.split(" ")[0])}

    def option_runs(self, variant: str | None = None, finished=None) -> claims_study.RowRuns:
        """An option's runs: its own rows' (only those ``finished``, if given), the per-step baseline's where it has
        none of its own: EE-ES (``paper``'s: its selector chooses every step) and SLE; the baseline's for None."""
        # found by key as the claims study finds them: one not found is made in its folder under this table's results
        out = os.path.join(self.results, os.path.relpath(claims_study.OUT, RESULTS))
        runs = claims_study.rule_runs(BY_NAME[BASELINE], out, self.reproduction)
        evolutions, tests = self.evolutions(), self.tests()
        for row in self.variants().get(variant, ()):
            for folders in runs:  # evolutions, tests, and the reproduction's variant of each borrowed run
                folders.pop(row.condition, None)
            if finished is None or row.condition in finished:
                runs.evolutions[row.condition], runs.tests[row.condition] = evolutions[row.name], tests[row.name]
        return runs

    def claims(self) -> dict:
        """The per-step baseline's claims and each option's: {variant: label, progress, measured}; an option's own
        runs are measured once finished (a running one's population is not its last): a claim needing one is n/a."""
        summary = self.summary if self.summary is not None else claims_study.reproduction_summary(self.document)
        whole = BY_NAME[BASELINE].sle_noise_steps == 0  # SLE's noise annealed over the whole test
        rows = {BASELINE: dict(label=f"{BASELINE}, per-step selector (the paper's)", progress=None,
                               measured=claims_study.measure_runs(BASELINE, self.option_runs(), summary, whole))}
        measured = {m["row"]: m for m in self.measure()}
        for variant, own in self.variants().items():
            finished = {r.condition for r in own if "final_mean" in measured[r.name]}
            rows[variant] = dict(label=variant.replace("+", ", ") + " selector", progress={
                r.condition: (measured[r.name]["generations"], measured[r.name]["seeds"])
                if measured[r.name]["generations"] else None for r in own}, measured=claims_study.measure_runs(
                    variant, self.option_runs(variant, finished), summary) if finished else None)
        return rows

    def figure(self, path: str) -> str:
        """Fig. 3a and 3b side by side for LE-LS and EE-LS: per-step (dashed) against each option (solid)."""
        from matplotlib.ticker import MaxNLocator

        sources = [(f"{BASELINE}, per-step", self.option_runs(), "--")]
        sources += [(variant.replace("+", ", "), self.option_runs(variant), "-") for variant in self.variants()]
        fig = new_figure(12.0, 4.0)
        evolution_ax, test_ax = fig.subplots(1, 2)
        style_axis(evolution_ax, "Best fitness per generation (best of a generation's lives; mean over seeds, +-1 "
                   "sd)", "generation", "best fitness")
        style_axis(test_ax, "Learning tests of the best (mean over tests and tasks, +-1 sd over runs)",
                   "cycles of the task", "performance per bin")
        for label, runs, ls in sources:
            for condition, colour in zip(EVOLVED, ("tab:blue", "tab:orange")):
                style = dict(color=colour, ls=ls, lw=1.5)
                run, test = read_evolution(runs.evolutions[condition]), read_test(runs.tests[condition])
                best = None if run is None else run["best"][~np.isnan(run["best"]).any(1)]  # seeds may be partial
                if best is not None and len(best):
                    running = ", running" if len(best) < (run["config"] or {}).get("num_generations", 0) else ""
                    evolution_ax.plot(np.arange(len(best)), best.mean(1), **style,
                                      label=f"{condition}, {label} ({best.shape[1]} seeds{running})")
                    _band(evolution_ax, np.arange(len(best)), best.mean(1), best.std(1), style, set())
                if test is not None:
                    test_ax.plot(test["steps"], test["mean"], label=f"{condition}, {label}", **style)
                    _band(test_ax, *(np.asarray(test[k]) for k in ("steps", "mean", "sd")), style, set())
        evolution_ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        for ax in (evolution_ax, test_ax):
            ax.set_ylim(0, 1)
            ax.legend(fontsize=7, loc="lower right")
        fig.tight_layout()
        return save(fig, path)

    def report(self) -> int:
        """Measure what has finished: evolutions.json and evolutions.png under ``out``, the document's tables."""
        if not self.rows:
            print(f"error: {self.out}: the measurements have not run, so no evolution is planned yet", file=sys.stderr)
            return 2
        rows = self.claims()
        write_json(os.path.join(self.out, "evolutions.json"),  # json writes the claims' numbers as keys
                   {variant: dict(label=row["label"], progress=row["progress"],
                                  **{k: (row["measured"] or {}).get(k) for k in ("claims", "fresh")})
                    for variant, row in rows.items()}, indent=2, default=str)
        drawn = self.figure(os.path.join(self.out, "evolutions.png"))
        write_table(self.document, report_table(rows), REPORT_START, REPORT_END)
        print(f"wrote {os.path.join(self.out, 'evolutions.json')}, {drawn} and the tables of {self.document}")
        return 0


def timescale_table(out: str = OUT, results: str = RESULTS, **fields) -> TimescaleTable:
    """The study's table as its measurements under ``out`` plan it now (no rows before they have run)."""
    # each measurement is this module's own command writing into the table's NAME; its cost in lane-steps
    lives = dict(ceiling=len(OPTIONS) * len(RULES) * LIVES, confirm=len(RATE_OPTIONS) * LIVES,
                 rates=len(RATE_OPTIONS) * len(list(itertools.product(*RATE_GRID.values()))) * RATE_LIVES)
    measures = tuple(Measure(name, "", (name,), "experiments.timescale", float(lives[name] * 6 * TASK_STEPS), name)
                     for name in ("ceiling", "rates", "confirm"))
    return TimescaleTable("timescale", fields.pop("document", DOCUMENT), 1, rows=evolution_groups(out), scale=SCREEN,
                          out=out, results=results, measures=measures, **fields)


def _cells(row: dict, condition: str) -> tuple:
    """A row's cells for one condition: its numbers once its evolution has finished, its progress before."""
    measured = row["measured"]
    if measured is None or condition not in measured["evolution"]:
        done = (row["progress"] or {}).get(condition)
        return ("not started" if done is None else f"{done[1]} x {done[0]} of {SCREEN['generations']}, running",
                "-", "-", "-", "-")
    e, t, f = (measured[part].get(condition) for part in ("evolution", "learning_tests", "fresh"))
    return (f"{len(e['final_best_per_seed'])} x {e['generations']}", mean_sd(e["final_best_mean"], e["final_best_sd"]),
            "-" if f is None else f"{f['fresh']:.3f} (sd {f['fresh_sd_over_seeds']:.3f} over seeds)",
            e["plateau_generation"],
            "-" if t is None else f"{mean_sd(t['steady_mean'], t['steady_sd'])} ({t['num_runs']} runs)")


def report_table(rows: dict) -> str:
    """Markdown: per row and condition the recorded and fresh fitness and the steady state, then claims 1-7."""
    lines = head("selector", "condition", "seeds x generations", "final best fitness (recorded)",
                 "fresh lives of each seed's best", "plateau generation", "steady state (learning test)")
    lines += [line(row["label"], condition, *_cells(row, condition)) for row in rows.values() for condition in EVOLVED]
    claims = [None if row["measured"] is None else row["measured"]["claims"] for row in rows.values()]
    lines += ["", *head("claim", *(row["label"] for row in rows.values()))]
    lines += [line(f"{k}: {CLAIMS[k]}", *("not finished" if c is None else claims_study.verdict_cell(c[k])
                                         for c in claims)) for k in range(1, 8)]
    return "\n".join(lines)


# ----------------------------------------------------------------------------- the measurements

def _numbers(config, result) -> dict:
    """Fitness over lives (the last axis) and each task's last tenth (the composition once learned), per point."""
    fitness, last = np.asarray(result.fitness), sweeps.normalised_curve(config, result.reward_curve)[..., -1]
    axes = tuple(range(fitness.ndim - 1, last.ndim))
    return dict(fitness=fitness.mean(-1), fitness_sd=fitness.std(-1), last_tenth=last.mean(axes))


def _composed(fields: dict, lives: int, key: int, task_steps: int) -> tuple[dict, object]:
    """Ideal followers composed by the paper's EE-LS selector with ``fields``: :func:`_numbers`, and the result."""
    config = make_config("paper", condition="EE-LS", task_steps=task_steps, num_bins=10, **fields)
    result = composition_ceiling(jax.random.key(key), config, lives)
    return {k: float(v) for k, v in _numbers(config, result).items()}, result


def _write_measure(out_dir: str, name: str, rows: list[dict], lives: int, key: int, **recorded) -> None:
    """A measurement's NAME.csv, then its result.json with its rows (the stage is done)."""
    write_measure(out_dir, name, rows, f"python -m experiments.timescale --out {out_dir} {name} --lives {lives} "
                  f"--key {key}", **recorded, rows=rows)


def measure_ceiling(out_dir: str, lives: int = LIVES, key: int = 0, task_steps: int = TASK_STEPS) -> list[dict]:
    """Stage 1: every option's ceiling under every rule set; writes ceiling.csv, the figure, then result.json."""
    rows = []
    for rules, option in itertools.product(RULES, OPTIONS):
        numbers, result = _composed({**RULES[rules], **OPTIONS[option]}, lives, key, task_steps)
        selections = np.asarray(result.adult_selections).sum(axis=2)  # (lives, tasks, K)
        rows.append(dict(rules=rules, option=option, lives=lives, task_steps=task_steps, **numbers,
                         **{f"task_{t + 1}": float(v) for t, v in enumerate(np.asarray(result.performance).mean(0))},
                         # the mean share of a task's steps its most used expert was in control (1: one does it all)
                         top_share=float((selections.max(-1) / selections.sum(-1)).mean())))
        print(f"ceiling ({len(rows)}/{len(RULES) * len(OPTIONS)}) {rules:>6} {option:>9}: {rows[-1]['fitness']:.3f}",
              file=sys.stderr, flush=True)
    plot_bars([(RULE_LABELS.get(rules, rules), ("0.35", "tab:orange", "0.75")[i % 3],
                [r for r in rows if r["rules"] == rules]) for i, rules in enumerate(RULES)], list(OPTIONS),
              os.path.join(out_dir, "ceiling.png"), "Ideal colour followers composed by a learning selector, per "
              f"option of the selector ({task_steps:,} steps per task)", threshold=COMPOSES)
    _write_measure(out_dir, "ceiling", rows, lives, key, options=OPTIONS, rules=RULES)
    return rows


def measure_rates(out_dir: str, lives: int = RATE_LIVES, key: int = 0, task_steps: int = TASK_STEPS) -> list[dict]:
    """Stage 2: the ceiling over :data:`RATE_GRID` per option: one program per option, every point the same lanes."""
    from matplotlib import colormaps

    rows = []
    for option in RATE_OPTIONS:
        config = make_config("paper", condition="EE-LS", task_steps=task_steps, num_bins=10, **OPTIONS[option])
        sweep, genome = sweeps.grid(config, **RATE_GRID), perceptron_followers(config).reshape(-1)
        result = sweeps.make_lifetime_sweep(config)(jax.random.key(key), jnp.broadcast_to(
            genome, (lives,) + genome.shape), sweep.points)
        numbers = _numbers(config, result)  # per point: (points, lives) fitness
        rows += [dict(option=option, **settings, lives=lives, **{k: float(v[i]) for k, v in numbers.items()})
                 for i, settings in enumerate(sweep.settings)]
        best = best_rates(rows, option)
        print(f"rates {option:>9}: best {best['fitness']:.3f} at {[best[f] for f in RATE_GRID]}", file=sys.stderr,
              flush=True)
    lambdas = RATE_GRID["trace_lambda"]  # a colour each, from dark to light
    plot_bars([(f"lambda {lam}: best rates", colormaps["viridis"](0.15 + 0.7 * i / max(len(lambdas) - 1, 1)),
                [best_rates(rows, option, lam) for option in RATE_OPTIONS]) for i, lam in enumerate(lambdas)],
              list(RATE_OPTIONS), os.path.join(out_dir, "rates.png"),
              "Ideal colour followers composed: the best selector rates for each option and trace decay", ncol=4)
    _write_measure(out_dir, "rates", rows, lives, key, grid=RATE_GRID)
    return rows


def measure_confirm(out_dir: str, lives: int = LIVES, key: int = 1, task_steps: int = TASK_STEPS) -> list[dict]:
    """Stage 3: each option at its best point of the sibling ``rates`` sweep in fresh lives of another key."""
    # the sweep's best of 54 points of 3 lives flatters itself
    rates = read_measure(os.path.dirname(os.path.normpath(out_dir)), "rates")
    if rates is None:
        raise UsageError(f"{out_dir}: the rate sweep has not run (its result.json is missing)")
    rows = []
    for option in RATE_OPTIONS:
        best = best_rates(rates, option)
        values = {field: best[field] for field in RATE_GRID}
        numbers, _ = _composed({**OPTIONS[option], **values}, lives, key, task_steps)
        rows.append(dict(option=option, **values, lives=lives, **numbers, sweep_fitness=best["fitness"]))
        print(f"confirm {option:>9}: {rows[-1]['fitness']:.3f} in {lives} fresh lives, {best['fitness']:.3f} in the "
              "sweep", file=sys.stderr, flush=True)
    _write_measure(out_dir, "confirm", rows, lives, key)
    return rows


def plot_bars(groups, options: list[str], path: str, title: str, threshold: float | None = None,
              ncol: int = 2) -> str:
    """Fitness per option (+-1 sd), a bar per group (label, colour, rows), its last tenth and the ``threshold``."""
    fig = new_figure(8.0, 4.0)
    ax = fig.add_subplot()
    width = 0.8 / len(groups)
    for i, (label, colour, rows) in enumerate(groups):
        xs = [j + (i - (len(groups) - 1) / 2) * width for j in range(len(options))]
        ax.bar(xs, [r["fitness"] for r in rows], width, yerr=[r["fitness_sd"] for r in rows], capsize=2,
               color=colour, label=label)
        ax.plot(xs, [r["last_tenth"] for r in rows], "v", color="black", ms=4,
                label="the last tenth of each task" if i == 0 else None)
    if threshold is not None:
        ax.axhline(threshold, color="0.5", lw=0.8, ls=":", label=f"composition pays ({threshold})")
    ax.set_xticks(range(len(options)), options)
    ax.set_ylabel(f"fitness (mean of {groups[0][2][0]['lives']} lives)")
    ax.set_ylim(0, 1.2)  # room for the legend above the bars
    ax.legend(fontsize=7, loc="upper left", ncol=ncol)
    ax.set_title(wrap_title(ax, title, 10), fontsize=10)
    fig.tight_layout()
    return save(fig, path)


#: Each measurement by name (its lives and key its function's defaults: the confirmation's fresh lives another key).
MEASUREMENTS = dict(ceiling=measure_ceiling, rates=measure_rates, confirm=measure_confirm)


def measure_parser() -> Parser:
    """A measurement's command line: ``--out DIR NAME [--lives N] [--key K] [--task-steps N]``."""
    p = Parser(prog="python -m experiments.timescale")
    p.add_argument("measurement", choices=MEASUREMENTS)
    p.add_argument("--out", dest="out_dir", metavar="OUT", required=True, help="its folder (the study's stage "
                   "gives its own: a committed one is not written over by hand)")
    for option in ("--lives", "--key"):  # absent: the measurement's own
        p.add_argument(option, type=int)
    p.add_argument("--task-steps", type=int, default=TASK_STEPS)
    return p



def read_rates(out_dir: str) -> list[dict]:
    """The rate sweep's rows beside the confirmation's folder ``out_dir``, checked (raises a user error naming the
    file): a point of every option of RATE_OPTIONS, its rates in the config's bounds, its fitness a number."""
    from imrl_jax.config import ConfigError
    from imrl_jax.runs.rundir import RunDirError, read_json

    path = os.path.join(os.path.dirname(os.path.normpath(out_dir)), "rates", MEASURED)
    if not os.path.isfile(path):
        raise UsageError(f"{out_dir}: the rate sweep has not run (its result.json is missing: {path})")
    rows = read_json(path, "rates")
    if not isinstance(rows, dict) or not isinstance(rows.get("rows"), list) or \
            not all(isinstance(r, dict) for r in rows["rows"]):
        raise RunDirError(f"rates: {path} holds no list of rows")
    config = make_config("paper", condition="EE-LS")
    for row in rows["rows"]:
        try:
            fitness = row["fitness"]
            if row["option"] not in OPTIONS or isinstance(fitness, bool) or not isinstance(fitness, (int, float)) or \
                    not np.isfinite(fitness):
                raise ValueError(f"option {row['option']!r}, fitness {fitness!r}")
            config.replace(**{field: row[field] for field in RATE_GRID})
        except (KeyError, TypeError, ValueError, ConfigError) as error:
            raise RunDirError(f"rates: {path}: a row is unreadable ({cli.one_line(error)})") from None
    for option in RATE_OPTIONS:
        best_rates(rows["rows"], option)
    return rows["rows"]


def measure_plan(argv: list[str]) -> cli.Call:
    """Parse and check a measurement: every value bounded, the sweep it reads, the memory, --out; nothing written."""
    from experiments.harness.measures import check_counts, check_out_dir
    from imrl_jax.evolution.devices import check_memory

    options = {k: v for k, v in vars(measure_parser().parse_args(argv)).items() if v is not None}
    name = options["measurement"]
    check_counts(options, dict(lives=cli.MAX_SEEDS, task_steps=cli.MAX_STEPS))
    cli.check_key("--key", options.get("key"))
    if name == "confirm":
        read_rates(options["out_dir"])
    lives = options.get("lives", MEASUREMENTS[name].__defaults__[0])
    points = len(list(itertools.product(*RATE_GRID.values()))) if name == "rates" else 1
    config = make_config("paper", condition="EE-LS", task_steps=options["task_steps"], num_bins=10)
    lanes = points * lives * config.num_tasks
    cli.check_at_most(f"--lives ({points} points x {config.num_tasks} tasks at once)", lanes, cli.MAX_LANES)
    check_memory(config, lanes, f"the {name} measurement")
    check_out_dir(options["out_dir"], (f"{name}.csv", f"{name}.png", MEASURED), f"{name} measurement")
    return cli.Call(lambda: measure_run(options), **options)


def measure_run(options: dict) -> int:
    """Carry out a checked measurement."""
    options = dict(options)
    MEASUREMENTS[options.pop("measurement")](**options)
    return 0


@exit_codes
def main(argv=None) -> int:
    """A measurement (``--out DIR NAME [--lives N] [--key K] [--task-steps N]``), or the study's run or report."""
    argv = sys.argv[1:] if argv is None else list(argv)
    if set(argv) & set(MEASUREMENTS):
        return cli.execute(measure_plan(argv))
    planned = timescale_table()
    code = planned.main(argv)
    if code or planned.rows or "--report" in argv:
        return code
    measured = timescale_table()  # the measurements have run since: the evolutions they call for
    return measured.main(argv) if measured.rows else code


def all_stages():
    """Every stage planned so far (the evolutions once the measurements have run), and their scale."""
    return timescale_table().all_stages()


#: The studies of this module (python -m experiments finds them).
STUDIES = (Study("timescale", "timescale", DOCUMENT, 1),)

if __name__ == "__main__":
    sys.exit(main())
