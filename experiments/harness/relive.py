"""Reliving for the reports: the best individuals' lives, fresh lives and probes (:mod:`imrl_jax.analysis.relive`)
kept beside their runs, and what reliving costs, said before it begins, then its progress."""

from __future__ import annotations

import hashlib
import json
import os
import sys
import time
from typing import NamedTuple

import numpy as np

from experiments.harness.loading import best_of_population, read_json, write_json
from experiments.harness import study
from imrl_jax.analysis.relive import FRESH_LIVES, FRESH_SEED, PATH_STEPS, followed_best, fresh_fitness, relive_best

#: Where :func:`run_fresh` keeps an evolution's fresh lives, beside its final population.
FRESH_FILE = "fresh.json"


def fresh_key(best: dict, config_dict: dict, num_lives: int = FRESH_LIVES, seed: int = FRESH_SEED) -> dict:
    """What :func:`run_fresh`'s kept lives depend on: the generation, seeds, genomes, config, lives and key."""
    genomes = np.ascontiguousarray(np.asarray(best["genomes"])[:, 0], np.float32)
    return dict(generations=int(best["generations"]), seeds=[int(s) for s in best["seeds"]], num_lives=num_lives,
                seed=seed, genomes_sha256=hashlib.sha256(genomes.tobytes()).hexdigest(),
                config_sha256=hashlib.sha256(json.dumps(config_dict, sort_keys=True).encode()).hexdigest())


def last_generation(run_dir: str, num_best: int = 1) -> dict | None:
    """Each seed's ``num_best`` fittest of an evolution's last evaluated generation (None without a population)."""
    population = os.path.join(run_dir, "final_population.npz")
    return best_of_population(population, num_best) if os.path.isfile(population) else None


def kept(path: str, key: dict, compute, stream=None) -> dict:
    """``compute()``'s numbers with ``key``, kept in ``path``: read back while ``key`` is the same (and said so on
    ``stream``, stderr by default: nothing to live, nothing to estimate), else computed again and written whole (a
    killed report leaves no half file)."""
    cached = read_json(path)
    if cached is not None and all(cached.get(k) == v for k, v in key.items()):
        print(f"kept in {path}: lived by an earlier report for the same generation, genomes and config; not lived "
              f"again", file=stream or sys.stderr, flush=True)
        return cached
    out = dict(key, **compute())
    write_json(path, out, indent=2)
    return out


def run_config(run_dir: str, config_dict: dict | None = None) -> dict:
    """An evolution's config as its config.json holds it (``config_dict`` when given)."""
    return config_dict if config_dict is not None else (read_json(os.path.join(run_dir, "config.json")) or {})["config"]


def run_fresh(run_dir: str, config_dict: dict | None = None, num_lives: int = FRESH_LIVES,
              seed: int = FRESH_SEED) -> dict | None:
    """Fresh lives of each seed's best genome of an evolution's last generation (its final_population.npz).

    Kept in ``run_dir/fresh.json`` and lived again only when what they depend on changed
    (:func:`fresh_key`: another generation, seeds, genomes, config, lives or key); None without a
    population. Returns the mean per seed,
    their mean and sd over seeds (ddof 1), and each genome's sd over its lives.
    """
    best = last_generation(run_dir)
    if best is None:
        return None
    config_dict = run_config(run_dir, config_dict)

    def live():
        part = fresh_part(run_dir, config_dict, len(best["seeds"]), num_lives)
        lives = relived(part, fresh_fitness, config_dict, best, num_lives, seed)
        means = [float(v) for v in lives["mean"]]
        return dict(mean_per_seed=means, sd_per_seed=[float(v) for v in lives["sd"]], mean=float(np.mean(means)),
                    sd_over_seeds=float(np.std(means, ddof=1)) if len(means) > 1 else 0.0)

    return kept(os.path.join(run_dir, FRESH_FILE), fresh_key(best, config_dict, num_lives, seed), live)


#: Where :func:`run_probe` keeps the junction probe of an evolution's best genomes, beside its final population.
PROBE_FILE = "probe.json"


def run_probe(run_dir: str, config_dict: dict | None = None, num_best: int = 10, key: int = 0) -> dict | None:
    """The colour each expert follows (:func:`followed_best`) for each seed's ``num_best`` fittest genomes of an
    evolution's last generation, as ``followed`` (seeds x best, in order).

    Kept in ``run_dir/probe.json`` and probed again only when what it depends on changed (:func:`fresh_key`
    with ``num_best`` and ``key`` for the lives and their key); None without a population.
    """
    best = last_generation(run_dir, num_best)
    if best is None:
        return None
    config_dict = run_config(run_dir, config_dict)

    def probe():
        part = probe_part(run_dir, config_dict, int(np.prod(np.asarray(best["genomes"]).shape[:2])))
        return dict(followed=relived(part, followed_best, config_dict, best, key))

    return kept(os.path.join(run_dir, PROBE_FILE), fresh_key(best, config_dict, num_lives=num_best, seed=key), probe)


#: Where :func:`run_path` keeps the path probe of an evolution's fittest genome, beside its final population.
PATH_FILE = "path.json"


def run_path(run_dir: str, config_dict: dict | None = None) -> dict | None:
    """The fittest genome of an evolution's last generation relived (:func:`relive_best`): claim 4's path probe.

    Returns its stereotypy per task, speed, seed, recorded and relived fitness; kept in ``run_dir/path.json``
    and relived again only when what it depends on changed (:func:`fresh_key`); None without a population.
    """
    best = last_generation(run_dir)
    if best is None:
        return None
    config_dict = run_config(run_dir, config_dict)

    def path():
        life = relived(life_part(run_dir, config_dict), relive_best, config_dict, best)
        return dict(stereotypy_per_task=[float(v) for v in life["stereotypy_per_task"]], speed=float(life["speed"]),
                    best_seed=life["seed"], fitness=life["fitness"], relived_fitness=life["relived_fitness"])

    return kept(os.path.join(run_dir, PATH_FILE), fresh_key(best, config_dict, num_lives=1, seed=0), path)


def reproduction_fresh(summary: dict, variant: str, condition: str) -> dict | None:
    """The reproduction report's fresh lives of a run (docs/reproduction/summary.json), in :func:`run_fresh`'s form."""
    entry = (summary.get("best_individuals") or {}).get(f"{variant}/{condition}") or {}
    means = entry.get("fresh_mean_per_seed")
    if not means:
        return None
    return dict(mean_per_seed=[float(v) for v in means], mean=float(np.mean(means)),
                sd_over_seeds=float(np.std(means, ddof=1)) if len(means) > 1 else 0.0,
                num_lives=int(entry.get("fresh_lives", FRESH_LIVES)))


# ----------------------------------------------------------------------------- what reliving costs, said first

#: Steps a probe drives each expert: :func:`imrl_jax.analysis.behaviour.specialisation`'s 3 x 8 starts of 100 steps.
PROBE_STEPS = 3 * 8 * 100


class Part(NamedTuple):
    """One call of a report's reliving: what it lives, in lives of its run's length, and in lane-steps."""

    what: str
    lives: int
    lane_steps: int
    compiles: int = 1  # programs it compiles (each several seconds on a CPU)


def _config(config_dict: dict):
    """A run's Config, or None where its dict is none (the made-up configs of tests: nothing to count)."""
    from imrl_jax.config import Config, ConfigError

    try:
        return Config.from_dict(config_dict)
    except (ConfigError, TypeError):
        return None


def life_part(name: str, config_dict: dict) -> Part:
    """:func:`relive_best` of a run: its best individual's life, each task driven after it, its childhood drawn."""
    config = _config(config_dict)
    if config is None:
        return Part(f"{name}: the best individual's life", 1, 0)
    child = config.childhood_steps if config.spec.has_childhood else 0
    return Part(f"{name}: the best individual's life, then {config.num_tasks} tasks driven", 1,
                config.lifetime_steps + config.num_tasks * PATH_STEPS + child, 3 if child else 2)


def fresh_part(name: str, config_dict: dict, seeds: int, num_lives: int = FRESH_LIVES) -> Part:
    """:func:`fresh_fitness` of a run: ``num_lives`` fresh lives of each of ``seeds`` genomes."""
    config = _config(config_dict)
    return Part(f"{name}: {num_lives} fresh lives of each of {seeds} seeds' best", seeds * num_lives,
                0 if config is None else seeds * num_lives * config.lifetime_steps)


def probe_part(name: str, config_dict: dict, individuals: int) -> Part:
    """:func:`followed_best` of a run's ``individuals`` genomes: a fresh childhood each (LE-LS), each expert driven."""
    config = _config(config_dict)
    child = 0 if config is None or not config.spec.has_childhood else config.childhood_steps
    steps = 0 if config is None else individuals * (child + config.num_experts * PROBE_STEPS)
    return Part(f"{name}: the experts of {individuals} best individuals probed"
                + (" after a fresh childhood each" if child else ""),
                1 if config is None else max(1, round(steps / config.lifetime_steps)), steps, 2 if child else 1)


def relive_parts(variant: str, condition: str, entry: dict) -> list[Part]:
    """What the reproduction report lives for one evolution's best genomes (``entry``: update_best_genomes's):
    the best one's life and its tasks driven, each seed's fresh lives, and for a learner the probe of its experts."""
    from imrl_jax import conditions

    seeds, num_best = np.asarray(entry["genomes"]).shape[:2]
    config = _config(entry["config"])
    name = f"{condition} ({variant}" + ("" if config is None else f", lives of {config.lifetime_steps:,} steps") + ")"
    parts = [life_part(name, entry["config"]), fresh_part(name, entry["config"], seeds)]
    if conditions.get(condition).learns:
        parts.append(probe_part(name, entry["config"], seeds * num_best))
    return parts


def relived(part: Part, fn, *args):
    """``fn(*args)`` as a report's one part of reliving: said with its cost first (:class:`Reliving`)."""
    return Reliving([part]).run(part, fn, *args)


def compile_seconds(source: str) -> float | None:
    """The median seconds the benchmark file ``source`` (docs/bench/NAME.json) took to compile a whole life."""
    data = read_json(os.path.join(study.ROOT, source)) if not os.path.isabs(source) else read_json(source)
    times = sorted(float(life.get("compile_and_first_run_s", 0)) for life in (data or {}).get("lifetimes", ()))
    return times[len(times) // 2] if times and times[len(times) // 2] > 0 else None


def plan_line(parts: list[Part], backend: str, bench_dir: str | None = None) -> str:
    """What reliving ``parts`` will cost, in one line: lives and lane-steps on ``backend``, and its time at the
    speed and compile time the benchmark measured there (the largest part's number of lives), if it did."""
    from imrl_jax.runs.progress import _amount, clock, measured_speed

    lives, lane_steps = sum(p.lives for p in parts), sum(p.lane_steps for p in parts)
    line = (f"reliving the best individuals: {len(parts)} part(s), {lives:,} lives' worth, "
            f"{_amount(lane_steps)} lane-steps on {backend}")
    speed = measured_speed(backend, max(parts, key=lambda p: p.lane_steps).lives, bench_dir)
    if speed is None:
        return line + f"; no speed measured on {backend} in docs/bench to estimate its time (an ETA follows part 2)"
    rate, source = speed
    compiled = compile_seconds(os.path.join(bench_dir, os.path.basename(source)) if bench_dir else source)
    compiles = sum(p.compiles for p in parts)
    seconds = lane_steps / rate + compiles * (compiled or 0)
    return line + (f"; about {clock(seconds)} (ETA) at the {rate / 1e6:.1f} M lane-steps/s {source} measured on "
                   f"{backend}" + (f" and {compiles} compilations of {compiled:.0f} s" if compiled else
                                   ", compilation aside"))


class Reliving:
    """A report's reliving said before it costs: :func:`plan_line` at once, a line as each part starts compiling,
    a progress line with an ETA as each ends (:class:`imrl_jax.runs.progress.Progress`: on stderr, its unit a life)."""

    def __init__(self, parts: list[Part], stream=None, backend: str | None = None, bench_dir: str | None = None,
                 log=None):
        from imrl_jax.runs.progress import Progress

        if backend is None:
            import jax

            backend = jax.default_backend()
        self.done, self.count, self.parts = 0, 0, len(parts)
        self.progress = Progress(max(1, sum(p.lives for p in parts)), unit="life", stream=stream, log=log)
        self.progress.note(plan_line(parts, backend, bench_dir) if parts else "reliving nobody")

    def run(self, part: Part, fn, *args):
        """``fn(*args)``, announced as ``part`` and counted when it returns."""
        self.count += 1
        self.progress.note(f"part {self.count}/{self.parts}, {part.what}: compiling, then "
                           f"{part.lane_steps:,} lane-steps")
        start = time.perf_counter()
        out = fn(*args)
        seconds = max(time.perf_counter() - start, 1e-9)
        self.done += part.lives
        self.progress.update(self.done, 0.0, 0.0, part.lane_steps / seconds,
                             scores=f"part {self.count}/{self.parts} done in {seconds:.1f} s")
        return out
