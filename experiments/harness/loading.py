"""Reading evolutions, learning tests and baselines as the reports read them, and keeping the best genomes."""

from __future__ import annotations

import csv
import io
import json
import os

import numpy as np

from imrl_jax.analysis.claims import NUM_BEST  # genomes kept per seed in best_genomes.npz: those claim 7 probes
from imrl_jax.config import Config
from imrl_jax.analysis.steady_state import pairs_both_ways, performance_curve, steady_bins
from imrl_jax.runs.rundir import write_atomic


def read_json(path: str) -> dict | None:
    """A JSON file, or None when it does not exist."""
    if not os.path.isfile(path):
        return None
    with open(path) as f:
        return json.load(f)


def write_json(path: str, data, **dumps) -> None:
    """``data`` as ``path``'s JSON (``json.dumps``'s options), written atomically: a kill leaves the old file whole."""
    write_atomic(path, json.dumps(data, **dumps).encode())


def read_curve(path: str) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """A learning test's curve.csv as (end cycle of each bin, mean over all tests, sd over runs)."""
    if not os.path.isfile(path):
        return None
    data = np.genfromtxt(path, delimiter=",", names=True)
    data = np.atleast_1d(data)
    return data["end_step"].astype(int), data["mean"].astype(float), data["sd_over_runs"].astype(float)


def read_evolution(run_dir: str) -> dict | None:
    """An evolution's history and config, as the report reads them (None before its first generation)."""
    history = history_seeds(run_dir, ["best"])
    if history is None:
        return None
    saved = read_json(os.path.join(run_dir, "config.json")) or {}
    return dict(dir=run_dir, seeds=history[0], best=history[1][..., 0], config=saved.get("config"),
                git_commit=saved.get("git_commit"))


def read_test(out_dir: str) -> dict | None:
    """A finished learning test's steady state and mean curve, as the report reads them (None if unfinished)."""
    steady = read_json(os.path.join(out_dir, "steady.json"))
    curve = read_curve(os.path.join(out_dir, "curve.csv"))
    if steady is None or curve is None:
        return None
    test = dict(dir=out_dir, steady=steady, steps=curve[0], mean=curve[1], sd=curve[2],
                pairs_both_ways=steady.get("pairs_both_ways"))
    curves_path = os.path.join(out_dir, "curves.npz")
    if test["pairs_both_ways"] is None and os.path.exists(curves_path):
        # Tests written before steady.json kept this number: recompute it from every
        # test's curves with the learning test's own statistics.
        config = Config.from_dict(steady["config"])
        with np.load(curves_path) as saved:
            performance = performance_curve(config, saved["reaches"])
        last = steady_bins(config, steady["steady_steps"])
        test["pairs_both_ways"] = pairs_both_ways(performance[..., -last:].mean(-1))
    return test


def _key(variant: str, condition: str, field: str) -> str:
    return f"{variant}__{condition}__{field}"


def best_of_population(path: str, num_best: int = NUM_BEST) -> dict | None:
    """The ``num_best`` fittest of each seed's last evaluated generation in a final_population.npz (None before
    the first): dict(genomes (S, B, G), fitness (S, B), index (S, B), seeds (S,), generations)."""
    with np.load(path) as pop:
        evaluated, fitness, generations, seeds = pop["evaluated"], pop["fitness"], int(pop["generation"]), pop["seeds"]
    if generations < 1:
        return None
    order = np.argsort(-fitness, axis=1, kind="stable")[:, :num_best]
    return dict(genomes=np.take_along_axis(evaluated, order[:, :, None], 1), fitness=np.take_along_axis(fitness, order, 1),
                index=order, seeds=np.asarray(seeds), generations=np.asarray(generations))


def update_best_genomes(data: dict, num_best: int = NUM_BEST) -> dict:
    """The best genomes of every evolution, from final_population.npz where present (else from best_genomes.npz).

    ``data``: a reproduction table's (``ReproductionTable.data``). Returns ``{(variant, condition): dict(genomes
    (S, B, G), fitness (S, B), index (S, B), seeds (S,), generations, config)}`` keyed by the variant whose folder
    holds each run (EE-ES under ``paper``) and rewrites the table's best_genomes.npz when anything came from a
    population.
    """
    path = os.path.join(data["results"], "best_genomes.npz")
    stored = {}
    if os.path.isfile(path):
        with np.load(path) as saved:
            stored = {name: saved[name] for name in saved.files}
    found, fresh = {}, False
    for (variant, condition), run in data["evolutions"].items():
        shared = data["owners"][variant, condition]
        if (shared, condition) in found:
            continue
        population = os.path.join(run["dir"], "final_population.npz")
        if os.path.isfile(population):
            entry = best_of_population(population, num_best)
            if entry is None:
                continue
            stored.update({_key(shared, condition, f): v for f, v in entry.items()})
            fresh = True
        elif _key(shared, condition, "genomes") not in stored:
            continue
        found[shared, condition] = {f: stored[_key(shared, condition, f)]
                                   for f in ("genomes", "fitness", "index", "seeds", "generations")}
        found[shared, condition]["config"] = run["config"]
    if fresh:
        buffer = io.BytesIO()
        np.savez_compressed(buffer, **stored)
        write_atomic(path, buffer.getvalue())
    return found


def read_baselines(path: str) -> dict:
    """The brax baselines under ``path`` (one directory per agent and budget, written by ``imrl_jax.commands.baselines``).

    Returns ``{name: dict(summary, steps, mean, sd, per_task)}`` ordered by agent (PPO, ES) then budget:
    ``mean`` and ``sd`` are the deterministic performance at each evaluation, over tasks
    then seeds (sd over seeds of the mean over tasks); ``per_task`` the final performance
    per task, mean over seeds. Directories without a finished run are left out.
    """
    found = []
    for name in sorted(os.listdir(path)) if os.path.isdir(path) else []:
        summary = read_json(os.path.join(path, name, "summary.json"))
        curves = os.path.join(path, name, "curves.csv")
        if summary is None or not os.path.isfile(curves):
            continue
        with open(curves) as f:
            rows = list(csv.DictReader(f))
        steps = sorted({int(r["step"]) for r in rows})
        seeds = sorted({int(r["seed"]) for r in rows})
        # (seeds, steps): each seed's mean over tasks at each evaluation
        by_seed = np.asarray([[np.mean([float(r["performance"]) for r in rows
                                        if int(r["seed"]) == s and int(r["step"]) == t]) for t in steps]
                              for s in seeds])
        per_task = [summary["per_task"][str(t)]["mean"] for t in summary["tasks"]]
        found.append((summary["agent"], summary["steps"], name,
                      dict(summary=summary, steps=np.asarray(steps), mean=by_seed.mean(0), sd=by_seed.std(0),
                           per_task=per_task)))
    order = lambda item: (["ppo", "es"].index(item[0]) if item[0] in ("ppo", "es") else 2, item[1])  # noqa: E731
    return {name: entry for _, _, name, entry in sorted(found, key=order)}


def history_seeds(run_dir: str | None, names) -> tuple[list[int], np.ndarray] | None:
    """A run's seeds and the columns ``names`` of its history.csv as (generations, seeds, names) (NaN where a seed has
    not written a generation); None without the file or any row."""
    path = os.path.join(run_dir or "", "history.csv")
    if not os.path.isfile(path):
        return None
    with open(path) as f:
        rows = list(csv.DictReader(f))
    if not rows:
        return None
    seeds = sorted({int(r["seed"]) for r in rows})
    values = np.full((max(int(r["generation"]) for r in rows) + 1, len(seeds), len(names)), np.nan)
    for r in rows:
        values[int(r["generation"]), seeds.index(int(r["seed"]))] = [float(r[n]) for n in names]
    return seeds, values


def history_columns(run_dir: str | None, names) -> np.ndarray | None:
    """The columns ``names`` of a run's history.csv as (generations, seeds, names); None without any row."""
    history = history_seeds(run_dir, names)
    return None if history is None else history[1]
