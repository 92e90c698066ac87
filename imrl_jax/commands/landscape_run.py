"""``python -m imrl_jax.landscape_run RUN --out DIR``: the landscape measures of an evolved run (docs/GOALS.md).

    python -m imrl_jax.landscape_run experiments/results/goals/EE-LS-T/evolve --out DIR --cut 0

For one seed of an evolution (``--seed``, default its first), at each of ``--generations`` (default
``0,10,last``; ``last`` is the last generation the run has evaluated) the generation's parents (its
``--parents`` best by their recorded fitness; at generation 0 the first of the random population, which
has none) are measured with :mod:`imrl_jax.evolution.landscape`: the effects of ``--mutants`` mutations of each
under the paper's operator and their evolvability, and the autocorrelation along ``--walks`` random
mutation walks of ``--walk-length`` steps from the best of them; once, the fitness of ``--random``
random genomes (generation 0's draw). Every genome lives ``--lives`` fresh lives. Each ``--cut F``
measures the same genomes again with learning cut to ``F`` (:func:`imrl_jax.evolution.landscape.learning_cut`;
H3), with the same keys (common random numbers).

A generation's population comes from the run: generation 0 is drawn again from the seed; the last
evaluated from ``final_population.npz`` (or, ``--best-genomes FILE``, a report's kept best); any other is
replayed (``DIR/landscape_replay``, an evolve run of the one seed: bitwise the run's, which ``result.json``
checks against the run's history). A run killed before its last generation (or still running) is refused
unless ``--allow-unfinished``; a generation it has not reached, always. Everything is checked before
anything is written (:func:`plan`); ``--out`` is apart from the run and holds nothing but this command's
files. ``DIR/landscape.json`` is rewritten (atomically) after every piece and a run killed goes on from
it; ``DIR/result.json`` is written last; both state the generations measured and the run's done.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import sys
import time
import warnings
from typing import Callable

import jax
import jax.numpy as jnp
import numpy as np

from imrl_jax.runs import cli
from imrl_jax.evolution import landscape as ls
from imrl_jax.runs.cli import HelpFormatter, Parser, UsageError, exit_codes
from imrl_jax.config import Config
from imrl_jax.evolution.ga import init_population
from imrl_jax.runs.run_state import generations_recorded
from imrl_jax.runs.rundir import (Run, RunDirError, best_genomes as best_of, check_unlocked, check_writable, entries,
                             is_output, load_run, lock_run_dir, make_dir, not_empty, read_config, read_json,
                             read_kept_best, unfinished, write_atomic)

#: What ``landscape.json`` records per piece: the summary numbers of each measure.
RESULT = "result.json"
PROGRESS = "landscape.json"
#: Where a generation is replayed (not a run of a study: runspec.run_dirs passes over it).
REPLAY = "landscape_replay"
#: The lives of one call at most (every measure, cut and generation): far past any measure that ends this decade.
MAX_TOTAL_LIVES = 10**8
#: The measures' key is 32 bits: ``jax.random.key`` wraps a larger one onto a smaller without a word.
#: Host copies of each genome measured (the padded chunks, the device's copy, the mutants kept): the estimate's factor.
HOST_COPIES = 4
#: The largest history.csv read (a million generation-seed rows is about 100 MB).
MAX_HISTORY_BYTES = 2**28
#: The longest name of a path's part (most file systems').
MAX_NAME_BYTES = 255


def check_path(value: str | None, flag: str) -> None:
    """Raise UsageError naming ``flag`` unless ``value`` (None: not given) is a usable path: not empty, no NUL, no
    name over :data:`MAX_NAME_BYTES` bytes (each would fail, or mean the current directory, only when written)."""
    if value is None:
        return
    if not value.strip():
        raise UsageError(f"{flag}: empty path")
    if "\x00" in value:
        raise UsageError(f"{flag}: {value!r} is not a path (it holds a NUL character)")
    if any(len(os.fsencode(part)) > MAX_NAME_BYTES for part in value.split(os.sep)):
        raise UsageError(f"{flag}: {value[:40]}...: a name longer than {MAX_NAME_BYTES} bytes")


def parse_cuts(text: str) -> tuple[float, ...]:
    """``--cut 0,0.33`` as fractions, each once (-0 is 0); "" none (raises UsageError naming the option)."""
    if not text.strip():
        return ()
    cuts = []
    for item in text.split(","):
        if not item.strip():
            raise UsageError(f"--cut: an empty item in {text!r} (give fractions separated by commas)")
        try:
            cuts.append(float(item) + 0.0)  # + 0.0: -0 is 0, one piece
        except ValueError:
            raise UsageError(f"--cut: expected fractions separated by commas (got {text!r})") from None
    return tuple(dict.fromkeys(cuts))


def parse_generations(text: str, num_generations: int, done: int | None = None) -> list[int]:
    """``0,10,last`` as generation indices, ``last`` the last of the ``done`` the run has evaluated (None: all of
    its ``num_generations``); one not reached is refused (raises UsageError naming the option)."""
    done = num_generations if done is None else done
    found = []
    for item in text.split(","):
        item = item.strip()
        try:
            g = done - 1 if item == "last" else int(item)
        except ValueError:
            raise UsageError(f"--generations: expected integers or 'last', separated by commas "
                             f"(got {text!r})") from None
        if not 0 <= g < num_generations:
            raise UsageError(f"--generations: {g} is not a generation of the run (0..{num_generations - 1})")
        if g >= done:
            raise UsageError(f"--generations: {g} is past the {done} generation(s) the run has evaluated "
                             f"(0..{done - 1} of its {num_generations}): it was never reached")
        found.append(g)
    return sorted(set(found))


def _finite_numbers(path: str, what: str, array: np.ndarray) -> None:
    if array.dtype.kind not in "fiu":
        raise RunDirError(f"{path}: {what} are not numbers ({array.dtype})")
    if not np.isfinite(array).all():
        raise RunDirError(f"{path}: {what} hold NaN or infinite values (a damaged file)")


def final_population(run_dir: str, config: Config) -> Run | None:
    """The run's ``final_population.npz``, checked (finite, of the config's population and genes), or None if the
    run kept none (raises RunDirError naming the file)."""
    path = os.path.join(run_dir, "final_population.npz")
    if not os.path.isfile(path):
        return None
    try:
        run = load_run(run_dir)
    except (TypeError, IndexError) as error:  # a "generation" that is not one number
        raise RunDirError(f"{path} is unreadable ({error})") from None
    want = (len(run.seeds), config.population_size, config.num_genes)
    if run.evaluated.shape != want:
        raise RunDirError(f"{path}: genomes of shape {run.evaluated.shape}, the run's config.json says {want} "
                          f"(seeds, population, genes)")
    _finite_numbers(path, "the fitness", run.fitness)
    _finite_numbers(path, "the genomes", run.evaluated)
    if run.generation > config.num_generations:
        raise RunDirError(f"{path}: generation {run.generation} of a run of {config.num_generations}")
    return run


def kept_best(run_dir: str, path: str, config: Config, seed: int, num_parents: int) -> np.ndarray:
    """The ``num_parents`` best of ``seed`` that a report's ``best_genomes.npz`` keeps, checked (raises a user error
    naming ``--best-genomes``); its key is the run's ``VARIANT/evolve/CONDITION`` path."""
    variant = os.path.basename(os.path.dirname(os.path.dirname(os.path.abspath(run_dir))))
    try:
        genomes, seeds, fitness = read_kept_best(path, variant, config.condition)
    except (TypeError, OverflowError, ValueError) as error:  # seeds that are not integers
        if isinstance(error, RunDirError):
            raise
        raise RunDirError(f"--best-genomes: {path} is unreadable ({error})") from None
    where = f"--best-genomes: {path}: {variant}__{config.condition}"
    if genomes.ndim != 3 or genomes.shape[0] != len(seeds) or genomes.shape[-1] != config.num_genes:
        raise RunDirError(f"{where}: genomes of shape {genomes.shape}, not (its {len(seeds)} seeds, best, the run's "
                          f"{config.num_genes} genes)")
    _finite_numbers(path, f"--best-genomes: {variant}__{config.condition}'s genomes", genomes)
    if fitness is not None:
        _finite_numbers(path, f"--best-genomes: {variant}__{config.condition}'s fitness", fitness)
    if seed not in seeds:
        raise RunDirError(f"{where}: keeps no seed {seed} (it keeps {', '.join(map(str, seeds))})")
    if num_parents > genomes.shape[1]:
        raise UsageError(f"--parents: at most the {genomes.shape[1]} best kept in {path} (got {num_parents})")
    return genomes[seeds.index(seed), :num_parents]


def read_history(run_dir: str) -> np.ndarray:
    """(generation, seed, best) of each row of the run's ``history.csv`` (raises RunDirError naming the file)."""
    path = os.path.join(run_dir, "history.csv")
    try:
        size = os.path.getsize(path)
    except OSError as error:
        raise RunDirError(f"{path}: cannot read it ({error.strerror or error})") from None
    if size > MAX_HISTORY_BYTES:
        raise RunDirError(f"{path} is larger than the limit of {MAX_HISTORY_BYTES:,} bytes (is it the right file?)")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # numpy's "no data" warning: an empty history is refused below
            rows = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)  # every column: a row cut short is refused
    except (OSError, ValueError, IndexError, UnicodeDecodeError) as error:
        reason = str(error).splitlines()[0] if str(error) else type(error).__name__
        raise RunDirError(f"{path} is unreadable ({reason})") from None
    with open(path, "rb") as f:
        header = f.readline(1 << 16).decode("utf-8", "replace").strip().split(",")
    if header[:3] != ["generation", "seed", "best"] or rows.ndim != 2 or rows.shape[1] != len(header) or \
            not np.isfinite(rows[:, :2]).all():  # a row cut short, too (a history written as it ran, then damaged)
        raise RunDirError(f"{path} is unreadable (not rows of its header's {len(header)} columns, generation, seed, "
                          f"best first)")
    return rows[:, :3]


def generations_in_history(run_dir: str, seed: int) -> int:
    """The generations of ``seed`` the run's history.csv records (raises RunDirError naming it if none)."""
    rows = read_history(run_dir)
    found = rows[rows[:, 1] == seed, 0]
    if not len(found):
        raise RunDirError(f"{os.path.join(run_dir, 'history.csv')}: no generation of seed {seed} recorded")
    return int(found.max()) + 1


def parents_at(run_dir: str, config: Config, seeds: list[int], seed: int, generation: int, num_parents: int,
               out_dir: str, best_genomes: str | None, done: int | None = None) -> tuple[np.ndarray, dict]:
    """The ``num_parents`` best of ``seed``'s generation (fittest first) and where they came from; ``done``: the
    generations the run has evaluated (None: all of its config's)."""
    from imrl_jax.commands import evolve

    done = config.num_generations if done is None else done
    if generation == 0:  # the seed's own draw, as evolve.initial_state makes it
        population = init_population(jax.random.fold_in(evolve.seed_keys([seed])[0], 0), config)
        return np.asarray(population)[:num_parents], {"source": "generation 0 drawn again from the seed"}
    index = seeds.index(seed)
    if generation == done - 1:
        if best_genomes:
            return kept_best(run_dir, best_genomes, config, seed, num_parents), \
                {"source": f"the best kept in {best_genomes}"}
        run = final_population(run_dir, config)
        if run is not None and run.generation == done:
            return best_of(run, num_parents)[index], {"source": "final_population.npz"}
    replay = os.path.join(out_dir, REPLAY)
    if generations_recorded(replay) > generation + 1:  # replayed further for a later generation: replay this one apart
        replay = os.path.join(out_dir, f"{REPLAY}-{generation}")
    resume = os.path.isfile(os.path.join(replay, "config.json"))  # a replay killed goes on from its checkpoint
    evolve.run(config.replace(num_generations=generation + 1), replay, [seed], resume=resume, quiet=True)
    run = load_run(replay)
    recorded = read_history(run_dir)
    row = recorded[(recorded[:, 0] == generation) & (recorded[:, 1] == seed)]
    matches = bool(len(row)) and f"{float(run.fitness.max()):.6f}" == f"{float(row[0, 2]):.6f}"
    order = np.argsort(-run.fitness[0], kind="stable")[:num_parents]
    return run.evaluated[0, order], {"source": f"replayed in {replay}", "replay_matches_run": matches}


def _is_ours(name: str) -> bool:
    """Whether an entry of ``--out`` is this command's: its two records, a replay."""
    return is_output(name, (PROGRESS, RESULT)) or name == REPLAY or \
        (name.startswith(f"{REPLAY}-") and name[len(REPLAY) + 1:].isdigit())


def read_record(path: str, identity: dict) -> dict:
    """The measures ``path`` (landscape.json or result.json) records, if it exists ({} if not), checked to be of
    ``identity`` (raises a user error naming the file, and what differs)."""
    if not os.path.lexists(path):
        return {}
    record = read_json(path, "--out")
    pieces = record.get("pieces") if isinstance(record, dict) else None
    if not isinstance(record.get("identity") if isinstance(record, dict) else None, dict) or \
            not isinstance(pieces, dict) or not all(isinstance(p, dict) for p in pieces.values()):
        raise RunDirError(f"--out: {path} is not a record of landscape measures (no identity or pieces): damaged? "
                          f"remove it to measure again, or choose another --out")
    there = record["identity"]
    differs = [f"{k} {there.get(k)!r} there, {identity.get(k)!r} here" for k in dict.fromkeys([*identity, *there])
               if there.get(k) != identity.get(k)]
    if differs:
        raise UsageError(f"--out: {os.path.dirname(path) or '.'} holds measures of other settings ({path}: "
                         f"{'; '.join(differs)}); choose another --out")
    return record


def check_out_dir(out_dir: str, run_dir: str, identity: dict) -> dict:
    """The measures ``--out`` holds to go on from ({} if none); refuses (a user error naming ``--out``) a folder of
    the run or holding it, one holding anything else, one another process writes, records of other settings."""
    real_out, real_run = os.path.realpath(out_dir), os.path.realpath(run_dir)
    if os.path.commonpath([real_out, real_run]) == real_run:
        where = "the run's own folder" if real_out == real_run else f"inside the run {run_dir}"
        raise RunDirError(f"--out: {out_dir} is {where}; choose a folder apart from the run")
    if os.path.commonpath([real_out, real_run]) == real_out:
        raise RunDirError(f"--out: {out_dir} holds the run {run_dir}; choose a folder apart from the run")
    check_writable(out_dir)
    others = [name for name in entries(out_dir) if not _is_ours(name)]
    if others:
        raise not_empty(out_dir, "landscape measures", others, PROGRESS)
    check_unlocked(out_dir)
    record = read_record(os.path.join(out_dir, PROGRESS), identity)
    read_record(os.path.join(out_dir, RESULT), identity)  # written last: of the same measures, or refused
    return record


def check_sizes(config: Config, generations: int, cuts: int, *, lives: int, num_parents: int, num_mutants: int,
                num_walks: int, walk_length: int, num_random: int, key: int, chunk: int) -> tuple[int, int]:
    """Every size bounded (raises UsageError naming the option); the genomes measured and the lives at once."""
    for name, value, low in (("--lives", lives, 2), ("--parents", num_parents, 1), ("--mutants", num_mutants, 2),
                             ("--walks", num_walks, 1), ("--walk-length", walk_length, 2), ("--random", num_random, 2),
                             ("--chunk", chunk, 1), ("--key", key, 0)):
        if value < low:
            raise UsageError(f"{name}: must be at least {low} (got {value})")
    cli.check_key("--key", key)
    if num_parents > config.population_size:
        raise UsageError(f"--parents: at most the population size ({config.population_size}; got {num_parents})")
    if num_walks > num_parents:
        raise UsageError(f"--walks: at most --parents ({num_parents}; got {num_walks}): the walks start from them")
    lanes = chunk * lives
    if lanes > cli.MAX_LANES:
        raise UsageError(f"--chunk x --lives: {chunk:,} x {lives:,} = {lanes:,} lives at once, above the limit of "
                         f"{cli.MAX_LANES:,}")
    genomes = num_random + generations * (num_parents * (1 + num_mutants) + num_walks * (walk_length + 1))
    total = lives * genomes * (1 + cuts)
    if total > MAX_TOTAL_LIVES:
        raise UsageError(f"--lives x (--random + generations x (--parents x (1 + --mutants) + --walks x "
                         f"(1 + --walk-length))) x cuts: {total:,} lives in all, above the limit of "
                         f"{MAX_TOTAL_LIVES:,}")
    return genomes, lanes


@dataclasses.dataclass(frozen=True)
class Measures:
    """What a call measures, all checked: the run and its generations, the sizes, the ``--out`` to go on from."""

    run_dir: str
    out_dir: str
    config: Config
    seeds: list[int]
    seed: int
    generations: list[int]  # the generations measured, each one the run has evaluated
    done: int  # the generations the run has evaluated
    why_unfinished: str  # "" for a finished run
    cut_configs: dict
    identity: dict
    sizes: dict  # lives, num_parents, num_mutants, num_walks, walk_length, num_random, key, chunk
    best_genomes: str | None
    log: Callable[[str], None]
    cost: str = ""  # what the measures cost (lives, lane-steps, time at the benchmark's speed, memory), said first

    def execute(self) -> int:
        """Measure (:meth:`measure`); the exit code."""
        self.measure()
        return 0

    def measure(self) -> dict:
        """Take ``--out``'s lock, check it again, measure each piece not yet measured; what result.json holds."""
        make_dir(self.out_dir)
        with lock_run_dir(self.out_dir):
            previous = check_out_dir(self.out_dir, self.run_dir, self.identity)  # again: another may have written
            return self._measure(previous.get("pieces", {}))

    def _measure(self, pieces: dict) -> dict:
        config, s = self.config, self.sizes
        self.log(self.cost + ("; the pieces measured before are not measured again" if pieces else ""))
        progress_path = os.path.join(self.out_dir, PROGRESS)
        before = {p["generation"] for p in pieces.values() if isinstance(p.get("generation"), int)}
        done = {"identity": self.identity, "run": self.run_dir, "condition": config.condition,
                "generations": sorted(before | set(self.generations)), "generations_done": self.done,
                "num_generations": config.num_generations, "unfinished": self.why_unfinished, "pieces": pieces}
        fitness = {"learning": ls.fitness_in_chunks(ls.lives_fitness(config, None, s["lives"]), s["chunk"])}
        fitness.update({name: ls.fitness_in_chunks(ls.lives_fitness(cut, None, s["lives"]), s["chunk"])
                        for name, cut in self.cut_configs.items()})
        root = jax.random.key(s["key"])

        def save(name: str, value: dict) -> None:
            done["pieces"][name] = value
            write_atomic(progress_path, json.dumps(done, indent=1).encode())

        for learning, fn in fitness.items():
            name = f"random genomes, {learning}"
            if name not in done["pieces"]:
                start = time.perf_counter()
                r = ls.random_fitness(jax.random.fold_in(root, 0), fn, config, s["num_random"])
                save(name, dict(mean=float(r.mean), std=float(r.std), noise_variance=float(r.noise_variance),
                                quantiles=[float(q) for q in r.quantiles], share_zero=float(r.share_zero),
                                fitness=[round(float(f), 6) for f in r.fitness],
                                seconds=round(time.perf_counter() - start, 1)))
                self.log(f"{config.condition} {name}: mean {float(r.mean):.4f}, sd {float(r.std):.4f}, at 0 "
                         f"{float(r.share_zero):.0%} ({time.perf_counter() - start:.0f} s)")
        for g in self.generations:
            parents, source = None, None
            for learning, fn in fitness.items():
                name = f"generation {g}, {learning}"
                if name in done["pieces"]:
                    continue
                if parents is None:
                    parents, source = parents_at(self.run_dir, config, self.seeds, self.seed, g, s["num_parents"],
                                                 self.out_dir, self.best_genomes, self.done)
                start = time.perf_counter()
                k_effects, k_walks = jax.random.split(jax.random.fold_in(root, 1 + g))
                effects = ls.mutation_effects(k_effects, fn, config, jnp.asarray(parents), s["num_mutants"])
                walks = ls.random_walks(k_walks, fn, config, jnp.asarray(parents[:s["num_walks"]]), s["walk_length"])
                rugged = ls.ruggedness(walks, max_lag=min(5, s["walk_length"]))
                piece = dict(generation=g, learning=learning, **source, **ls.summary(effects, rugged),
                             seconds=round(time.perf_counter() - start, 1))
                save(name, piece)
                self.log(f"{config.condition} {name}: parents {piece['parent_mean']:.4f}, mutants neutral "
                         f"{piece['share_neutral']:.0%} deleterious {piece['share_deleterious']:.0%} beneficial "
                         f"{piece['share_beneficial']:.0%}; rho(1) {piece['rho'][0]} ({piece['seconds']:.0f} s)")
        write_atomic(progress_path, json.dumps(done, indent=1).encode())  # its generations, even with no piece new
        write_atomic(os.path.join(self.out_dir, RESULT), json.dumps(done, indent=1).encode())
        return done


def plan(run_dir: str, out_dir: str, *, generations: str = "0,10,last", seed: int | None = None, lives: int = 4,
         num_parents: int = 10, num_mutants: int = 9, num_walks: int = 5, walk_length: int = 9, num_random: int = 50,
         cuts: tuple[float, ...] = (), key: int = 0, chunk: int = 50, best_genomes: str | None = None,
         allow_unfinished: bool = False, log=print) -> Measures:
    """Everything a call will measure, read and checked, nothing written (raises a user error at the first wrong)."""
    from imrl_jax.evolution.devices import check_memory, memory_needed
    from imrl_jax.runs.progress import cost_line
    from imrl_jax.runs.run_state import read_search
    from imrl_jax.runs.runspec import RunSpec
    from imrl_jax.evolution.strategies import GA_RECORD

    check_path(run_dir, "run")
    check_path(out_dir, "--out")
    check_path(best_genomes, "--best-genomes")
    if not os.path.isfile(os.path.join(run_dir, "config.json")):
        raise RunDirError(f"{run_dir}: no config.json (give an evolution's run directory)")
    config, seeds = read_config(run_dir)
    if read_search(run_dir) != GA_RECORD:  # generation 0 and the replays are the GA's
        raise UsageError(f"run: {run_dir} was evolved with {read_search(run_dir)['strategy']}; the landscape measures "
                         f"take their parents and mutations from the paper's GA")
    seed = seeds[0] if seed is None else seed
    if seed not in seeds:
        raise UsageError(f"--seed: {seed} is not a seed of {run_dir} ({', '.join(map(str, seeds))})")
    sizes = dict(lives=lives, num_parents=num_parents, num_mutants=num_mutants, num_walks=num_walks,
                 walk_length=walk_length, num_random=num_random, key=key, chunk=chunk)
    check_sizes(config, 1, 0, **sizes)  # each size alone first, so that a wrong one is named before any file
    cut_configs = {}
    for fraction in cuts:
        try:
            cut_configs[f"cut {fraction + 0.0:g}"] = ls.learning_cut(config, fraction)
        except ValueError as error:
            raise UsageError(f"--cut: {error}") from None
    run = final_population(run_dir, config)
    if best_genomes:
        kept_best(run_dir, best_genomes, config, seed, num_parents)
    done = run.generation if run is not None else generations_in_history(run_dir, seed)
    why = unfinished(run_dir, Run(config, seeds, done, None, None))
    if why and not allow_unfinished:
        raise UsageError(f"run: {why}: its evolution is unfinished (pass --allow-unfinished to measure the generations "
                         f"it has evaluated, 0..{done - 1})")
    wanted = parse_generations(generations, config.num_generations, done)
    last_kept = best_genomes or run is not None
    if any(0 < g and not (g == done - 1 and last_kept) for g in wanted):
        read_history(run_dir)  # a replay checks its best against the run's
    genomes, lanes = check_sizes(config, len(wanted), len(cut_configs), **sizes)
    if any(0 < g < done - 1 or (g == done - 1 and not last_kept) for g in wanted):
        lanes = max(lanes, config.population_size * config.lives_per_fitness)  # a replay's generation
    host = HOST_COPIES * genomes * 4 * (config.num_genes + 2) * (1 + len(cut_configs))
    cost = cost_line(f"measuring generation(s) {', '.join(map(str, wanted))} of seed {seed}", lives * genomes
                     * (1 + len(cut_configs)), lives * genomes * (1 + len(cut_configs)) * config.lifetime_steps, 1,
                     jax.default_backend(), memory_needed(config, lanes, jax.device_count(), host), unit="call",
                     world=config.world)
    try:
        check_memory(config, lanes, "the landscape measures", host_bytes=host)
    except UsageError as error:  # its advice is an evolution's: say this command's sizes instead
        raise UsageError(f"{str(error).split('; use ')[0]}; use a smaller --chunk, fewer --lives or fewer genomes "
                         f"(--parents, --mutants, --walks, --walk-length, --random)") from None
    identity = dict(run_key=RunSpec.from_run_dir(run_dir).key(),
                    best_genomes=None if best_genomes is None else os.path.basename(best_genomes), seed=seed,
                    lives=lives, parents=num_parents, mutants=num_mutants, walks=num_walks, walk_length=walk_length,
                    random=num_random, key=key, chunk=chunk)
    check_out_dir(out_dir, run_dir, identity)
    if why:
        print(f"warning: {why}: measuring generation(s) {', '.join(map(str, wanted))} of the {done} it has evaluated "
              f"(landscape.json records it)", file=sys.stderr, flush=True)
    return Measures(run_dir, out_dir, config, seeds, seed, wanted, done, why, cut_configs, identity, sizes,
                    best_genomes, log, cost)


def run(run_dir: str, out_dir: str, *, generations: str = "0,10,last", seed: int | None = None, lives: int = 4,
        num_parents: int = 10, num_mutants: int = 9, num_walks: int = 5, walk_length: int = 9, num_random: int = 50,
        cuts: tuple[float, ...] = (), key: int = 0, chunk: int = 50, best_genomes: str | None = None,
        log=print, allow_unfinished: bool = False) -> dict:
    """Measure the landscape around ``run_dir``'s seed's generations into ``out_dir``; return what result.json holds."""
    return plan(run_dir, out_dir, generations=generations, seed=seed, lives=lives, num_parents=num_parents,
                num_mutants=num_mutants, num_walks=num_walks, walk_length=walk_length, num_random=num_random,
                cuts=cuts, key=key, chunk=chunk, best_genomes=best_genomes, allow_unfinished=allow_unfinished,
                log=log).measure()


def parser() -> argparse.ArgumentParser:
    p = Parser(prog="python -m imrl_jax.landscape_run", description=__doc__.split("\n")[0],
               formatter_class=HelpFormatter)
    p.add_argument("run", help="an evolution's run directory")
    p.add_argument("--out", required=True, help="the measures' folder, apart from the run (goes on from what it holds)")
    p.add_argument("--generations", default="0,10,last",
                   help="the generations whose parents are measured (last: the last the run has evaluated)")
    p.add_argument("--allow-unfinished", action="store_true",
                   help="measure a run whose evolution has not reached its last generation (killed, or still "
                        "running): the generations it has evaluated, with a warning (result.json records them)")
    p.add_argument("--seed", type=int, help="the seed whose generations are measured (default: the run's first)")
    p.add_argument("--lives", type=int, default=4, help="fresh lives per genome")
    p.add_argument("--parents", type=int, default=10, help="the generation's best measured")
    p.add_argument("--mutants", type=int, default=9, help="mutants of each parent")
    p.add_argument("--walks", type=int, default=5, help="random mutation walks, from the best parents")
    p.add_argument("--walk-length", type=int, default=9, help="steps of each walk")
    p.add_argument("--random", type=int, default=50, help="random genomes (generation 0's draw)")
    p.add_argument("--cut", default="", help="learning cut to these fractions too (comma-separated; H3)")
    p.add_argument("--key", type=int, default=0, help=f"the measures' random key (0..{cli.MAX_KEY})")
    p.add_argument("--chunk", type=int, default=50, help="genomes lived at once (one compiled program)")
    p.add_argument("--best-genomes", metavar="FILE", help="the last generation's best from a report's "
                   "best_genomes.npz (a run whose final population was not kept)")
    cli.add_register(p)
    return p


@exit_codes  # its user errors one line, a line break the user typed shown escaped (cli.one_line)
def main(argv=None) -> int:
    args = parser().parse_args(argv)
    cli.register(args.register)  # before the run's config.json is read: its row may be one of these
    measures = plan(args.run, args.out, generations=args.generations, seed=args.seed, lives=args.lives,
                    num_parents=args.parents, num_mutants=args.mutants, num_walks=args.walks,
                    walk_length=args.walk_length, num_random=args.random, cuts=parse_cuts(args.cut), key=args.key,
                    chunk=args.chunk, best_genomes=args.best_genomes, allow_unfinished=args.allow_unfinished,
                    log=lambda text: print(text, file=sys.stderr, flush=True))
    return cli.execute(measures)


if __name__ == "__main__":
    sys.exit(main())
