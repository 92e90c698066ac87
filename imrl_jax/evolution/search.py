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
come from (:func:`life_key`: the key the GA lived an individual with, which ``render`` relives).
"""

from __future__ import annotations

import contextvars
from typing import Any, Callable, NamedTuple, Protocol, Sequence

import jax
import jax.numpy as jnp
import numpy as np

from imrl_jax.evolution.devices import AXIS, sharded_axis

#: True while :func:`shard_lanes` traces a population split over the devices: each lives its share.
_SHARE = contextvars.ContextVar("share", default=False)


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
    performance: Any  # (P, tasks) gathered when ``lives`` are this device's share (under a split), else None


def performance(result: Generation) -> jnp.ndarray:
    """(P, tasks): each individual's mean performance over its lives (taken from the lives where it was not gathered)."""
    # Taken where the caller asks, as ever: the XLA step's program stays what it was.
    return result.lives.performance.mean(1) if result.performance is None else result.performance


def generation_keys(key: jax.Array, generation) -> tuple[jax.Array, jax.Array]:
    """The keys of one generation of a seed: its lives, its search (ask and tell)."""
    return tuple(jax.random.split(jax.random.fold_in(key, generation)))


def seed_keys(seeds: Sequence[int]) -> jax.Array:
    """One typed key per seed."""
    return jax.vmap(jax.random.key)(np.asarray(seeds, np.uint32))


def evolution_keys(key_data: np.ndarray) -> jax.Array:
    """The keys the generations of each seed draw from (distinct from the initial population's)."""
    keys = jax.random.wrap_key_data(np.asarray(key_data))
    return jax.vmap(lambda k: jax.random.fold_in(k, 1))(keys)


def life_key(config, seed: int, generation: int, index: int, life: int = 0):
    """The key of life ``life`` (of ``config.lives_per_fitness``) of individual ``index`` of ``seed`` in
    ``generation`` of an evolve run: the key the GA lived it with."""
    key = evolution_keys(np.asarray(jax.random.key_data(seed_keys([seed]))))[0]
    key_life, _ = generation_keys(key, generation)
    return life_keys(key_life, config.population_size, config.lives_per_fitness)[index, life]


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
    if _SHARE.get():  # this device's lives only (the whole population's keys sliced), their means gathered
        share = genomes.shape[0] // jax.lax.psum(1, AXIS)
        start = jax.lax.axis_index(AXIS) * share
        lives = jax.vmap(jax.vmap(live, (0, None)))(*(jax.lax.dynamic_slice_in_dim(x, start, share)
                                                      for x in (keys, genomes)))
        gather = lambda x: jax.lax.all_gather(x, AXIS, tiled=True)  # noqa: E731
        fitness, performed = gather(lives.fitness.mean(1)), gather(lives.performance.mean(1))
    else:
        lives = jax.vmap(jax.vmap(live, (0, None)))(keys, genomes)
        fitness, performed = lives.fitness.mean(1), None  # None: :func:`performance` takes it from the lives
    state, info = strategy.tell(key_search, genomes, fitness, state, params)
    return state, Generation(genomes, fitness, lives, info, performed)


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


def make_generation(strategy: Strategy, live: Callable, lives_per_fitness: int = 1, sharding=None,
                    kernel: bool = False):
    """A jitted ``generation(keys, params, populations, states, search_params, index)`` vmapped over seeds.

    ``populations`` (seeds, P, genes) are generation ``index``'s genomes (asked for before), ``states``
    the strategies' states after that ask; ``live(key, params, genome)`` is one life. It lives and tells
    generation ``index``, then asks for generation ``index + 1``: it returns the next populations (kept
    in ``sharding``, so that the next lives are divided over the devices as these were), the states
    and each seed's :class:`Evaluated`. The same draws as :func:`generation` run generation by generation.
    ``kernel``: whether the Pallas kernel lives them (:func:`over_seeds`).
    """

    def one(key, params, genomes, state, search_params, index):
        state, result = evaluate_and_tell(key, strategy, lambda k, g: live(k, params, g), genomes, state,
                                          search_params, index, lives_per_fitness)
        following, state = ask(key, strategy, state, search_params, index + 1)
        return following, state, Evaluated(result.fitness, performance(result))

    return over_seeds(one, (0, None, 0, 0, None, None), sharding, kernel=kernel)


def over_seeds(one: Callable, in_axes: tuple, sharding=None, *, genomes: int = 2, kernel: bool = False):
    """``one`` generation of one seed, vmapped over the seeds (``in_axes``) and jitted.

    Its first output, the next populations, is kept in ``sharding``: otherwise XLA returns them
    replicated (reproduction gathers genomes across the population axis), and every later
    generation would run unsharded, each device living every life. When the Pallas kernel lives
    them (``kernel``) and ``sharding`` splits an axis, it runs under :func:`shard_lanes` (``genomes``:
    which argument is the populations).
    """

    def step(*args):
        split = sharding is not None and sharded_axis(sharding) != "none"
        if split and kernel:
            return shard_lanes(one, in_axes, sharding, genomes)(*args)
        following, *rest = jax.vmap(one, in_axes)(*args)
        if sharding is not None:
            following = jax.lax.with_sharding_constraint(following, sharding)
        return (following, *rest)

    return jax.jit(step)


def shard_lanes(one: Callable, in_axes: tuple, sharding, genomes: int):
    """``one`` vmapped over the seeds under ``jax.shard_map``: each device calls the kernel on its share of the lanes.

    XLA's partitioner cannot split a ``pallas_call`` (a custom call on a GPU, a loop over the
    grid in the interpreter): under plain jit it gathers every lane's state to every device,
    each living all the lanes. Sharded seeds need nothing else; a sharded population (argument
    ``genomes``) is gathered, each device lives its share (:func:`evaluate_and_tell`) and gathers
    the fitness and performance, so that every device tells and asks for the whole population
    alike, the same values as on one device, and keeps its share of the next populations.
    """
    from jax.sharding import PartitionSpec as P

    if sharded_axis(sharding) == "seeds":  # each device its seeds: one as on one device
        specs = tuple(P() if axis is None else P(AXIS) for axis in in_axes)
        local, out = jax.vmap(one, in_axes), P(AXIS)
    else:
        specs = tuple(P(None, AXIS) if i == genomes else P() for i in range(len(in_axes)))
        out = (P(None, AXIS), P())

        def local(*args):
            args = list(args)
            args[genomes] = jax.lax.all_gather(args[genomes], AXIS, axis=1, tiled=True)
            token = _SHARE.set(True)
            try:
                following, *rest = jax.vmap(one, in_axes)(*args)
            finally:
                _SHARE.reset(token)
            share = following.shape[1] // jax.lax.psum(1, AXIS)
            return jax.lax.dynamic_slice_in_dim(following, jax.lax.axis_index(AXIS) * share, share, 1), tuple(rest)

    # check_vma off: pallas_call's outputs would each need to declare how they vary over the mesh.
    mapped = jax.shard_map(local, mesh=sharding.mesh, in_specs=specs, out_specs=out, check_vma=False)
    if sharded_axis(sharding) == "seeds":
        return mapped
    return lambda *args: (lambda following, rest: (following, *rest))(*mapped(*args))
