"""The landscape measures (imrl_jax.evolution.landscape, docs/GOALS.md "Measures") on hand-made landscapes whose answer is
known: flat, a needle, a slope, white noise, a slope with per-life noise; and one tiny check on the model's lives."""

import functools

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from imrl_jax.evolution import landscape as ls
from imrl_jax.config import make_config
from imrl_jax.agent.lifetime import make_evaluate

from helpers import tiny_config

#: The GA's settings of the hand-made landscapes: not the paper's 0.1 and U[-1, 1], so that a measure reading
#: anything but the config's operator is found out.
CONFIG = make_config("paper", condition="LE-LS", mutation_prob=0.2, mutation_scale=0.5, init_scale=0.5)
G = CONFIG.num_genes
SLOPE = jnp.linspace(-1.0, 2.0, G)


def deterministic(f):
    """A landscape without noise: every life of a genome has the fitness f(genome)."""
    return ls.from_lives(lambda key, genomes: f(genomes), 2)


flat = deterministic(lambda genomes: jnp.full(genomes.shape[:1], 0.3))
slope = deterministic(lambda genomes: genomes @ SLOPE)


def test_a_flat_landscape_has_only_neutral_mutations_no_offspring_variance_and_no_autocorrelation():
    random = ls.random_fitness(jax.random.key(0), flat, CONFIG, 50)
    assert float(random.std) == 0.0 and float(random.mean) == pytest.approx(0.3) and float(random.share_zero) == 0.0
    parents = ls.random_genomes(jax.random.key(1), CONFIG, 10)
    effects = ls.mutation_effects(jax.random.key(2), flat, CONFIG, parents, 5)
    assert effects.effect.shape == (10, 5) and effects.mutants.shape == (10, 5, G)
    assert float(effects.share_neutral) == 1.0 and float(effects.share_beneficial + effects.share_deleterious) == 0.0
    evolvability = ls.evolvability(effects)
    np.testing.assert_array_equal(evolvability.offspring_variance, 0.0)
    np.testing.assert_array_equal(evolvability.share_better, 0.0)
    # No variance to correlate: the autocorrelation and the correlation length are undefined (NaN), not 1.
    rugged = ls.ruggedness(ls.random_walks(jax.random.key(3), flat, CONFIG, parents, 8), 3)
    assert float(rugged.variance) == 0.0
    assert np.isnan(rugged.rho).all() and np.isnan(rugged.correlation_length)


def test_a_needle_is_never_drawn_and_every_mutation_of_it_is_deleterious():
    needle = ls.random_genomes(jax.random.key(4), CONFIG, 1)[0]
    at_needle = deterministic(lambda genomes: jnp.all(genomes == needle, axis=1).astype(jnp.float32))
    random = ls.random_fitness(jax.random.key(5), at_needle, CONFIG, 200)
    assert float(random.share_zero) == 1.0 and float(random.quantiles[-1]) == 0.0
    effects = ls.mutation_effects(jax.random.key(6), at_needle, CONFIG, jnp.tile(needle, (8, 1)), 6)
    np.testing.assert_array_equal(effects.parent, 1.0)
    np.testing.assert_array_equal(effects.effect, -1.0)
    assert float(effects.share_deleterious) == 1.0 and float(effects.share_neutral) == 0.0
    evolvability = ls.evolvability(effects)
    np.testing.assert_array_equal(evolvability.offspring_variance, 0.0)
    assert float(evolvability.mean_share_better) == 0.0


def test_on_a_slope_random_fitness_and_mutation_effects_have_the_hand_computed_moments():
    # f = a . g. Generation 0: g_i ~ U[-s0, s0], so var f = s0^2 / 3 |a|^2. A mutation adds b_i u_i with
    # b_i ~ Bernoulli(p), u_i ~ U[-s, s]: the effect a . (b u) has mean 0 and variance p s^2 / 3 |a|^2.
    a2 = float(SLOPE @ SLOPE)
    random = ls.random_fitness(jax.random.key(7), slope, CONFIG, 2000)
    assert abs(float(random.mean)) < 4 * np.sqrt(0.5 ** 2 / 3 * a2 / 2000)
    assert float(random.std) ** 2 == pytest.approx(0.5 ** 2 / 3 * a2, rel=0.1)
    parents = ls.random_genomes(jax.random.key(8), CONFIG, 200)
    measure = functools.partial(ls.mutation_effects, fitness_fn=slope, config=CONFIG, num_mutants=10)
    effects = measure(jax.random.key(9), parents=parents)
    variance = 0.2 * 0.5 ** 2 / 3 * a2
    assert abs(float(effects.mean)) < 4 * np.sqrt(variance / 2000)
    assert float(effects.variance) == pytest.approx(variance, rel=0.1)
    np.testing.assert_allclose(effects.effect, (effects.mutants - parents[:, None]) @ SLOPE, atol=1e-4)
    # No noise: every mutation changes the fitness, up or down with equal chance.
    assert float(effects.share_neutral) == 0.0 and abs(float(effects.share_beneficial) - 0.5) < 0.05
    evolvability = ls.evolvability(effects)
    assert float(evolvability.mean_mutational_variance) == pytest.approx(variance, rel=0.1)
    assert abs(float(evolvability.mean_share_better) - 0.5) < 0.05
    jitted = jax.jit(measure)(jax.random.key(9), parents=parents)
    np.testing.assert_allclose(jitted.effect, effects.effect, atol=1e-5)


def test_a_slope_is_smooth_along_walks_and_white_noise_is_not():
    starts = ls.random_genomes(jax.random.key(10), CONFIG, 20)
    walks = ls.random_walks(jax.random.key(11), slope, CONFIG, starts, 30)
    assert walks.fitness.shape == (20, 31)
    np.testing.assert_allclose(walks.fitness[:, 0], starts @ SLOPE, rtol=1e-5)
    rugged = ls.ruggedness(walks, 5)
    assert float(rugged.rho[0]) > 0.95 and np.all(np.diff(rugged.rho) < 0)
    assert float(rugged.correlation_length) > 15
    # Fitness a hash of the genome: a mutation draws a new, independent fitness, so rho(s) = 0 for s >= 1.
    hashed = deterministic(lambda genomes: jnp.sin(1e3 * genomes @ jnp.arange(1.0, G + 1)))
    rugged = ls.ruggedness(ls.random_walks(jax.random.key(12), hashed, CONFIG, starts, 60), 5)
    assert np.all(np.abs(rugged.rho) < 4 / np.sqrt(20 * 60)) and float(rugged.correlation_length) < 0.5


def test_correlation_length_is_minus_one_over_log_rho():
    np.testing.assert_allclose(ls.correlation_length(np.exp(-1 / 5)), 5.0, rtol=1e-5)
    assert float(ls.correlation_length(1.0)) == np.inf and float(ls.correlation_length(-0.2)) == 0.0
    assert np.isnan(ls.correlation_length(np.nan))


def test_with_noisy_lives_a_mutation_of_no_effect_is_neutral_at_the_stated_rate():
    # f = 5 g_0 + N(0, 1) per life: a mutant that left gene 0 alone has no effect. With 10 lives per
    # genome, effect / se is Student's t with 18 degrees of freedom: neutral with P(|t| <= 2) = 0.939.
    config = make_config("paper", condition="LE-LS")
    noisy = ls.from_lives(lambda key, genomes: 5.0 * genomes[:, 0] + jax.random.normal(key, genomes.shape[:1]), 10)
    parents = ls.random_genomes(jax.random.key(13), config, 500)
    effects = ls.mutation_effects(jax.random.key(14), noisy, config, parents, 4)
    true = 5.0 * np.asarray(effects.mutants[..., 0] - parents[:, None, 0])
    no_effect = true == 0
    assert no_effect.sum() > 1500
    stated = float(ls.neutral_rate(2.0, 10))
    assert stated == pytest.approx(0.9392, abs=1e-3)
    assert float(np.asarray(effects.neutral)[no_effect].mean()) == pytest.approx(stated, abs=0.02)
    # An effect of 5 noise standard errors or more is classified by its sign.
    large = np.abs(true) > 5 * np.sqrt(2 / 10)
    assert large.sum() > 50
    np.testing.assert_array_equal(np.asarray(effects.beneficial)[large], true[large] > 0)
    np.testing.assert_array_equal(np.asarray(effects.deleterious)[large], true[large] < 0)


def test_from_lives_needs_two_lives_and_ruggedness_a_lag_within_the_walks():
    with pytest.raises(ValueError, match="num_lives"):
        ls.from_lives(lambda key, genomes: genomes[:, 0], 1)
    walks = ls.Walks(jnp.zeros((2, 4)), jnp.zeros((2, 4)))
    with pytest.raises(ValueError, match="max_lag"):
        ls.ruggedness(walks, 4)


def test_learning_cut_per_condition():
    le = make_config("paper", condition="LE-LS")
    none = ls.learning_cut(le)  # no childhood: one bin of it, in which nothing learns; the adult selector as before
    assert none.childhood_steps == le.num_bins
    assert (none.eta_actor, none.eta_evaluator, none.childhood_eta_selector_actor,
            none.childhood_eta_selector_critic) == (0.0, 0.0, 0.0, 0.0)
    assert none.eta_selector_actor == le.eta_selector_actor
    tenth = ls.learning_cut(le, 0.1)  # a tenth of the childhood, its rates as they are
    assert tenth.childhood_steps == 15_000 and tenth.eta_actor == le.eta_actor
    both = ls.learning_cut(le, 0.5, adult=True)
    assert both.childhood_steps == 75_000 and both.eta_selector_actor == pytest.approx(0.005)
    ee = make_config("paper", condition="EE-LS")
    cut = ls.learning_cut(ee)  # the adult selector learns nothing
    assert (cut.eta_selector_actor, cut.eta_selector_critic) == (0.0, 0.0) and cut.childhood_steps == ee.childhood_steps
    assert cut.learning_params().eta_selector_actor == 0.0
    es = make_config("paper", condition="EE-ES")
    assert ls.learning_cut(es) == es  # nothing learns in EE-ES
    with pytest.raises(ValueError, match="learning rates"):
        ls.learning_cut(make_config("paper", condition="LE-LS-P"))
    with pytest.raises(ValueError, match="fraction"):
        ls.learning_cut(le, 1.5)


def test_lives_fitness_is_make_evaluate_averaged_over_the_same_keys():
    config = tiny_config("EE-LS", task_steps=200, target_radius=40.0)
    genomes = ls.random_genomes(jax.random.key(15), config, 3)
    key = jax.random.key(16)
    estimate = ls.lives_fitness(config, None, 2)(key, genomes)
    assert estimate.mean.shape == estimate.se.shape == (3,)
    evaluate = make_evaluate(config)
    lives = np.stack([np.asarray(evaluate(k, config.learning_params(), genomes).fitness)
                      for k in jax.random.split(key, 2)])
    np.testing.assert_allclose(estimate.mean, lives.mean(0), rtol=1e-6)
    np.testing.assert_allclose(estimate.se, lives.std(0, ddof=1) / np.sqrt(2), rtol=1e-5, atol=1e-7)
    assert np.all(lives >= 0) and lives.max() > 0  # a 40 cm target: some reaches even at this size
