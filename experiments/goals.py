"""Why evolving goals is easier than evolving behaviours (docs/GOALS.md): the size-matched controls' first runs.

    python -m experiments run goals          # run (or go on with) every stage, in order
    python -m experiments list goals         # the stages, done or to run

The paper's conditions (LE-LS: 111 reinforcer genes; EE-LS: 222 actor genes) differ in both the size
and the kind of what is evolved. The controls cross the two (MODEL.md "Size-matched controls"):
EE-LS-T evolves behaviours at LE-LS's size, LE-LS-2R goals at EE-LS's size. Each is evolved under
``skills`` and ``faithful`` for 5 seeds x 100 generations of 50 lives at the paper's lengths (150,000 +
6 x 100,000 steps), then its 5 best x 4 tests are learning-tested, as in the future-work study. Then the landscape
measures (``python -m imrl_jax.landscape_run``) of seed 0 of each condition under ``skills`` at
generations 0, 10 and the last, with learning cut too (H3), and the fitness of random genomes (H4).
"""

import os
import sys

import numpy as np

from experiments.harness.study import RESULTS, SCALES, SCREEN
from experiments.harness.table import Measure, Row, Table

#: The study's manifest, logs and measures (its runs lie wherever their keys find them).
OUT = os.path.join(RESULTS, "goals")
#: The paper's runs whose last population was not kept: their best 10 of each seed are (the reproduction's report).
KEPT = ("--best-genomes", os.path.join(RESULTS, "paper", "best_genomes.npz"))
#: A life of each condition, in steps (childhood 150,000 + 6 x 100,000), for the measures' costs.
LIFE = {"LE-LS": 750_000, "EE-LS": 600_000}
#: Lives of a landscape measure: 3 generations x (10 parents x 10 + 5 walks x 10) genomes x 4 lives, 50 random
#: genomes x 4, and 11 generations x 50 replayed; twice the measures with a learning cut.
LIVES, CUT_LIVES = 3 * 150 * 4 + 200 + 550, 3 * 150 * 4 + 200


def landscape(name: str, run: "str | Row", life: int, cut: str | None = None, *extra: str) -> Measure:
    """The landscape measures (H3, H4) of a row's or a committed run's seed 0 at generations 0, 10 and the last."""
    args = (("--cut", cut) if cut else ()) + extra
    return Measure(f"landscape-{name}", run, args, cost=float(life * (LIVES + (CUT_LIVES if cut else 0))))


#: The conditions in the order the landscape tables and figure show them (behaviours, then goals): what each evolves,
#: with its genes, and its colour in the figure (behaviours warm, goals and evaluators cool).
KINDS = {"EE-ES": ("behaviours + selector, 333", "#8c2d04"), "EE-LS": ("behaviours, 222", "#e6550d"),
         "EE-LS-T": ("behaviours (turn), 111", "#fdae6b"), "LE-LS": ("goals, 111", "#08519c"),
         "LE-LS-2R": ("goals (2 units), 222", "#6baed6"), "EV-LS": ("evaluators, 111", "#31a354")}


def read_landscapes(out: str) -> dict[str, dict]:
    """Each condition's landscape measures as far as they have come (landscape.json, result.json once done): its
    random genomes by learning ("learning" or its cut) and its generations' mutations, in the order measured."""
    from experiments.harness.loading import read_json

    found = {}
    for name in KINDS:
        folder = os.path.join(out, "measures", f"landscape-{name}")
        done = read_json(os.path.join(folder, "result.json"))
        if (measured := done or read_json(os.path.join(folder, "landscape.json"))) is not None:
            pieces = measured["pieces"].items()
            found[name] = dict(done=done is not None, generations=[r for p, r in pieces if p.startswith("generation")],
                               random={p.split(", ")[1]: r for p, r in pieces if p.startswith("random genomes")})
    return found


def landscape_tables(found: dict[str, dict]) -> str:
    """H4's table (random genomes) and H3's (mutations and ruggedness around each generation's parents)."""
    from experiments.harness.markdown import table

    random = table(("condition", "evolves, genes", "learning", "mean", "sd", "median", "best", "share at 0"), [
        (name, KINDS[name][0], learning, *(f"{v:.4f}" for v in (r["mean"], r["std"], *r["quantiles"][2::2])),
         f"{r['share_zero']:.0%}") for name, m in found.items() for learning, r in m["random"].items()])
    mutations = table(("condition", "generation", "learning", "parents' fitness", "mean effect", "relative", "neutral",
                       "deleterious", "beneficial", "mutational variance", "rho(1)"), [
        (name, r["generation"], r["learning"], f"{r['parent_mean']:.4f}", f"{r['effect_mean']:+.4f}",
         # relative to the parents' fitness: a measure the lives' noise does not bias
         f"{r['effect_mean'] / r['parent_mean']:+.1%}" if r["parent_mean"] else "-",
         *(f"{r[f'share_{k}']:.0%}" for k in ("neutral", "deleterious", "beneficial")),
         f"{r['mutational_variance']:.2e}", "NaN" if (rho := r["rho_noise_corrected"][0]) is None else f"{rho:.2f}")
        for name, m in found.items() for r in m["generations"]])
    lines = ["**Random genomes** (H4): 50 genomes of generation 0's draw, 4 fresh lives each; fitness = the mean of a "
             "genome's lives.", "", random, "",
             "**Mutations around the parents** (H3): each generation's 10 parents (the GA's), 9 mutants each under the "
             "paper's operator, 4 fresh lives per genome; mean effect: of fitness(mutant) - fitness(parent), relative: "
             "over the parents' fitness; an effect is neutral within 2 standard errors of its lives' noise (noisier "
             "lives call more neutral); rho(1): the fitness autocorrelation one mutation apart along 5 random walks of "
             "9 steps, corrected for the lives' noise (NaN: no variance; with 5 short walks an uncertain estimate, "
             "past 1 where the walks vary little).", "", mutations]
    still = [f"{name} (running)" for name, m in found.items() if not m["done"]] + [n for n in KINDS if n not in found]
    return "\n".join(lines + (["", f"Still to measure: {', '.join(still)}."] if still else []))


def landscape_figure(found: dict[str, dict], path: str) -> str:
    """H4: random genomes' fitness per condition; H3: a mutation's mean effect relative to its parents, the share
    of deleterious mutations and rho(1) at generations 0, 10 and the last, with learning (solid) and cut (dashed:
    the cut the condition's row names; dotted: a second, smaller one)."""
    from imrl_jax.analysis.plotting import new_figure, save, style_axis

    fig = new_figure(13.0, 3.5)
    ax_random, ax_effect, ax_bad, ax_rho = fig.subplots(1, 4, gridspec_kw=dict(width_ratios=[1.3, 1, 1, 1]))
    for i, (name, m) in enumerate(found.items()):
        for j, (learning, r) in enumerate(m["random"].items()):
            x = i + (j - (len(m["random"]) - 1) / 2) * 0.6 / len(m["random"])  # side by side in the condition's slot
            faded = learning != "learning"
            ax_random.scatter(x + np.linspace(-0.06, 0.06, len(r["fitness"])), r["fitness"], s=3, color=KINDS[name][1],
                              alpha=0.3 if faded else 0.9)
            ax_random.plot([x - 0.09, x + 0.09], [r["mean"]] * 2, color="k", lw=1.2, ls="--" if faded else "-")
    ax_random.set_xticks(range(len(found)), list(found), rotation=30, fontsize=7)
    style_axis(ax_random, "H4: random genomes (faded: learning cut)", "", "fitness (mean of 4 lives)")
    # A relative effect beyond 0.25 is drawn at the edge, as a triangle (a parent of almost no fitness).
    panels = ((ax_effect, lambda b: b["effect_mean"] / b["parent_mean"] if b["parent_mean"] else None,
               "a mutation's mean effect", "over its parents' fitness", 0.25),
              (ax_bad, lambda b: b["share_deleterious"], "deleterious mutations", "share of mutants", np.inf),
              # As observed: the correction for the lives' noise overshoots 1 where the walks' variance is small.
              (ax_rho, lambda b: b["rho"][0], "rho(1), lives' noise included", "autocorrelation", np.inf))
    for ax, value, title, ylabel, limit in panels:
        for name, m in found.items():
            cuts = sorted({b["learning"] for b in m["generations"]} - {"learning"}, key=lambda c: -float(c.split()[1]))
            for learning, ls_ in [("learning", "-"), *zip(cuts, ("--", ":"))]:
                points = sorted(({0: 0, 10: 1}.get(b["generation"], 2), value(b)) for b in m["generations"]
                                if b["learning"] == learning and value(b) is not None)  # x: generation 0, 10, last
                if points:
                    x, y = np.array(points).T
                    y = np.clip(y, -limit, limit)
                    ax.scatter(x[np.abs(y) >= limit], y[np.abs(y) >= limit], marker="^", s=30, color=KINDS[name][1])
                    ax.plot(x, y, marker="o", ms=3, ls=ls_, color=KINDS[name][1],
                            label=name if learning == "learning" else None)
        ax.set_xticks(range(3), ["0", "10", "last"])
        ax.axhline(0, color="0.6", lw=0.6)
        style_axis(ax, f"H3: {title}", "generation", ylabel)
    handles, labels = ax_rho.get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=len(labels), fontsize=7, frameon=False)
    fig.suptitle("Landscapes around each condition's generations, seed 0 (solid: with learning; dashed, dotted: "
                 "learning cut)", fontsize=9)
    fig.tight_layout(rect=(0, 0.06, 1, 1))
    return save(fig, path)


class GoalsTable(Table):
    """The goals study's table, whose report also writes the landscape measures' tables and figure."""

    def report(self) -> int:
        from experiments.harness.study import markers, write_table

        code = super().report()
        found = read_landscapes(self.out)
        if found:
            drawn = landscape_figure(found, os.path.join(self.out, "landscape.png"))
            write_table(self.document, landscape_tables(found), *markers("goals landscape", self.name))
            print(f"landscape measures of {len(found)} condition(s); wrote {drawn}")
        return code


PAPER = SCALES["paper"]
TABLE = GoalsTable("goals", "docs/GOALS.md", 9, out=OUT, scale=SCREEN, rows=(
    Row("EE-LS-T", "EE-LS-T", "skills"),  # behaviours at goals' size
    Row("LE-LS-2R", "LE-LS-2R", "skills"),  # goals at behaviours' size
    Row("EE-LS-T-faithful", "EE-LS-T", "faithful"),
    Row("LE-LS-2R-faithful", "LE-LS-2R", "faithful"),
), measures=(  # under skills, on the paper-scale runs of the reproduction and others' runs, found by key (EE-ES
    # learns nothing: its paper run is its only one); H3's cuts: LE-LS-like
    # childhoods to a third (LE-LS's to a tenth too: no genome scores then), EE-LS-like adult selectors to nothing
    # (imrl_jax.evolution.landscape.learning_cut)
    landscape("EE-ES", Row("EE-ES", "EE-ES", "skills", scale=PAPER), LIFE["EE-LS"], None, *KEPT),
    landscape("EE-LS-T", "EE-LS-T", LIFE["EE-LS"], "0"),
    landscape("EE-LS", Row("EE-LS", "EE-LS", "skills", scale=PAPER), LIFE["EE-LS"], "0", *KEPT),
    landscape("LE-LS", Row("LE-LS", "LE-LS", "skills", scale=PAPER), LIFE["LE-LS"], "0.1,0.33", *KEPT),
    landscape("LE-LS-2R", "LE-LS-2R", LIFE["LE-LS"], "0.33"),
    landscape("EV-LS", Row("EV-LS", "EV-LS", "skills"), LIFE["LE-LS"], "0.33"),  # the future-work study's run
))
all_stages, main = TABLE.all_stages, TABLE.main
#: The studies of this module (python -m experiments finds them).
STUDIES = (TABLE.study(__name__.rsplit(".", 1)[-1]),)

if __name__ == "__main__":
    sys.exit(main())
