"""Invariants of the genetic algorithm (MODEL.md "Genetic algorithm")."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from imrl_jax.evolution import ga
from imrl_jax.config import make_config


def _config(**overrides):
    return make_config("paper", condition="EE-ES", **overrides)


def test_initial_population_is_uniform_in_range():
    config = _config()
    population = ga.init_population(jax.random.key(0), config)
    assert population.shape == (50, 333) and population.dtype == jnp.float32
    assert float(population.min()) >= -1.0 and float(population.max()) <= 1.0
    assert abs(float(population.mean())) < 0.02 and abs(float(population.std()) - 1 / np.sqrt(3)) < 0.01


def test_the_best_ten_are_the_parents():
    fitness = jax.random.permutation(jax.random.key(1), jnp.arange(50.0)) / 50
    parents = np.asarray(ga.select(fitness, 10))
    order = np.argsort(-np.asarray(fitness))
    np.testing.assert_array_equal(parents, order[:10])
    assert np.all(np.asarray(fitness)[parents] >= np.sort(np.asarray(fitness))[-10])


def test_each_parent_has_five_offspring_and_zero_mutation_is_identity():
    config = _config(mutation_prob=0.0)
    population = ga.init_population(jax.random.key(2), config)
    parents = jnp.array([7, 3, 12, 0, 49, 8, 9, 10, 11, 1])
    children = np.asarray(ga.reproduce(jax.random.key(3), config, population, parents))
    for slot in range(50):
        np.testing.assert_array_equal(children[slot], np.asarray(population)[int(parents[slot // 5])])


def test_mutation_rate_and_size():
    config = _config()
    genomes = jnp.zeros((400, 333))
    mutated = np.asarray(ga.mutate(jax.random.key(4), config, genomes))
    changed = mutated != 0
    assert abs(changed.mean() - 0.1) < 0.005
    assert np.abs(mutated).max() <= 1.0 and abs(mutated[changed].mean()) < 0.02
    assert abs(np.abs(mutated[changed]).mean() - 0.5) < 0.02  # U[-1, 1] has mean |x| 1/2


def test_no_elites_by_default_and_elites_are_exact_copies():
    population = ga.init_population(jax.random.key(5), _config())
    parents = jnp.arange(10)
    plain = np.asarray(ga.reproduce(jax.random.key(6), _config(), population, parents))
    assert not any(np.array_equal(plain[5 * i], np.asarray(population)[i]) for i in range(10))
    elitist = np.asarray(ga.reproduce(jax.random.key(6), _config(num_elites=2), population, parents))
    np.testing.assert_array_equal(elitist[0], np.asarray(population)[0])
    np.testing.assert_array_equal(elitist[5], np.asarray(population)[1])
    np.testing.assert_array_equal(elitist[1:5], plain[1:5])  # only the elite slots change
    np.testing.assert_array_equal(elitist[10:], plain[10:])


def test_generation_step_over_seeds(tiny):
    """One jitted generation: every seed selects its own best and reproduces from them."""
    config = tiny("EE-ES")
    generation = ga.make_generation(config)
    keys = jax.vmap(jax.random.key)(jnp.arange(2))
    populations = jax.vmap(lambda k: ga.init_population(k, config))(keys)
    children, stats = generation(keys, config.learning_params(), populations, 0)
    assert children.shape == populations.shape and stats.fitness.shape == (2, 4)
    for s in range(2):
        best = np.argsort(-np.asarray(stats.fitness[s]), kind="stable")[:2]
        assert set(np.asarray(stats.parents[s])) == set(best)
    # Seed 0 evolved alone gives exactly what it gives beside seed 1.
    alone, alone_stats = generation(keys[:1], config.learning_params(), populations[:1], 0)
    np.testing.assert_array_equal(alone[0], children[0])
    np.testing.assert_array_equal(alone_stats.fitness[0], stats.fitness[0])


def test_the_ga_behind_ask_and_tell():
    """ask gives the population as it is; tell selects by the fitness passed in (maximised) and mutates."""
    strategy = ga.GA(_config(population_size=10, num_parents=2))
    params = strategy.default_params()
    assert params == ga.GAParams(0.1, 1.0)
    state = strategy.init(jax.random.key(0), params)
    genomes, asked = strategy.ask(jax.random.key(1), state, params)
    np.testing.assert_array_equal(genomes, state.population)
    assert asked is state and genomes.shape == (10, 333)
    fitness = jnp.arange(10.0)
    nxt, parents = strategy.tell(jax.random.key(2), genomes, fitness, state, params._replace(mutation_prob=0.0))
    np.testing.assert_array_equal(parents, [9, 8])  # the highest fitness first: it maximises
    np.testing.assert_array_equal(nxt.population[:5], np.repeat(np.asarray(genomes)[9:10], 5, 0))
    np.testing.assert_array_equal(nxt.population[5:], np.repeat(np.asarray(genomes)[8:9], 5, 0))


@pytest.mark.slow  # lives_per_fitness 2; the one-life relive is checked by test_render and the report's tests
def test_render_relives_each_of_several_lives_the_ga_lived(tiny, tmp_path):
    """With lives_per_fitness 2 the recorded fitness is the mean of the two lives render's keys relive."""
    from imrl_jax.commands import evolve
    from imrl_jax.evolution import search
    from imrl_jax.agent.lifetime import live

    config = tiny("EE-ES", task_steps=300, num_bins=1, lives_per_fitness=2, num_generations=1,
                  target_radius=40.0)  # reaches are common: the two lives differ
    out = str(tmp_path / "run")
    evolve.run(config, out, [3], quiet=True)
    with np.load(f"{out}/final_population.npz") as data:
        evaluated, fitness = data["evaluated"][0], data["fitness"][0]
    best = int(np.argmax(fitness))
    lives = [float(jax.jit(live, static_argnums=1)(search.life_key(config, 3, 0, best, life), config,
                                                   config.learning_params(), jnp.asarray(evaluated[best])).fitness)
             for life in range(2)]
    assert lives[0] != lives[1]
    np.testing.assert_allclose(np.mean(lives), fitness[best], rtol=1e-6)
