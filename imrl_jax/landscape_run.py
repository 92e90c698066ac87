"""``python -m imrl_jax.landscape_run RUN --out DIR``: the landscape measures of an evolved run (docs/GOALS.md).

    python -m imrl_jax.landscape_run experiments/results/goals/EE-LS-T/evolve --out DIR --cut 0

For one seed of an evolution (``--seed``, default its first), at each of ``--generations`` (default
``0,10,last``) the generation's parents (its ``--parents`` best by their recorded fitness; at generation
0 the first of the random population, which has none) are measured with :mod:`imrl_jax.landscape`:
the effects of ``--mutants`` mutations of each under the paper's operator and their evolvability, and
the autocorrelation along ``--walks`` random mutation walks of ``--walk-length`` steps from the best
of them; once, the fitness of ``--random`` random genomes (generation 0's draw). Every genome lives
``--lives`` fresh lives. Each ``--cut F`` measures the same genomes again with learning cut to
``F`` (:func:`imrl_jax.landscape.learning_cut`; H3), with the same keys (common random numbers).

A generation's population comes from the run: generation 0 is drawn again from the seed; the last
from ``final_population.npz`` (or, ``--best-genomes FILE``, a report's kept best); any other is
replayed (``DIR/landscape_replay``, an evolve run of the one seed: bitwise the run's, which ``result.json`` checks
against the run's history). ``DIR/landscape.json`` is rewritten after every piece and a run killed goes
on from it; ``DIR/result.json`` is written last.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time

import jax
import jax.numpy as jnp
import numpy as np

from imrl_jax import landscape as ls
from imrl_jax.cli import HelpFormatter, Parser, UsageError, exit_codes
from imrl_jax.config import Config
from imrl_jax.ga import init_population
from imrl_jax.run_state import generations_recorded
from imrl_jax.rundir import (RunDirError, best_genomes as best_of, check_writable, load_kept_best, load_run, make_dir,
                             read_config, read_json, write_atomic)

#: What ``landscape.json`` records per piece: the summary numbers of each measure.
RESULT = "result.json"
PROGRESS = "landscape.json"
#: Where a generation is replayed (not a run of a study: runspec.run_dirs passes over it).
REPLAY = "landscape_replay"


def fitness_in_chunks(fitness_fn: ls.FitnessFn, size: int) -> ls.FitnessFn:
    """``fitness_fn`` applied to at most ``size`` genomes at a time (padded), so that one program serves every
    batch of a measure (chunk ``i`` lives from ``fold_in(key, i)``)."""
    def fn(key, genomes):
        genomes = np.asarray(genomes)
        n = len(genomes)
        padded = np.concatenate([genomes, np.repeat(genomes[-1:], (-n) % size, 0)])
        parts = [fitness_fn(jax.random.fold_in(key, i), padded[i * size:(i + 1) * size])
                 for i in range(len(padded) // size)]
        return ls.Estimate(*(jnp.concatenate(x)[:n] for x in zip(*parts)))

    return fn


def parse_generations(text: str, num_generations: int) -> list[int]:
    """``0,10,last`` as generation indices (raises UsageError naming the option)."""
    found = []
    for item in text.split(","):
        item = item.strip()
        try:
            g = num_generations - 1 if item == "last" else int(item)
        except ValueError:
            raise UsageError(f"--generations: expected integers or 'last', separated by commas (got {text!r})") from None
        if not 0 <= g < num_generations:
            raise UsageError(f"--generations: {g} is not a generation of the run (0..{num_generations - 1})")
        found.append(g)
    return sorted(set(found))


def parents_at(run_dir: str, config: Config, seeds: list[int], seed: int, generation: int, num_parents: int,
               out_dir: str, best_genomes: str | None) -> tuple[np.ndarray, dict]:
    """The ``num_parents`` best of ``seed``'s generation (fittest first) and where they came from."""
    from imrl_jax import evolve

    if generation == 0:  # the seed's own draw, as evolve.initial_state makes it
        population = init_population(jax.random.fold_in(evolve.seed_keys([seed])[0], 0), config)
        return np.asarray(population)[:num_parents], {"source": "generation 0 drawn again from the seed"}
    index = seeds.index(seed)
    if generation == config.num_generations - 1:
        if best_genomes:
            _, kept_seeds, genomes = load_kept_best(run_dir, best_genomes, num_parents)
            return genomes[kept_seeds.index(seed)], {"source": f"the best kept in {best_genomes}"}
        path = os.path.join(run_dir, "final_population.npz")
        if os.path.isfile(path):
            run = load_run(run_dir)
            if run.generation == config.num_generations:
                return best_of(run, num_parents)[index], {"source": "final_population.npz"}
    replay = os.path.join(out_dir, REPLAY)
    if generations_recorded(replay) > generation + 1:  # replayed further for a later generation: replay this one apart
        replay = os.path.join(out_dir, f"{REPLAY}-{generation}")
    resume = os.path.isfile(os.path.join(replay, "config.json"))  # a replay killed goes on from its checkpoint
    evolve.run(config.replace(num_generations=generation + 1), replay, [seed], resume=resume, quiet=True)
    run = load_run(replay)
    recorded = np.loadtxt(os.path.join(run_dir, "history.csv"), delimiter=",", skiprows=1, usecols=(0, 1, 2),
                          ndmin=2)
    row = recorded[(recorded[:, 0] == generation) & (recorded[:, 1] == seed)]
    matches = bool(len(row)) and f"{float(run.fitness.max()):.6f}" == f"{float(row[0, 2]):.6f}"
    order = np.argsort(-run.fitness[0], kind="stable")[:num_parents]
    return run.evaluated[0, order], {"source": f"replayed in {replay}", "replay_matches_run": matches}


def summary(effects: ls.MutationEffects, rugged: ls.Ruggedness) -> dict:
    """The numbers of one piece: mutation effects, evolvability and ruggedness."""
    evo = ls.evolvability(effects)
    value = lambda x: None if not np.isfinite(float(x)) else round(float(x), 6)  # noqa: E731
    return dict(parent_mean=value(effects.parent.mean()), mutant_mean=value(effects.mutant.mean()),
                share_neutral=value(effects.share_neutral), share_deleterious=value(effects.share_deleterious),
                share_beneficial=value(effects.share_beneficial), effect_mean=value(effects.mean),
                effect_variance=value(effects.variance), effect_noise_variance=value(effects.noise_variance),
                mutational_variance=value(evo.mean_mutational_variance), share_better=value(evo.mean_share_better),
                rho=[value(r) for r in rugged.rho], rho_noise_corrected=[value(r) for r in rugged.rho_noise_corrected],
                correlation_length=value(rugged.correlation_length),
                correlation_length_noise_corrected=value(rugged.correlation_length_noise_corrected),
                walk_variance=value(rugged.variance), walk_noise_variance=value(rugged.noise_variance))


def run(run_dir: str, out_dir: str, *, generations: str = "0,10,last", seed: int | None = None, lives: int = 4,
        num_parents: int = 10, num_mutants: int = 9, num_walks: int = 5, walk_length: int = 9, num_random: int = 50,
        cuts: tuple[float, ...] = (), key: int = 0, chunk: int = 50, best_genomes: str | None = None,
        log=print) -> dict:
    """Measure the landscape around ``run_dir``'s seed's generations into ``out_dir``; return what result.json holds."""
    config, seeds = read_config(run_dir)
    from imrl_jax.run_state import read_search
    from imrl_jax.runspec import RunSpec
    from imrl_jax.strategies import GA_RECORD

    if read_search(run_dir) != GA_RECORD:  # generation 0 and the replays are the GA's
        raise UsageError(f"run: {run_dir} was evolved with {read_search(run_dir)['strategy']}; the landscape measures "
                         f"take their parents and mutations from the paper's GA")
    seed = seeds[0] if seed is None else seed
    if seed not in seeds:
        raise UsageError(f"--seed: {seed} is not a seed of {run_dir} ({', '.join(map(str, seeds))})")
    for name, value, low in (("--lives", lives, 2), ("--parents", num_parents, 1), ("--mutants", num_mutants, 2),
                             ("--walks", num_walks, 1), ("--walk-length", walk_length, 2), ("--random", num_random, 2),
                             ("--chunk", chunk, 1)):
        if value < low:
            raise UsageError(f"{name}: must be at least {low} (got {value})")
    if num_parents > config.population_size:
        raise UsageError(f"--parents: at most the population size ({config.population_size}; got {num_parents})")
    if num_walks > num_parents:
        raise UsageError(f"--walks: at most --parents ({num_parents}; got {num_walks}): the walks start from them")
    wanted = parse_generations(generations, config.num_generations)
    cut_configs = {}
    for fraction in cuts:
        try:
            cut_configs[f"cut {fraction:g}"] = ls.learning_cut(config, fraction)
        except ValueError as error:
            raise UsageError(f"--cut: {error}") from None
    check_writable(out_dir)
    make_dir(out_dir)
    progress_path = os.path.join(out_dir, PROGRESS)
    # The pieces are named by generation and cut: more of either adds pieces to the same measures.
    identity = dict(run_key=RunSpec.from_run_dir(run_dir).key(),
                    best_genomes=None if best_genomes is None else os.path.basename(best_genomes), seed=seed, lives=lives, parents=num_parents, mutants=num_mutants,
                    walks=num_walks, walk_length=walk_length, random=num_random, key=key, chunk=chunk)
    done = read_json(progress_path, "") if os.path.isfile(progress_path) else {}
    if done and done.get("identity") != identity:
        raise UsageError(f"--out: {out_dir} holds measures of other settings ({progress_path}); choose another --out")
    done = {"identity": identity, "run": run_dir, "condition": config.condition, "pieces": done.get("pieces", {})}
    fitness = {"learning": fitness_in_chunks(ls.lives_fitness(config, None, lives), chunk)}
    fitness.update({name: fitness_in_chunks(ls.lives_fitness(cut, None, lives), chunk)
                    for name, cut in cut_configs.items()})
    root = jax.random.key(key)

    def save(name: str, value: dict) -> None:
        done["pieces"][name] = value
        write_atomic(progress_path, json.dumps(done, indent=1).encode())

    for learning, fn in fitness.items():
        name = f"random genomes, {learning}"
        if name not in done["pieces"]:
            start = time.perf_counter()
            r = ls.random_fitness(jax.random.fold_in(root, 0), fn, config, num_random)
            save(name, dict(mean=float(r.mean), std=float(r.std), noise_variance=float(r.noise_variance),
                            quantiles=[float(q) for q in r.quantiles], share_zero=float(r.share_zero),
                            fitness=[round(float(f), 6) for f in r.fitness], seconds=round(time.perf_counter() - start, 1)))
            log(f"{config.condition} {name}: mean {float(r.mean):.4f}, sd {float(r.std):.4f}, at 0 "
                f"{float(r.share_zero):.0%} ({time.perf_counter() - start:.0f} s)")
    for g in wanted:
        parents, source = None, None
        for learning, fn in fitness.items():
            name = f"generation {g}, {learning}"
            if name in done["pieces"]:
                continue
            if parents is None:
                parents, source = parents_at(run_dir, config, seeds, seed, g, num_parents, out_dir, best_genomes)
            start = time.perf_counter()
            k = jax.random.fold_in(root, 1 + g)
            k_effects, k_walks = jax.random.split(k)
            effects = ls.mutation_effects(k_effects, fn, config, jnp.asarray(parents), num_mutants)
            rugged = ls.ruggedness(ls.random_walks(k_walks, fn, config, jnp.asarray(parents[:num_walks]), walk_length),
                                   max_lag=min(5, walk_length))
            piece = dict(generation=g, learning=learning, **source, **summary(effects, rugged),
                         seconds=round(time.perf_counter() - start, 1))
            save(name, piece)
            log(f"{config.condition} {name}: parents {piece['parent_mean']:.4f}, mutants neutral "
                f"{piece['share_neutral']:.0%} deleterious {piece['share_deleterious']:.0%} beneficial "
                f"{piece['share_beneficial']:.0%}; rho(1) {piece['rho'][0]} ({piece['seconds']:.0f} s)")
    write_atomic(os.path.join(out_dir, RESULT), json.dumps(done, indent=1).encode())
    return done


def parser() -> argparse.ArgumentParser:
    p = Parser(prog="python -m imrl_jax.landscape_run", description=__doc__.split("\n")[0],
                                formatter_class=HelpFormatter)
    p.add_argument("run", help="an evolution's run directory")
    p.add_argument("--out", required=True, help="the measures' folder (goes on from what it holds)")
    p.add_argument("--generations", default="0,10,last", help="the generations whose parents are measured")
    p.add_argument("--seed", type=int, help="the seed whose generations are measured (default: the run's first)")
    p.add_argument("--lives", type=int, default=4, help="fresh lives per genome")
    p.add_argument("--parents", type=int, default=10, help="the generation's best measured")
    p.add_argument("--mutants", type=int, default=9, help="mutants of each parent")
    p.add_argument("--walks", type=int, default=5, help="random mutation walks, from the best parents")
    p.add_argument("--walk-length", type=int, default=9, help="steps of each walk")
    p.add_argument("--random", type=int, default=50, help="random genomes (generation 0's draw)")
    p.add_argument("--cut", default="", help="learning cut to these fractions too (comma-separated; H3)")
    p.add_argument("--key", type=int, default=0, help="the measures' random key")
    p.add_argument("--chunk", type=int, default=50, help="genomes lived at once (one compiled program)")
    p.add_argument("--best-genomes", metavar="FILE", help="the last generation's best from a report's "
                                                          "best_genomes.npz (a run whose final population was not kept)")
    return p


@exit_codes
def main(argv=None) -> int:
    args = parser().parse_args(argv)
    try:
        cuts = tuple(float(c) for c in args.cut.split(",") if c.strip())
    except ValueError:
        raise UsageError(f"--cut: expected fractions separated by commas (got {args.cut!r})") from None
    if not os.path.isfile(os.path.join(args.run, "config.json")):
        raise RunDirError(f"{args.run}: no config.json (give an evolution's run directory)")
    run(args.run, args.out, generations=args.generations, seed=args.seed, lives=args.lives,
        num_parents=args.parents, num_mutants=args.mutants, num_walks=args.walks, walk_length=args.walk_length,
        num_random=args.random, cuts=cuts, key=args.key, chunk=args.chunk, best_genomes=args.best_genomes,
        log=lambda text: print(text, file=sys.stderr, flush=True))
    return 0


if __name__ == "__main__":
    sys.exit(main())
