"""The paper's Fig. 3 and its seven claims (section 3), from a reproduction table's runs (experiments.reproduction).

    python -m experiments report reproduction       # docs/REPRODUCTION.md, docs/reproduction/
    python -m experiments report reproduction-cpu   # docs/REPRODUCTION_CPU.md, docs/reproduction_cpu/

``loading`` reads the results, ``claims`` holds the verdict rules (pure functions), ``relive`` lives the best
individuals again, ``figures`` draws and ``document`` writes the markdown; this module runs them in order. Into the
document's figures folder (beside it, named after it): Fig. 1 (arena and tasks), Fig. 3a and 3b per variant, Fig. 3c,
the best evolved individuals' paths coloured by the expert in control, ``summary.json``, ``specialisation.csv`` and
``claims.json``; into the table's folder, ``best_genomes.npz``, each seed's 10 best genomes of every evolution's last
generation, so that the paths can be drawn again without ``final_population.npz`` (not kept for the finished paper-
and cpu-scale runs). The document labels every number with the run's scale, gives the rule behind each verdict and
ends with the table's hand-written ``discussion.md`` when it exists.

The best individual of an evolution (the fittest of the last generation over all seeds) lives again the very life
that earned its fitness (:func:`imrl_jax.evolution.search.life_key`), then drives each task for a while from the weights it
ended that task with: the trajectory figures, the expert-specialisation table and EE-ES's stereotypy per task (claim
4). Claim 7 probes the experts of the 10 best LE-LS and EE-LS individuals of every seed
(:func:`imrl_jax.analysis.behaviour.specialisation`; LE-LS after a fresh childhood). ``behaviour=False`` skips both.
Those lives take minutes: before any is drawn or compiled the report says on stderr what it will live and its
estimated time (``experiments.harness.relive.Reliving``), then a line as each part compiles and a progress line with an ETA.
"""

from __future__ import annotations

import csv
import io
import json
import math
import os

import numpy as np

from experiments.harness.study import RESULTS
from experiments.document import (ROOT, figures_of, pipeline_command, scale_label, sharers, specialisation_rows,
                                  write_document)
from experiments.harness.figures import fig3, fig_baselines, fig_curves, fig_paths, fig_steady
from experiments.harness.loading import read_baselines, update_best_genomes
from imrl_jax.runs.rundir import write_atomic
from imrl_jax.analysis.relive import DRAWN_STEPS, PATH_STEPS, fresh_fitness, probe_best, relive_best
from experiments.harness.relive import Reliving, relive_parts
from imrl_jax.analysis.claims import CLAIMS, EVOLVED, PAPER, RULES, SEEN, TESTED, measure
from imrl_jax import conditions


def _jsonable(value):
    """``value`` as JSON takes it: numpy's numbers and arrays as Python's, a number that is not finite as null."""
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [_jsonable(v) for v in value]
    value = value.item() if isinstance(value, np.generic) else value
    return None if isinstance(value, float) and not math.isfinite(value) else value


#: Where the baselines study (experiments/baselines.py) writes the brax baselines (the report shows them when present).
BASELINES = os.path.join(ROOT, RESULTS, "baselines")


def run(table, behaviour: bool = True, baselines_dir: str = BASELINES) -> dict:
    """Write a reproduction table's figures, summaries and document from what has finished; the paths written."""
    from imrl_jax.runs.checkpoint import git_commit
    from imrl_jax.config import make_config
    from imrl_jax.analysis.arena_figures import plot_arena
    from imrl_jax.analysis.plotting import save

    data, doc = table.data(), os.path.abspath(table.document)
    manifest, figures, label = data["manifest"], figures_of(doc), scale_label(data["manifest"])
    short = manifest["scale"] + " scale"
    written = dict(fig3={}, fig3a={}, fig3b={}, paths={})
    at = lambda name: os.path.join(figures, name)  # noqa: E731
    best = update_best_genomes(data)  # kept whether or not the individuals are relived
    relived = {key: entry for key, entry in best.items() if behaviour and entry["config"] is not None}
    # the long part (minutes at the paper's scale) is said with its estimated time before anything is drawn
    parts = {key: relive_parts(*key, entry) for key, entry in relived.items()}
    reliving = Reliving([p for ps in parts.values() for p in ps]) if relived else None

    written["arena"] = save(plot_arena(make_config("paper"), "the arena and the six tasks"), at("fig1_arena.png"))
    steady = {k: t["steady"] for k, t in data["tests"].items()}
    for variant in data["variants"]:
        evolutions = {c: data["evolutions"][variant, c]["best"] for c in EVOLVED if (variant, c) in data["evolutions"]}
        tests = {c: data["tests"][variant, c] for c in TESTED if (variant, c) in data["tests"]}
        for panel, runs in (("a", evolutions), ("b", tests)):  # Fig. 3a and 3b alone, each beside its numbers
            if runs:
                title = f"Fig. 3{panel}, {variant} rules ({short})"
                written[f"fig3{panel}"][variant] = save(fig_curves(panel, runs, title),
                                                        at(f"fig3{panel}_{variant}.png"))
        if evolutions or tests:  # the three panels side by side, as the paper draws them
            written["fig3"][variant] = save(fig3(evolutions, tests, steady, variant,
                                                 f"Fig. 3, {variant} rules ({short})"), at(f"fig3_{variant}.png"))
    if steady:
        variants = [v for v in data["variants"] if any((v, c) in steady for c in TESTED)]
        written["fig3c"] = save(fig_steady(steady, variants, f"Fig. 3c: steady state ({short})"), at("fig3c.png"))
    baselines = read_baselines(baselines_dir)
    if baselines:
        written["baselines"] = save(fig_baselines(baselines, shared_once(data["tests"], data),
                                                  f"brax.training baselines beside the learning tests ({short})"),
                                    at("baselines.png"))

    lives, probes = {}, {}
    for (variant, condition), entry in relived.items():
        own = parts[variant, condition]
        life = lives[variant, condition] = reliving.run(own[0], relive_best, entry["config"], entry)
        life["fresh"] = reliving.run(own[1], fresh_fitness, entry["config"], entry)
        one_for_all = not conditions.get(condition).learns
        title = (f"{condition}{'' if one_for_all else f', {variant} rules'}: best individual (seed "
                 f"{life['seed']}, generation {life['generation']}, fitness {life['fitness']:.3f}, relived "
                 f"{life['relived_fitness']:.3f}); {short}\npaths: the last {DRAWN_STEPS} of {PATH_STEPS:,} "
                 f"steps driven after each task's learning period, coloured by the expert in control")
        written["paths"][variant, condition] = save(fig_paths(life, title), at(
            f"paths_{condition}.png" if one_for_all else f"paths_{variant}_{condition}.png"))
        if not one_for_all:
            probes[variant, condition] = reliving.run(own[2], probe_best, entry["config"], entry)

    probes = share_probes(probes, data)
    # a variant whose SLE explores the whole test by definition (faithful) has claim 5 measured at the test's length
    numbers = measure(data, lives, probes, sle_whole_test=set(table.whole_test))
    spec_rows = specialisation_rows(lives)
    written["specialisation"] = at("specialisation.csv")
    text = io.StringIO(newline="")
    writer = csv.DictWriter(text, ["variant", "condition", "phase", "seed", "generation", "expert", "steps",
                                   "control_share", *SEEN, "follows"])
    writer.writeheader()
    writer.writerows(spec_rows)
    write_atomic(written["specialisation"], text.getvalue().encode())

    summary = dict(scale=manifest["scale"], scale_label=label, sizes=manifest.get("sizes"),
                   variants=data["variants"], command=pipeline_command(table.name).replace("`", ""),
                   results_commit=manifest.get("git_commit"), report_commit=git_commit(),
                   stages=manifest.get("stages", {}),
                   evolution={v: numbers[v]["evolution"] for v in numbers},
                   learning_tests={v: numbers[v]["learning_tests"] for v in numbers},
                   best_individuals={f"{v}/{c}": best_individual(life) for (v, c), life in lives.items()},
                   colours_followed={f"{v}/{c}": colours for (v, c), colours in probes.items()})
    claims = dict(scale=summary["scale"], scale_label=label, rules={str(n): r for n, r in RULES.items()},
                  claims={str(n): dict(text=text, paper=PAPER[n],
                                       variants={v: numbers[v]["claims"][n] for v in numbers})
                          for n, text in CLAIMS.items()})
    for name, content in (("summary.json", summary), ("claims.json", claims)):
        written[name] = at(name)
        text = json.dumps(_jsonable(content), indent=2)  # all of it first: a failure leaves the old file whole
        write_atomic(written[name], (text + "\n").encode())
    write_document(doc, figures, data, numbers, lives, spec_rows, written, baselines, table.name)
    written["doc"] = doc
    return written


def best_individual(life: dict) -> dict:
    """A relived best individual as summary.json keeps it: the life's numbers, the colours its experts follow, its
    fresh lives."""
    return dict({name: life[name] for name in ("seed", "index", "generation", "fitness", "relived_fitness",
                                               "performance", "stereotypy", "stereotypy_per_task", "speed")},
                dominant_expert_share=life["dominant_expert"], follows=[int(c) for c in life["probe"].followed],
                fresh_mean_per_seed=life["fresh"]["mean"], fresh_sd_per_seed=life["fresh"]["sd"],
                fresh_lives=life["fresh"]["num_lives"])


def shared_once(runs: dict, data: dict) -> dict:
    """``{(variant, condition): run}`` with a run that several variants share once, labelled by them all."""
    return {("every variant" if not conditions.get(condition).learns else ", ".join(sharers(data, variant, condition)),
             condition): run for (variant, condition), run in runs.items()
            if data["owners"][variant, condition] == variant}


def share_probes(probes: dict, data: dict) -> dict:
    """The probes of every variant: one that shares a condition's runs (faithful's EE-LS) shares their probes."""
    out = dict(probes)
    for (variant, condition), owner in data["owners"].items():
        if (owner, condition) in probes:
            out.setdefault((variant, condition), probes[owner, condition])
    return out
