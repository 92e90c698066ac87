"""Search strategies beside the paper's GA (section 2 "Genetic algorithm"): evosax's evolution strategies.

A strategy here has the interface of :mod:`imrl_jax.search` (``default_params``, ``init``,
``ask``, ``tell``; fitness maximised). :data:`STRATEGIES` names the offered evosax
algorithms; :func:`make_strategy` builds one for a config: the paper's GA (``"ga"``, the
default, :class:`imrl_jax.ga.GA`) or an evosax strategy (:class:`Evosax`), whose initial
mean and spread match the paper's U[-init_scale, init_scale] start (mean 0, sd
init_scale / sqrt(3)). evosax minimises: :class:`Evosax` negates the fitness it tells it.

evosax is an optional dependency (``pip install -e ".[evosax]"``), imported only when an
evosax strategy is built.
"""

from __future__ import annotations

import dataclasses
import functools
import math

import jax
import jax.numpy as jnp

from imrl_jax.config import Config, ConfigError
from imrl_jax.search import split_search_key

#: The evosax strategies offered, by the name ``--strategy`` takes: distribution-based ones suited to a
#: hundred or a few hundred genes and 50 lives a generation.
STRATEGIES = {"sep_cma_es": "Sep_CMA_ES", "cma_es": "CMA_ES", "snes": "SNES", "xnes": "xNES", "open_es": "Open_ES",
              "pgpe": "PGPE"}
#: The paper's genetic algorithm, by the name ``--strategy`` takes (the default), and what a run records of it (also
#: what a run made before ``--strategy`` existed was evolved with).
GA_NAME = "ga"
GA_RECORD = {"strategy": GA_NAME, "settings": {}}


def _import_evosax():
    try:
        import evosax.algorithms
    except ImportError as error:
        raise ConfigError("strategy: evosax strategies need the evosax extra: pip install -e \".[evosax]\" "
                          f"({error})") from None
    return evosax.algorithms


@functools.lru_cache(maxsize=16)
def _algorithm(name: str, population_size: int, num_genes: int):
    """One evosax algorithm object per (name, sizes): its jitted methods take it as a static argument."""
    algorithms = _import_evosax()
    return getattr(algorithms, STRATEGIES[name])(population_size=population_size, solution=jnp.zeros(num_genes))


@dataclasses.dataclass(frozen=True)
class Evosax:
    """An evosax evolution strategy behind the search interface (fitness maximised)."""

    name: str
    population_size: int
    num_genes: int
    init_scale: float = 1.0  # the paper's U[-1, 1] start: mean 0, sd init_scale / sqrt(3)
    settings: tuple = ()  # (field, value) pairs replacing evosax's default params

    @property
    def algorithm(self):
        return _algorithm(self.name, self.population_size, self.num_genes)

    def default_params(self):
        """evosax's defaults, with the initial spread of the paper's start and the given settings."""
        params = self.algorithm.default_params
        changes = dict(self.settings)
        if hasattr(params, "std_init") and "std_init" not in changes:
            changes["std_init"] = self.init_scale / math.sqrt(3.0)
        unknown = [k for k in changes if not hasattr(params, k)]
        if unknown:
            fields = ", ".join(f.name for f in dataclasses.fields(params))
            raise ConfigError(f"strategy {self.name}: {unknown[0]} is not a parameter (choose from {fields})")
        return params.replace(**{k: jnp.asarray(v, jnp.float32) for k, v in changes.items()})

    def init(self, key: jax.Array, params):
        """The search distribution at the paper's start: mean 0."""
        return self.algorithm.init(key, jnp.zeros(self.num_genes), params)

    def ask(self, key: jax.Array, state, params):
        """A population drawn from the search distribution."""
        return self.algorithm.ask(split_search_key(key)[0], state, params)

    def tell(self, key: jax.Array, genomes, fitness, state, params):
        """The distribution moved towards the fitter genomes (evosax minimises: it is told -fitness)."""
        state, metrics = self.algorithm.tell(split_search_key(key)[1], genomes, -fitness, state, params)
        return state, metrics


def make_strategy(name: str, config: Config, settings: dict | None = None):
    """The search strategy ``name`` for ``config``'s population and genome: ``"ga"`` (the paper's) or an evosax one."""
    if name == GA_NAME:
        if settings:
            raise ConfigError("strategy ga: its settings are config fields (mutation_prob, mutation_scale, ...); "
                              "use --set")
        from imrl_jax.ga import GA

        return GA(config)
    if name not in STRATEGIES:
        raise ConfigError(f"strategy: unknown strategy {name!r} (choose from {GA_NAME}, {', '.join(STRATEGIES)})")
    strategy = Evosax(name, config.population_size, config.num_genes, config.init_scale,
                      tuple(sorted((settings or {}).items())))
    strategy.default_params()  # checks the settings now: one line naming a bad one
    return strategy


def describe(strategy) -> dict:
    """What a run records of its strategy (config.json's ``search``): its name and the settings given."""
    if isinstance(strategy, Evosax):
        return {"strategy": strategy.name, "settings": dict(strategy.settings)}
    return GA_RECORD


def parse_settings(items) -> dict:
    """``--strategy-set FIELD=VALUE`` items as {field: float} (raises ConfigError naming a bad one)."""
    settings = {}
    for item in items or ():
        name, sep, value = item.partition("=")
        try:
            settings[name.strip()] = float(value)
        except ValueError:
            sep = ""
        if not sep or not name.strip():
            raise ConfigError(f"--strategy-set: expected FIELD=NUMBER, got {item!r}")
    return settings
