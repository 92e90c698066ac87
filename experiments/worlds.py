"""The paper's questions in a second world (docs/WORLDS.md): its conditions and controls in XLand-MiniGrid.

    python -m experiments run worlds         # run (or go on with) every stage, in order
    python -m experiments list worlds        # the stages, done or to run
    python -m experiments report worlds      # the curves and tables of what has finished

Each row is a condition of the paper (and the length control LE-LS-Z, EE-LS's genome length in this world) evolved
in the XLand world of ``imrl_jax/world/xland.py`` (``--world xland``) under the paper's rules, at :data:`SCALE`:
5 seeds x 50 generations of the paper's GA (50 lives, 10 parents), a childhood of 20,000 steps and tasks of 10,000
(the paper's 150,000 and 100,000 scaled to two CPU cores: a task's shortest solution is 12-14 steps, so 10,000
steps still hold 700-800 of them), then a learning test of each seed's 5 best x 2 tests at 10 x the task length.
SLE learns each task from scratch there. The measures test the evolved rows on the world's novel tasks
(``--world-set task_set=xland-novel``), SLE beside them, and measure the landscapes of goals and behaviours (H1, H2,
H4 of docs/GOALS.md: ``imrl_jax.landscape_run`` on each row's seed 0).
"""

from __future__ import annotations

import os
import sys

import numpy as np

from experiments.harness.loading import read_test, write_json
from experiments.harness.markdown import head, line, mean_sd
from experiments.harness.reproduce import test_command, test_cost
from experiments.harness.study import RESULTS, markers, write_table
from experiments.harness.table import Measure, Row, Table

#: The study's manifest, logs and measures (its runs lie wherever their keys find them).
OUT = os.path.join(RESULTS, "worlds")
WORLD = ("--world", "xland")
NOVEL = ("--world-set", "task_set=xland-novel")
#: The sizes of its runs (see the module's docstring).
SCALE = dict(seeds=5, generations=50, childhood_steps=20_000, task_steps=10_000, bins=10, best=5, tests=2,
             test_steps=100_000, test_bins=50, steady_steps=10_000)
#: The evolved conditions: the paper's three and the length control.
EVOLVED = ("LE-LS", "EE-LS", "EE-ES", "LE-LS-Z")


#: A life of each condition in steps (childhood, six tasks), for the measures' costs.
LIFE = {"LE-LS": 20_000 + 6 * 10_000, "EE-LS": 6 * 10_000, "EE-ES": 6 * 10_000}
#: Lives of a landscape measure (imrl_jax.landscape_run's defaults, as the goals study): 3 generations x (10 parents
#: x 10 + 5 walks x 10) genomes x 4 lives, 50 random genomes x 4, and replays; twice with a learning cut.
LIVES, CUT_LIVES = 3 * 150 * 4 + 200 + 550, 3 * 150 * 4 + 200
#: The learning cuts of the landscape measures (H4: how much of a goal's value needs learning), as the goals study's.
CUTS = {"LE-LS": "0.1,0.33", "EE-LS": "0", "EE-ES": None}


def landscape(row: Row) -> Measure:
    """The landscape measures (H1, H2, H4) of a row's seed 0 at generations 0, 10 and the last (docs/GOALS.md)."""
    cut = CUTS[row.condition]
    return Measure(f"landscape-{row.name}", row.name, ("--cut", cut) if cut else (),
                   cost=float(LIFE[row.condition] * (LIVES + (CUT_LIVES if cut else 0))))


def novel_test(row: Row) -> Measure:
    """A learning test of ``row``'s run on the world's novel tasks, at the table's sizes."""
    runner = tuple(test_command(SCALE, "paper", "EE-ES", "RUN", "OUT")[4:-2])  # the runner's options, at SCALE
    return Measure(f"{row.name} on novel", row.name, runner + NOVEL, "imrl_jax.learning_test",
                   test_cost(SCALE, row.condition), os.path.join("novel", row.condition), kind="test")


#: The variant name the report's claims and figures file this world's numbers under.
VARIANT = "xland"


def claims_of(rows: dict, tests: dict) -> dict:
    """The seven claims judged on this world's finished evolutions and tests, by the arena's rules
    (``imrl_jax.analysis.claims.RULES``); claim 4's path and claim 7's junction probe are the arena's: not measured."""
    from imrl_jax.analysis.claims import (NOT_AVAILABLE, STEADY_ORDER, claim_learning_speed, evolved_claims,
                                          final_best)

    done = {c: dict(final_best_mean=m["final_mean"], final_best_sd=m["final_sd"], plateau_generation=m["plateau"],
                    final_best_per_seed=final_best(m["best"]).tolist())
            for c, m in rows.items() if "final_mean" in m}
    per_run = {c: tests[c]["steady"]["steady_per_run"] if tests.get(c) else None for c in STEADY_ORDER}
    claims = evolved_claims(done, per_run, None)
    learning = {c: tests[c] for c in ("LE-LS", "EE-LS", "SLE") if tests.get(c)}
    sle_noise = (learning["SLE"]["steady"].get("config") or {}).get("sle_noise_steps") if "SLE" in learning else None
    claims[5] = claim_learning_speed({c: (t["steps"], t["mean"]) for c, t in learning.items()},
                                     {c: t["steady"]["steady_mean"] for c, t in learning.items()}, sle_noise)
    claims[7] = dict(verdict=NOT_AVAILABLE, measured="not measured: its probe (experts at the arena's junctions) is "
                                                     "the arena's")
    claims[4]["measured"] += " (path: the arena's measure, not taken here; the verdict is the ratio's)"
    return dict(sorted(claims.items()))


def landscapes(out: str) -> dict:
    """Each landscape measure's numbers as far as it has come, read as the goals study reads its own: random genomes
    by learning (H4) and the measured generations' mutations, in the order measured."""
    from experiments.goals import read_landscapes

    return {condition: entry for condition, entry in read_landscapes(out).items() if condition in LIFE}


def learned(entry: dict) -> list[dict]:
    """A landscape measure's generations with learning as it is (not cut), in order."""
    return sorted((g for g in entry["generations"] if g["learning"] == "learning"), key=lambda g: g["generation"])


def relative_effect(piece: dict) -> float | None:
    """A mutation's mean effect relative to its parents' fitness (None: parents at 0)."""
    return (piece["mutant_mean"] - piece["parent_mean"]) / piece["parent_mean"] if piece["parent_mean"] > 0 else None


def genes(condition: str) -> int:
    """The genome length of the table's row of ``condition`` (its evolution's config)."""
    from experiments.harness.table import evolution_spec

    return evolution_spec(next(r for r in ROWS if r.condition == condition), SCALE).config.num_genes


def landscape_table(found: dict) -> str:
    """H4 (random genomes' fitness) and the mutations around each measured generation's parents, per condition."""
    lines = head("condition", "genes", "random genomes: mean (sd)", "at 0",
                 "generation: parents, mutants' mean effect; the last: deleterious, rho(1)")
    for condition, entry in found.items():
        random, generations = entry["random"].get("learning"), learned(entry)
        text = "; ".join(f"{g['generation']}: {g['parent_mean']:.3f}, " + (
            "-" if relative_effect(g) is None else f"{relative_effect(g):+.1%}") for g in generations)
        text += "".join(f", {g['share_deleterious']:.0%}, {g['rho'][0]:.2f}" for g in generations[-1:])
        lines.append(line(condition + ("" if entry["done"] else " (running)"), genes(condition),
                          f"{random['mean']:.3f} ({random['std']:.3f})" if random else "-",
                          f"{random['share_zero']:.0%}" if random else "-", text or "-"))
    return "\n".join(lines)


class WorldsTable(Table):
    """The worlds study's table: its rows' table and curves, then Fig. 3 in this world, the claims, the novel tasks
    and the landscapes."""

    def measure_world(self) -> dict:
        """Every number of the report: the rows, fresh lives of each finished run's best, the claims, the novel
        tasks' tests beside the tasks' own, and the landscape measures."""
        from experiments.harness.relive import run_fresh

        rows = {m["row"]: m for m in self.measure()}
        tests = {name: read_test(folder) for name, folder in self.tests().items()}
        novel = {m.name.removesuffix(" on novel"): read_test(self.measure_folder(m)) for m in self.measures
                 if m.kind == "test"}
        novel["SLE"] = tests.pop("SLE on novel", None)
        fresh = {}
        for name, m in rows.items():
            if "final_mean" in m and (lives := run_fresh(m["dir"])) is not None:
                fresh[name] = lives
        return dict(rows=rows, tests=tests, novel=novel, fresh=fresh, claims=claims_of(rows, tests),
                    landscapes=landscapes(self.out))

    def report(self) -> int:
        """The rows' table and curves; then Fig. 3, the claims, the novel tasks, the landscapes and report.json."""
        from experiments.harness.figures import fig3, finish

        code = super().report()
        measured = self.measure_world()
        rows, tests = measured["rows"], measured["tests"]
        evolutions = {c: rows[c]["best"] for c in EVOLVED if c != "LE-LS-Z" and rows[c]["generations"]}
        steady = {(VARIANT, c): t["steady"] for c, t in tests.items() if t}
        drawn = finish(fig3(evolutions, {c: t for c, t in tests.items() if t}, steady, VARIANT,
                            "The paper's Fig. 3 in XLand (reduced scale: docs/WORLDS.md)"),
                       os.path.join(self.out, "fig3.png"))
        drawn += ", " + questions_figure(measured, os.path.join(self.out, "questions.png"))
        write_table(self.document, results_text(measured), *markers("worlds results", self.name))
        write_json(os.path.join(self.out, "report.json"), dict(
            claims=measured["claims"], fresh=measured["fresh"],
            final_best={c: {k: m[k] for k in ("final_mean", "final_sd", "plateau")} for c, m in rows.items()
                        if "final_mean" in m},
            steady={c: {k: t["steady"][k] for k in ("steady_mean", "steady_sd", "steady_per_run")}
                    for c, t in tests.items() if t},
            novel={c: {k: t["steady"][k] for k in ("steady_mean", "steady_sd", "steady_per_run")}
                   for c, t in measured["novel"].items() if t},
            landscapes={c: dict(done=e["done"], random={k: {f: v for f, v in r.items() if f != "fitness"}
                                                        for k, r in e["random"].items()}, generations=e["generations"])
                        for c, e in measured["landscapes"].items()}), indent=2)
        print(f"wrote {drawn}, {os.path.join(self.out, 'report.json')} and the results of {self.document}")
        return code


def questions_figure(measured: dict, path: str) -> str:
    """Goals against behaviours and the novel tasks in one figure: (a) the best of a generation's lives against fresh
    lives of the best, (b) the learning tests on the tasks of evolution and on novel ones, (c) random genomes and
    mutations around the last generation's parents (seed 0's landscape)."""
    from experiments.harness.figures import finish
    from imrl_jax.analysis.plotting import new_figure, style_axis

    fig = new_figure(14.0, 3.8)
    a, b, c = fig.subplots(1, 3)
    rows, width = measured["rows"], 0.38
    shown = [r for r in EVOLVED if "final_mean" in rows.get(r, {})]
    x = np.arange(len(shown))
    a.bar(x - width / 2, [rows[r]["final_mean"] for r in shown], width, yerr=[rows[r]["final_sd"] for r in shown],
          color="0.7", capsize=3, label="best of a generation's lives (last 10)")
    fresh = [measured["fresh"].get(r) for r in shown]
    a.bar(x + width / 2, [f["mean"] if f else np.nan for f in fresh], width,
          yerr=[f["sd_over_seeds"] if f else 0 for f in fresh], color="0.3", capsize=3,
          label="fresh lives of each seed's best")
    a.axhline(0.01, color="tab:red", lw=1, ls=":", label="random actions")
    a.set_xticks(x, shown)
    style_axis(a, "(a) selected lives against fresh ones", "", "fitness (mean +- sd over seeds)")
    tested = [c for c in ("LE-LS", "EE-LS", "EE-ES", "SLE") if measured["tests"].get(c)]
    x = np.arange(len(tested))
    for shift, which, colour, label in ((-width / 2, measured["tests"], "0.3", "tasks of evolution"),
                                        (width / 2, measured["novel"], "tab:blue", "novel tasks")):
        found = [which.get(c) for c in tested]
        b.bar(x + shift, [t["steady"]["steady_mean"] if t else np.nan for t in found], width,
              yerr=[t["steady"]["steady_sd"] if t else 0 for t in found], color=colour, capsize=3, label=label)
    b.set_xticks(x, tested)
    style_axis(b, "(b) learning tests: steady state", "", "performance (mean +- sd over runs)")
    found = measured["landscapes"]
    names = [n for n in LIFE if n in found]
    x = np.arange(len(names))
    last = [(learned(found[n]) or [None])[-1] for n in names]
    effect = [np.nan if p is None or relative_effect(p) is None else relative_effect(p) for p in last]
    c.bar(x - width / 2, effect, width, color="0.3", label="a mutation's mean effect, relative")
    c.bar(x + width / 2, [p["share_deleterious"] if p else np.nan for p in last], width, color="tab:orange",
          label="share of mutants deleterious")
    c.axhline(0, color="0.2", lw=0.8)
    c.set_xticks(x, [f"{n}\n(random {found[n]['random'].get('learning', {}).get('mean', np.nan):.3f})"
                     for n in names])
    style_axis(c, "(c) mutations of the last parents, seed 0", "", "relative effect; share")
    a.set_ylim(top=max(0.3, a.get_ylim()[1]))  # room for the legend above the bars
    for ax in (a, b, c):
        if ax.patches:
            ax.legend(fontsize=7, loc="upper right")
    return finish(fig, path)


def results_text(measured: dict) -> str:
    """The report's markdown: fresh lives, the claims' verdicts, the novel tasks and the landscapes."""
    from imrl_jax.analysis.claims import CLAIMS

    lines = ["**Fresh lives** (the mean of 10 fresh lives of each seed's best genome of the last generation; mean "
             "and sd over seeds):", "", *head("condition", "final best fitness (best of a generation's lives)",
                                               "fresh lives of the best")]
    for c, m in measured["rows"].items():
        if m["generations"] and m["row"] in EVOLVED:
            f = measured["fresh"].get(c)
            lines.append(line(c, mean_sd(m["final_mean"], m["final_sd"]) if "final_mean" in m else "running",
                              mean_sd(f["mean"], f["sd_over_seeds"]) if f else "-"))
    lines += ["", "**The claims** (the arena's rules, `imrl_jax.analysis.claims.RULES`):", "",
              *head("claim", "verdict", "measured")]
    lines += [line(f"{n}: {CLAIMS[n]}", f"**{c['verdict']}**", c["measured"]) for n, c in measured["claims"].items()]
    lines += ["", "**Novel tasks** (learning tests on `xland-novel`, beside the tests on the six of evolution; "
              "steady state, mean +- sd over runs):", "", *head("condition", "own tasks", "novel tasks")]
    for c in ("LE-LS", "EE-LS", "EE-ES", "SLE"):
        own, new = measured["tests"].get(c), measured["novel"].get(c)
        lines.append(line(c, *(mean_sd(t["steady"]["steady_mean"], t["steady"]["steady_sd"]) if t else "-"
                               for t in (own, new))))
    lines += ["", "**Landscapes** (seed 0; `imrl_jax.landscape_run`'s measures, docs/GOALS.md; mean effect relative "
              "to the parents' fitness):", "", landscape_table(measured["landscapes"]) if measured["landscapes"]
              else "not measured yet"]
    return "\n".join(lines)


ROWS = tuple(Row(condition, condition, "paper", options=WORLD) for condition in EVOLVED)
TABLE = WorldsTable("worlds", "docs/WORLDS.md", 12, out=OUT, scale=SCALE, rows=(
    *ROWS, Row("SLE", "SLE", "paper", options=WORLD), Row("SLE on novel", "SLE", "paper", options=WORLD + NOVEL),
), measures=(*(novel_test(row) for row in ROWS if row.condition in LIFE),
             *(landscape(row) for row in ROWS if row.condition in LIFE)))
all_stages, main = TABLE.all_stages, TABLE.main
#: The studies of this module (python -m experiments finds them).
STUDIES = (TABLE.study(__name__.rsplit(".", 1)[-1]),)

if __name__ == "__main__":
    sys.exit(main())
