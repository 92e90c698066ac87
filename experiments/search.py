"""Modern evolution strategies beside the paper's GA (docs/SEARCH.md): EE-LS, EE-ES and LE-LS under ``skills``.

    python -m experiments run search         # run (or go on with) every stage, in order
    python -m experiments list search        # the stages, done or to run
    python -m experiments report search      # the curves, tables and claims of what has finished

Each row is a search strategy (``python -m imrl_jax.evolve --strategy NAME``) evolving a condition of the
paper under ``skills`` at the screen's sizes (5 seeds x 100 generations of 50 lives, paper lengths), then a
learning test of its 5 best x 4 tests. The GA's rows are the reproduction's ``skills`` runs at the paper's
sizes (10 seeds; their keys find them): the search is the only difference. The report adds claims 1-4 and 6
recomputed per strategy with the verdict rules of :mod:`imrl_jax.analysis.claims`, and the experts, paths and
learning tests behind them.
"""

from __future__ import annotations

import dataclasses
import os
import sys

import numpy as np

from experiments.harness.figures import not_run
from experiments.harness.loading import write_json
from experiments.harness.study import RESULTS, SCALES, SCREEN
from experiments.harness.table import Row, Table, row_option
from experiments.harness.markdown import head, line, mean_sd
from imrl_jax import conditions
from imrl_jax.evolution.strategies import GA_NAME

PRESET = "skills"
CONDITIONS = ("EE-LS", "EE-ES", "LE-LS")
#: Sep-CMA-ES (diagonal covariance: 111-333 genes, 50 lives) and SNES (separable natural ES), at evosax's
#: defaults and the paper's initial spread (mean 0, sd 1/sqrt(3) as U[-1, 1]).
STRATEGIES = ("sep_cma_es", "snes")
#: The strategies the report compares, the paper's GA first.
COMPARED = (GA_NAME, *STRATEGIES)
#: Their lines in the figures.
STRATEGY_STYLES = {GA_NAME: dict(color="black", lw=2.0), "sep_cma_es": dict(color="tab:blue", lw=1.6, ls="--"),
                   "snes": dict(color="tab:orange", lw=1.6, ls=":")}
#: SLE evolves nothing: the reproduction's ``skills`` test of it is every strategy's SLE in claim 6.
SLE = Row("SLE", "SLE", PRESET, scale=SCALES["paper"])
#: The claims that depend on the search (the evolutions, or the learning tests of what they found).
CLAIM_NUMBERS = (1, 2, 3, 4, 6)


def strategy_of(row: Row) -> str:
    """The search a row evolves with: its ``--strategy`` option, or the paper's GA."""
    return row_option(row, "--strategy", GA_NAME)


def judge(strategies, rows: list[dict], sle_per_run: list[float] | None, paths: dict) -> dict:
    """Claims 1-4 and 6 per strategy from its rows (finished evolutions only), SLE's test and its EE-ES's path."""
    from imrl_jax.analysis.claims import evolved_claims

    claims = {}
    for strategy in strategies:
        mine = {r["condition"]: r for r in rows if r["strategy"] == strategy}
        claims[strategy] = evolved_claims({c: r for c, r in mine.items() if r["finished"]}, {
            **{c: mine[c].get("steady_per_run") if c in mine else None for c in CONDITIONS}, "SLE": sle_per_run},
            paths.get(strategy))
        claims[strategy][4]["path_probe"] = paths.get(strategy) is not None
    return claims


def steady(tested: str) -> dict | None:
    """A learning test's steady state: mean and sd over runs (ddof 0, as learning_test writes them); None: not run."""
    from experiments.harness.loading import read_test

    if (test := read_test(tested)) is None:
        return None
    per_run = [float(v) for v in test["steady"]["steady_per_run"]]
    return dict(steady_mean=float(test["steady"]["steady_mean"]), steady_sd=float(test["steady"]["steady_sd"]),
                test_runs=len(per_run), steady_per_run=per_run)


def table(measured: dict) -> str:
    """The report's markdown beyond the rows' table: each row's fresh lives and experts, then the claims' verdicts
    per strategy."""
    from imrl_jax.analysis.claims import CLAIMS

    lines = head("strategy", "condition", "fresh lives (sd over seeds)", "colours followed (share with 3)")
    lines += [line(r["strategy"], r["condition"],
                   "-" if r.get("fresh_mean") is None else f"{r['fresh_mean']:.3f} ({r['fresh_sd']:.3f})",
                   "-" if r.get("colours_mean") is None else f"{r['colours_mean']:.2f} ({r['specialised_share']:.2f})")
              for r in measured["rows"]]
    sle = measured["sle"]
    lines += ["", "SLE evolves nothing: every strategy's claim 6 uses the reproduction's `skills` test of it"
              + (f" (steady state {mean_sd(sle['steady_mean'], sle['steady_sd'])} over {sle['test_runs']} runs)."
                 if sle else " (not found)."), "", *head("claim", "strategy", "verdict", "measured")]
    shown = [strategy for strategy in measured["claims"] if any(r["strategy"] == strategy for r in measured["rows"])]
    for number in CLAIM_NUMBERS:
        for i, strategy in enumerate(shown):
            claim = measured["claims"][strategy][number]
            whose = "the GA's" if strategy == GA_NAME else "its"
            note = "" if number != 4 else "; path: " + (f"{whose} relived best EE-ES" if claim["path_probe"] else
                                                         "not measured")
            lines.append(line("" if i else f"{number}: {CLAIMS[number]}", strategy, f"**{claim['verdict']}**",
                              claim["measured"] + note))
    lines += ["", "Claim 4's path: for the GA, the path is that of the reproduction's relived best EE-ES individual "
              "(docs/reproduction/summary.json); for the others, the fittest genome of the last generation relived, "
              "then each task driven (`experiments.harness.relive.run_path`, kept in the run's `path.json`). The rules are "
              "`imrl_jax.analysis.claims.RULES`, as in [REPRODUCTION.md](REPRODUCTION.md); the claims judge finished "
              "evolutions only (n/a: a condition not finished), and a strategy with nothing run yet is left out."]
    return "\n".join(lines)


def claims_figure(measured: dict, path: str) -> str:
    """What the claims judge, per strategy: the experts' colours (claim 3's explanation), EE-ES's path (claim 4)
    and the learning tests' steady states (claim 6)."""
    from imrl_jax.analysis.claims import STEREOTYPED_TURNS
    from imrl_jax.analysis.plotting import new_figure, save, style_axis

    fig = new_figure(13.0, 3.8)
    ax_colours, ax_path, ax_steady = fig.subplots(1, 3)
    width = 0.8 / len(COMPARED)
    rows = {(r["strategy"], r["condition"]): r for r in measured["rows"]}
    probed = [c for c in CONDITIONS if any("colours_mean" in rows.get((s, c), {}) for s in COMPARED)]
    for ax, names, key, sd_key in ((ax_colours, probed, "colours_mean", None),
                                   (ax_steady, CONDITIONS, "steady_mean", "steady_sd")):
        for j, strategy in enumerate(COMPARED):
            found = [(i, rows[strategy, c]) for i, c in enumerate(names) if key in rows.get((strategy, c), {})]
            if found:
                x = np.asarray([i for i, _ in found]) + (j - (len(COMPARED) - 1) / 2) * width
                ax.bar(x, [r[key] for _, r in found], width, yerr=[r[sd_key] for _, r in found] if sd_key else None,
                       capsize=2, color=STRATEGY_STYLES[strategy]["color"], alpha=0.8, label=strategy)
        ax.set_xticks(range(len(names)), names)
        if ax.patches:  # a bar drawn: there is a legend to show
            ax.legend(fontsize=7)
    style_axis(ax_colours, "claim 3's experts: colours followed", "", "colours an individual's experts follow")
    ax_colours.set_ylim(0, 3)
    if measured["sle"]:
        ax_steady.axhline(measured["sle"]["steady_mean"], color="0.4", lw=1, ls="--", label="SLE (reproduction)")
        ax_steady.legend(fontsize=7, loc="upper center")
    style_axis(ax_steady, "claim 6: learning tests", "", "steady state (mean +- sd over runs)")
    for strategy, life in measured["paths"].items():
        if life is not None:
            ax_path.plot(np.arange(1, len(life["stereotypy_per_task"]) + 1), life["stereotypy_per_task"], marker="o",
                         label=strategy, **STRATEGY_STYLES[strategy])
    ax_path.axhline(STEREOTYPED_TURNS, color="0.4", lw=1, ls="--", label="circular from here")
    ax_path.set_ylim(0, 1)
    style_axis(ax_path, "claim 4: the best EE-ES's path", "task", "stereotypy (turns the same way)")
    ax_path.legend(fontsize=7)
    fig.tight_layout()
    return save(fig, path)


class SearchTable(Table):
    """The search study's table: its rows measured per strategy, the claims judged per strategy, its figures."""

    def measure_search(self) -> dict:
        """Per strategy and condition the evolution's and learning test's numbers, and claims 1-4 and 6 per
        strategy; the GA's fresh lives, junction probes and relived best EE-ES (claim 4's path) are the reproduction's
        report's."""
        from imrl_jax.analysis.claims import final_best
        from experiments.claims_study import probed, reproduction_summary, reproduction_variant
        from experiments.harness.relive import reproduction_fresh, run_fresh, run_path

        summary = reproduction_summary(self.document) or {}
        rows, paths = [], {}
        for row, m, tested in zip(self.rows, self.measure(), self.tests().values()):
            strategy, condition = strategy_of(row), row.condition
            if not m["generations"] and "steady_mean" not in m:
                continue  # not started: no row
            entry = dict(strategy=strategy, condition=condition, generations=m["generations"],
                         finished="final_mean" in m, **({"seeds": m["seeds"]} if m["generations"] else {}))
            if entry["finished"]:  # a running evolution is drawn but not measured: its last generations are to come
                entry.update(final_best_mean=m["final_mean"], final_best_sd=m["final_sd"],
                             final_best_per_seed=final_best(m["best"]).tolist(), plateau_generation=m["plateau"])
                # the GA's runs kept no population: their fresh lives, probes and path are the reproduction's
                ga, variant = strategy == GA_NAME, reproduction_variant(m["dir"], self.reproduction)
                if conditions.get(condition).learns:  # claim 7's probe of each seed's 10 best: what it learns with
                    colours, _, fresh = probed(m["dir"], None, summary if ga else None, variant, condition)
                else:  # claim 4's path: the best individual that learns nothing
                    fresh = reproduction_fresh(summary, variant, condition) if ga else run_fresh(m["dir"])
                    life = (summary.get("best_individuals") or {}).get(f"{variant}/{condition}")
                    paths[strategy] = run_path(m["dir"]) if not ga else None if life is None else dict(
                        stereotypy_per_task=life["stereotypy_per_task"], speed=life["speed"])
                    colours = None
                if fresh is not None:
                    entry.update(fresh_mean=fresh["mean"], fresh_sd=fresh["sd_over_seeds"])
                if colours:
                    entry.update(colours_mean=float(np.mean(colours)),
                                 specialised_share=float(np.mean(np.asarray(colours) == 3)), probed=len(colours))
            entry.update(steady(tested) or {})
            rows.append(entry)
        sle = steady(dataclasses.replace(self, rows=(SLE,)).tests()[SLE.name])  # the reproduction's, by key
        return dict(rows=rows, claims=judge(COMPARED, rows, sle["steady_per_run"] if sle else None, paths), sle=sle,
                    paths=paths)

    def figure(self, measured: list[dict], path: str) -> str:
        """Fig. 3a-style curves: best fitness per generation (mean over seeds +- sd), a panel per condition, a line
        per strategy."""
        from matplotlib.ticker import MaxNLocator

        from experiments.harness.figures import _band
        from imrl_jax.analysis.plotting import new_figure, save, style_axis

        fig = new_figure(13.0, 3.8)
        axes = fig.subplots(1, len(CONDITIONS), sharey=True)  # one y-axis: the conditions' levels compare across panels
        for i, (ax, condition) in enumerate(zip(axes, CONDITIONS)):
            drawn = [(strategy_of(r), m) for r, m in zip(self.rows, measured) if r.condition == condition
                     and m["generations"]]
            style_axis(ax, f"{condition} under {PRESET}, by search strategy", "generation",
                       "" if i else "best fitness (best of a generation's lives)")
            if not drawn:  # an unfinished stage: say so rather than leave a blank panel
                not_run(ax)
                continue
            banded = set()
            for strategy, m in drawn:
                x, mean, sd = np.arange(m["generations"]), m["best"].mean(1), m["best"].std(1)
                ax.plot(x, mean, label=f"{strategy} ({m['seeds']} seeds)" + ("" if "final_mean" in m else ", running"),
                        **STRATEGY_STYLES[strategy])
                _band(ax, x, mean, sd, STRATEGY_STYLES[strategy], banded)
            ax.xaxis.set_major_locator(MaxNLocator(integer=True))
            ax.legend(fontsize=7)
        axes[0].set_ylim(bottom=0)  # once, after every panel is drawn: the shared top must still scale to all of them
        fig.tight_layout()
        return save(fig, path)

    def report(self) -> int:
        """The rows' table and curves; then report.json, the claims' figure and the study's tables."""
        from experiments.harness.study import markers, write_table

        code = super().report()
        measured = self.measure_search()
        write_json(os.path.join(self.out, "report.json"),
                   {k: measured[k] for k in ("rows", "sle", "claims")}, indent=2)  # claim numbers as keys: "1"
        drawn = claims_figure(measured, os.path.join(self.out, "claims.png"))
        write_table(self.document, table(measured), *markers("search tables", self.name))
        print(f"wrote {os.path.join(self.out, 'report.json')}, {drawn} and the claims of {self.document}")
        return code


TABLE = SearchTable("search", "docs/SEARCH.md", 6, out=os.path.join(RESULTS, "search"), scale=SCREEN, rows=(
    *(Row(f"{GA_NAME}-{c}", c, PRESET, scale=SCALES["paper"]) for c in CONDITIONS),  # the reproduction's runs
    *(Row(f"{s}-{c}", c, PRESET, options=("--strategy", s)) for s in STRATEGIES for c in CONDITIONS)))
all_stages, main = TABLE.all_stages, TABLE.main
#: The studies of this module (python -m experiments finds them).
STUDIES = (TABLE.study(__name__.rsplit(".", 1)[-1]),)

if __name__ == "__main__":
    sys.exit(main())
