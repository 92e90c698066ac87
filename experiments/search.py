"""Modern evolution strategies beside the paper's GA (docs/SEARCH.md): EE-LS, EE-ES and LE-LS under ``skills``.

    python -m experiments.search                    # run (or go on with) every stage, in order
    python -m experiments.search --only snes        # the rows of some strategies
    python -m experiments.search --list             # the stages and their commands, nothing run
    python -m experiments.search --report           # the curves, tables and claims of what has finished

Each row is a search strategy (``python -m imrl_jax.evolve --strategy NAME``) and an evolved
condition of the paper under the ``skills`` preset, evolved at the paper's life lengths
(150,000 + 6 x 100,000 steps) for 5 seeds x 100 generations of 50 lives, then a learning
test of its 5 best x 4 tests (1,000,000 cycles per task). The GA's rows are the finished
paper-scale reproduction's ``skills`` runs (``experiments/results/paper/skills``: 10 seeds,
learning tests of 10 x 10 x 10), not run again: the search is the only difference. The stages
run through the reproduction's resumable stage runner
(:func:`experiments.reproduce.run_stages`): run the same command again after an interruption.

``--report`` (:func:`report`) reads whatever has finished, the GA's rows and this study's: Fig. 3a-style
curves per condition (one line per strategy), the final best fitness, its spread and plateau and the
learning test's steady state per row, and claims 1-4 and 6 recomputed per strategy with the verdict rules
of :mod:`experiments.claims`; it writes them under ``--out`` and into docs/SEARCH.md.
"""

from __future__ import annotations

import argparse
import os
import sys
from typing import NamedTuple

from experiments.study import REPRODUCTION, SCREEN
from experiments.reproduce import (Stage, evolution_cost, evolution_dir, evolve_command, load_manifest, run_stages,
                                   test_command, test_cost, test_dir)
from experiments.executor import add_options, from_options
from experiments.study import RESULTS, Study
from imrl_jax.strategies import GA_NAME

OUT = os.path.join(RESULTS, "search")
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


def run_dirs(strategy: str, condition: str, out: str = OUT, reproduction: str = REPRODUCTION) -> tuple[str, str]:
    """A row's evolution and learning-test folders: the reproduction's ``skills`` runs for the GA, else this study's."""
    if strategy == GA_NAME:  # EE-ES's are the reproduction's shared ones under paper (it learns nothing)
        return evolution_dir(reproduction, PRESET, condition), test_dir(reproduction, PRESET, condition)
    folder = os.path.join(out, strategy, condition)
    return os.path.join(folder, "evolve"), os.path.join(folder, "test")


def plan(rows, scale: dict = SCREEN, out: str = OUT) -> list[Stage]:
    """The stages of ``rows``, in order: each evolution then its learning test."""
    stages = []
    for row in rows:
        evolved, tested = run_dirs(row.strategy, row.condition, out)
        stages.append(Stage(f"evolve {row.name}", "evolve", row.name, row.condition, evolved,
                            evolution_cost(scale, row.condition)))
        stages.append(Stage(f"learning test {row.name}", "test", row.name, row.condition, tested,
                            test_cost(scale, row.condition)))
    return stages


def stage_command(stage: Stage, scale: dict = SCREEN) -> tuple[list[str], None]:
    """A stage's command line: evolve with the row's strategy, or the learning test of its run."""
    row = BY_NAME[stage.variant]
    if stage.kind == "evolve":
        return evolve_command(scale, PRESET, row.condition, stage.out_dir) + ["--strategy", row.strategy], None
    evolved = os.path.join(os.path.dirname(stage.out_dir), "evolve")
    return test_command(scale, PRESET, row.condition, evolved, stage.out_dir), None


#: The strategies the report compares, the paper's GA first.
COMPARED = (GA_NAME, *dict.fromkeys(row.strategy for row in ROWS))
#: Their lines in the figure.
STRATEGY_STYLES = {GA_NAME: dict(color="black", lw=2.0), "sep_cma_es": dict(color="tab:blue", lw=1.6, ls="--"),
                   "snes": dict(color="tab:orange", lw=1.6, ls=":")}
#: The finished reproduction's report: its relived best EE-ES individual (the GA's) is claim 4's path probe.
GA_SUMMARY = os.path.join("docs", "reproduction", "summary.json")
#: SLE evolves nothing: the reproduction's ``skills`` test of it is every strategy's SLE in claim 6.
SLE = "SLE"
#: The claims that depend on the search (the evolutions, or the learning tests of what they found).
CLAIM_NUMBERS = (1, 2, 3, 4, 6)
GA_PATH = f"the path is that of the reproduction's relived best EE-ES individual ({GA_SUMMARY})"
#: The conditions whose experts the junction probe checks (claim 7's probe: does the search find accurate experts?).
PROBED = ("EE-LS", "LE-LS")
#: Claim 4's path for a strategy: its own best EE-ES individual relived (experiments.relive.run_path).
OWN_PATH = ("the fittest genome of the last generation relived, then each task driven "
            "(`experiments.relive.run_path`, kept in the run's `path.json`)")
#: Where the report's tables go in docs/SEARCH.md.
TABLE_START = "<!-- search tables: python -m experiments.search --report -->"
TABLE_END = "<!-- end of search tables -->"


def _complete(best):
    """The leading generations that every seed has finished (a running evolution's last one may be partial)."""
    import numpy as np

    done = ~np.isnan(best).any(1)
    return best[:len(best) if done.all() else int(np.argmin(done))]


def _steady(test: dict) -> dict:
    """A finished learning test's steady state: mean and sd over runs (ddof 0, as learning_test writes them)."""
    import numpy as np

    s = test["steady"]
    per_run = [float(v) for v in s["steady_per_run"]]
    return dict(steady_mean=float(s.get("steady_mean", np.mean(per_run))),
                steady_sd=float(s.get("steady_sd", np.std(per_run))), test_runs=len(per_run), steady_per_run=per_run)


def _ga_path(summary_path: str) -> dict | None:
    """The GA's best EE-ES individual's path probe from the reproduction's summary.json (None without it)."""
    from experiments.loading import read_json
    from experiments.reproduce import owner

    life = ((read_json(summary_path) or {}).get("best_individuals") or {}).get(f"{owner(PRESET, 'EE-ES')}/EE-ES")
    return None if life is None else dict(stereotypy_per_task=life["stereotypy_per_task"], speed=life["speed"])


def measure(out: str = OUT, reproduction: str = REPRODUCTION, ga_summary: str = GA_SUMMARY,
            generations: int = SCREEN["generations"]) -> dict:
    """Per strategy and condition the evolution's and learning test's numbers, and claims 1-4 and 6 per strategy."""
    import numpy as np

    from experiments.claims import (EVOLVED, claim_evolvability, claim_ee_es_about, claim_ee_ls_higher,
                                    claim_ordering, claim_reliability, final_best, plateau_generation)
    from experiments.loading import read_evolution, read_json, read_test
    from experiments.relive import colours_followed, reproduction_fresh, run_fresh, run_path, run_probe
    from experiments.reproduce import owner

    summary = read_json(ga_summary) or {}
    rows, curves = [], {}
    for strategy in COMPARED:
        for condition in CONDITIONS:
            evolved, tested = run_dirs(strategy, condition, out, reproduction)
            run, test = read_evolution(evolved), read_test(tested)
            best = _complete(run["best"]) if run is not None else None
            if (best is None or not len(best)) and test is None:
                continue  # not started: no row
            row = dict(strategy=strategy, condition=condition, generations=0 if best is None else len(best),
                       finished=best is not None and len(best) >= generations)
            if best is not None and len(best):
                curves[strategy, condition] = best
                row["seeds"] = int(best.shape[1])
            if row["finished"]:  # a running evolution is drawn but not measured: its last generations are to come
                final = final_best(best)
                row.update(final_best_mean=float(final.mean()), final_best_sd=float(final.std()),
                           final_best_per_seed=[float(v) for v in final],
                           plateau_generation=plateau_generation(best.mean(1)))
                # each seed's best genome in fresh lives: the GA's from the reproduction's report
                fresh = (reproduction_fresh(summary, owner(PRESET, condition), condition) if strategy == GA_NAME
                         else run_fresh(evolved, run["config"]))
                if fresh is not None:
                    row.update(fresh_mean=fresh["mean"], fresh_sd=fresh["sd_over_seeds"])
                if condition in PROBED:  # claim 7's probe of each seed's 10 best: the GA's from the reproduction
                    if strategy == GA_NAME:
                        colours = (summary.get("colours_followed") or {}).get(f"{owner(PRESET, condition)}/{condition}")
                    else:
                        probe = run_probe(evolved, run["config"])
                        colours = None if probe is None else colours_followed(probe["followed"])
                    if colours:
                        row.update(colours_mean=float(np.mean(colours)),
                                   specialised_share=float(np.mean(np.asarray(colours) == 3)), probed=len(colours))
            if test is not None:
                row.update(_steady(test))
            rows.append(row)
    sle = read_test(test_dir(reproduction, PRESET, SLE))
    sle = _steady(sle) if sle is not None else None
    ga_path = _ga_path(ga_summary)
    claims = {}
    for strategy in COMPARED:
        mine = {r["condition"]: r for r in rows if r["strategy"] == strategy}
        done = {c: r for c, r in mine.items() if r["finished"]}  # the claims judge finished evolutions only
        get = lambda d, c, k: d[c].get(k) if c in d else None  # noqa: E731
        # the path of the best EE-ES individual: the GA's from the reproduction's report, a strategy's relived here
        path = (ga_path if strategy == GA_NAME else
                run_path(run_dirs(strategy, "EE-ES", out, reproduction)[0]) if "EE-ES" in done else None)
        claims[strategy] = {
            1: claim_evolvability({c: get(done, c, "plateau_generation") for c in EVOLVED}),
            2: claim_reliability({c: get(done, c, "final_best_sd") for c in EVOLVED}),
            3: claim_ee_ls_higher(get(done, "EE-LS", "final_best_per_seed"), get(done, "LE-LS", "final_best_per_seed")),
            4: claim_ee_es_about(get(done, "EE-ES", "final_best_mean"), get(done, "LE-LS", "final_best_mean"),
                                 path["stereotypy_per_task"] if path else None, path["speed"] if path else None),
            6: claim_ordering({**{c: get(mine, c, "steady_per_run") for c in CONDITIONS},
                               SLE: sle["steady_per_run"] if sle else None}),
        }
        claims[strategy][4]["path_probe"] = path is not None
    return dict(rows=rows, curves=curves, claims=claims, sle=sle, generations=generations)


def _number(value, digits: int = 3) -> str:
    """A number of the tables, or "-" when not measured."""
    return "-" if value is None else f"{value:.{digits}f}" if isinstance(value, float) else str(value)


def table(measured: dict) -> str:
    """The report's markdown: a row per strategy and condition, then the claims' verdicts per strategy."""
    from experiments.claims import CLAIMS, LAST_GENERATIONS, PLATEAU_FRACTION

    lines = ["| strategy | condition | seeds | generations | final best fitness | sd over seeds | fresh lives (sd over "
             "seeds) | plateau generation | colours followed (share with 3) | test runs | steady state | sd over runs |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in measured["rows"]:
        generations = str(r["generations"]) if r["finished"] else f"{r['generations']} of {measured['generations']}"
        lines.append(f"| {r['strategy']} | {r['condition']} | {r.get('seeds', '-')} | {generations} | "
                     f"{_number(r.get('final_best_mean'))} | {_number(r.get('final_best_sd'))} | "
                     + ("-" if r.get("fresh_mean") is None else f"{r['fresh_mean']:.3f} ({r['fresh_sd']:.3f})")
                     + f" | {_number(r.get('plateau_generation'))} | "
                     + ("-" if r.get("colours_mean") is None else
                        f"{r['colours_mean']:.2f} ({r['specialised_share']:.2f})")
                     + f" | {r.get('test_runs', '-')} | "
                     f"{_number(r.get('steady_mean'))} | {_number(r.get('steady_sd'))} |")
    if not measured["rows"]:
        lines.append("| (no stage has finished yet) | | | | | | | | | | | |")
    sle = measured["sle"]
    lines += ["", f"Final best fitness: the best of a generation's noisy lives, mean of the last {LAST_GENERATIONS} "
              f"generations per seed, then mean and sd (ddof 0) over seeds; fresh lives: each seed's best genome "
              f"of the last generation in 10 new lives (keys the search never used), mean over seeds and sd over seeds (ddof 1; "
              f"the GA's from the reproduction's report); plateau generation: the first at which the "
              f"mean over seeds reaches {PLATEAU_FRACTION:.0%} of its final value; colours followed: claim 7's junction "
              f"probe of each seed's 10 best genomes of the last generation (LE-LS after a fresh childhood), the mean "
              f"number of colours their experts follow and the share following all 3 (the GA's from the "
              f"reproduction's report; EE-LS and LE-LS only); steady state: the learning test's "
              f"last {SCREEN['steady_steps']:,} cycles of each task, mean and sd over runs. A running evolution shows "
              "its generations so far and is drawn, not measured. SLE evolves "
              "nothing: every strategy's claim 6 uses the reproduction's `skills` test of it"
              + (f" (steady state {sle['steady_mean']:.3f} +- {sle['steady_sd']:.3f} over {sle['test_runs']} runs)."
                 if sle else " (not found)."), "",
              "| claim | strategy | verdict | measured |", "|---|---|---|---|"]
    shown = [strategy for strategy in measured["claims"] if any(r["strategy"] == strategy for r in measured["rows"])]
    for number in CLAIM_NUMBERS:
        for i, strategy in enumerate(shown):
            claim = measured["claims"][strategy][number]
            note = "" if number != 4 else "; path: " + ("not measured" if not claim["path_probe"] else
                                                         "the GA's relived best EE-ES" if strategy == GA_NAME else
                                                         "its relived best EE-ES")
            lines.append(f"| {'' if i else f'{number}: {CLAIMS[number]}'} | {strategy} | **{claim['verdict']}** | "
                         f"{claim['measured']}{note} |")
    lines += ["", f"Claim 4's path: for the GA, {GA_PATH}; for the others, {OWN_PATH}. The rules are "
              "`experiments.claims.RULES`, as in [REPRODUCTION.md](REPRODUCTION.md); the claims judge finished "
              "evolutions only (n/a: a condition not finished), and a strategy with nothing run yet is left out."]
    return "\n".join(lines)


def figure(measured: dict, path: str) -> str:
    """Fig. 3a-style curves: best fitness per generation (mean over seeds +- sd), a panel per condition, a line per
    strategy."""
    from matplotlib.ticker import MaxNLocator

    from experiments.figures import _band, _fitness_series
    from imrl_jax.plotting import new_figure, save, style_axis

    fig = new_figure(13.0, 3.8)
    finished = {(r["strategy"], r["condition"]): r["finished"] for r in measured["rows"]}
    axes = fig.subplots(1, len(CONDITIONS), sharey=True)  # one y-axis: the conditions' levels compare across panels
    for i, (ax, condition) in enumerate(zip(axes, CONDITIONS)):
        title = f"{condition} under {PRESET}, by search strategy"
        series = _fitness_series({s: best for (s, c), best in measured["curves"].items() if c == condition})
        style_axis(ax, title, "generation", "" if i else "best fitness (best of a generation's lives)")
        if not series:  # an unfinished stage: say so rather than leave a blank panel
            ax.text(0.5, 0.5, "not run yet", transform=ax.transAxes, ha="center", va="center", color="0.4")
            continue
        banded = set()
        for strategy, (x, mean, sd, label) in series.items():
            label += "" if finished[strategy, condition] else ", running"
            ax.plot(x, mean, label=label, **STRATEGY_STYLES[strategy])
            _band(ax, x, mean, sd, STRATEGY_STYLES[strategy], banded)
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        ax.legend(fontsize=7)
    axes[0].set_ylim(bottom=0)  # once, after every panel is drawn: the shared top must still scale to all of them
    fig.tight_layout()
    return save(fig, path)


def report(out: str = OUT, document: str = os.path.join("docs", "SEARCH.md"), reproduction: str = REPRODUCTION,
           ga_summary: str = GA_SUMMARY) -> int:
    """Measure, write report.json and search.png under ``out``, and the tables into ``document``."""
    import json

    from experiments.study import write_table

    measured = measure(out, reproduction, ga_summary)
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, "report.json"), "w") as f:
        json.dump(dict(rows=measured["rows"], sle=measured["sle"],
                       claims={s: {str(n): c for n, c in claims.items()} for s, claims in measured["claims"].items()}),
                  f, indent=2)
    drawn = figure(measured, os.path.join(out, "search.png"))
    write_table(document, table(measured), TABLE_START, TABLE_END)
    finished = sum(r["finished"] for r in measured["rows"])
    print(f"{len(measured['rows'])} rows read ({finished} finished evolutions); wrote "
          f"{os.path.join(out, 'report.json')}, {drawn} and the tables of {document}")
    return 0


def all_stages(out: str = OUT) -> tuple[list[Stage], dict]:
    """Every stage the command runs by default (every row), and their scale."""
    return plan(ROWS, SCREEN, out), SCREEN


def main(argv=None) -> int:
    """The command line: list the chosen rows' stages, or run (or go on with) them."""
    p = argparse.ArgumentParser(prog="python -m experiments.search", description=__doc__.split("\n\n")[0])
    strategies = sorted({row.strategy for row in ROWS})
    p.add_argument("--only", help=f"comma-separated strategies or rows (default: all: {', '.join(strategies)})")
    p.add_argument("--out", default=OUT, help=f"results directory (default: {OUT})")
    p.add_argument("--list", action="store_true", help="print the stages and their commands, run nothing")
    p.add_argument("--report", action="store_true", help="measure what has finished, draw the figure and write "
                   "docs/SEARCH.md's tables (runs nothing)")
    add_options(p)
    args = p.parse_args(argv)
    if args.report:
        return report(args.out)
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
    return run_stages(stages, SCREEN, manifest, manifest_path, lambda stage: stage_command(stage, SCREEN),
                      **from_options(args, args.out))


#: The studies of this module (python -m experiments finds them).
STUDIES = (Study("search", "search", "docs/SEARCH.md", 6),)


if __name__ == "__main__":
    sys.exit(main())
