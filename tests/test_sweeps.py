"""Sweeps: one vmapped program over parameter values gives what separate runs give."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import random_genomes

from imrl_jax.analysis import behaviour
from imrl_jax.commands import evolve, render
from imrl_jax.evolution import sweeps
from imrl_jax.config import Config, ConfigError
from imrl_jax.evolution.ga import reproduce
from imrl_jax.evolution.search import generation_keys
from imrl_jax.agent.networks import decode


def test_points(tiny):
    config = tiny()
    sweep = sweeps.one_at_a_time(config, {"eta": [0.1, 0.001], "mutation_prob": [0.3]})
    assert len(sweep) == 3 and sweep.points.params.gamma.shape == (3,)
    np.testing.assert_allclose(sweep.points.params.eta_selector_critic, [0.1, 0.001, 0.01])
    np.testing.assert_allclose(sweep.points.ga.mutation_prob, [0.1, 0.1, 0.3])
    assert sweeps.indices(sweep, "eta") == [1, 0]
    assert len(sweeps.grid(config, gamma=[0.9, 0.99], noise_std=[0.1, 0.2, 0.3])) == 6
    with pytest.raises(ValueError, match="num_experts"):
        sweeps.point(config, num_experts=2)  # static: not a sweep value
    with pytest.raises(ConfigError, match="gamma"):
        sweeps.point(config, gamma=1.5)


def test_evolution_sweep_is_the_evolve_command(tiny_run):
    """A one-point program at the run's values gives the run exactly."""
    config = render.best_individual(tiny_run).config
    with np.load(f"{tiny_run}/final_population.npz") as data:
        evaluated, fitness = data["evaluated"], data["fitness"]
    (alone,) = sweeps.evolve_points(config, [{}], [0, 1])
    assert alone.best.shape == (2, config.num_generations)
    assert alone.best_reward_curve.shape == (2, config.num_generations, config.num_tasks, config.num_bins)
    np.testing.assert_array_equal(alone.final_evaluated, evaluated)
    np.testing.assert_array_equal(alone.final_fitness, fitness)
    np.testing.assert_array_equal(alone.best[:, -1], fitness.max(1))


def test_reproduction_with_traced_mutation_values(tiny):
    config = tiny("EE-LS", population_size=6, num_parents=2, num_elites=1)
    population = random_genomes(config, 6)
    parents = jnp.asarray([4, 1])
    ga_values = sweeps.point(config).ga
    expected = reproduce(jax.random.key(1), config, population, parents)
    np.testing.assert_array_equal(reproduce(jax.random.key(1), config, population, parents, *ga_values), expected)
    traced = jax.jit(lambda ga: reproduce(jax.random.key(1), config, population, parents, *ga))
    np.testing.assert_array_equal(traced(ga_values), expected)
    more = traced(sweeps.point(config, mutation_prob=0.9).ga)
    assert (more != population[jnp.repeat(parents, 3)]).mean() > 0.5
    np.testing.assert_array_equal(more[0], population[4])  # the elite is copied unmutated


def test_run_padded():
    points = sweeps.stack([sweeps.point(Config(), gamma=g) for g in (0.5, 0.9)])
    calls = []

    def fn(scale, pts):
        calls.append(pts.params.gamma.shape)
        return pts.params.gamma * scale

    np.testing.assert_allclose(sweeps.run_padded(fn, points, 5, 2.0), [1.0, 1.8])
    assert calls == [(5,)]
    with pytest.raises(ValueError):
        sweeps.pad(points, 1)


def test_lifetime_sweep_relives_the_run(tiny_run):
    """Living seed 0's last population with its generation's key gives its fitness, and each point its values."""
    config = render.best_individual(tiny_run).config
    with np.load(f"{tiny_run}/final_population.npz") as data:
        evaluated, fitness, generation = data["evaluated"], data["fitness"], int(data["generation"]) - 1
    seed_key = evolve.evolution_keys(np.asarray(jax.random.key_data(evolve.seed_keys([0]))))[0]
    key_life, _ = generation_keys(seed_key, generation)
    sweep = sweeps.from_settings(config, [{}, {"gamma": 0.5}, {}])
    result = sweeps.make_lifetime_sweep(config)(key_life, jnp.asarray(evaluated[0]), sweep.points)
    assert result.fitness.shape == (3, config.population_size)
    assert fitness[0].max() > 0  # something to compare
    np.testing.assert_allclose(result.fitness[0], fitness[0], atol=1e-6)
    np.testing.assert_array_equal(result.fitness[2], result.fitness[0])
    selectors = result.adult_agents.selector_critic
    assert not np.allclose(selectors[1], selectors[0])  # learned with another discount


def test_colour_shares_and_probe(tiny):
    config = tiny()
    # Expert 0 drives along a red edge (task 1 starts on one); expert 1 sits on the background.
    task = config.tasks[0]
    on_red = np.asarray(task.start) + np.outer(np.arange(5.0), [1.0, 0.0])
    pos = np.concatenate([on_red, np.full((5, 2), [20.0, 20.0])])
    heading = np.zeros(10)
    k = np.repeat([0, 1], 5)
    no = np.zeros(10, bool)
    trajectory = behaviour.Trajectory(pos, heading, pos, heading, k, no, no, no)
    shares, steps = behaviour.colour_shares(config, trajectory, 3)
    np.testing.assert_allclose(shares[0], [1, 0, 0, 0])
    np.testing.assert_allclose(shares[1], [0, 0, 0, 1])
    assert np.isnan(shares[2]).all() and list(steps) == [5, 5, 0]
    # A probe gives control to each expert alone.
    agent = decode(config, jnp.asarray(behaviour.colour_reinforcers(config)))
    probe = behaviour.probe_experts(jax.random.key(0), config, agent, num_starts=2, num_steps=20)
    assert probe.k.shape == (3, 2, 20)
    assert all((probe.k[e] == e).all() for e in range(3))
    np.testing.assert_allclose(probe.seen_pos[:, :, 1:], probe.pos[:, :, :-1])


def test_a_life_reads_its_dynamic_values_from_its_params_not_its_config():
    """What lets a sweep's points and learning tests share one program: an LE-LS-P life lived with the config of
    other dynamic values equals the life of its own config (the genome's learning values included)."""
    import jax

    from helpers import random_genomes, tiny_config

    from imrl_jax.agent.lifetime import live

    own = tiny_config("LE-LS-P", childhood_selector_reward="progress", progress_rate=0.2, noise_std=0.1)
    other = sweeps.static_part(own)
    assert (other.progress_rate, other.noise_std) != (own.progress_rate, own.noise_std)
    genome = jax.numpy.asarray(random_genomes(own, 1)[0])
    key = jax.random.key(3)
    a = jax.jit(lambda k, p, g: live(k, own, p, g))(key, own.learning_params(), genome)
    b = jax.jit(lambda k, p, g: live(k, other, p, g))(key, own.learning_params(), genome)
    for name in ("fitness", "reward_curve", "childhood_selections"):
        assert np.array_equal(np.asarray(getattr(a, name)), np.asarray(getattr(b, name))), name
    c = jax.jit(lambda k, p, g: live(k, other, p, g))(key, other.learning_params(), genome)
    assert not np.array_equal(np.asarray(a.childhood_selections), np.asarray(c.childhood_selections))
