"""The paper's Fig. 3 and its seven claims (section 3), from a results directory of reproduce.py.

    python -m experiments.report experiments/results/paper   # docs/REPRODUCTION.md, docs/reproduction/
    python -m experiments.report experiments/results/cpu     # docs/REPRODUCTION_CPU.md, docs/reproduction_cpu/

(from the repository root). The pieces: ``loading`` reads the results, ``claims`` holds the
verdict rules (pure functions), ``relive`` lives the best individuals again, ``figures``
draws and ``document`` writes the markdown; this module runs them in order.

Reads what ``experiments/reproduce.py`` wrote (the evolutions' histories and last
populations, the learning tests' curves and steady states, ``manifest.json``) and writes:

- into ``--figures``: Fig. 1 (arena and tasks), Fig. 3a and 3b per variant, Fig. 3c, the
  paths of the best evolved individuals coloured by the expert in control,
  ``summary.json``, ``specialisation.csv`` and ``claims.json``;
- into RESULTS_DIR: ``best_genomes.npz``, the 10 best genomes of each seed's last
  generation of every evolution, so that the paths can be drawn again without
  ``final_population.npz`` (not kept for the finished paper- and cpu-scale runs; committed for new ones);
- ``--doc``: the markdown report, with every number labelled with the run's scale, the
  claims table with the rule that gave each verdict, and a "Discussion" section read from
  ``RESULTS_DIR/discussion.md`` (written by hand) when it exists.

The best individual of an evolution (the fittest of the last generation over all seeds)
lives again the very life that earned its fitness (:func:`imrl_jax.render.life_key`), then
drives each task for a while from the weights it ended that task with: those paths give
the trajectory figures, the expert-specialisation table and the stereotypy of EE-ES per
task (claim 4). Claim 7 probes the experts of the 10 best LE-LS and EE-LS individuals of
every seed (:func:`imrl_jax.behaviour.specialisation`; LE-LS after a fresh childhood).
``--no-behaviour`` skips both.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import os
import sys

import numpy as np

from experiments.study import RESULTS
from experiments.claims import CLAIMS, PAPER, RULES, SEEN, measure
from experiments.document import (ROOT, pipeline_command, report_paths, scale_label, specialisation_rows,
                                  write_document)
from experiments.figures import fig3, fig_baselines, fig_fitness, fig_learning, fig_paths, fig_steady
from experiments.loading import load, read_baselines, read_json, update_best_genomes
from experiments.relive import DRAWN_STEPS, FRESH_LIVES, PATH_STEPS, fresh_fitness, probe_best, relive_best
from experiments.reproduce import EVOLVED, LEARNING_EVOLVED, TESTED, owner, shared, sharers, variant_spec


def _jsonable(value):
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [_jsonable(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


#: Where experiments/baselines.py writes the brax baselines (the report shows them when present).
BASELINES = os.path.join(ROOT, RESULTS, "baselines")


def run(results: str, doc: str, figures: str, behaviour: bool = True, baselines_dir: str = BASELINES) -> dict:
    """Write the figures, the summaries and the document; return the paths written."""
    from imrl_jax.config import make_config
    from imrl_jax.plotting import plot_arena, save

    data = load(results)
    if not data["evolutions"] and not data["tests"]:
        raise FileNotFoundError(f"{results}: no evolution or learning test found "
                                f"(not a results directory of experiments/reproduce.py?)")
    os.makedirs(figures, exist_ok=True)
    label = scale_label(data["manifest"])
    short = (data["manifest"] or {}).get("scale", "unknown") + " scale"
    written = dict(fig3={}, fig3a={}, fig3b={}, paths={})

    written["arena"] = save(plot_arena(make_config("paper"), "the arena and the six tasks"),
                            os.path.join(figures, "fig1_arena.png"))
    for variant in data["variants"]:
        evolutions = {c: data["evolutions"][variant, c]["best"] for c in EVOLVED if (variant, c) in data["evolutions"]}
        if evolutions:
            written["fig3a"][variant] = save(fig_fitness(evolutions, f"Fig. 3a, {variant} rules ({short})"),
                                             os.path.join(figures, f"fig3a_{variant}.png"))
        tests = {c: data["tests"][variant, c] for c in TESTED if (variant, c) in data["tests"]}
        if tests:
            written["fig3b"][variant] = save(fig_learning(tests, f"Fig. 3b, {variant} rules ({short})"),
                                             os.path.join(figures, f"fig3b_{variant}.png"))
    steady = {k: t["steady"] for k, t in data["tests"].items()}
    if steady:
        variants = [v for v in data["variants"] if any((v, c) in steady for c in TESTED)]
        written["fig3c"] = save(fig_steady(steady, variants, f"Fig. 3c: steady state ({short})"),
                                os.path.join(figures, "fig3c.png"))
    for variant in data["variants"]:  # the three panels side by side, as the paper draws them
        evolutions = {c: data["evolutions"][variant, c]["best"] for c in EVOLVED if (variant, c) in data["evolutions"]}
        tests = {c: data["tests"][variant, c] for c in TESTED if (variant, c) in data["tests"]}
        if evolutions or tests:
            written["fig3"][variant] = save(fig3(evolutions, tests, steady, variant,
                                                 f"Fig. 3, {variant} rules ({short})"),
                                            os.path.join(figures, f"fig3_{variant}.png"))

    baselines = read_baselines(baselines_dir)
    if baselines:
        tests = shared_once(data["tests"], data["variants"])
        written["baselines"] = save(fig_baselines(baselines, tests, f"brax.training baselines beside the learning "
                                                                    f"tests ({short})"),
                                    os.path.join(figures, "baselines.png"))

    best = update_best_genomes(data)
    lives, probes = {}, {}
    if behaviour:
        for (variant, condition), entry in best.items():
            if entry["config"] is None:
                continue
            print(f"reliving the best {condition} individual ({variant})", flush=True)
            life = lives[variant, condition] = relive_best(entry["config"], entry)
            print(f"{FRESH_LIVES} fresh lives of each seed's best {condition} genome ({variant})", flush=True)
            life["fresh"] = fresh_fitness(entry["config"], entry)
            one_for_all = shared(condition)
            name = f"paths_{condition}.png" if one_for_all else f"paths_{variant}_{condition}.png"
            title = (f"{condition}{'' if one_for_all else f', {variant} rules'}: best individual (seed "
                     f"{life['seed']}, generation {life['generation']}, fitness {life['fitness']:.3f}, relived "
                     f"{life['relived_fitness']:.3f}); {short}\npaths: the last {DRAWN_STEPS} of {PATH_STEPS:,} "
                     f"steps driven after each task's learning period, coloured by the expert in control")
            written["paths"][variant, condition] = save(fig_paths(life, title), os.path.join(figures, name))
        for (variant, condition), entry in best.items():
            if entry["config"] is not None and condition in LEARNING_EVOLVED:
                print(f"probing the experts of the {entry['genomes'].shape[1]} best {condition} individuals of "
                      f"every seed ({variant})", flush=True)
                probes[variant, condition] = probe_best(entry["config"], entry)

    probes = share_probes(probes, data["variants"])
    # a variant whose SLE explores the whole test by definition (faithful) has claim 5 measured at the test's length
    whole = {v for v in data["variants"] if variant_spec(v).sle_noise_steps == 0}
    numbers = measure(data, lives, probes, sle_whole_test=whole)
    spec_rows = specialisation_rows(lives)
    written["specialisation"] = os.path.join(figures, "specialisation.csv")
    with open(written["specialisation"], "w", newline="") as f:
        fields = ["variant", "condition", "phase", "seed", "generation", "expert", "steps", "control_share", *SEEN,
                  "follows"]
        writer = csv.DictWriter(f, fields)
        writer.writeheader()
        writer.writerows(spec_rows)

    manifest = data["manifest"] or {}
    from imrl_jax.checkpoint import git_commit

    summary = dict(scale=manifest.get("scale", "unknown"), scale_label=label, sizes=manifest.get("sizes"),
                   variants=data["variants"], command=pipeline_command(results, data["manifest"]).replace("`", ""),
                   results_commit=manifest.get("git_commit"), report_commit=git_commit(),
                   stages=manifest.get("stages", {}),
                   evolution={v: numbers[v]["evolution"] for v in numbers},
                   learning_tests={v: numbers[v]["learning_tests"] for v in numbers},
                   best_individuals={f"{v}/{c}": dict(seed=life["seed"], index=life["index"],
                                                      generation=life["generation"], fitness=life["fitness"],
                                                      relived_fitness=life["relived_fitness"],
                                                      performance=life["performance"],
                                                      stereotypy=life["stereotypy"],
                                                      stereotypy_per_task=life["stereotypy_per_task"],
                                                      speed=life["speed"],
                                                      dominant_expert_share=life["dominant_expert"],
                                                      follows=[int(c) for c in life["probe"].followed],
                                                      fresh_mean_per_seed=life["fresh"]["mean"],
                                                      fresh_sd_per_seed=life["fresh"]["sd"],
                                                      fresh_lives=life["fresh"]["num_lives"])
                                     for (v, c), life in lives.items()},
                   colours_followed={f"{v}/{c}": colours for (v, c), colours in probes.items()})
    claims = dict(scale=summary["scale"], scale_label=label, rules={str(n): r for n, r in RULES.items()},
                  claims={str(n): dict(text=text, paper=PAPER[n],
                                       variants={v: numbers[v]["claims"][n] for v in numbers})
                          for n, text in CLAIMS.items()})
    for name, content in (("summary.json", summary), ("claims.json", claims)):
        written[name] = os.path.join(figures, name)
        text = json.dumps(_jsonable(content), indent=2)  # all of it first: a failure leaves the old file whole
        with open(written[name], "w") as f:
            f.write(text)
            f.write("\n")
    write_document(doc, figures, data, numbers, lives, spec_rows, written, baselines)
    written["doc"] = doc
    return written


def shared_once(runs: dict, variants) -> dict:
    """``{(variant, condition): run}`` with a run that several variants share once, labelled by them all."""
    out = {}
    for (variant, condition), run in runs.items():
        if owner(variant, condition) != variant:
            continue
        if shared(condition):
            out["every variant", condition] = run
            continue
        out[", ".join(sharers(variant, condition, variants)) or variant, condition] = run
    return out


def share_probes(probes: dict, variants) -> dict:
    """The probes of every variant: one that shares a condition's runs (faithful's EE-LS) shares their probes."""
    out = dict(probes)
    for variant in variants:
        for condition in LEARNING_EVOLVED:
            if (owner(variant, condition), condition) in probes:
                out.setdefault((variant, condition), probes[owner(variant, condition), condition])
    return out


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("results", metavar="RESULTS_DIR", help="a results directory of experiments/reproduce.py")
    p.add_argument("--doc", help="the markdown report (default: docs/REPRODUCTION.md for the paper scale, "
                                 "docs/REPRODUCTION_CPU.md for the cpu scale, and so on)")
    p.add_argument("--figures", help="directory of the figures and summaries (default: docs/reproduction for the "
                                     "paper scale, docs/reproduction_cpu for the cpu scale, and so on)")
    p.add_argument("--no-behaviour", action="store_true", help="skip reliving the best individuals (paths, claim 7)")
    p.add_argument("--baselines", default=BASELINES, help="directory of the brax baselines (experiments/baselines.py)")
    args = p.parse_args(argv)
    if not os.path.isdir(args.results):
        print(f"error: RESULTS_DIR: {args.results} is not a directory", file=sys.stderr)
        return 2
    scale = (read_json(os.path.join(args.results, "manifest.json")) or {}).get("scale", "unknown")
    doc, figures = report_paths(scale)
    args.doc, args.figures = args.doc or doc, args.figures or figures
    try:
        written = run(args.results, args.doc, args.figures, behaviour=not args.no_behaviour,
                      baselines_dir=args.baselines)
    except FileNotFoundError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    print(f"wrote {written['doc']} and the figures and summaries in {args.figures}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
