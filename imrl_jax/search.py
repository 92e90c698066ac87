"""The search behind evolution (section 2 "Genetic algorithm"): a strategy's ``init``, ``ask``, ``tell``.

A strategy is an object with evosax's small interface over State and Params pytrees, for
one population, pure and jit-able:

* ``default_params()`` -> Params: its dynamic values (the GA's mutation probability and size);
* ``init(key, params)`` -> State: generation 0;
* ``ask(key, state, params)`` -> (genomes (P, genes), State): the individuals to live;
* ``tell(key, genomes, fitness, state, params)`` -> (State, info): the next state, from the
  fitness (P,) of those genomes, which it **maximises**.

Within a generation ``ask`` and ``tell`` receive the same search key: a strategy that draws in
both splits it (:func:`split_search_key`), one that draws in one of them uses it whole (the
paper's GA draws only in ``tell``). :func:`generation` is the one generation step that
``evolve`` and ``sweeps`` share, and :func:`life_keys` the one place a generation's life keys
come from (``render`` relives the key the GA used with it).
"""

from __future__ import annotations

from typing import Any, Callable, NamedTuple, Protocol

import jax
import jax.numpy as jnp


class Strategy(Protocol):
    """What ``evolve`` needs of a search strategy (evosax's interface; fitness is maximised)."""

    def default_params(self) -> Any: ...

    def init(self, key: jax.Array, params) -> Any: ...

    def ask(self, key: jax.Array, state, params) -> tuple[jnp.ndarray, Any]: ...

    def tell(self, key: jax.Array, genomes: jnp.ndarray, fitness: jnp.ndarray, state, params) -> tuple[Any, Any]: ...


class Generation(NamedTuple):
    """What one generation of one seed produced."""

    genomes: jnp.ndarray  # (P, genes): the individuals that lived
    fitness: jnp.ndarray  # (P,): the mean of each one's lives
    lives: Any  # the lives' LifetimeResult, axes (P, lives_per_fitness, ...)
    info: Any  # what the strategy's tell reported (the GA: the parents, best first)


def generation_keys(key: jax.Array, generation) -> tuple[jax.Array, jax.Array]:
    """The keys of one generation of a seed: its lives, its search (ask and tell)."""
    return tuple(jax.random.split(jax.random.fold_in(key, generation)))


def split_search_key(key: jax.Array) -> tuple[jax.Array, jax.Array]:
    """The keys of ask and tell, for a strategy that draws in both."""
    return tuple(jax.random.split(key))


def life_keys(key: jax.Array, num_individuals: int, lives_per_fitness: int) -> jax.Array:
    """(P, lives) keys of a generation's lives from its life key."""
    # split(key, (P, 1))[:, 0] is split(key, P): one life each gets the keys it always had.
    return jax.random.split(key, (num_individuals, lives_per_fitness))


def ask(key: jax.Array, strategy: Strategy, state, params, index) -> tuple[jnp.ndarray, Any]:
    """The genomes of generation ``index`` of one seed, drawn with that generation's search key."""
    _, key_search = generation_keys(key, index)
    return strategy.ask(key_search, state, params)


def evaluate_and_tell(key: jax.Array, strategy: Strategy, live: Callable, genomes: jnp.ndarray, state, params, index,
                      lives_per_fitness: int = 1) -> tuple[Any, Generation]:
    """Live generation ``index``'s ``genomes`` ``lives_per_fitness`` times each and tell the strategy their mean fitness."""
    key_life, key_search = generation_keys(key, index)
    keys = life_keys(key_life, genomes.shape[0], lives_per_fitness)
    lives = jax.vmap(jax.vmap(live, (0, None)))(keys, genomes)
    fitness = lives.fitness.mean(1)
    state, info = strategy.tell(key_search, genomes, fitness, state, params)
    return state, Generation(genomes, fitness, lives, info)


def generation(key: jax.Array, strategy: Strategy, live: Callable, state, params, index,
               lives_per_fitness: int = 1) -> tuple[Any, Generation]:
    """One generation of one seed: ask for genomes, live each ``lives_per_fitness`` times, tell the mean fitness.

    ``live(key, genome)`` is one life (a LifetimeResult); ``index`` the generation's number.
    """
    genomes, state = ask(key, strategy, state, params, index)
    return evaluate_and_tell(key, strategy, live, genomes, state, params, index, lives_per_fitness)


class Evaluated(NamedTuple):
    """What a generation of one seed reports to ``evolve``."""

    fitness: jnp.ndarray  # (P,) the mean of each individual's lives
    performance: jnp.ndarray  # (P, tasks) likewise


def make_generation(strategy: Strategy, live: Callable, lives_per_fitness: int = 1, sharding=None):
    """A jitted ``generation(keys, params, populations, states, search_params, index)`` vmapped over seeds.

    ``populations`` (seeds, P, genes) are generation ``index``'s genomes (asked for before), ``states``
    the strategies' states after that ask; ``live(key, params, genome)`` is one life. It lives and tells
    generation ``index``, then asks for generation ``index + 1``: it returns the next populations (kept
    in ``sharding``, so that the next lives are divided over the devices as these were), the states
    and each seed's :class:`Evaluated`. The same draws as :func:`generation` run generation by generation.
    """

    def one(key, params, genomes, state, search_params, index):
        state, result = evaluate_and_tell(key, strategy, lambda k, g: live(k, params, g), genomes, state,
                                          search_params, index, lives_per_fitness)
        following, state = ask(key, strategy, state, search_params, index + 1)
        return following, state, Evaluated(result.fitness, result.lives.performance.mean(1))

    return over_seeds(one, (0, None, 0, 0, None, None), sharding)


def over_seeds(one: Callable, in_axes: tuple, sharding=None):
    """``one`` generation of one seed, vmapped over the seeds (``in_axes``) and jitted.

    Its first output, the next populations, is kept in ``sharding``: otherwise XLA returns them
    replicated (reproduction gathers genomes across the population axis), and every later
    generation would run unsharded, each device living every life.
    """

    def step(*args):
        following, *rest = jax.vmap(one, in_axes)(*args)
        if sharding is not None:
            following = jax.lax.with_sharding_constraint(following, sharding)
        return (following, *rest)

    return jax.jit(step)
