"""The genetic algorithm of section 2 and MODEL.md "Genetic algorithm".

Generation 0 is uniform in [-1, 1]; the best 10 of 50 individuals each produce 5
offspring; each gene of an offspring is mutated with probability 0.1 by adding U[-1, 1].
No elitism unless ``num_elites`` > 0 (then the first offspring of each of the best
``num_elites`` parents is an unmutated copy). All functions are for one population and
pure; :class:`GA` is them as a search strategy (:mod:`imrl_jax.evolution.search`), and
:func:`make_generation` composes it with the lifetimes into one jitted step that is vmapped
over independent seeds.
"""

from __future__ import annotations

import dataclasses
from typing import NamedTuple

import jax
import jax.numpy as jnp

from imrl_jax.agent import kernel_choice
from imrl_jax.evolution import search
from imrl_jax.config import Config, LearningParams
from imrl_jax.agent.lifetime import LifetimeResult, live


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


class GAParams(NamedTuple):
    """The GA's dynamic values: per-gene mutation probability and the U[-scale, scale] size."""

    mutation_prob: float
    mutation_scale: float


class GAState(NamedTuple):
    """The GA's state: the population that lives next."""

    population: jnp.ndarray  # (P, genes)


@dataclasses.dataclass(frozen=True)
class GA:
    """The paper's genetic algorithm as a search strategy (:mod:`imrl_jax.evolution.search`): the default.

    Its static settings are the config's (population, parents, elites, initial range); its
    dynamic values are :class:`GAParams`. It draws only in ``tell`` (the mutations).
    """

    config: Config

    def default_params(self) -> GAParams:
        """The config's mutation probability and size (Python floats: a program closing over them
        compiles them in, as the GA always has)."""
        return GAParams(self.config.mutation_prob, self.config.mutation_scale)

    def init(self, key: jax.Array, params: GAParams | None = None, dtype=jnp.float32) -> GAState:
        """Generation 0: uniform in [-init_scale, init_scale]."""
        return GAState(init_population(key, self.config, dtype))

    def ask(self, key: jax.Array, state: GAState, params: GAParams) -> tuple[jnp.ndarray, GAState]:
        """The population as it is (the GA draws nothing here)."""
        return state.population, state

    def tell(self, key: jax.Array, genomes: jnp.ndarray, fitness: jnp.ndarray, state: GAState,
             params: GAParams) -> tuple[GAState, jnp.ndarray]:
        """Select the best, reproduce them with mutations; report the parents, best first."""
        parents = select(fitness, self.config.num_parents)
        children = reproduce(key, self.config, genomes, parents, params.mutation_prob, params.mutation_scale)
        return GAState(children), parents


def evolve_step(key: jax.Array, config: Config, params: LearningParams, population: jnp.ndarray,
                generation, ga_params: GAParams | None = None) -> tuple[jnp.ndarray, GenerationStats]:
    """One generation of one seed: live every individual, select the best, reproduce.

    ``ga_params``: the mutation's values (traced in a sweep); None compiles in the config's.
    """
    strategy = GA(config)
    ga_params = strategy.default_params() if ga_params is None else ga_params
    state, result = search.generation(key, strategy, lambda k, g: live(k, config, params, g),
                                      GAState(population), ga_params, generation,
                                      config.lives_per_fitness)
    return state.population, GenerationStats(result.fitness, search.performance(result), result.info)


def evaluate(key: jax.Array, config: Config, params: LearningParams,
             population: jnp.ndarray) -> tuple[jnp.ndarray, jnp.ndarray]:
    """Fitness (P,) and task performance (P, tasks) of a population: one life each (the paper),
    or the mean of ``config.lives_per_fitness`` independent lives (a GA extension, less noisy)."""
    keys = search.life_keys(key, config.population_size, config.lives_per_fitness)
    lives = jax.vmap(lambda k, g: live(k, config, params, g), (0, None))
    result: LifetimeResult = jax.vmap(lives)(keys, population)
    return result.fitness.mean(1), result.performance.mean(1)


def make_generation(config: Config, sharding=None):
    """A jitted ``generation(keys, params, populations, generation)`` vmapped over seeds.

    ``keys`` (seeds,) are the seeds' own keys; ``populations`` (seeds, P, genes). Returns
    the next populations and each seed's :class:`GenerationStats`. With ``sharding`` (of
    the populations), the next populations keep it (:func:`imrl_jax.evolution.search.over_seeds`);
    when the Pallas kernel lives them, each device lives its own lanes (:func:`imrl_jax.evolution.search.shard_lanes`).
    """
    return search.over_seeds(lambda k, p, g, i: evolve_step(k, config, p, g, i), (0, None, 0, None), sharding,
                             kernel=kernel_choice.chosen(config) == "pallas")
