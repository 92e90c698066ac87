"""The paper's future work as conditions (docs/FUTURE_WORK.md): evolutions and learning tests of the new rows.

    python -m experiments.future_work               # run (or go on with) every stage, in order
    python -m experiments.future_work --only EV-LS,EXT-LS
    python -m experiments.future_work --list        # the stages and their commands, nothing run
    python -m experiments.future_work --report      # the tables and figure of whatever has finished

Each row of :data:`RUNS` is a condition of the table (``imrl_jax.conditions``) under a preset
and ``--set`` overrides, evolved (5 seeds x 100 generations at the paper's life lengths, then
a learning test of its 5 best x 4 tests) or, for a condition that is not evolved, tested from
scratch (5 runs x 5 x 4). The paper's four conditions under the same rules come from the
finished paper-scale reproduction (``experiments/results/paper``). The stages run through
the reproduction's resumable stage runner (:func:`experiments.reproduce.run_stages`): run the
same command again after an interruption.

``--report`` (:func:`report`) measures every finished row beside the reproduction's: final best
fitness, its spread and plateau, and the learning tests' steady state; (c)'s evolved learning
values beside the presets'; (d)'s number of expressed experts and its fitness against 6 and 3
experts. It writes report.json and future_work.png under ``--out`` and the tables into
docs/FUTURE_WORK.md, from whatever has finished.
"""

from __future__ import annotations

import argparse
import csv
import os
import sys
from typing import NamedTuple

# NUM_BEST: the junction probe drives claim 7's number of each seed's fittest genomes, so that a run shared with
# the claims study (LE-LS-6) keeps one probe.json
from experiments.claims import NUM_BEST
from experiments.study import REPRODUCTION, SCREEN
from experiments.reproduce import (Stage, evolution_cost, evolution_dir, evolve_command, load_manifest, run_stages,
                                   test_command, test_cost, test_dir)
from experiments.executor import add_options, from_options
from experiments.study import RESULTS, Study
from imrl_jax import conditions

OUT = os.path.join(RESULTS, "future_work")


class Run(NamedTuple):
    """One row of the study: a condition under a preset and overrides."""

    name: str
    condition: str
    preset: str
    sets: tuple[str, ...]
    about: str
    # > 0: the claims study's claim-8 run with this many experts under this preset is this row's run, the same
    # lives: the row reads it there and runs nothing of its own
    claims_experts: int = 0
    claims_rule: str = ""  # the claims study's rule set of that run ("": the preset's name)


RUNS: tuple[Run, ...] = (
    Run("EV-LS", "EV-LS", "skills", (), "(a) evolved evaluators, gamma V(x_t) - V(x_{t-1})"),
    Run("EV-LS-diff", "EV-LS-diff", "skills", (), "(a) evolved evaluators, V(x_t) - V(x_{t-1})"),
    Run("EXT-LS", "EXT-LS", "skills", (), "(b) the hierarchy on the task's reward only, SLE's noise over 100,000 cycles"),
    Run("EXT-LS-whole", "EXT-LS", "skills", ("sle_noise_steps=0",), "(b), the noise over the whole test"),
    Run("LE-LS-P", "LE-LS-P", "skills", (), "(c) evolved learning parameters"),
    Run("LE-LS-PC", "LE-LS-PC", "skills", (), "(c) evolved learning parameters and childhood length"),
    Run("LE-LS-N6", "LE-LS-N", "skills", ("num_experts=6",), "(d) up to 6 experts, each expressed by a gene"),
    Run("LE-LS-6", "LE-LS", "skills", ("num_experts=6",), "(d)'s comparison: 6 experts, all expressed (the claims "
        "study's claim-8 run)", claims_experts=6),
    # The same questions under the claims map's chosen rule set (docs/CLAIMS.md, "The decision"): run after skills'.
    Run("EV-LS-faithful", "EV-LS", "faithful", (), "(a) under `faithful`"),
    Run("EXT-LS-faithful", "EXT-LS", "faithful", ("sle_noise_steps=0",),
        "(b) under `faithful`, the noise over the whole test (its SLE's reading)"),
    Run("LE-LS-P-faithful", "LE-LS-P", "faithful", (), "(c) under `faithful`"),
    Run("LE-LS-N6-faithful", "LE-LS-N", "faithful", ("num_experts=6",), "(d) under `faithful`"),
    Run("LE-LS-6-faithful", "LE-LS", "faithful", ("num_experts=6",), "(d)'s comparison under `faithful` (the claims "
        "study's claim-8 run of paper-selector, the same lives)", claims_experts=6, claims_rule="paper-selector"),
)
BY_NAME = {run.name: run for run in RUNS}
#: The claims study's results, where rows with ``claims_experts`` find their runs.
CLAIMS_OUT = os.path.join(RESULTS, "claims")


def run_dirs(run: Run, out: str = OUT, claims: str = CLAIMS_OUT) -> tuple[str, str]:
    """A row's evolution and learning-test folders: its own, or the claims study's identical claim-8 run."""
    if run.claims_experts:
        from experiments.claims_study import experts_dir

        return tuple(experts_dir(run.claims_rule or run.preset, run.condition, run.claims_experts, kind, claims)
                     for kind in ("evolve", "test"))
    return os.path.join(out, run.name, "evolve"), os.path.join(out, run.name, "test")


def plan(names, scale: dict = SCREEN, out: str = OUT) -> list[Stage]:
    """The stages of the rows ``names``, in order: each evolution then its learning test."""
    stages = []
    for name in names:
        run = BY_NAME[name]
        if run.claims_experts:
            continue  # the claims study runs it
        if conditions.get(run.condition).evolved:
            stages.append(Stage(f"evolve {name}", "evolve", name, run.condition,
                                os.path.join(out, name, "evolve"), evolution_cost(scale, run.condition)))
        stages.append(Stage(f"learning test {name}", "test", name, run.condition, os.path.join(out, name, "test"),
                            test_cost(scale, run.condition)))
    return stages


def stage_command(stage: Stage, scale: dict = SCREEN, out: str = OUT) -> tuple[list[str], None]:
    """A stage's command line: the package's evolve or learning_test with the row's preset and overrides."""
    run = BY_NAME[stage.variant]
    if stage.kind == "evolve":
        return evolve_command(scale, run.preset, run.condition, stage.out_dir, sets=run.sets), None
    evolved_dir = os.path.join(out, run.name, "evolve")
    noise = [s for s in run.sets if s.startswith("sle_noise_steps=")]
    sets = tuple(s for s in run.sets if s not in noise)
    return test_command(scale, run.preset, run.condition, evolved_dir, stage.out_dir, sets=sets,
                        sle_noise_steps=int(noise[0].split("=")[1]) if noise else None), None


#: The paper's four conditions under ``skills``, from the finished reproduction (EE-ES's runs are shared, under
#: ``paper``: :func:`experiments.reproduce.evolution_dir` finds them).
REPRODUCED = ("LE-LS", "EE-LS", "EE-ES", "SLE")
#: The reproduction's runs of the ``faithful`` variant that are its own (its EE-LS is skills', EE-ES paper's).
FAITHFUL_REPRODUCED = ("LE-LS", "SLE")
#: SLE with its noise annealed over the whole test (the claims study's ``skills-sle-test``): EXT-LS-whole's
#: reference, as the reproduction's SLE (noise over 100,000 cycles) is EXT-LS's.
SLE_WHOLE = os.path.join(RESULTS, "claims", "skills-sle-test", "test", "SLE")
#: The reproduction's evolutions drawn beside the study's (the paper's Fig. 3a).
DRAWN_BESIDE = ("LE-LS", "EE-LS")
#: (c)'s rows: their evolved learning values beside the presets'.
PARAMETER_ROWS = ("LE-LS-P", "LE-LS-PC", "LE-LS-P-faithful")
#: The presets whose values (c)'s table shows beside the evolved ones.
HAND_PRESETS = ("skills", "paper", "faithful")
#: (d)'s rows, each with what its fitness is compared with: 6 experts all expressed, and the reproduction's 3.
EXPERTS_ROWS = (("LE-LS-N6", ("LE-LS-6", "skills LE-LS")),
                ("LE-LS-N6-faithful", ("LE-LS-6-faithful", "faithful LE-LS")))


class Judged(NamedTuple):
    """One verdict of the report: a question of the paper's (``claims.FUTURE``) on some rows, under a rule set."""

    question: str  # "a" to "d"
    rules: str  # the rule set, in words
    rows: tuple[str, ...]  # (a): EE-LS, then the criterion rows; (b): EXT-LS, LE-LS, SLE; (c): the row;
    # (d): the evolved number, 3 experts, 6 all expressed


JUDGED: tuple[Judged, ...] = (
    Judged("a", "skills", ("skills EE-LS", "skills LE-LS", "EV-LS", "EV-LS-diff")),
    Judged("a", "faithful (its EE-LS is skills')", ("skills EE-LS", "faithful LE-LS", "EV-LS-faithful")),
    Judged("b", "skills, noise over 100,000 cycles", ("EXT-LS", "skills LE-LS", "skills SLE")),
    Judged("b", "skills, noise over the whole test", ("EXT-LS-whole", "skills LE-LS", "skills SLE-whole")),
    Judged("b", "faithful", ("EXT-LS-faithful", "faithful LE-LS", "faithful SLE")),
    Judged("c", "skills", ("LE-LS-P",)),
    Judged("c", "skills, childhood length evolved", ("LE-LS-PC",)),
    Judged("c", "faithful", ("LE-LS-P-faithful",)),
    Judged("d", "skills", ("LE-LS-N6", "skills LE-LS", "LE-LS-6")),
    Judged("d", "faithful", ("LE-LS-N6-faithful", "faithful LE-LS", "LE-LS-6-faithful")),
)
#: The generations of (d)'s table of expressed experts (the last one is added).
GENERATIONS_SHOWN = (0, 10, 25, 50)
NOT_RUN = "not run yet"
#: The reproduction's report, whose fresh lives of its runs' best genomes the reference rows show.
SUMMARY = os.path.join("docs", "reproduction", "summary.json")
DOCUMENT = os.path.join("docs", "FUTURE_WORK.md")
#: Where the report's tables go in docs/FUTURE_WORK.md.
TABLE_START = "<!-- future-work tables: python -m experiments.future_work --report -->"
TABLE_END = "<!-- end of future-work tables -->"
#: Line styles of the rows that share their condition with another drawn row (the rest take their condition's).
STYLES = {"LE-LS-6": dict(color="0.3", lw=1.2, ls="-."), "EXT-LS-whole": dict(color="tab:purple", lw=1.0, ls=":"),
          "skills SLE-whole": dict(color="tab:blue", lw=1.2, ls="-."),
          "LE-LS-6-faithful": dict(color="0.3", lw=1.0, ls=":")}


def read_traits(run_dir: str) -> dict | None:
    """An evolution's evolved values from its history.csv: names and (generations, seeds, values, 2) (population
    mean, the best's), or None without any."""
    import numpy as np

    path = os.path.join(run_dir, "history.csv")
    if not os.path.isfile(path):
        return None
    with open(path) as f:
        rows = list(csv.DictReader(f))
    names = [c[len("mean_"):] for c in (rows[0] if rows else ()) if c.startswith("mean_")
             and f"best_{c[len('mean_'):]}" in rows[0]]
    if not names:
        return None
    seeds = sorted({int(r["seed"]) for r in rows})
    values = np.full((max(int(r["generation"]) for r in rows) + 1, len(seeds), len(names), 2), np.nan)
    for r in rows:
        values[int(r["generation"]), seeds.index(int(r["seed"]))] = [[float(r[f"{which}_{n}"]) for which in
                                                                      ("mean", "best")] for n in names]
    return dict(names=names, values=values)


def _evolution(run_dir: str, fresh=None) -> dict | None:
    """A row's evolution as the report shows it: its size and, once finished, its final best, spread and plateau,
    and ``fresh(run)``: the fresh lives of each seed's best genome (None: not measured)."""
    from experiments.claims import final_best, plateau_generation
    from experiments.loading import read_evolution

    run = read_evolution(run_dir)
    if run is None:
        return None
    best, planned = run["best"], (run["config"] or {}).get("num_generations")
    entry = dict(dir=run_dir, seeds=len(run["seeds"]), generations=len(best), planned=planned,
                 finished=planned is None or len(best) >= planned)
    if entry["finished"]:
        final = final_best(best)
        # sd with ddof 0 over seeds, as the reproduction's report (claims.measure) gives it
        entry.update(final_best=float(final.mean()), final_best_sd=float(final.std()),
                     final_best_per_seed=final.tolist(), plateau_generation=plateau_generation(best.mean(1)),
                     best_per_generation_mean=best.mean(1).tolist(), best_per_generation_sd=best.std(1).tolist())
        lives = fresh(run) if fresh is not None else None
        if lives is not None:
            entry.update(fresh=lives["mean"], fresh_sd=lives["sd_over_seeds"])
    return entry


def _test(out_dir: str) -> dict | None:
    """A finished learning test's steady state per run, its mean and sd (ddof 0, as steady.json's) and best run."""
    import numpy as np

    from experiments.loading import read_test

    test = read_test(out_dir)
    if test is None:
        return None
    per_run = np.asarray(test["steady"]["steady_per_run"], float)
    return dict(dir=out_dir, runs=len(per_run), steady_mean=float(per_run.mean()), steady_sd=float(per_run.std()),
                steady_best_run=float(per_run.max()), steady_per_run=per_run.tolist(),
                sle_noise_steps=(test["steady"].get("config") or {}).get("sle_noise_steps"),
                curve_steps=[int(v) for v in test["steps"]], curve_mean=[float(v) for v in test["mean"]])


def _last_values(run_dir: str, evolution: dict | None) -> dict | None:
    """A finished evolution's evolved values in its last generation, mean over seeds: {name: dict(mean, best)}."""
    traits = read_traits(run_dir) if evolution and evolution["finished"] else None
    if traits is None:
        return None
    values = traits["values"][-1]  # (seeds, values, 2)
    last = values.mean(0)
    return {n: dict(mean=float(last[t, 0]), best=float(last[t, 1]), best_per_seed=values[:, t, 1].tolist())
            for t, n in enumerate(traits["names"])}


def _expressed(run_dir: str, evolution: dict | None) -> list[dict] | None:
    """(d): per shown generation, the expressed experts (population mean, the best's) and the population's share
    expressing each number, mean over seeds."""
    traits = read_traits(run_dir) if evolution and evolution["finished"] else None
    if traits is None or "expressed_experts" not in traits["names"]:
        return None
    names, values = traits["names"], traits["values"].mean(1)  # (generations, values, 2)
    counts = sorted(int(n.split("_")[1]) for n in names if n.startswith("share_") and n.endswith("_experts"))
    shown = sorted({g for g in GENERATIONS_SHOWN if g < len(values)} | {len(values) - 1})
    e = names.index("expressed_experts")
    return [dict(generation=g, mean=float(values[g, e, 0]), best=float(values[g, e, 1]),
                 shares={k: float(values[g, names.index(f"share_{k}_experts"), 0]) for k in counts},
                 best_per_seed=traits["values"][g, :, e, 1].tolist()) for g in shown]


def colour_sets(followed: list[list[int]] | None) -> dict | None:
    """From the colour each probed genome's experts follow (-1: none, or not expressed), how many genomes
    follow each set of colours (``"blue + red"``; ``"none"``), the mean number of experts following one and of
    distinct colours followed (claim 7's colours followed)."""
    from experiments.relive import colours_followed
    from imrl_jax.behaviour import SEEN

    if not followed:
        return None
    sets: dict[str, int] = {}
    for experts in followed:
        name = " + ".join(SEEN[c] for c in sorted(set(experts) - {-1})) or "none"
        sets[name] = sets.get(name, 0) + 1
    following = [sum(c >= 0 for c in experts) for experts in followed]
    distinct = colours_followed(followed)
    return dict(genomes=len(followed), sets=dict(sorted(sets.items(), key=lambda kv: (-kv[1], kv[0]))),
                experts_following=float(sum(following) / len(following)),
                colours=float(sum(distinct) / len(distinct)))


def _noise(test: dict | None) -> str:
    """How a finished SLE test annealed its noise, in words ("" before it has finished or without its config)."""
    steps = (test or {}).get("sle_noise_steps")
    if steps is None:
        return ""
    return ", noise over the whole test" if not steps else f", noise over {steps:,} cycles"


def measure(out: str = OUT, reproduction: str = REPRODUCTION, sle_whole: str = SLE_WHOLE,
            claims: str = CLAIMS_OUT, summary: str = SUMMARY) -> dict:
    """Every row's evolution and learning test, (c)'s evolved learning values and (d)'s experts, from what finished."""
    import numpy as np

    from experiments.claims import _standard_error
    from imrl_jax import networks
    from imrl_jax.config import make_config

    from experiments.loading import read_json
    from experiments.relive import reproduction_fresh, run_fresh, run_probe
    from experiments.reproduce import owner

    report = read_json(summary) or {}
    shared = lambda v, c: lambda run: reproduction_fresh(report, owner(v, c), c)  # noqa: E731

    def reference(variant: str, c: str) -> dict:
        evolved = conditions.get(c).evolved
        return dict(name=f"{variant} {c}", condition=c, about=f"the reproduction's {c}", evolved=evolved,
                    evolution=_evolution(evolution_dir(reproduction, variant, c), shared(variant, c))
                    if evolved else None, test=_test(test_dir(reproduction, variant, c)), reference=True,
                    preset=variant)

    rows = [reference("skills", c) for c in REPRODUCED]
    rows.append(dict(name="skills SLE-whole", condition="SLE", about="the claims study's SLE (skills-sle-test)",
                     evolved=False, evolution=None, test=_test(sle_whole), reference=True, preset="skills"))
    rows += [reference("faithful", c) for c in FAITHFUL_REPRODUCED]
    for row in rows:
        row["about"] += "" if conditions.get(row["condition"]).evolved else _noise(row["test"])
    for run in RUNS:
        evolved = conditions.get(run.condition).evolved
        evolution, test = run_dirs(run, out, claims)
        entry = _evolution(evolution, lambda r, d=evolution: run_fresh(d, r["config"])) if evolved else None
        # what the experts do (claim 7's junction probe), kept beside the run as its fresh lives are
        probe = run_probe(evolution, num_best=NUM_BEST) if (entry or {}).get("finished") else None
        rows.append(dict(name=run.name, condition=run.condition, about=run.about, evolved=evolved, evolution=entry,
                         test=_test(test), reference=False, preset=run.preset,
                         colours=colour_sets(probe["followed"] if probe else None)))
    by_name = {row["name"]: row for row in rows}
    # (c): the values of the genes LE-LS-PC carries (LE-LS-P's and the childhood's length), beside the presets'
    names = networks.trait_names(make_config("skills", condition="LE-LS-PC"))
    hand = {preset: {n: float(config.childhood_steps if n == "childhood_length" else getattr(config, n)) for n in names}
            for preset, config in ((p, make_config(p)) for p in HAND_PRESETS)}
    evolved_values = {name: _last_values(os.path.join(out, name, "evolve"), by_name[name]["evolution"])
                      for name in PARAMETER_ROWS}
    # (d): the expressed experts over generations, and the final best against 6 experts all expressed and 3
    final = lambda name: (by_name[name]["evolution"] or {}).get("final_best_per_seed")  # noqa: E731
    experts = []
    for row, others in EXPERTS_ROWS:
        mine, compared = final(row), []
        for other in others:
            theirs = final(other)
            if mine and theirs:
                a, b = np.asarray(mine), np.asarray(theirs)
                compared.append(dict(name=other, final_best=float(b.mean()), seeds=len(b),
                                     difference=float(a.mean() - b.mean()), standard_error=_standard_error(a, b)))
        experts.append(dict(row=row, against=list(others), compared=compared,
                            generations=_expressed(os.path.join(out, row, "evolve"), by_name[row]["evolution"])))
    measured = dict(rows=rows, learning_values=dict(names=list(names), hand=hand, evolved=evolved_values),
                    experts=experts)
    measured["verdicts"] = judge(measured)
    return measured


def judge(measured: dict) -> list[dict]:
    """The verdicts of :data:`JUDGED` from :func:`measure`'s rows, (c)'s evolved values and (d)'s experts."""
    from experiments import claims
    from imrl_jax.config import make_config

    rows = {r["name"]: r for r in measured["rows"]}

    def evolution(name):
        r = rows[name]
        e = r["evolution"]
        if not (e or {}).get("finished"):
            return None
        return dict(plateau=e["plateau_generation"], final_per_seed=e["final_best_per_seed"], fresh=e.get("fresh"),
                    genes=make_config(r["preset"], condition=r["condition"]).num_genes)

    def test(name):
        t = rows[name]["test"]
        return None if t is None else dict(steps=t["curve_steps"], mean=t["curve_mean"], per_run=t["steady_per_run"])

    final = lambda name: (rows[name]["evolution"] or {}).get("final_best_per_seed")  # noqa: E731
    experts = {e["row"]: e for e in measured["experts"]}
    hand = measured["learning_values"]["hand"]
    out = []
    for j in JUDGED:
        if j.question == "a":
            criteria = {n: evolution(n) for n in j.rows[1:]}
            claim = claims.claim_criteria_easier({n: c for n, c in criteria.items() if c is not None},
                                                 evolution(j.rows[0]))
        elif j.question == "b":
            claim = claims.claim_motivation_needed(*(test(n) for n in j.rows))
        elif j.question == "c":
            evolved = measured["learning_values"]["evolved"].get(j.rows[0])
            claim = claims.claim_hand_values({n: v["best_per_seed"] for n, v in (evolved or {}).items()},
                                             hand["skills"], hand["paper"])
        else:
            shown = (experts.get(j.rows[0]) or {}).get("generations")
            claim = claims.claim_three_enough(shown[-1]["best_per_seed"] if shown else None, final(j.rows[0]),
                                              final(j.rows[1]), final(j.rows[2]))
        # (a) judges the criterion rows that finished; the others are named until they have
        missing = [n for n in j.rows[1:] if j.question == "a" and evolution(n) is None]
        out.append(dict(question=j.question, rules=j.rules, rows=list(j.rows), missing=missing, **claim))
    return out


def verdict_lines(verdicts: list[dict]) -> list[str]:
    """The verdicts' table and the rules behind them."""
    from experiments.claims import FUTURE, FUTURE_RULES

    lines = ["| question | rules | rows | verdict | measured |", "|---|---|---|---|---|"]
    shown = set()
    for v in verdicts:
        first = v["question"] not in shown
        shown.add(v["question"])
        question = f"({v['question']}) {FUTURE[v['question']]}" if first else ""
        verdict = f"**{v['verdict']}**" + (f" so far (not finished: {', '.join(v['missing'])})"
                                             if v["missing"] and v["verdict"] != "n/a" else "")
        lines.append(f"| {question} | {v['rules']} | {', '.join(v['rows'])} | {verdict} | {v['measured']} |")
    lines += ["", "Rules (n/a: a row not finished yet):", ""]
    lines += [f"- ({q}) {rule}" for q, rule in FUTURE_RULES.items()]
    return lines


def _value(v: float) -> str:
    """A learning value for the table: 3 significant digits, a count of steps in full."""
    return f"{v:,.0f}" if abs(v) >= 1000 else f"{v:.3g}"


def _row_cells(row: dict) -> list[str]:
    """The main table's cells of a row after its name, condition and description."""
    e, t = row["evolution"], row["test"]
    if not row["evolved"]:
        cells = ["not evolved", "-", "-", "-", "-"]
    elif e is None:
        cells = ["-", NOT_RUN, "-", "-", "-"]
    elif not e["finished"]:
        cells = [f"{e['seeds']} x {e['generations']} of {e['planned']}", "running", "-", "-", "-"]
    else:
        plateau = "-" if e["plateau_generation"] is None else str(e["plateau_generation"])
        fresh = "-" if e.get("fresh") is None else f"{e['fresh']:.3f} ({e['fresh_sd']:.3f})"
        cells = [f"{e['seeds']} x {e['generations']}", f"{e['final_best']:.3f}", f"{e['final_best_sd']:.3f}", fresh,
                 plateau]
    return cells + ([NOT_RUN, "-"] if t is None else [f"{t['steady_mean']:.3f} +- {t['steady_sd']:.3f}",
                                                        str(t["runs"])])


def table(measured: dict) -> str:
    """The report's markdown: every row's fitness and steady state, (c)'s evolved learning values, (d)'s experts."""
    from experiments.claims import LAST_GENERATIONS, PLATEAU_FRACTION

    lines = ["| row | condition | what | seeds x generations | final best fitness (best of a generation's noisy lives) "
             "| sd over seeds | fresh lives (sd over seeds) | plateau generation | steady state (mean +- sd over runs) "
             "| runs |", "|---|---|---|---|---|---|---|---|---|---|"]
    lines += [f"| {r['name']} | {r['condition']} | {r['about']} | " + " | ".join(_row_cells(r)) + " |"
              for r in measured["rows"]]
    lines += ["", f"Final best fitness: a seed's mean of its last {LAST_GENERATIONS} generations' best, then the mean "
              f"over seeds; fresh lives: each seed's best genome of the last generation in 10 new lives (keys the GA "
              f"never used), mean and sd over seeds (ddof 1); plateau: the first generation whose best (mean over seeds) reaches {PLATEAU_FRACTION:.0%} "
              f"of that; steady state: each learning-test run's last cycles (docs/CLAIMS.md's claims 1, 2 and 6).",
              *_colour_lines(measured["rows"]),
              "", "(c) The evolved learning values, last generation, mean over seeds, beside the values set by hand:", ""]
    values = measured["learning_values"]
    lines += ["| value | " + " | ".join(f"{p} (by hand)" for p in values["hand"]) + " | " + " | ".join(
        f"{r}: population mean | {r}: the best's" for r in PARAMETER_ROWS) + " |",
              "|---|" + "---|" * len(values["hand"]) + "---|---|" * len(PARAMETER_ROWS)]
    for name in values["names"]:
        cells = [_value(hand[name]) for hand in values["hand"].values()]
        for row in PARAMETER_ROWS:
            evolved = values["evolved"][row]
            if evolved is None:
                cells += [NOT_RUN, NOT_RUN]
            else:  # a value the row does not evolve (LE-LS-P's childhood) is the preset's
                cells += [_value(evolved[name][w]) if name in evolved else "-" for w in ("mean", "best")]
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    for experts in measured["experts"]:
        lines += _experts_lines(experts, measured["rows"])
    lines += ["", "The paper's questions, each with its verdict:", ""] + verdict_lines(measured["verdicts"])
    return "\n".join(lines)


def _colour_lines(rows: list[dict]) -> list[str]:
    """What the experts of the study's finished evolutions do: the colours they follow, as a table."""
    from imrl_jax.behaviour import FOLLOW_CHOICE

    probed = [r for r in rows if r.get("colours")]
    if not probed:
        return []
    lines = ["", f"What the experts do (claim 7's junction probe of each seed's {NUM_BEST} fittest genomes of the last "
             "generation, after a fresh childhood; an expert follows a colour when it takes it at "
             f"{FOLLOW_CHOICE:.0%} of the junctions "
             "offering it; an expert not expressed follows none):", "",
             "| row | genomes | experts following a colour, per genome | distinct colours followed, per genome "
             "| the colours followed: genomes |", "|---|---|---|---|---|"]
    lines += [f"| {r['name']} | {r['colours']['genomes']} | {r['colours']['experts_following']:.2f} | "
              f"{r['colours']['colours']:.2f} | "
              + ", ".join(f"{name} {n}" for name, n in r["colours"]["sets"].items()) + " |" for r in probed]
    return lines


def _experts_lines(experts: dict, rows: list[dict]) -> list[str]:
    """(d)'s tables of one row: the experts expressed over generations, and its final best against the others."""
    lines = ["", f"(d) {experts['row']}: the experts expressed, mean over seeds:", ""]
    if experts["generations"] is None:
        lines.append(f"{experts['row']}: {NOT_RUN}.")
    else:
        counts = list(experts["generations"][0]["shares"])
        lines += ["| generation | expressed: population mean | the best's | " + " | ".join(
            f"share with {k}" for k in counts) + " |", "|---|---|---|" + "---|" * len(counts)]
        lines += [f"| {g['generation']} | {g['mean']:.2f} | {g['best']:.2f} | " + " | ".join(
            f"{g['shares'][k]:.3f}" for k in counts) + " |" for g in experts["generations"]]
    if experts["generations"] is not None and not experts["compared"]:
        lines.append(f"\nIts final best fitness against {' and '.join(experts['against'])}: {NOT_RUN}.")
    if experts["compared"]:
        mine = next(r for r in rows if r["name"] == experts["row"])["evolution"]
        lines += ["", f"| final best fitness of {experts['row']} ({mine['seeds']} seeds) | its | theirs | their seeds | "
                  "difference | se |", "|---|---|---|---|---|---|"]
        lines += [f"| against {c['name']} | {mine['final_best']:.3f} | {c['final_best']:.3f} | {c['seeds']} | "
                  f"{c['difference']:+.3f} | {c['standard_error']:.3f} |" for c in experts["compared"]]
    return lines


def _style(row: dict) -> dict:
    """A row's line style: its own, else its condition's; dashed under ``faithful`` (the same condition twice)."""
    from imrl_jax.plotting import CONDITION_STYLES

    style = STYLES.get(row["name"], CONDITION_STYLES[row["condition"]])
    return dict(style, ls="--") if row.get("preset") == "faithful" and row["name"] not in STYLES else style


def figure(measured: dict, path: str) -> str:
    """Fig. 3's three panels: (a) best fitness per generation of every finished evolution (the study's and the
    reproduction's LE-LS and EE-LS), (b) the mean learning curve and (c) the steady state of every finished
    learning test (EE-ES's in (c) only, as in the paper); written to ``path``."""
    import numpy as np
    from matplotlib.ticker import MaxNLocator

    from experiments.figures import _band
    from imrl_jax.plotting import new_figure, save, style_axis

    fig = new_figure(17.0, 6.0)
    curves, learning, bars = fig.subplots(1, 3, gridspec_kw=dict(width_ratios=[1.0, 1.0, 1.1]))
    drawn = [r for r in measured["rows"] if (r["evolution"] or {}).get("finished")
             and (not r.get("reference") or r["condition"] in DRAWN_BESIDE)]
    banded = set()
    # figures._draw_curves styles by condition: LE-LS-6 shares LE-LS's, so the rows are drawn here with _style
    for row in drawn:
        e = row["evolution"]
        mean, sd = np.asarray(e["best_per_generation_mean"]), np.asarray(e["best_per_generation_sd"])
        style = _style(row)
        curves.plot(np.arange(len(mean)), mean, label=f"{row['name']} ({e['seeds']} seeds)", **style)
        _band(curves, np.arange(len(mean)), mean, sd, style, banded)
    curves.xaxis.set_major_locator(MaxNLocator(integer=True))
    style_axis(curves, "(a) best fitness, mean +-1 sd over seeds", "generation",
               "best fitness (best of a generation's noisy lives)")
    tested = [r for r in measured["rows"] if r["test"] is not None]
    learned = [r for r in tested if conditions.get(r["condition"]).learns]  # as the paper's Fig. 3b
    for row in learned:
        learning.plot(np.asarray(row["test"]["curve_steps"]) / 1e6, row["test"]["curve_mean"], label=row["name"],
                      **_style(row))
    style_axis(learning, "(b) learning tests, mean over runs", "million cycles of the task", "performance per bin")
    x = np.arange(len(tested))
    bars.bar(x - 0.19, [r["test"]["steady_mean"] for r in tested], 0.38, yerr=[r["test"]["steady_sd"] for r in tested],
             color="0.35", capsize=3, label="mean over runs (+-1 sd)")
    bars.bar(x + 0.19, [r["test"]["steady_best_run"] for r in tested], 0.38, color="0.75", label="best run")
    bars.set_xticks(x, [r["name"] for r in tested], rotation=30, ha="right", fontsize=7)
    style_axis(bars, "(c) steady state of the learning tests", "", "steady-state performance")
    bars.grid(False, axis="x")
    for ax, rows in ((curves, drawn), (learning, learned), (bars, tested)):
        if not rows:  # an unfinished study: say so rather than leave a blank panel
            ax.set_ylim(0, 1)
            ax.text(0.5, 0.5, NOT_RUN, transform=ax.transAxes, ha="center", va="center", color="0.4")
            continue
        # room above the highest bar or curve for the legend and the note
        top = (max(np.asarray(r["evolution"]["best_per_generation_mean"]).max() for r in drawn) if ax is curves else
               max(max(r["test"]["curve_mean"]) for r in learned) if ax is learning else
               max(r["test"]["steady_best_run"] for r in tested))
        if ax is bars:
            ax.set_ylim(0, 1.3 * max(top, 1e-9))
            ax.legend(fontsize=6, loc="upper left", ncol=2)
        else:  # many rows: the legend below the panel, where it hides no curve
            ax.set_ylim(0, 1.08 * max(top, 1e-9))
            ax.legend(fontsize=6, loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=3)
        if all(r.get("reference") for r in rows):  # only the references: the study's rows are to come
            ax.text(0.98, 0.97, f"the study's rows: {NOT_RUN}", transform=ax.transAxes, ha="right", va="top",
                    color="0.4", fontsize=8)
    fig.suptitle("The paper's future work beside the reproduction's runs (dashed: under faithful)", fontsize=10)
    fig.tight_layout()
    return save(fig, path)


def report(out: str = OUT, document: str = DOCUMENT, reproduction: str = REPRODUCTION, sle_whole: str = SLE_WHOLE,
           claims: str = CLAIMS_OUT, summary: str = SUMMARY) -> int:
    """Measure, write report.json and future_work.png under ``out``, and the tables into ``document``."""
    import json

    from experiments.study import write_table

    measured = measure(out, reproduction, sle_whole, claims, summary)
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, "report.json"), "w") as f:
        json.dump(measured, f, indent=2)
    drawn = figure(measured, os.path.join(out, "future_work.png"))
    write_table(document, table(measured), TABLE_START, TABLE_END)
    done = [r["name"] for r in measured["rows"] if (r["evolution"] or {}).get("finished") or r["test"]]
    print(f"{len(done)} of {len(measured['rows'])} rows have finished stages ({', '.join(done) or 'none'}); wrote "
          f"{os.path.join(out, 'report.json')}, {drawn} and the tables of {document}")
    return 0


def all_stages(out: str = OUT) -> tuple[list[Stage], dict]:
    """Every stage the command runs by default (every row), and their scale."""
    return plan(list(BY_NAME), SCREEN, out), SCREEN


def main(argv=None) -> int:
    """The command line: list the stages, run (or go on with) them, or write the report of what has finished."""
    p = argparse.ArgumentParser(prog="python -m experiments.future_work", description=__doc__.split("\n\n")[0])
    p.add_argument("--only", help=f"comma-separated rows, in order (default: all: {', '.join(BY_NAME)})")
    p.add_argument("--out", default=OUT, help=f"results directory (default: {OUT})")
    p.add_argument("--list", action="store_true", help="print the stages and their commands, run nothing")
    p.add_argument("--report", action="store_true", help="measure every finished row, draw the figure and write "
                   "docs/FUTURE_WORK.md's tables (runs nothing)")
    add_options(p)
    args = p.parse_args(argv)
    if args.report:
        return report(args.out)
    names = args.only.split(",") if args.only else list(BY_NAME)
    unknown = [n for n in names if n not in BY_NAME]
    if unknown:
        print(f"error: --only: unknown row {unknown[0]!r} (choose from {', '.join(BY_NAME)})", file=sys.stderr)
        return 2
    stages = plan(names, SCREEN, args.out)
    if args.list:
        for stage in stages:
            print(f"{stage.name}: {' '.join(stage_command(stage, SCREEN, args.out)[0][1:])}")
        return 0
    manifest, manifest_path = load_manifest(args.out, study="future_work", sizes=SCREEN, rows=names)
    return run_stages(stages, SCREEN, manifest, manifest_path, lambda stage: stage_command(stage, SCREEN, args.out),
                      **from_options(args, args.out))


#: The studies of this module (python -m experiments finds them).
STUDIES = (Study("future-work", "future_work", "docs/FUTURE_WORK.md", 7),)


if __name__ == "__main__":
    sys.exit(main())
