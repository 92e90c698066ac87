"""Which reading of the paper reproduces its Fig. 3: the seven claims under every candidate rule set (docs/CLAIMS.md).

    python -m experiments run claims-screen       # run (or go on with) the screen's runs
    python -m experiments run claims-experts      # claim 8's: more experts
    python -m experiments report claims-screen    # docs/CLAIMS.md's tables and figures (and claim 8's)

A rule set (``experiments.rule_sets``) is a preset of ``imrl_jax.config`` and ``--set`` overrides
of values the paper does not state; its runs are the rows of a table (:func:`rule_rows`): each of
the paper's conditions at the paper's life lengths (150,000 + 6 x 100,000 steps; learning tests of
1,000,000 cycles per task), at the screen's sizes (5 seeds x 100 generations, 5 best x 4 tests:
``SCREEN``) or, for the conditions of ``RuleSet.full``, the paper's (the reproduction's runs). Each
run is found by what it computes (``imrl_jax.runs.runspec``), so rule sets whose lives are the same share
it: EE-ES's one run, EE-LS's under ``skills``' or ``paper``'s adult selector, SLE's tests of equal
adult values, bias and noise schedule. Claim 8's table adds 4 and 6 experts to two rule sets.
"""

from __future__ import annotations

import collections
import dataclasses
import functools
import os
import sys

import numpy as np

from experiments.harness.loading import read_evolution, read_json, read_test, write_json
from experiments.harness.markdown import table
from imrl_jax.analysis.relive import colours_followed
from experiments.harness.relive import reproduction_fresh, run_fresh, run_probe
from experiments.harness.reproduce import EVOLVED, TESTED
from experiments.rule_sets import BY_NAME, RULE_SETS, RuleSet
from experiments.harness.study import REPRODUCTION, RESULTS, SCALES, SCREEN, markers, write_table
from experiments.harness.table import Measure, Row, Table, dispatch, studies_of
from imrl_jax import conditions
from imrl_jax.analysis.claims import (ABOUT, DOES_NOT, HOLDS, NOT_AVAILABLE, NUM_BEST, PARTLY, final_best,
                                      measure as measure_claims)
from imrl_jax.analysis.further_claims import claim_experts
from imrl_jax.analysis.plotting import new_figure, save

OUT = os.path.join(RESULTS, "claims")
#: The order the screen runs its rule sets in: the cheap SLE tests first, then the evolutions that matter most (bias 1:
#: where between 0 and 2 claim 3 turns), the reproduction's rule sets (whose runs the reproduction made) last.
SCREEN_ORDER = ("skills-sle-test", "paper-sle-test", "skills-bias0", "skills-bias0-sle-test", "paper-selector",
                "paper-selector-sle-test", "skills-bias2", "skills-clamp", "skills-bias1", "extension",
                "skills-bias2-sle-test", "skills-clamp-sle-test", "skills-bias1-sle-test", "extension-sle-test",
                "paper", "skills", "faithful")
#: Claim 8 (the paper: "the quality of results did not change in tests with a higher number of experts"):
#: LE-LS and EE-LS with these many experts, under these rule sets, against their own 3-expert runs.
EXPERT_COUNTS = (4, 6)
#: skills, and the screen's most faithful row that composes (paper-selector: its LE-LS is also
#: paper-selector-sle-test's; its EE-LS is skills', as with 3 experts).
EXPERT_RULE_SETS = ("skills", "paper-selector")
EXPERT_CONDITIONS = ("LE-LS", "EE-LS")
#: The rows that differ from ``skills`` only in the learned actors' initial speed bias (``skills`` is bias 4).
DIAL_ROWS = ("skills-bias0", "skills-bias1", "skills-bias2", "skills")

#: Where the report's tables go in docs/CLAIMS.md (the text around them is written by hand), and claim 8's figure.
TABLE_START, TABLE_END = "<!-- claims table: python -m experiments report claims-screen -->", "<!-- end of table -->"
FRESH_START, FRESH_END = markers("fresh-life table", "claims-screen")
EXPERTS_START, EXPERTS_END = markers("claim 8 table", "claims-experts")
EXPERTS_RUNS_START, EXPERTS_RUNS_END = markers("claim 8 runs", "claims-experts")
EXPERTS_FIGURE = os.path.join("docs", "claims", "experts.png")
#: A verdict in one word and its colour, as the map's table and figure show it; the figures' resolution.
SHORT = {HOLDS: "holds", PARTLY: "partly", DOES_NOT: "no", NOT_AVAILABLE: "n/a"}
SHADES = {HOLDS: "#2e7d32", PARTLY: "#f9a825", DOES_NOT: "#c62828", NOT_AVAILABLE: "#bdbdbd"}
DPI = 120


def rule_rows(rule: RuleSet, num_experts: int | None = None) -> tuple[Row, ...]:
    """A rule set's runs as rows (``RULE CONDITION``; with ``num_experts``, claim 8's ``RULE CONDITION K experts``)."""
    if num_experts is not None:  # claim 8's LE-LS and EE-LS, at the screen's sizes
        return tuple(Row(f"{rule.name} {c} {num_experts} experts", c, rule.preset,
                         (*rule.sets, f"num_experts={num_experts}"), scale=SCREEN) for c in EXPERT_CONDITIONS)
    # each of the paper's conditions (SLE's with the rule set's noise horizon), at the paper's sizes for rule.full
    noise = () if rule.sle_noise_steps is None else (f"sle_noise_steps={rule.sle_noise_steps}",)
    return tuple(Row(f"{rule.name} {c}", c, rule.preset, rule.sets + (() if conditions.get(c).evolved else noise),
                     scale=SCALES["paper"] if c in rule.full else SCREEN) for c in TESTED)


def reproduction_variant(folder: str, reproduction: str = REPRODUCTION) -> str | None:
    """The reproduction's variant whose run (or test) ``folder`` is (``REPRODUCTION/VARIANT/...``), or None."""
    relative = os.path.relpath(folder, reproduction)
    return None if relative.startswith(os.pardir) else relative.split(os.sep)[0]


#: Where one row's runs live, each a dict by condition: its evolutions' folders, its learning tests' folders, and the
#: reproduction's variant (of ``make reproduce``) whose run each evolution is (absent: the row's own run).
RowRuns = collections.namedtuple("RowRuns", ("evolutions", "tests", "reproduction"))


def rule_runs(rule: RuleSet, out: str = OUT, reproduction: str = REPRODUCTION) -> RowRuns:
    """A rule set's runs (its own and the ones it shares), found by key under the results folder of ``reproduction``."""
    rows, results = rule_rows(rule), os.path.dirname(os.path.normpath(reproduction))
    table = Table("rule", "", 0, rows=rows, scale=SCREEN, out=out, results=results)
    evolutions, tests = table.evolutions(), table.tests()
    found = {row.condition: evolutions[row.name] for row in rows if row.evolved}
    return RowRuns(found, {row.condition: tests[row.name] for row in rows},
                   {c: v for c, folder in found.items() if (v := reproduction_variant(folder, table.reproduction))})


def probed(folder: str, config: dict | None, summary: dict | None = None, owner: str = "",
           condition: str = "") -> tuple[list | None, list | None, dict | None]:
    """A finished run's best: colours each of the 10 best per seed follows, its experts following none, fresh lives."""
    if summary is not None:  # a reproduction run (``owner``'s): its report keeps only the colours followed
        colours = (summary.get("colours_followed") or {}).get(f"{owner}/{condition}")
        return colours, None, reproduction_fresh(summary, owner, condition)
    followed = (run_probe(folder, config, NUM_BEST) or {}).get("followed")  # kept beside the run, as its fresh lives
    idle = None if followed is None else [sum(c == -1 for c in f) for f in followed]
    return None if followed is None else colours_followed(followed), idle, run_fresh(folder, config)


def measure_runs(name: str, runs: RowRuns, reproduction_summary: dict, sle_whole_test: bool = False) -> dict:
    """The seven claims of one row of runs by the report's own rules, with the numbers behind them."""
    evolutions = {c: run for c, folder in runs.evolutions.items() if (run := read_evolution(folder)) is not None}
    tests = {(name, c): test for c, folder in runs.tests.items() if (test := read_test(folder)) is not None}
    probes, fresh = {}, {}
    for condition, run in evolutions.items():  # a shared run's probe is the reproduction report's (its summary.json)
        owner = runs.reproduction.get(condition)
        probes[name, condition], _, lived = probed(runs.evolutions[condition], run["config"],
                                                   reproduction_summary if owner else None, owner or "", condition)
        if lived is not None:  # the recorded best beside the same genomes' fresh lives
            fresh[condition] = dict(recorded=float(final_best(run["best"]).mean()), fresh=lived["mean"],
                                    fresh_sd_over_seeds=lived["sd_over_seeds"], seeds=len(lived["mean_per_seed"]))
    # the reproduction's relived best EE-ES individual: claim 4's paths
    ee_es = (reproduction_summary.get("best_individuals") or {}).get(f"{runs.reproduction.get('EE-ES')}/EE-ES")
    data = dict(manifest=dict(sizes=dict(generations=SCREEN["generations"])), variants=[name], tests=tests,
                evolutions={(name, c): run for c, run in evolutions.items()})
    lives = {} if ee_es is None else {("paper", "EE-ES"): ee_es}
    return dict(measure_claims(data, lives, probes, sle_whole_test=sle_whole_test)[name], fresh=fresh)


def measure_rule(rule: RuleSet, reproduction_summary: dict, out: str = OUT, reproduction: str = REPRODUCTION) -> dict:
    """The seven claims of one rule set (:func:`measure_runs` on its own and shared runs)."""
    return measure_runs(rule.name, rule_runs(rule, out, reproduction), reproduction_summary,
                        sle_whole_test=rule.sle_noise_steps == 0)


def config_of(rule: RuleSet, condition: str, num_experts: int | None = None):
    """The config of a rule set's run of ``condition`` (its learning test's for SLE; claim 8's with ``num_experts``)."""
    from imrl_jax.runs.cli import parse_sets
    from imrl_jax.config import make_config

    overrides = parse_sets(list(rule.sets))
    if num_experts is not None:
        overrides["num_experts"] = num_experts
    if not conditions.get(condition).evolved:  # SLE: its noise's horizon is the rule set's
        overrides["sle_noise_steps"] = SCREEN["task_steps"] if rule.sle_noise_steps is None else rule.sle_noise_steps
    return make_config(rule.preset, condition=condition, **overrides)


def verdict_cell(claim: dict) -> str:
    """A claim's verdict in one word (holds in bold) and its first number, as the studies' tables show it."""
    return f"{'**holds**' if claim['verdict'] == HOLDS else SHORT[claim['verdict']]}: {claim['measured'].split(';')[0]}"


def table_markdown(measured: dict, names) -> str:
    """The claims map as markdown: rule sets as rows, the seven claims as columns (verdict, then the numbers)."""
    def cells(name: str) -> tuple:
        """A measured rule set's sizes (LE-LS's seeds x generations, SLE's runs x best x tests), then each claim's
        verdict in one word and its first number."""
        le_ls, sle = (SCALES["paper"] if c in BY_NAME[name].full else SCREEN for c in ("LE-LS", "SLE"))
        return (f"{le_ls['seeds']}x{le_ls['generations']}, {sle['seeds']}x{sle['best']}x{sle['tests']}",
                *(verdict_cell(measured[name]["claims"][k]) for k in range(1, 8)))

    return table(("rule set", "runs (LE-LS, SLE)", *(f"claim {k}" for k in range(1, 8))), [
        (f"`{name}`", *(cells(name) if name in measured else ("not finished", *["-"] * 7))) for name in names])


def figure(measured: dict, names, path: str) -> str:
    """The claims map as a grid: rule sets as rows, claims as columns, coloured by verdict; written to ``path``."""
    from matplotlib.patches import Rectangle

    fig = new_figure(8.5, 0.45 * len(names) + 1.6)
    ax = fig.add_subplot()
    for row, name in enumerate(names):
        for k in range(1, 8):
            verdict = measured[name]["claims"][k]["verdict"] if name in measured else None
            ax.add_patch(Rectangle((k - 1, row), 0.95, 0.9, color=SHADES.get(verdict, "white"), ec="0.6", lw=0.5))
            ax.text(k - 0.53, row + 0.45, SHORT.get(verdict, "not run"), ha="center", va="center", fontsize=8,
                    color="white" if verdict in (HOLDS, DOES_NOT) else "black")
    ax.set(xlim=(0, 7), ylim=(len(names), 0))
    ax.set_xticks([k - 0.53 for k in range(1, 8)], [f"claim {k}" for k in range(1, 8)], fontsize=9)
    ax.set_yticks([r + 0.45 for r in range(len(names))], names, fontsize=9)
    ax.tick_params(length=0)
    ax.spines[:].set_visible(False)
    ax.set_title("The paper's seven claims under each rule set (the report's verdict rules; paper lengths)",
                 fontsize=10)
    fig.tight_layout()
    return save(fig, path, DPI)


#: One speed bias's LE-LS against the shared EE-LS: final best (recorded and fresh) and learning-test level, and
#: ``speed``, the learned actors' initial speed, sigmoid(bias), as a fraction of full speed.
DialPoint = collections.namedtuple("DialPoint", ("bias", "speed", "le_ls_recorded", "le_ls_fresh", "le_ls_fresh_sd",
                                                 "le_ls_steady", "ee_ls_recorded", "ee_ls_steady"))


def speed_dial(claims: dict, rows=DIAL_ROWS) -> list[DialPoint]:
    """Claim 3's two sides against the initial speed bias, from claims.json's ``claims`` (unmeasured rows left out)."""
    points = []
    for name in (n for n in rows if n in claims and "LE-LS" in claims[n]["fresh"]):  # measured, its fresh lives lived
        bias = float(config_of(BY_NAME[name], "LE-LS").initial_speed_bias)
        three, fresh = claims[name]["3"]["numbers"], claims[name]["fresh"]["LE-LS"]
        levels = claims[name]["6"]["numbers"]["mean"]  # the learning tests' steady states, per condition
        points.append(DialPoint(bias, float(1 / (1 + np.exp(-bias))), three["le_ls"], fresh["fresh"],
                                fresh["fresh_sd_over_seeds"], float(levels["LE-LS"]), three["ee_ls"],
                                float(levels["EE-LS"])))
    return sorted(points)


def dial_figure(points: list[DialPoint], path: str) -> str:
    """LE-LS's final best and learning-test level against the learned actors' initial speed, EE-LS's as lines."""
    speed = [100 * p.speed for p in points]
    fig = new_figure(9, 3.6)
    axes = fig.subplots(1, 2, sharey=True)
    axes[0].plot(speed, [p.le_ls_recorded for p in points], "o-", color="C0", label="LE-LS, recorded best")
    axes[0].errorbar(speed, [p.le_ls_fresh for p in points], [p.le_ls_fresh_sd for p in points], fmt="s--",
                     color="C0", alpha=0.6, capsize=3, label="LE-LS, fresh lives (sd over seeds)")
    axes[0].axhline(points[0].ee_ls_recorded, color="C1", label="EE-LS, recorded best (shared)")
    axes[0].set_title("a. final best fitness (claim 3)", fontsize=10)
    axes[0].set_ylabel("fitness")
    axes[1].plot(speed, [p.le_ls_steady for p in points], "o-", color="C0", label="LE-LS")
    axes[1].axhline(points[0].ee_ls_steady, color="C1", label="EE-LS (shared)")
    axes[1].set_title("b. learning tests' steady state", fontsize=10)
    for ax in axes:
        ax.set_xlabel("learned actors' initial speed (% of full; bias 0, 1, 2, 4)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="lower right")
    fig.suptitle("skills with only the initial speed bias changed: where LE-LS passes EE-LS", fontsize=10)
    fig.tight_layout()
    return save(fig, path, DPI)


def fresh_table(measured: dict, names) -> str:
    """Recorded final best fitness (claims 1-4's measure) beside the fresh-life fitness of each seed's best genome."""
    return table(("rule set", *(f"{c} recorded / fresh" for c in EVOLVED)), [(f"`{name}`", *(
        "-" if f is None else f"{f['recorded']:.3f} / {f['fresh']:.3f} (sd {f['fresh_sd_over_seeds']:.3f}, "
        f"{f['seeds']} seeds)" for f in (measured[name].get("fresh", {}).get(c) for c in EVOLVED)))
        for name in names if name in measured])


def experts_runs(table: Table) -> dict[tuple[str, str, int], tuple[str, str, str]]:
    """Claim 8's runs and their 3-expert ones: (rule set, condition, experts) -> (evolution, learning test, owner)."""
    rows = {(name, row.condition, k): row for name in EXPERT_RULE_SETS for k in (3, *EXPERT_COUNTS)
            for row in rule_rows(BY_NAME[name], None if k == 3 else k) if row.condition in EXPERT_CONDITIONS}
    table = dataclasses.replace(table, rows=tuple(dict.fromkeys((*table.rows, *rows.values()))))
    evolutions, tests, owners = table.evolutions(), table.tests(), {}  # owner: the first rule set whose run it is
    for (name, _, _), row in rows.items():
        owners.setdefault(evolutions[row.name], name)
    return {at: (evolutions[row.name], tests[row.name], owners[evolutions[row.name]]) for at, row in rows.items()}


def measure_experts(rule: RuleSet, found: dict, summary: dict | None = None, reproduction: str = REPRODUCTION) -> dict:
    """Claim 8 for a rule set: its 4- and 6-expert runs (:func:`experts_runs`) against its 3-expert ones, probed."""
    final, steady, sizes, runs = {}, {}, {}, []
    for condition, k in ((c, k) for c in EXPERT_CONDITIONS for k in (3, *EXPERT_COUNTS)):
        evolved, tested, owner = found[rule.name, condition, k]
        run, test = read_evolution(evolved), read_test(tested)
        if test is not None:
            steady[condition, k] = test["steady"]["steady_per_run"]
        if run is None or not run["config"] or len(run["best"]) < run["config"]["num_generations"]:
            continue  # not finished
        final[condition, k] = final_best(run["best"]).tolist()
        size = sizes[f"{condition} {k}"] = f"{len(run['seeds'])}x{len(run['best'])}"
        variant = reproduction_variant(evolved, reproduction)  # its probe the reproduction report's (``summary``)
        colours, idle, fresh = probed(evolved, run["config"], summary if variant else None, variant or "", condition)
        runs.append(dict(rule=owner, condition=condition, num_experts=k, size=size,
                         fresh=fresh and fresh["mean"], fresh_sd=fresh and fresh["sd_over_seeds"],
                         colours=None if colours is None else [colours.count(c) for c in range(4)],
                         idle_experts=None if idle is None else float(np.mean(idle))))
    have = {"final": final, "steady": steady}
    missing = [f"{c} {m} {k}" for m in have for c in EXPERT_CONDITIONS for k in (3, *EXPERT_COUNTS)
               if (c, k) not in have[m]]
    # a point of claim 8's figure: "final", the final best per seed, or "steady", the steady state per run (sd ddof 1)
    levels = [dict(rule=rule.name, condition=c, measure=m, num_experts=k, mean=float(np.mean(v)),
                   sd=float(np.std(v, ddof=1)) if len(v) > 1 else 0.0, count=len(v))
              for m, values in have.items() for (c, k), v in sorted(values.items())]
    return dict(claim_experts(final, steady), sizes=sizes, missing=missing, levels=levels, runs=runs)


def experts_table(measured: dict) -> str:
    """Claim 8 as markdown: a row per rule set, the verdict and the comparisons (``so far`` while runs are missing)."""
    return table(("rule set", "runs (seeds x generations)", "claim 8"), [
        (f"`{name}`", ", ".join(f"{k}: {v}" for k, v in claim["sizes"].items()) or "none finished", claim["verdict"]
         + (f" so far (not finished: {', '.join(claim['missing'])})" if claim.get("missing") else "")
         + f": {claim['measured']}") for name, claim in measured.items()])


def experts_runs_table(measured: dict) -> str:
    """Claim 8's runs as markdown, each once (a shared run under its owner): fitness, and what the best do."""
    levels = {(p["rule"], p["condition"], p["measure"], p["num_experts"]): p
              for claim in measured.values() for p in claim.get("levels", [])}
    runs = {}  # each run once, with the rule set it was first measured under
    for name, claim in measured.items():
        for run in claim.get("runs", []):
            runs.setdefault((run["rule"], run["condition"], run["num_experts"]), (name, run))
    rows = []
    for name, run in runs.values():
        final, steady = (levels.get((name, run["condition"], m, run["num_experts"])) for m in ("final", "steady"))
        rows.append((f"{run['rule']} {run['condition']}", run["num_experts"], run["size"],
                     f"{final['mean']:.3f}" if final else "-",
                     "-" if run["fresh"] is None else f"{run['fresh']:.3f} ({run['fresh_sd']:.3f})",
                     f"{steady['mean']:.3f} ({steady['sd']:.3f})" if steady else "-",
                     "-" if run["colours"] is None else "/".join(map(str, run["colours"])),
                     "-" if run["idle_experts"] is None else f"{run['idle_experts']:.1f}"))
    return table(("run", "experts", "seeds x generations", "final best (recorded)", "fresh lives (sd over seeds)",
                  "steady state (sd over runs)", "best individuals following 0/1/2/3 colours",
                  "experts following none (mean)"), rows)


def experts_figure(measured: dict, path: str = EXPERTS_FIGURE) -> str:
    """Final best fitness and steady state against the number of experts, a line per rule set and condition."""
    fig = new_figure(9, 3.8)
    axes = fig.subplots(1, 2, sharey=True)
    titles = {"final": "a. final best fitness (recorded best; sd over seeds)",
              "steady": "b. learning tests' steady state (sd over runs)"}
    colours: dict = {}  # one colour per run, the same in both panels
    for ax, measure in zip(axes, titles):
        drawn = set()
        for name, condition in ((n, c) for n in measured for c in EXPERT_CONDITIONS):
            claim = measured[name]
            points = sorted((p["num_experts"], p["mean"], p["sd"]) for p in claim.get("levels", [])
                            if p["measure"] == measure and p["condition"] == condition)
            owner = next((r["rule"] for r in claim.get("runs", []) if r["condition"] == condition), name)
            if not points or (owner, condition) in drawn:
                continue  # a shared run (paper-selector's EE-LS is skills') is drawn once
            drawn.add((owner, condition))
            colour, dashed = colours.setdefault((owner, condition), f"C{len(colours)}"), name != EXPERT_RULE_SETS[0]
            k, mean, sd = (np.array(v) for v in zip(*points))
            ax.errorbar(k + (0.05 if dashed else 0), mean, sd, fmt={"LE-LS": "o", "EE-LS": "s"}[condition] +
                        ("--" if dashed else "-"), color=colour, capsize=3, label=f"{condition}, {owner}")
            base = dict(zip(k, mean)).get(3)
            if base is not None:  # the rule's band: within [0.8, 1.25] of 3 experts is "unchanged"
                ax.fill_between([2.8, 6.2], ABOUT[0] * base, min(ABOUT[1] * base, 1), color=colour, alpha=0.06)
        ax.set_title(titles[measure], fontsize=10)
        ax.set(xticks=[3, *EXPERT_COUNTS], xlabel="number of experts")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="upper right")
    axes[0].set_ylabel("fitness")
    fig.suptitle("claim 8: more experts, 100 generations (shaded: within [0.8, 1.25] of 3 experts)", fontsize=10)
    fig.tight_layout()
    return save(fig, path, DPI)


def reproduction_summary(document: str) -> dict | None:
    """The reproduction report's summary beside ``document`` (reproduction/summary.json), or None."""
    return read_json(os.path.join(os.path.dirname(document), "reproduction", "summary.json"))


def write_experts(table: Table) -> dict:
    """Claim 8 of every rule set that runs it: claim8.json, the document's tables and the figure."""
    summary, found = reproduction_summary(table.document), experts_runs(table)  # a run's fresh lives, probe: kept
    claim8 = {name: measure_experts(BY_NAME[name], found, summary, table.reproduction) for name in EXPERT_RULE_SETS}
    os.makedirs(table.out, exist_ok=True)
    write_json(os.path.join(table.out, "claim8.json"), claim8, indent=2, default=str)
    write_table(table.document, experts_table(claim8), EXPERTS_START, EXPERTS_END)
    write_table(table.document, experts_runs_table(claim8), EXPERTS_RUNS_START, EXPERTS_RUNS_END)
    if any(claim["levels"] for claim in claim8.values()):
        experts_figure(claim8, os.path.join(os.path.dirname(table.document), "claims", "experts.png"))
    return claim8


class ScreenTable(Table):
    """The claims map: every rule set's runs; its report, the map's tables and figures (and claim 8's)."""

    def report(self) -> int:
        """Measure every finished rule set; write claims.json, the document's tables and figures, and claim 8's."""
        summary, measured, names = reproduction_summary(self.document) or {}, {}, [rule.name for rule in RULE_SETS]
        for rule in RULE_SETS:
            if all("steady_mean" in m and ("final_mean" in m or m["dir"] is None)  # every run of its row finished
                   for m in dataclasses.replace(self, rows=rule_rows(rule)).measure()):
                print(f"measuring {rule.name}", flush=True)
                measured[rule.name] = measure_rule(rule, summary, self.out, self.reproduction)
        numbers = {name: {**{str(k): v for k, v in m["claims"].items()}, "fresh": m.get("fresh", {})}
                   for name, m in measured.items()}
        os.makedirs(self.out, exist_ok=True)
        write_json(os.path.join(self.out, "claims.json"), dict(sizes=dict(screen=SCREEN, full=SCALES["paper"]),
                   rule_sets={r.name: r._asdict() for r in RULE_SETS}, claims=numbers), indent=2, default=str)
        write_table(self.document, table_markdown(measured, names), TABLE_START, TABLE_END)
        write_table(self.document, fresh_table(measured, names), FRESH_START, FRESH_END)
        figures = os.path.join(os.path.dirname(self.document), "claims")
        figure(measured, names, os.path.join(figures, "claims_map.png"))
        points = speed_dial(numbers)
        if len(points) > 1:
            dial_figure(points, os.path.join(figures, "speed_dial.png"))
        write_experts(dataclasses.replace(EXPERTS_TABLE, results=self.results, out=self.out, document=self.document))
        print(f"wrote {self.document}'s tables and {os.path.join(self.out, 'claims.json')}: {len(measured)} of "
              f"{len(names)} rule sets finished ({self.reproduction})")
        return 0


class ExpertsTable(Table):
    """Claim 8's runs: skills and paper-selector with 4 and 6 experts; its report, claim 8's tables and figure."""

    def report(self) -> int:
        for name, claim in write_experts(self).items():
            print(f"claim 8, {name}: {claim['verdict']}{' so far' if claim['missing'] else ''}")
        return 0


#: Claim 4 and the arena: what a circular path can score on the six tasks (experiments/circular_paths.py).
CIRCLES = Measure("circles", "", module="experiments.circular_paths", out="circles",
                  cost=1001 * 6 * 6 * 20_000.0)  # its grid: 1,001 turns x 6 speeds, 6 tasks of 20,000 steps
SCREEN_TABLE = ScreenTable("claims-screen", "docs/CLAIMS.md", 3, scale=SCREEN, out=OUT, measures=(CIRCLES,),
                           rows=tuple(row for name in SCREEN_ORDER for row in rule_rows(BY_NAME[name])))
EXPERTS_TABLE = ExpertsTable("claims-experts", "docs/CLAIMS.md", 5, scale=SCREEN, out=OUT, rows=tuple(
    row for name in EXPERT_RULE_SETS for k in EXPERT_COUNTS for row in rule_rows(BY_NAME[name], k)))
#: The module's tables by the name its command line takes first (``screen`` when none is given).
TABLES = {"screen": SCREEN_TABLE, "experts": EXPERTS_TABLE}
#: The studies of this module (python -m experiments finds them).
STUDIES = studies_of("claims_study", TABLES)
main = functools.partial(dispatch, TABLES)


if __name__ == "__main__":
    sys.exit(main())
