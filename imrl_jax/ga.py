"""The genetic algorithm of section 2 and MODEL.md "Genetic algorithm".

Generation 0 is uniform in [-1, 1]; the best 10 of 50 individuals each produce 5
offspring; each gene of an offspring is mutated with probability 0.1 by adding U[-1, 1].
No elitism unless ``num_elites`` > 0 (then the first offspring of each of the best
``num_elites`` parents is an unmutated copy). All functions are for one population and
pure; :func:`make_generation` composes them with the lifetimes into one jitted step that
is vmapped over independent seeds.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from imrl_jax.config import Config, LearningParams
from imrl_jax.lifetime import LifetimeResult, live


class GenerationStats(NamedTuple):
    """What one generation of one seed reports."""

    fitness: jnp.ndarray  # (P,) of every individual
    performance: jnp.ndarray  # (P, tasks)
    parents: jnp.ndarray  # (num_parents,) indices of the selected parents, best first


def init_population(key: jax.Array, config: Config, dtype=jnp.float32) -> jnp.ndarray:
    """Generation 0: (population, genes) uniform in [-init_scale, init_scale]."""
    s = config.init_scale
    return jax.random.uniform(key, (config.population_size, config.num_genes), dtype, -s, s)


def select(fitness: jnp.ndarray, num_parents: int) -> jnp.ndarray:
    """Indices of the ``num_parents`` fittest individuals, best first (ties: lower index)."""
    return jax.lax.top_k(fitness, num_parents)[1]


def mutate(key: jax.Array, config: Config, genomes: jnp.ndarray, mutation_prob=None,
           mutation_scale=None) -> jnp.ndarray:
    """Add U[-scale, scale] to each gene with probability ``mutation_prob``.

    The probability and scale default to the config's; passed in, they may be traced
    values (so a sweep can vmap over them).
    """
    prob = config.mutation_prob if mutation_prob is None else mutation_prob
    s = config.mutation_scale if mutation_scale is None else mutation_scale
    key_where, key_delta = jax.random.split(key)
    where = jax.random.bernoulli(key_where, prob, genomes.shape)
    delta = jax.random.uniform(key_delta, genomes.shape, genomes.dtype, -s, s)
    return jnp.where(where, genomes + delta, genomes)


def reproduce(key: jax.Array, config: Config, population: jnp.ndarray, parents: jnp.ndarray,
              mutation_prob=None, mutation_scale=None) -> jnp.ndarray:
    """The next population: ``offspring_per_parent`` mutated copies of each parent, in parent order."""
    offspring = jnp.repeat(population[parents], config.offspring_per_parent, axis=0)
    mutated = mutate(key, config, offspring, mutation_prob, mutation_scale)
    if config.num_elites:
        slot = jnp.arange(config.population_size)
        elite = (slot % config.offspring_per_parent == 0) & (slot // config.offspring_per_parent < config.num_elites)
        mutated = jnp.where(elite[:, None], offspring, mutated)
    return mutated


def generation_keys(key: jax.Array, generation) -> tuple[jax.Array, jax.Array]:
    """The keys of one generation of a seed: lifetimes, reproduction."""
    return tuple(jax.random.split(jax.random.fold_in(key, generation)))


def evolve_step(key: jax.Array, config: Config, params: LearningParams, population: jnp.ndarray,
                generation) -> tuple[jnp.ndarray, GenerationStats]:
    """One generation of one seed: live every individual, select the best, reproduce."""
    key_life, key_reproduce = generation_keys(key, generation)
    fitness, performance = evaluate(key_life, config, params, population)
    parents = select(fitness, config.num_parents)
    children = reproduce(key_reproduce, config, population, parents)
    return children, GenerationStats(fitness, performance, parents)


def evaluate(key: jax.Array, config: Config, params: LearningParams,
             population: jnp.ndarray) -> tuple[jnp.ndarray, jnp.ndarray]:
    """Fitness (P,) and task performance (P, tasks) of a population: one life each (the paper),
    or the mean of ``config.lives_per_fitness`` independent lives (a GA extension, less noisy)."""
    # split(key, (P, 1))[:, 0] is split(key, P): one life each gets the keys it always had.
    keys = jax.random.split(key, (config.population_size, config.lives_per_fitness))
    lives = jax.vmap(lambda k, g: live(k, config, params, g), (0, None))
    result: LifetimeResult = jax.vmap(lives)(keys, population)
    return result.fitness.mean(1), result.performance.mean(1)


def make_generation(config: Config, sharding=None):
    """A jitted ``generation(keys, params, populations, generation)`` vmapped over seeds.

    ``keys`` (seeds,) are the seeds' own keys; ``populations`` (seeds, P, genes). Returns
    the next populations and each seed's :class:`GenerationStats`. With ``sharding`` (of
    the populations), the next populations keep it: otherwise XLA returns them replicated
    (reproduction gathers parents across the population axis), and every later
    generation would run unsharded, each device living every life.
    """

    def generation(keys, params, populations, index):
        children, stats = jax.vmap(lambda k, p: evolve_step(k, config, params, p, index))(keys, populations)
        if sharding is not None:
            children = jax.lax.with_sharding_constraint(children, sharding)
        return children, stats

    return jax.jit(generation)
