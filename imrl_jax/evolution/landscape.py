"""Fitness-landscape measures for issue 48: why is evolving goals easier than evolving behaviours?

The paper (section 3, Fig. 3a) finds LE-LS, whose genome encodes the experts' reinforcers (goals,
111 genes), about an order of magnitude more evolvable than EE-LS (the experts' actors, behaviours,
222 genes) and EE-ES (actors and selector, 333). These measures describe the landscape that the
paper's genetic algorithm (section 2, "Genetic algorithm"; MODEL.md; :mod:`imrl_jax.evolution.ga`) searches,
for any condition and population, with the GA's own generation-0 draw and mutation operator:

* :func:`random_fitness`: the fitness distribution of random genomes (generation 0's);
* :func:`mutation_effects`: fitness(mutant) - fitness(parent), each neutral, deleterious or
  beneficial beyond the lives' noise; :func:`evolvability`: from the same data, the offspring's
  fitness variance and the share of offspring better than their parent;
* :func:`random_walks` and :func:`ruggedness`: the autocorrelation of fitness along mutation
  walks and the correlation length;
* :func:`learning_cut`: the config whose lives learn less (learning smoothing the landscape).

The fitness is an argument, ``fitness_fn(key, genomes (N, genes)) -> Estimate``: the mean of fresh
lives per genome and its standard error. :func:`from_lives` makes one from any per-life function
(hand-made landscapes), :func:`lives_fitness` from the model's lives, :func:`fitness_in_chunks` any number
of genomes through one program of a fixed batch (host-side). Every measure is pure and
jittable with ``fitness_fn``, ``config`` and the sizes static. docs/GOALS.md "Measures".
"""

from __future__ import annotations

from typing import Callable, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from imrl_jax.evolution import ga
from imrl_jax.config import Config, LearningParams
from imrl_jax.agent.lifetime import make_evaluate

#: The quantiles of a fitness distribution that :class:`RandomFitness` reports.
QUANTILES = (0.0, 0.25, 0.5, 0.75, 1.0)


class Estimate(NamedTuple):
    """Each genome's fitness: the mean of its lives and that mean's standard error."""

    mean: jnp.ndarray  # (N,)
    se: jnp.ndarray  # (N,): the lives' standard deviation (ddof 1) / sqrt(lives)


def _moments(x: jnp.ndarray, axis: int) -> tuple[jnp.ndarray, jnp.ndarray]:
    """The mean and the variance (ddof 1) of ``x`` along ``axis``, computed about its first element."""
    # About the first element, equal values have exactly their value as mean and 0 as variance: in float32 the
    # plain mean of fifty 0.3s is not 0.3, and a flat landscape would seem to vary (and correlate perfectly).
    first = jnp.take(x, jnp.array([0]), axis=axis)
    shifted = x - first
    return jnp.squeeze(first, axis) + shifted.mean(axis), shifted.var(axis, ddof=1)


#: ``fitness_fn(key, genomes (N, genes)) -> Estimate``, every life fresh (drawn from ``key``).
FitnessFn = Callable[[jax.Array, jnp.ndarray], Estimate]


def from_lives(life_fn: Callable[[jax.Array, jnp.ndarray], jnp.ndarray], num_lives: int) -> FitnessFn:
    """A fitness function averaging ``num_lives`` fresh lives ``life_fn(key, genomes) -> (N,)`` per genome."""
    # One life says nothing of the lives' noise, and the classifications below need it.
    if num_lives < 2:
        raise ValueError(f"num_lives: at least 2 lives per genome estimate their noise (got {num_lives})")

    def fitness_fn(key: jax.Array, genomes: jnp.ndarray) -> Estimate:
        lives = jax.vmap(life_fn, (0, None))(jax.random.split(key, num_lives), genomes)  # (lives, N)
        mean, variance = _moments(lives, 0)
        return Estimate(mean, jnp.sqrt(variance / num_lives))

    return fitness_fn


def lives_fitness(config: Config, params: LearningParams | None, num_lives: int) -> FitnessFn:
    """The model's fitness: the mean of ``num_lives`` lives of :func:`imrl_jax.agent.lifetime.make_evaluate`, jitted.

    Life ``l`` of the batch is ``make_evaluate(config)(split(key, num_lives)[l], params, genomes)``.
    ``params`` None: ``config.learning_params()`` (the values of a :func:`learning_cut` config).
    """
    evaluate = make_evaluate(config)
    params = config.learning_params() if params is None else params
    return jax.jit(from_lives(lambda key, genomes: evaluate(key, params, genomes).fitness, num_lives))


def fitness_in_chunks(fitness_fn: FitnessFn, size: int) -> FitnessFn:
    """``fitness_fn`` applied on the host to at most ``size`` genomes at a time (padded), so that one program serves
    every batch of a measure (chunk ``i`` lives from ``fold_in(key, i)``)."""
    def fn(key, genomes):
        genomes = np.asarray(genomes)
        n = len(genomes)
        padded = np.concatenate([genomes, np.repeat(genomes[-1:], (-n) % size, 0)])
        parts = [fitness_fn(jax.random.fold_in(key, i), padded[i * size:(i + 1) * size])
                 for i in range(len(padded) // size)]
        return Estimate(*(jnp.concatenate(x)[:n] for x in zip(*parts)))

    return fn


def random_genomes(key: jax.Array, config: Config, num_genomes: int) -> jnp.ndarray:
    """(num_genomes, genes) drawn as the GA draws generation 0: uniform in [-init_scale, init_scale]."""
    # The GA's own draw; one parent makes any population size pass the config's checks.
    return ga.init_population(key, config.replace(population_size=num_genomes, num_parents=1, num_elites=0))


class RandomFitness(NamedTuple):
    """The fitness distribution of random genomes."""

    fitness: jnp.ndarray  # (N,): each genome's mean over its lives
    se: jnp.ndarray  # (N,)
    mean: jnp.ndarray  # ()
    std: jnp.ndarray  # (): of the means (ddof 1), the lives' noise included
    noise_variance: jnp.ndarray  # (): mean se^2, the part of std^2 that the lives' noise explains
    quantiles: jnp.ndarray  # (len(QUANTILES),)
    share_zero: jnp.ndarray  # (): share of genomes at fitness 0 (for the model: no reach in any life)


def random_fitness(key: jax.Array, fitness_fn: FitnessFn, config: Config, num_genomes: int) -> RandomFitness:
    """The fitness of ``num_genomes`` genomes drawn as generation 0."""
    key_genomes, key_fitness = jax.random.split(key)
    estimate = fitness_fn(key_fitness, random_genomes(key_genomes, config, num_genomes))
    f = estimate.mean
    mean, variance = _moments(f, 0)
    return RandomFitness(f, estimate.se, mean, jnp.sqrt(variance), (estimate.se ** 2).mean(),
                         jnp.quantile(f, jnp.array(QUANTILES)), (f == 0).mean())


class MutationEffects(NamedTuple):
    """Fitness(mutant) - fitness(parent) for M parents and K mutants each, classified beyond the noise."""

    mutants: jnp.ndarray  # (M, K, genes)
    parent: jnp.ndarray  # (M,): each parent's mean over its lives
    parent_se: jnp.ndarray  # (M,)
    mutant: jnp.ndarray  # (M, K)
    mutant_se: jnp.ndarray  # (M, K)
    effect: jnp.ndarray  # (M, K): mutant - parent
    se: jnp.ndarray  # (M, K): of the effect, sqrt(parent_se^2 + mutant_se^2)
    neutral: jnp.ndarray  # (M, K) bool: |effect| <= z se
    deleterious: jnp.ndarray  # (M, K) bool: effect < -z se
    beneficial: jnp.ndarray  # (M, K) bool: effect > z se
    share_neutral: jnp.ndarray  # ()
    share_deleterious: jnp.ndarray  # ()
    share_beneficial: jnp.ndarray  # ()
    mean: jnp.ndarray  # (): of the effects
    variance: jnp.ndarray  # (): of the effects (ddof 1), the lives' noise included
    noise_variance: jnp.ndarray  # (): mean se^2, the part of the variance that the lives' noise explains


def mutation_effects(key: jax.Array, fitness_fn: FitnessFn, config: Config, parents: jnp.ndarray,
                     num_mutants: int, z: float = 2.0) -> MutationEffects:
    """Live ``parents`` (M, genes) and ``num_mutants`` mutants of each (:func:`imrl_jax.evolution.ga.mutate`, the config's
    probability and size), all with fresh lives, and classify each effect against ``z`` standard errors."""
    key_mutate, key_fitness = jax.random.split(key)
    m, genes = parents.shape
    mutants = ga.mutate(key_mutate, config, jnp.repeat(parents, num_mutants, axis=0))
    # Parents and mutants live in one batch: one compilation, and every life runs in parallel.
    estimate = fitness_fn(key_fitness, jnp.concatenate([parents, mutants]))
    parent, parent_se = estimate.mean[:m], estimate.se[:m]
    mutant, mutant_se = (x[m:].reshape(m, num_mutants) for x in estimate)
    effect = mutant - parent[:, None]
    se = jnp.sqrt(parent_se[:, None] ** 2 + mutant_se ** 2)
    threshold = z * se
    neutral, deleterious, beneficial = jnp.abs(effect) <= threshold, effect < -threshold, effect > threshold
    mean, variance = _moments(effect.reshape(-1), 0)
    return MutationEffects(mutants.reshape(m, num_mutants, genes), parent, parent_se, mutant, mutant_se, effect, se,
                           neutral, deleterious, beneficial, neutral.mean(), deleterious.mean(), beneficial.mean(),
                           mean, variance, (se ** 2).mean())


def neutral_rate(z: float, num_lives: int) -> jnp.ndarray:
    """The chance that a mutation of no effect is classified neutral, lives with normal noise of one variance.

    The effect over its standard error is then Student's t with 2 (num_lives - 1) degrees of freedom (the
    pooled two-sample t: both genomes live ``num_lives`` lives), so the rate is P(|t| <= z).
    """
    df = 2.0 * (num_lives - 1)
    return 1.0 - jax.scipy.special.betainc(df / 2.0, 0.5, df / (df + z * z))


class Evolvability(NamedTuple):
    """What each parent's offspring offer selection."""

    offspring_variance: jnp.ndarray  # (M,): of the K offspring's mean fitness (ddof 1)
    noise_variance: jnp.ndarray  # (M,): mean of the offspring's se^2
    mutational_variance: jnp.ndarray  # (M,): offspring_variance - noise_variance (unbiased; < 0 by chance)
    share_better: jnp.ndarray  # (M,): share of offspring beneficial (better beyond the noise)
    mean_mutational_variance: jnp.ndarray  # ()
    mean_share_better: jnp.ndarray  # ()


def evolvability(effects: MutationEffects) -> Evolvability:
    """The offspring fitness variance and the share of offspring better than their parent (no new lives)."""
    offspring = _moments(effects.mutant, 1)[1]
    # A mean of lives varies by se^2 around the genome's fitness even where mutations change nothing.
    noise = (effects.mutant_se ** 2).mean(1)
    better = effects.beneficial.mean(1)
    return Evolvability(offspring, noise, offspring - noise, better, (offspring - noise).mean(), better.mean())


class Walks(NamedTuple):
    """The fitness along W random mutation walks of T steps, the start included."""

    fitness: jnp.ndarray  # (W, T + 1)
    se: jnp.ndarray  # (W, T + 1)


def random_walks(key: jax.Array, fitness_fn: FitnessFn, config: Config, starts: jnp.ndarray,
                 length: int) -> Walks:
    """From each of ``starts`` (W, genes), ``length`` steps each one application of :func:`imrl_jax.evolution.ga.mutate`."""
    key_walk, key_fitness = jax.random.split(key)

    def step(genomes, key_step):
        following = ga.mutate(key_step, config, genomes)
        return following, following

    _, steps = jax.lax.scan(step, starts, jax.random.split(key_walk, length))  # (T, W, genes)
    # The walk's genomes are lived in one batch after the scan, not step by step inside it, so that
    # every life of every step runs in parallel: (W, T + 1, genes) genomes are small beside their lives.
    genomes = jnp.concatenate([starts[None], steps]).swapaxes(0, 1)
    estimate = fitness_fn(key_fitness, genomes.reshape(-1, starts.shape[1]))
    return Walks(*(x.reshape(starts.shape[0], length + 1) for x in estimate))


class Ruggedness(NamedTuple):
    """The autocorrelation of fitness along mutation walks at lags 1..k, and the correlation length."""

    rho: jnp.ndarray  # (k,): NaN on a flat landscape (no variance to correlate)
    rho_noise_corrected: jnp.ndarray  # (k,): the autocovariance over (variance - noise_variance)
    correlation_length: jnp.ndarray  # (): -1 / ln rho(1)
    correlation_length_noise_corrected: jnp.ndarray  # ()
    variance: jnp.ndarray  # (): of every walk's fitness about their common mean
    noise_variance: jnp.ndarray  # (): mean se^2


def correlation_length(rho1) -> jnp.ndarray:
    """-1 / ln rho(1): the steps over which fitness stays correlated (inf at rho(1) >= 1, 0 at rho(1) <= 0)."""
    rho1 = jnp.asarray(rho1, float)
    inside = -1.0 / jnp.log(jnp.clip(rho1, jnp.finfo(rho1.dtype).tiny, 1.0 - jnp.finfo(rho1.dtype).eps))
    return jnp.where(rho1 >= 1.0, jnp.inf, jnp.where(rho1 <= 0.0, 0.0, inside))  # NaN stays NaN


def ruggedness(walks: Walks, max_lag: int) -> Ruggedness:
    """Weinberger's autocorrelation rho(s) = cov(f_t, f_{t+s}) / var(f), the walks pooled, s = 1..max_lag."""
    f = walks.fitness
    if not 1 <= max_lag < f.shape[1]:
        raise ValueError(f"max_lag: must be in [1, {f.shape[1] - 1}], the walks' length (got {max_lag})")
    # The walks are samples of one landscape: one mean and one variance for all of them.
    centred = f - _moments(f.reshape(-1), 0)[0]
    variance = (centred ** 2).mean()
    covariance = jnp.stack([(centred[:, :-s] * centred[:, s:]).mean() for s in range(1, max_lag + 1)])
    # Each point lives its own lives: their noise adds to the variance but to no covariance at lag >= 1.
    noise = (walks.se ** 2).mean()
    rho, corrected = covariance / variance, covariance / (variance - noise)
    return Ruggedness(rho, corrected, correlation_length(rho[0]), correlation_length(corrected[0]), variance, noise)


def learning_cut(config: Config, fraction: float = 0.0, adult: bool | None = None) -> Config:
    """``config`` whose lives learn ``fraction`` of what they learn, for the hypothesis that learning smooths the
    landscape (docs/GOALS.md "Learning cut"); pass it to :func:`lives_fitness` with ``params`` None.

    A childhood lasts ``fraction`` of its steps (a whole number of bins); where that is no bin, it lasts one bin
    in which nothing learns (the engine needs a childhood of at least a bin). The adult learning rates (the
    selector's; the experts' where they learn in adulthood) are multiplied by ``fraction`` where ``adult`` is
    true; ``adult`` None: only in conditions without a childhood (EE-LS: the selector learns nothing at 0).
    A condition in which nothing learns (EE-ES) is returned as it is.
    """
    if not 0.0 <= fraction <= 1.0:
        raise ValueError(f"fraction: must be in [0, 1] (got {fraction!r})")
    spec = config.spec
    adult = not spec.has_childhood if adult is None else adult
    changes = {}
    bins = round(fraction * config.childhood_steps / config.num_bins) if spec.has_childhood else None
    if bins is not None:
        changes["childhood_steps"] = max(bins, 1) * config.num_bins
    zero_rates = bins == 0
    scaled_rates = adult and (spec.adult.selector_learns or spec.adult.experts_learn)
    # An evolved-parameters genome replaces the config's rates with its own: they cannot be cut here.
    if "parameters" in spec.genome and (zero_rates or scaled_rates):
        raise ValueError(f"learning_cut: {config.condition}'s genome carries its learning rates; cut only its "
                         "childhood's length (fraction > 0, adult=False)")
    if zero_rates:
        changes.update(eta_actor=0.0, eta_evaluator=0.0, childhood_eta_selector_actor=0.0,
                       childhood_eta_selector_critic=0.0)
    if adult and spec.adult.selector_learns:
        changes.update(eta_selector_actor=fraction * config.eta_selector_actor,
                       eta_selector_critic=fraction * config.eta_selector_critic)
    if adult and spec.adult.experts_learn:
        changes.update(eta_actor=fraction * changes.get("eta_actor", config.eta_actor),
                       eta_evaluator=fraction * changes.get("eta_evaluator", config.eta_evaluator))
    return config.replace(**changes)


def summary(effects: MutationEffects, rugged: Ruggedness) -> dict:
    """The numbers of one measure around a population (a piece of ``landscape_run``): mutation effects,
    evolvability and ruggedness, None where not finite."""
    evo = evolvability(effects)
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
