"""Parameter sweeps of the learning rules (section 2 "Learning") and the GA (section 2 "Genetic algorithm").

The values MODEL.md lets a researcher vary split in two kinds:

* **dynamic** values are arguments of the compiled program, so a whole grid of them runs
  as one ``vmap`` in one compilation: the :class:`~imrl_jax.config.LearningParams`
  (discount ``gamma``, ``trace_lambda``, the learning rates, the childhood noise
  ``noise_std``; ``eta`` here sets every rate at once, childhood's included: the paper's single rate) and
  the GA's mutation (``mutation_prob``, ``mutation_scale``, see :class:`GAParams`);
* **static** values fix shapes or loop lengths (``childhood_steps``, ``task_steps``,
  ``num_experts``, ``population_size``, ...): every value is its own compilation
  (:func:`evolve_static` loops over them and says so).

A sweep point is a :class:`SweepPoint` (learning values + GA values); a :class:`Sweep`
holds a batch of them with a leading axis V and the settings each one varies.
:func:`make_evolution_sweep` runs a short evolution for every point and seed at once, with
the same keys as ``python -m imrl_jax.evolve``: a one-point program at the config's own
values (:func:`evolve_points`) gives exactly that command's run. A batch of several points
is another compiled program, which rounds a few operations differently; over long lives
such differences can send single lives elsewhere, so the same values in different batches
agree statistically, not bit for bit (within one program they are reproducible).
:func:`make_lifetime_sweep` lives one population under every point (the same keys for
every point, so only the values differ).
"""

from __future__ import annotations

import dataclasses
import functools
import itertools
import math
from typing import Callable, NamedTuple, Sequence

import jax
import jax.numpy as jnp
import numpy as np

from imrl_jax.config import UsageError
from imrl_jax.world.worlds import task_maxima
from imrl_jax.config import Config, LearningParams
from imrl_jax.evolution import search
from imrl_jax.evolution.ga import GA, GAParams
from imrl_jax.agent.lifetime import live

#: Learning rates set together by the pseudo-field ``eta`` (the paper has one rate).
ETA_FIELDS = ("eta_actor", "eta_evaluator", "eta_selector_actor", "eta_selector_critic",
              "childhood_eta_selector_actor", "childhood_eta_selector_critic")


class SweepPoint(NamedTuple):
    """One point of a sweep: learning values and GA values (a pytree of scalars)."""

    params: LearningParams
    ga: GAParams


@dataclasses.dataclass(frozen=True)
class Sweep:
    """A batch of V points (leading axis V on every leaf) and what each one sets."""

    points: SweepPoint
    settings: tuple  # V dicts {field: value} of the fields the point varies

    def __len__(self) -> int:
        return len(self.settings)


class EvolutionCurves(NamedTuple):
    """What a short evolution reports per point and seed (leading axes (V, S) in a sweep)."""

    best: jnp.ndarray  # (G,) best fitness of each generation
    mean: jnp.ndarray  # (G,) mean fitness of each generation
    best_performance: jnp.ndarray  # (G, tasks) task performances of each generation's best
    best_reward_curve: jnp.ndarray  # (G, tasks, bins) reaches per bin of each generation's best
    best_childhood_selections: jnp.ndarray  # (G, bins, K) steps each expert led in childhood
    final_evaluated: jnp.ndarray  # (P, genes) the last evaluated population
    final_fitness: jnp.ndarray  # (P,) its fitness


DYNAMIC_FIELDS = LearningParams._fields + GAParams._fields + ("eta",)


#: At most this many points in a sweep of the evolve command (each is a run directory and a checkpoint per generation).
MAX_POINTS = 1000


def parse(items: Sequence[str], zipped: bool = False) -> list[dict]:
    """The points of ``--sweep FIELD=V1,V2,...`` options: their product, or with ``zipped`` their values in step.

    Raises UsageError naming the option and the field (unknown, static, repeated, unreadable value).
    """
    values: dict[str, list[float]] = {}
    for item in items:
        field, sep, text = item.partition("=")
        field = field.strip()
        if not sep or not text.strip():
            raise UsageError(f"--sweep: expected FIELD=V1,V2,... (got {item!r})")
        if field not in DYNAMIC_FIELDS:
            if field in {f.name for f in dataclasses.fields(Config)}:
                raise UsageError(f"--sweep: {field} is static (it changes the program's shapes or loop lengths): "
                                 f"evolve once per value; sweepable: {', '.join(DYNAMIC_FIELDS)}")
            raise UsageError(f"--sweep: unknown field {field!r} (sweepable: {', '.join(DYNAMIC_FIELDS)})")
        if field in values:
            raise UsageError(f"--sweep: {field} is given twice (give its values once, comma-separated)")
        texts = [v.strip() for v in text.split(",")]
        values[field] = [swept_value(field, v, text) for v in texts]
        if not zipped:  # in step, a value may come again beside others
            for i, value in enumerate(values[field]):
                if value in values[field][:i]:
                    raise UsageError(f"--sweep: {field}: {texts[values[field].index(value)]} and {texts[i]} are one "
                                     f"value in float32 ({value!r}), one point: give it once")
    if not values:
        raise UsageError("--sweep: give at least one FIELD=V1,V2,...")
    names = list(values)
    if zipped:
        counts = {len(v) for v in values.values()}
        if len(counts) > 1:
            raise UsageError(f"--zip: every --sweep needs as many values ({', '.join(f'{n}: {len(values[n])}' for n in names)})")
        combos = list(zip(*values.values()))
    else:
        combos = list(itertools.product(*values.values()))
    if len(combos) > MAX_POINTS:
        raise UsageError(f"--sweep: {len(combos):,} points; at most {MAX_POINTS:,}")
    return [dict(zip(names, combo)) for combo in combos]


def swept_value(field: str, text: str, given: str = "") -> float:
    """The value a swept number means: the float32 the program computes with, as the shortest decimal that gives it
    (so that ``0.9`` stays ``0.9``, the key of ``--set field=0.9``; ``-0`` and ``1e-320`` are ``0``), refused in one
    line if it is no finite number or beyond float32's range."""
    try:
        value = float(text)
    except ValueError:
        raise UsageError(f"--sweep: {field}: expected numbers separated by commas (got {given or text!r})") from None
    if not math.isfinite(value):
        raise UsageError(f"--sweep: {field}: {text.strip()} is not a finite number")
    with np.errstate(over="ignore", under="ignore"):
        single = np.float32(value)
    if not np.isfinite(single):
        raise UsageError(f"--sweep: {field}: {text.strip()} is beyond the range of float32 (the program's numbers)")
    return float(str(single)) + 0.0  # + 0.0: -0.0 is 0.0


def swept_fields(settings: Sequence[dict]) -> dict[str, str]:
    """Every config field the points set: field -> the swept name that sets it (``eta`` sets every rate)."""
    found = {}
    for values in settings:
        for name in values:
            found.update({field: name for field in (ETA_FIELDS if name == "eta" else (name,))})
    return found


def changed(config: Config, **values) -> Config:
    """``config`` with some dynamic values changed (``eta`` sets every rate; a static field is a ValueError)."""
    unknown = set(values) - set(DYNAMIC_FIELDS)
    if unknown:
        raise ValueError(f"not a dynamic field: {sorted(unknown)[0]} (choose from {', '.join(DYNAMIC_FIELDS)}; "
                         f"static fields need one compilation per value: see evolve_static)")
    values = dict(values)
    if "eta" in values:
        eta = values.pop("eta")
        values = {**{f: eta for f in ETA_FIELDS}, **values}
    return config.replace(**values)  # validates every value


def static_part(config: Config) -> Config:
    """``config`` with every dynamic value at its default: what the compiled program of a life is made of (the
    dynamic values are its arguments), so configs of one ``static_part`` share one program."""
    defaults = {f.name: f.default for f in dataclasses.fields(Config) if f.name in DYNAMIC_FIELDS}
    return config.replace(**defaults)


def point(config: Config, **values) -> SweepPoint:
    """The sweep point of ``config`` with some dynamic values changed (``eta`` sets every rate)."""
    changed_config = changed(config, **values)
    params = changed_config.learning_params()
    ga = GAParams(changed_config.mutation_prob, changed_config.mutation_scale)
    return SweepPoint(jax.tree.map(lambda v: jnp.asarray(v, jnp.float32), params),
                      jax.tree.map(lambda v: jnp.asarray(v, jnp.float32), ga))


def stack(points: Sequence[SweepPoint]) -> SweepPoint:
    """Points stacked along a new leading axis."""
    return jax.tree.map(lambda *xs: jnp.stack(xs), *points)


def from_settings(config: Config, settings: Sequence[dict]) -> Sweep:
    """A sweep of the given settings, each a dict of dynamic fields changed from ``config``."""
    settings = tuple(dict(s) for s in settings)
    if not settings:
        raise ValueError("a sweep needs at least one point")
    return Sweep(stack([point(config, **s) for s in settings]), settings)


def grid(config: Config, **values: Sequence[float]) -> Sweep:
    """Every combination of the given values (a full factorial design)."""
    names = list(values)
    return from_settings(config, [dict(zip(names, combo)) for combo in itertools.product(*values.values())])


def one_at_a_time(config: Config, values: dict) -> Sweep:
    """Each field varied alone over its values, the others at the config's (V = total number of values)."""
    return from_settings(config, [{name: v} for name, vs in values.items() for v in vs])


def indices(sweep: Sweep, field: str) -> list[int]:
    """The points of ``sweep`` that set ``field``, in order of its value."""
    found = [i for i, s in enumerate(sweep.settings) if field in s]
    return sorted(found, key=lambda i: sweep.settings[i][field])


def pad(points: SweepPoint, size: int) -> SweepPoint:
    """Points padded to ``size`` by repeating the last (to reuse a program compiled for ``size``)."""
    n = jax.tree.leaves(points)[0].shape[0]
    if n > size:
        raise ValueError(f"{n} points do not fit a sweep of {size}")
    return jax.tree.map(lambda x: jnp.concatenate([x, jnp.repeat(x[-1:], size - n, 0)]), points)


def run_padded(fn: Callable, points: SweepPoint, size: int, *args):
    """``fn(*args, points)`` with points padded to ``size``, results cut back to the real points."""
    n = jax.tree.leaves(points)[0].shape[0]
    out = fn(*args, pad(points, size))
    return jax.tree.map(lambda x: x[:n], out)


# ----------------------------------------------------------------------------- lifetimes


def make_lifetime_sweep(config: Config):
    """A jitted ``fn(key, genomes (P, genes), points (V,)) -> LifetimeResult`` with axes (V, P, ...).

    Every point lives the same individuals with the same keys (common random numbers).
    """

    def lives(key, genomes, points):
        keys = jax.random.split(key, genomes.shape[0])

        def population(params):
            return jax.vmap(lambda k, g: live(k, config, params, g))(keys, genomes)

        return jax.vmap(population)(points.params)

    return jax.jit(lives)


# ----------------------------------------------------------------------------- evolution


def evolve_one(config: Config, num_generations: int, seed_key: jax.Array, sweep_point: SweepPoint) -> EvolutionCurves:
    """A short evolution of one seed at one point, with the keys of ``python -m imrl_jax.evolve``."""
    strategy = GA(config)
    state = strategy.init(jax.random.fold_in(seed_key, 0))
    key = jax.random.fold_in(seed_key, 1)
    params = sweep_point.params

    def generation(carry, g):
        state, _, _ = carry
        state, result = search.generation(key, strategy, lambda k, genome: live(k, config, params, genome), state,
                                          sweep_point.ga, g)
        best, life = result.info[0], jax.tree.map(lambda x: x[:, 0], result.lives)  # parents best first; one life
        stats = (result.fitness.max(), result.fitness.mean(), life.performance[best],
                 life.reward_curve[best], life.childhood_selections[best])
        return (state, result.genomes, result.fitness), stats

    population = state.population
    start = (state, population, jnp.zeros((config.population_size,), population.dtype))
    (_, evaluated, fitness), stats = jax.lax.scan(generation, start, jnp.arange(num_generations))
    return EvolutionCurves(*stats, evaluated, fitness)


def make_evolution_sweep(config: Config, num_generations: int | None = None):
    """A jitted ``fn(seeds (S,), points (V,)) -> EvolutionCurves`` with axes (V, S, ...).

    ``seeds`` are integers (the evolve command's ``--seeds``); generations default to
    ``config.num_generations``. One compilation serves any points and seeds of the same counts.
    """
    if config.lives_per_fitness != 1:
        raise ValueError(f"lives_per_fitness: evolution sweeps score one life per individual "
                         f"(got {config.lives_per_fitness}); use python -m imrl_jax.evolve for more")
    num_generations = config.num_generations if num_generations is None else num_generations

    def sweep(seeds, points):
        keys = jax.vmap(jax.random.key)(seeds.astype(jnp.uint32))
        per_seed = jax.vmap(lambda k, p: evolve_one(config, num_generations, k, p), (0, None))
        return jax.vmap(lambda p: per_seed(keys, p))(points)

    return jax.jit(sweep)


@functools.lru_cache(maxsize=32)
def cached_evolution_sweep(config: Config, num_generations: int | None = None):
    """:func:`make_evolution_sweep`, built once per config (so its compilations are reused)."""
    return make_evolution_sweep(config, num_generations)


def evolve_points(config: Config, settings: Sequence[dict], seeds: Sequence[int]) -> list[EvolutionCurves]:
    """Short evolutions at a few points, one after the other, with the config's one-point program.

    The program is compiled once per config and shape (:func:`cached_evolution_sweep`), so
    further calls with any values reuse it. Returns one :class:`EvolutionCurves` per
    point, with axes (S, ...).
    """
    fn = cached_evolution_sweep(config)
    return [jax.tree.map(lambda x: np.asarray(x[0]), fn(jnp.asarray(seeds), stack([point(config, **s)])))
            for s in settings]


def evolve_static(config: Config, field: str, values: Sequence, seeds: Sequence[int],
                  **dynamic) -> list[EvolutionCurves]:
    """Short evolutions for each value of a static field: one compilation per value.

    Returns one :class:`EvolutionCurves` per value, with axes (S, ...) (shapes may differ
    between values, e.g. genes with ``num_experts``). ``dynamic`` sets dynamic values.
    A value equal to the config's reuses the program of :func:`evolve_points`.
    """
    return [evolve_points(config.replace(**{field: value}), [dynamic], seeds)[0] for value in values]


# ----------------------------------------------------------------------------- curves


def bin_maximum(config: Config) -> np.ndarray:
    """(tasks,) the theoretical maximum of reaches in one bin of a task."""
    return task_maxima(config) / config.num_bins


def normalised_curve(config: Config, reward_curve) -> np.ndarray:
    """Reaches per bin (..., tasks, bins) divided by the bin's theoretical maximum (task performance per bin)."""
    return np.asarray(reward_curve, float) / bin_maximum(config)[:, None]


def describe(settings: dict) -> str:
    """A short label of a point's settings, e.g. ``eta=0.01, gamma=0.99``."""
    return ", ".join(f"{k}={v:g}" if isinstance(v, (int, float)) else f"{k}={v}" for k, v in settings.items())


def fields(sweep: Sweep) -> list[str]:
    """The fields a sweep varies, in order of first appearance."""
    return list(dict.fromkeys(name for s in sweep.settings for name in s))


def summary(sweep: Sweep, curves: EvolutionCurves, generation: int = -1) -> dict:
    """``{field: (values (n,), best fitness (n, seeds))}`` at a generation, for :func:`charts.plot_sweep_summary`."""
    best = np.asarray(curves.best)[..., generation]  # (V, S)
    out = {}
    for name in fields(sweep):
        found = indices(sweep, name)
        out[name] = (np.asarray([sweep.settings[i][name] for i in found], float), best[found])
    return out


def by_field(config: Config, sweep: Sweep, curves: EvolutionCurves, field: str,
             generation: int = -1) -> tuple[dict, dict]:
    """The points of one field as plot inputs: fitness curves and the best individuals' learning curves.

    Returns ``({label: best fitness (seeds, G)}, {label: performance per bin (tasks, bins)})``,
    the learning curves those of each generation's best at ``generation``, averaged over seeds.
    """
    fitness, learning = {}, {}
    for i in indices(sweep, field):
        label = describe(sweep.settings[i])
        fitness[label] = np.asarray(curves.best[i])
        learning[label] = normalised_curve(config, np.asarray(curves.best_reward_curve[i])[:, generation]).mean(0)
    return fitness, learning
