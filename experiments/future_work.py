"""The paper's future work as conditions (docs/FUTURE_WORK.md): evolutions and learning tests of the new rows.

    python -m experiments run future-work       # run (or go on with) every stage, in order
    python -m experiments list future-work      # the stages, done or to run
    python -m experiments report future-work    # the tables and figures of whatever has finished

Each row is a condition (``imrl_jax.conditions``) under a preset and ``--set`` overrides, evolved at the paper's
lengths (5 seeds x 100 generations, then its 5 best x 4 learning tests) or tested from scratch (5 runs x 5 x 4),
beside the reproduction's paper runs (10 seeds); each run is found by its key wherever a study made it. The report
measures every finished row, (c)'s evolved learning values and (d)'s expressed experts, judges the paper's four
questions (``further_claims.FUTURE``) and draws a figure per question.
"""

from __future__ import annotations

import os
import sys

import numpy as np

# NUM_BEST: the junction probe drives claim 7's number of each seed's fittest genomes, so that a run shared with
# the claims study (LE-LS-6) keeps one probe.json
from experiments.harness.figures import not_run
from experiments.harness.loading import write_json
from experiments.harness.markdown import head, line, mean_sd
from experiments.harness.study import REPRODUCTION, RESULTS, SCALES, SCREEN, markers
from experiments.harness.table import Row, Table
from imrl_jax.analysis.claims import NUM_BEST

OUT = os.path.join(RESULTS, "future_work")
DOCUMENT = os.path.join("docs", "FUTURE_WORK.md")
PAPER = SCALES["paper"]
#: The reproduction's rows, each with what it is, in the report's order: its runs at the paper's sizes (its EE-ES
#: is paper's: the same lives) and SLE's tests, found by their keys (the claims study's ``skills-sle-test``: the
#: noise over the whole test, EXT-LS-whole's reference). Their fresh lives come from the reproduction's report.
REFERENCES = (
    (Row("skills LE-LS", "LE-LS", "skills", scale=PAPER), "the reproduction's LE-LS"),
    (Row("skills EE-LS", "EE-LS", "skills", scale=PAPER), "the reproduction's EE-LS"),
    (Row("skills EE-ES", "EE-ES", "skills", scale=PAPER), "the reproduction's EE-ES"),
    (Row("skills SLE", "SLE", "skills", scale=PAPER), "the reproduction's SLE"),
    (Row("skills SLE-whole", "SLE", "skills", ("sle_noise_steps=0",)), "the claims study's SLE (skills-sle-test)"),
    (Row("faithful LE-LS", "LE-LS", "faithful", scale=PAPER), "the reproduction's LE-LS"),
    (Row("faithful SLE", "SLE", "faithful", ("sle_noise_steps=0",), scale=PAPER), "the reproduction's SLE"))
#: The study's rows, each with what it is.
STUDIED = (
    (Row("EV-LS", "EV-LS", "skills"), "(a) evolved evaluators, gamma V(x_t) - V(x_{t-1})"),
    (Row("EV-LS-diff", "EV-LS-diff", "skills"), "(a) evolved evaluators, V(x_t) - V(x_{t-1})"),
    (Row("EXT-LS", "EXT-LS", "skills"), "(b) the hierarchy on the task's reward only, SLE's noise over 100,000 cycles"),
    (Row("EXT-LS-whole", "EXT-LS", "skills", ("sle_noise_steps=0",)), "(b), the noise over the whole test"),
    (Row("LE-LS-P", "LE-LS-P", "skills"), "(c) evolved learning parameters"),
    (Row("LE-LS-PC", "LE-LS-PC", "skills"), "(c) evolved learning parameters and childhood length"),
    (Row("LE-LS-N6", "LE-LS-N", "skills", ("num_experts=6",)), "(d) up to 6 experts, each expressed by a gene"),
    (Row("LE-LS-6", "LE-LS", "skills", ("num_experts=6",)),
     "(d)'s comparison: 6 experts, all expressed (the claims study's claim-8 run)"),
    # The same questions under the claims map's chosen rule set (docs/CLAIMS.md, "The decision"): run after skills'.
    (Row("EV-LS-faithful", "EV-LS", "faithful"), "(a) under `faithful`"),
    (Row("EXT-LS-faithful", "EXT-LS", "faithful", ("sle_noise_steps=0",)),
     "(b) under `faithful`, the noise over the whole test (its SLE's reading)"),
    (Row("LE-LS-P-faithful", "LE-LS-P", "faithful"), "(c) under `faithful`"),
    (Row("LE-LS-N6-faithful", "LE-LS-N", "faithful", ("num_experts=6",)), "(d) under `faithful`"),
    (Row("LE-LS-6-faithful", "LE-LS", "faithful", ("num_experts=6",)),
     "(d)'s comparison under `faithful` (the claims study's claim-8 run of paper-selector, the same lives)"))
#: Every row the report shows, in order, with what it is: the reproduction's first, then the study's.
ABOUT = {row.name: about for row, about in REFERENCES + STUDIED}
#: The report's verdicts: a question of the paper's (``further_claims.FUTURE``), its rule set in words, and its rows:
#: (a) EE-LS, then the criterion rows; (b) EXT-LS, LE-LS, SLE; (c) the row; (d) the evolved number, 3 experts, 6 all
#: expressed.
JUDGED = (
    ("a", "skills", ("skills EE-LS", "skills LE-LS", "EV-LS", "EV-LS-diff")),
    ("a", "faithful (its EE-LS is skills')", ("skills EE-LS", "faithful LE-LS", "EV-LS-faithful")),
    ("b", "skills, noise over 100,000 cycles", ("EXT-LS", "skills LE-LS", "skills SLE")),
    ("b", "skills, noise over the whole test", ("EXT-LS-whole", "skills LE-LS", "skills SLE-whole")),
    ("b", "faithful", ("EXT-LS-faithful", "faithful LE-LS", "faithful SLE")),
    ("c", "skills", ("LE-LS-P",)),
    ("c", "skills, childhood length evolved", ("LE-LS-PC",)),
    ("c", "faithful", ("LE-LS-P-faithful",)),
    ("d", "skills", ("LE-LS-N6", "skills LE-LS", "LE-LS-6")),
    ("d", "faithful", ("LE-LS-N6-faithful", "faithful LE-LS", "LE-LS-6-faithful")))
NOT_RUN = "not run yet"
#: Where the report's tables go in docs/FUTURE_WORK.md.
TABLE_START, TABLE_END = markers("future-work tables", "future-work")
#: Line styles of the rows that share their condition with another drawn row (the rest take their condition's).
STYLES = {"LE-LS-6": dict(color="0.3", lw=1.2, ls="-."), "EXT-LS-whole": dict(color="tab:purple", lw=1.0, ls=":"),
          "skills SLE-whole": dict(color="tab:blue", lw=1.2, ls="-."),
          "LE-LS-6-faithful": dict(color="0.3", lw=1.0, ls=":")}


def read_traits(run_dir: str | None) -> dict | None:
    """An evolution's evolved values from history.csv: names, (generations, seeds, values, 2) (mean, the best's)."""
    from experiments.harness.loading import history_columns

    path = os.path.join(run_dir or "", "history.csv")
    if not os.path.isfile(path):
        return None
    with open(path) as f:
        header = f.readline().strip().split(",")
    names = [c[len("mean_"):] for c in header if c.startswith("mean_") and f"best_{c[len('mean_'):]}" in header]
    values = history_columns(run_dir, [f"{which}_{n}" for n in names for which in ("mean", "best")]) if names else None
    return None if values is None else dict(names=names, values=values.reshape(*values.shape[:2], len(names), 2))


def _evolution(run_dir: str | None) -> dict | None:
    """A row's evolution as the report shows it: its size and, once finished, its final best, spread and plateau."""
    from imrl_jax.analysis.claims import final_best, plateau_generation
    from experiments.harness.loading import read_evolution

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
    return entry


def _test(out_dir: str) -> dict | None:
    """A finished learning test's steady state per run, its mean and sd (ddof 0, as steady.json's) and best run."""
    from experiments.harness.loading import read_test

    test = read_test(out_dir)
    if test is None:
        return None
    per_run = np.asarray(test["steady"]["steady_per_run"], float)
    return dict(dir=out_dir, runs=len(per_run), steady_mean=float(per_run.mean()), steady_sd=float(per_run.std()),
                steady_best_run=float(per_run.max()), steady_per_run=per_run.tolist(),
                sle_noise_steps=(test["steady"].get("config") or {}).get("sle_noise_steps"),
                curve_steps=test["steps"].tolist(), curve_mean=test["mean"].tolist())


def _expressed(evolution: dict | None) -> list[dict] | None:
    """(d): at generations 0, 10, 25, 50 and the last, the experts expressed (mean, the best's) and their shares."""
    traits = read_traits(evolution["dir"]) if (evolution or {}).get("finished") else None
    if traits is None or "expressed_experts" not in traits["names"]:
        return None
    names, values = traits["names"], traits["values"].mean(1)  # (generations, values, 2)
    counts = sorted(int(n.split("_")[1]) for n in names if n.startswith("share_") and n.endswith("_experts"))
    e = names.index("expressed_experts")
    return [dict(generation=g, mean=float(values[g, e, 0]), best=float(values[g, e, 1]),
                 shares={k: float(values[g, names.index(f"share_{k}_experts"), 0]) for k in counts},
                 best_per_seed=traits["values"][g, :, e, 1].tolist())
            for g in sorted({g for g in (0, 10, 25, 50) if g < len(values)} | {len(values) - 1})]


def colour_sets(followed: list[list[int]] | None) -> dict | None:
    """From the colour each probed genome's experts follow (-1: none): the genomes per set of colours followed
    (``"blue + red"``, ``"none"``), the mean number of experts following one and of colours followed (claim 7's)."""
    from collections import Counter

    from imrl_jax.analysis.relive import colours_followed
    from imrl_jax.analysis.behaviour import SEEN

    if not followed:
        return None
    sets = Counter(" + ".join(SEEN[c] for c in sorted(set(experts) - {-1})) or "none" for experts in followed)
    return dict(genomes=len(followed), sets=dict(sorted(sets.items(), key=lambda kv: (-kv[1], kv[0]))),
                experts_following=float(np.mean([sum(c >= 0 for c in experts) for experts in followed])),
                colours=float(np.mean(colours_followed(followed))))


def measure(rows: dict[str, Row], evolutions: dict, tests: dict, summary: dict,
            reproduction: str = REPRODUCTION) -> dict:
    """Every row of :data:`ABOUT`, (c)'s values and (d)'s experts; ``summary``: the reproduction's report."""
    from imrl_jax.analysis.claims import _difference
    from experiments.claims_study import reproduction_variant
    from experiments.harness.relive import reproduction_fresh, run_fresh, run_probe
    from imrl_jax.agent import networks
    from imrl_jax.config import make_config

    measured_rows, references = [], {row.name for row, _ in REFERENCES}
    for name, about in ABOUT.items():
        row, reference = rows[name], name in references
        evolution, test = _evolution(evolutions.get(name)) if row.evolved else None, _test(tests[name])
        if (evolution or {}).get("finished"):  # the fresh lives of each seed's best genome
            lives = (reproduction_fresh(summary, reproduction_variant(evolution["dir"], reproduction), row.condition)
                     if reference else run_fresh(evolution["dir"]))
            evolution.update({} if lives is None else dict(fresh=lives["mean"], fresh_sd=lives["sd_over_seeds"]))
        noise = (test or {}).get("sle_noise_steps") if reference and not row.evolved else None  # how SLE annealed it
        about += "" if noise is None else f", noise over {noise:,} cycles" if noise else ", noise over the whole test"
        entry = dict(name=name, condition=row.condition, about=about, evolved=row.evolved, evolution=evolution,
                     test=test, reference=reference, preset=row.preset)
        if not reference:  # what the experts do (claim 7's junction probe), kept beside the run as its fresh lives
            probe = run_probe(evolution["dir"], num_best=NUM_BEST) if (evolution or {}).get("finished") else None
            entry["colours"] = colour_sets(probe["followed"] if probe else None)
        measured_rows.append(entry)
    by_name = {row["name"]: row["evolution"] for row in measured_rows}
    # (c): the values of the genes LE-LS-PC carries (LE-LS-P's and the childhood's length), beside the presets'
    names = networks.trait_names(make_config("skills", condition="LE-LS-PC"))
    hand = {preset: {n: float(config.childhood_steps if n == "childhood_length" else getattr(config, n)) for n in names}
            for preset, config in ((p, make_config(p)) for p in ("skills", "paper", "faithful"))}
    evolved = {}
    for name in ("LE-LS-P", "LE-LS-PC", "LE-LS-P-faithful"):
        traits = read_traits(by_name[name]["dir"]) if (by_name[name] or {}).get("finished") else None
        last = None if traits is None else traits["values"][-1]  # the last generation's (seeds, values, 2)
        evolved[name] = None if last is None else {
            n: dict(mean=float(mean[0]), best=float(mean[1]), best_per_seed=last[:, t, 1].tolist())
            for t, (n, mean) in enumerate(zip(traits["names"], last.mean(0)))}
    # (d): the expressed experts over generations, and the final best against 6 experts all expressed and 3
    final = lambda name: (by_name[name] or {}).get("final_best_per_seed")  # noqa: E731
    experts = []
    for row, others in (("LE-LS-N6", ("LE-LS-6", "skills LE-LS")),
                        ("LE-LS-N6-faithful", ("LE-LS-6-faithful", "faithful LE-LS"))):
        compared = []
        for other in (o for o in others if final(row) and final(o)):
            difference, se = _difference(final(row), final(other))
            compared.append(dict(name=other, final_best=float(np.mean(final(other))), seeds=len(final(other)),
                                 difference=difference, standard_error=se))
        experts.append(dict(row=row, against=list(others), compared=compared, generations=_expressed(by_name[row])))
    measured = dict(rows=measured_rows, learning_values=dict(names=list(names), hand=hand, evolved=evolved),
                    experts=experts)
    measured["verdicts"] = judge(measured)
    return measured


def judge(measured: dict) -> list[dict]:
    """The verdicts of :data:`JUDGED` from :func:`measure`'s rows, (c)'s evolved values and (d)'s experts."""
    from imrl_jax.analysis import further_claims
    from imrl_jax.config import make_config

    rows, values = {r["name"]: r for r in measured["rows"]}, measured["learning_values"]
    experts = {e["row"]: e["generations"] for e in measured["experts"]}
    final = lambda name: (rows[name]["evolution"] or {}).get("final_best_per_seed")  # noqa: E731

    def evolution(name):
        r, e = rows[name], rows[name]["evolution"]
        return dict(plateau=e["plateau_generation"], final_per_seed=e["final_best_per_seed"], fresh=e.get("fresh"),
                    genes=make_config(r["preset"], condition=r["condition"]).num_genes) if final(name) else None

    def test(name):
        t = rows[name]["test"]
        return None if t is None else dict(steps=t["curve_steps"], mean=t["curve_mean"], per_run=t["steady_per_run"])

    def hand_values(row):
        """(c) of a row: its seeds' best's evolved values against the presets'."""
        evolved = values["evolved"].get(row) or {}
        return further_claims.claim_hand_values({n: v["best_per_seed"] for n, v in evolved.items()},
                                                values["hand"]["skills"], values["hand"]["paper"])

    def three_enough(row, *others):
        """(d) of a row: its best's expressed experts, its final best against 3 experts' and 6 all expressed."""
        kept = experts.get(row)
        return further_claims.claim_three_enough(kept[-1]["best_per_seed"] if kept else None, final(row),
                                                 *map(final, others))

    rules = dict(a=lambda actors, *criteria: further_claims.claim_criteria_easier(  # the criterion rows that finished
        {n: evolution(n) for n in criteria if final(n)}, evolution(actors)),
        b=lambda *names: further_claims.claim_motivation_needed(*map(test, names)), c=hand_values, d=three_enough)
    # (a) names the criterion rows not finished until they have
    return [dict(question=q, rules=rule, rows=list(names), missing=[n for n in names[1:] if q == "a" and not final(n)],
                 **rules[q](*names)) for q, rule, names in JUDGED]


def table(measured: dict) -> str:
    """The report's markdown: every row's fitness and steady state, (c)'s evolved learning values, (d)'s experts."""
    from imrl_jax.analysis.claims import LAST_GENERATIONS, PLATEAU_FRACTION
    from imrl_jax.analysis.further_claims import FUTURE, FUTURE_RULES

    lines = head("row", "condition", "what", "seeds x generations",
                 "final best fitness (best of a generation's noisy lives)", "sd over seeds",
                 "fresh lives (sd over seeds)", "plateau generation", "steady state (mean +- sd over runs)", "runs")
    for r in measured["rows"]:
        e, t = r["evolution"], r["test"]
        if not (e or {}).get("finished"):
            cells = (["not evolved", "-"] if not r["evolved"] else ["-", NOT_RUN] if e is None else
                     [f"{e['seeds']} x {e['generations']} of {e['planned']}", "running"]) + ["-"] * 3
        else:
            cells = [f"{e['seeds']} x {e['generations']}", f"{e['final_best']:.3f}", f"{e['final_best_sd']:.3f}",
                     "-" if e.get("fresh") is None else f"{e['fresh']:.3f} ({e['fresh_sd']:.3f})",
                     "-" if e["plateau_generation"] is None else str(e["plateau_generation"])]
        cells += [NOT_RUN, "-"] if t is None else [mean_sd(t["steady_mean"], t["steady_sd"]), t["runs"]]
        lines.append(line(r["name"], r["condition"], r["about"], *cells))
    lines += ["", f"Final best fitness: a seed's mean of its last {LAST_GENERATIONS} generations' best, then the mean "
              f"over seeds; fresh lives: each seed's best genome of the last generation in 10 new lives (keys the GA "
              f"never used), mean and sd over seeds (ddof 1); plateau: the first generation whose best (mean over "
              f"seeds) reaches {PLATEAU_FRACTION:.0%} "
              f"of that; steady state: each learning-test run's last cycles (docs/CLAIMS.md's claims 1, 2 and 6).",
              *_colour_lines(measured["rows"]),
              "", "(c) The evolved learning values, last generation, mean over seeds, beside the values set by hand:",
              ""]
    values = measured["learning_values"]
    value = lambda v: f"{v:,.0f}" if abs(v) >= 1000 else f"{v:.3g}"  # noqa: E731 (a count of steps in full)
    lines += head("value", *(f"{p} (by hand)" for p in values["hand"]),
                  *(f"{r}: {w}" for r in values["evolved"] for w in ("population mean", "the best's")))
    for name in values["names"]:
        cells = [value(hand[name]) for hand in values["hand"].values()]
        for evolved in values["evolved"].values():
            # a value the row does not evolve (LE-LS-P's childhood) is the preset's
            cells += ([NOT_RUN] * 2 if evolved is None else
                      [value(evolved[name][w]) if name in evolved else "-" for w in ("mean", "best")])
        lines.append(line(name, *cells))
    for experts in measured["experts"]:  # (d): the experts expressed over generations, its final best against others
        row, shown, compared = experts["row"], experts["generations"], experts["compared"]
        lines += ["", f"(d) {row}: the experts expressed, mean over seeds:", ""]
        if shown is None:
            lines.append(f"{row}: {NOT_RUN}.")
        else:
            lines += head("generation", "expressed: population mean", "the best's",
                          *(f"share with {k}" for k in shown[0]["shares"]))
            lines += [line(g["generation"], f"{g['mean']:.2f}", f"{g['best']:.2f}",
                           *(f"{s:.3f}" for s in g["shares"].values())) for g in shown]
            if not compared:
                lines.append(f"\nIts final best fitness against {' and '.join(experts['against'])}: {NOT_RUN}.")
        if compared:
            mine = next(r for r in measured["rows"] if r["name"] == row)["evolution"]
            lines += ["", *head(f"final best fitness of {row} ({mine['seeds']} seeds)", "its", "theirs", "their seeds",
                                "difference", "se")]
            lines += [line(f"against {c['name']}", f"{mine['final_best']:.3f}", f"{c['final_best']:.3f}", c["seeds"],
                           f"{c['difference']:+.3f}", f"{c['standard_error']:.3f}") for c in compared]
    lines += ["", "The paper's questions, each with its verdict:", "",
              *head("question", "rules", "rows", "verdict", "measured")]
    for i, v in enumerate(measured["verdicts"]):  # the question named on its first verdict
        first = all(w["question"] != v["question"] for w in measured["verdicts"][:i])
        verdict = f"**{v['verdict']}**" + (f" so far (not finished: {', '.join(v['missing'])})"
                                             if v["missing"] and v["verdict"] != "n/a" else "")
        lines.append(line(f"({v['question']}) {FUTURE[v['question']]}" if first else "", v["rules"],
                          ", ".join(v["rows"]), verdict, v["measured"]))
    lines += ["", "Rules (n/a: a row not finished yet):", "", *(f"- ({q}) {r}" for q, r in FUTURE_RULES.items())]
    return "\n".join(lines)


def _colour_lines(rows: list[dict]) -> list[str]:
    """What the experts of the study's finished evolutions do: the colours they follow, as a table."""
    from imrl_jax.analysis.behaviour import FOLLOW_CHOICE

    probed = [(r["name"], r["colours"]) for r in rows if r.get("colours")]
    if not probed:
        return []
    return ["", f"What the experts do (claim 7's junction probe of each seed's {NUM_BEST} fittest genomes of the last "
            "generation, after a fresh childhood; an expert follows a colour when it takes it at "
            f"{FOLLOW_CHOICE:.0%} of the junctions offering it; an expert not expressed follows none):", "",
            *head("row", "genomes", "experts following a colour, per genome", "distinct colours followed, per genome",
                  "the colours followed: genomes"),
            *(line(name, c["genomes"], f"{c['experts_following']:.2f}", f"{c['colours']:.2f}",
                   ", ".join(f"{k} {n}" for k, n in c["sets"].items())) for name, c in probed)]


def _style(row: dict) -> dict:
    """A row's line style: its own, else its condition's; dashed under ``faithful`` (the same condition twice)."""
    from imrl_jax.analysis.plotting import CONDITION_STYLES

    style = STYLES.get(row["name"], CONDITION_STYLES[row["condition"]])
    return dict(style, ls="--") if row.get("preset") == "faithful" and row["name"] not in STYLES else style


def _fitness(ax, rows: list[dict], measured: dict) -> bool:
    """Best fitness per generation of the rows' finished evolutions, mean +-1 sd over seeds (the paper's Fig. 3a)."""
    from experiments.harness.figures import _band

    drawn, banded = [r for r in rows if (r["evolution"] or {}).get("finished")], set()
    for row in drawn:
        e, style = row["evolution"], _style(row)
        mean, sd = np.asarray(e["best_per_generation_mean"]), np.asarray(e["best_per_generation_sd"])
        ax.plot(np.arange(len(mean)), mean, label=f"{row['name']} ({e['seeds']} seeds)", **style)
        _band(ax, np.arange(len(mean)), mean, sd, style, banded)
    ax.set(title="best fitness, mean +-1 sd over seeds", xlabel="generation",
           ylabel="best fitness (best of a generation's noisy lives)")
    return bool(drawn)


def _learning(ax, rows: list[dict], measured: dict) -> bool:
    """The rows' learning tests' mean curves (the paper's Fig. 3b)."""
    drawn = [r for r in rows if r["test"] is not None]
    for row in drawn:
        ax.plot(np.asarray(row["test"]["curve_steps"]) / 1e6, row["test"]["curve_mean"], label=row["name"],
                **_style(row))
    ax.set(title="learning tests, mean over runs", xlabel="million cycles of the task", ylabel="performance per bin")
    if drawn:  # between the curves, where it hides none of their rises
        ax.legend(fontsize=6.5, loc="center", bbox_to_anchor=(0.35, 0.6))
    return bool(drawn)


def _steady(ax, rows: list[dict], measured: dict) -> bool:
    """The rows' learning tests' steady states: mean over runs (+-1 sd) and best run (the paper's Fig. 3c)."""
    drawn = [r["test"] | dict(name=r["name"]) for r in rows if r["test"] is not None]
    x = np.arange(len(drawn))
    ax.bar(x - 0.19, [t["steady_mean"] for t in drawn], 0.38, yerr=[t["steady_sd"] for t in drawn], color="0.35",
           capsize=3, label="mean over runs (+-1 sd)")
    ax.bar(x + 0.19, [t["steady_best_run"] for t in drawn], 0.38, color="0.75", label="best run")
    ax.set_xticks(x, [t["name"] for t in drawn], rotation=30, ha="right", fontsize=7)
    ax.set(title="steady state of the learning tests", ylabel="steady-state performance")
    ax.grid(False, axis="x")
    return bool(drawn)


def _values(ax, rows: list[dict], measured: dict) -> bool:
    """(c): each seed's best's evolved values (dots; their mean, a bar) in their genes' ranges, beside the hand-set."""
    from imrl_jax.analysis.further_claims import map_position
    from imrl_jax.conditions import EVOLVED_FIELDS

    values = measured["learning_values"]
    names = [n for n in values["names"] if n in EVOLVED_FIELDS]
    for preset, marker, colour in (("skills", "s", "k"), ("paper", "x", "0.5")):
        ax.scatter(range(len(names)), [map_position(n, values["hand"][preset][n]) for n in names], marker=marker,
                   s=40, color=colour, zorder=5, label=f"{preset} (by hand)")
    drawn = [r for r in rows if values["evolved"].get(r["name"])]
    for i, row in enumerate(drawn):
        evolved, colour = values["evolved"][row["name"]], _style(row)["color"]
        face = "none" if row["preset"] == "faithful" else colour  # hollow under faithful
        for j, name in enumerate(names):
            u = [map_position(name, v) for v in evolved[name]["best_per_seed"]]
            x = j + (i - (len(drawn) - 1) / 2) * 0.22
            ax.scatter([x] * len(u), u, s=12, facecolors=face, edgecolors=colour, label=None if j else row["name"])
            ax.plot([x - 0.09, x + 0.09], [np.mean(u)] * 2, color=colour, lw=2)
    ax.set_xticks(range(len(names)), names, rotation=30, ha="right", fontsize=7)
    ax.set(title="the best's evolved values, each seed's, in its gene's range", ylim=(-0.05, 1.05),
           ylabel="position in the gene's range (MODEL.md's maps)")
    return bool(drawn)


def _experts(ax, rows: list[dict], measured: dict) -> bool:
    """(d): the experts expressed per generation, mean over seeds: the population's and the best's (dotted)."""
    drawn = []
    for row in rows:
        traits = read_traits((row["evolution"] or {}).get("dir"))
        if traits is not None and "expressed_experts" in traits["names"]:
            expressed = traits["values"][:, :, traits["names"].index("expressed_experts")].mean(1)
            ax.plot(expressed[:, 0], **_style(row), label=f"{row['name']}: population mean")
            ax.plot(expressed[:, 1], color=_style(row)["color"], lw=0.8, ls=":", label=f"{row['name']}: the best's")
            drawn.append(row)
    ax.axhline(3, color="0.5", lw=0.8, ls="--", label="the paper's 3")
    ax.set(title="experts expressed, mean over seeds", xlabel="generation", ylabel="experts expressed", ylim=(0, 6.2))
    return bool(drawn)


#: Each question's figure, its panels drawn from the rows of its verdicts.
PANELS = {"a": (_fitness, _steady), "b": (_learning, _steady), "c": (_values,), "d": (_experts, _fitness)}


def figure(measured: dict, question: str, path: str) -> str:
    """The figure of one of the paper's questions (:data:`PANELS`), written to ``path``."""
    import textwrap

    from imrl_jax.analysis.further_claims import FUTURE
    from imrl_jax.analysis.plotting import new_figure, save, style_axis

    rows = [r for r in measured["rows"] if any(r["name"] in names for q, _, names in JUDGED if q == question)]
    fig = new_figure(6.4 * len(PANELS[question]), 4.6)
    for ax, panel in zip(fig.subplots(1, len(PANELS[question]), squeeze=False)[0], PANELS[question]):
        drawn = panel(ax, rows, measured)
        style_axis(ax, ax.get_title(), ax.get_xlabel(), ax.get_ylabel())
        ax.set_ylim(bottom=0) if panel is not _values else None
        if drawn and ax.get_legend() is None:
            ax.legend(fontsize=6.5)
        elif not drawn:  # an unfinished study: say so rather than leave a blank panel
            not_run(ax)
    fig.suptitle(textwrap.fill(f"({question}) {FUTURE[question]} (dashed or hollow: under faithful)",
                               int(14 * fig.get_figwidth())), fontsize=9)
    fig.tight_layout()
    return save(fig, path)


class FutureWorkTable(Table):
    """The future-work study's table, whose report (:func:`measure`, :func:`table`, :func:`figure`) is its own."""

    def report(self) -> int:
        from experiments.claims_study import reproduction_summary
        from experiments.harness.study import write_table

        # the reproduction's report beside the study's document: its runs' fresh lives, which the reference rows show
        measured = measure({row.name: row for row in self.rows}, self.evolutions(), self.tests(),
                           reproduction_summary(self.document) or {}, self.reproduction)
        os.makedirs(self.out, exist_ok=True)
        write_json(os.path.join(self.out, "report.json"), measured, indent=2)
        drawn = [figure(measured, q, os.path.join(self.out, f"question_{q}.png")) for q in PANELS]
        write_table(self.document, table(measured), TABLE_START, TABLE_END)
        done = [r["name"] for r in measured["rows"] if (r["evolution"] or {}).get("finished") or r["test"]]
        print(f"{len(done)} of {len(measured['rows'])} rows have finished stages ({', '.join(done) or 'none'}); wrote "
              f"{os.path.join(self.out, 'report.json')}, {', '.join(drawn)} and the tables of {self.document}")
        return 0


# the reproduction's evolutions, then SLE's tests (the order of their stages), then the study's rows
TABLE = FutureWorkTable("future-work", DOCUMENT, 7, scale=SCREEN, out=OUT, rows=(
    *sorted((row for row, _ in REFERENCES), key=lambda row: not row.evolved), *(row for row, _ in STUDIED)))
all_stages, main = TABLE.all_stages, TABLE.main
#: The studies of this module (python -m experiments finds them).
STUDIES = (TABLE.study(__name__.rsplit(".", 1)[-1]),)

if __name__ == "__main__":
    sys.exit(main())
