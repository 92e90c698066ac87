"""Search strategies beside the paper's GA (section 2 "Genetic algorithm"): evosax's evolution strategies.

A strategy here has the interface of :mod:`imrl_jax.evolution.search` (``default_params``, ``init``,
``ask``, ``tell``; fitness maximised). :data:`STRATEGIES` names the offered evosax
algorithms; :func:`make_strategy` builds one for a config: the paper's GA (``"ga"``, the
default, :class:`imrl_jax.evolution.ga.GA`) or an evosax strategy (:class:`Evosax`), whose initial
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
from imrl_jax.evolution.search import split_search_key

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


#: Strategies whose spread is not a parameter but a schedule given when the algorithm is built (Open-ES's
#: ``std_schedule``): here a constant ``std_init``, set like the others' parameter.
SCHEDULED_STD = ("open_es",)


@functools.lru_cache(maxsize=16)
def _algorithm(name: str, population_size: int, num_genes: int, std: float | None = None):
    """One evosax algorithm object per (name, sizes, scheduled spread): its jitted methods take it as static."""
    algorithms = _import_evosax()
    options = {}
    if name in SCHEDULED_STD:
        import optax

        options["std_schedule"] = optax.constant_schedule(std)
    return getattr(algorithms, STRATEGIES[name])(population_size=population_size, solution=jnp.zeros(num_genes),
                                                 **options)


@dataclasses.dataclass(frozen=True)
class Evosax:
    """An evosax evolution strategy behind the search interface (fitness maximised)."""

    name: str
    population_size: int
    num_genes: int
    init_scale: float = 1.0  # the paper's U[-1, 1] start: mean 0, sd init_scale / sqrt(3)
    settings: tuple = ()  # (field, value) pairs replacing evosax's default params

    @property
    def std_init(self) -> float:
        """The initial spread: the setting ``std_init`` if given, else the paper's init_scale / sqrt(3)."""
        return float(dict(self.settings).get("std_init", self.init_scale / math.sqrt(3.0)))

    @property
    def algorithm(self):
        return _algorithm(self.name, self.population_size, self.num_genes,
                          self.std_init if self.name in SCHEDULED_STD else None)

    def default_params(self):
        """evosax's defaults, with the initial spread of the paper's start and the given settings."""
        params = self.algorithm.default_params
        changes = dict(self.settings)
        if self.name in SCHEDULED_STD:
            changes.pop("std_init", None)  # built into the algorithm's schedule
        elif hasattr(params, "std_init"):
            changes["std_init"] = self.std_init
        settable = [f.name for f in dataclasses.fields(params) if jnp.ndim(getattr(params, f.name)) == 0]
        settable += ["std_init"] if self.name in SCHEDULED_STD else []
        for name, value in dict(self.settings).items():
            if name not in settable:
                kind = "a scalar parameter" if hasattr(params, name) else "a parameter"
                raise ConfigError(f"strategy {self.name}: {name} is not {kind} (choose from {', '.join(settable)})")
            positive = name == "std_init" or name.startswith("lr_")  # a spread or a rate
            if not math.isfinite(value) or (positive and value <= 0):
                raise ConfigError(f"strategy {self.name}: {name} must be a finite number{' > 0' if positive else ''}, "
                                  f"got {value}")
        return params.replace(**{k: jnp.asarray(v, jnp.float32) for k, v in changes.items()})

    def init(self, key: jax.Array, params):
        """The search distribution at the paper's start: mean 0."""
        state = self.algorithm.init(key, jnp.zeros(self.num_genes), params)
        if self.name == "xnes":
            # xNES samples mean + std z B with B of determinant 1 at the start (Glasmachers et al. 2010); evosax
            # 0.3.2 starts B at std_init I, which makes the first spread std_init^2 (0.33, not the paper's 0.577).
            state = state.replace(B=jnp.eye(self.num_genes, dtype=state.B.dtype))
        return state

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
            raise ConfigError("--strategy-set: strategy ga's settings are config fields (mutation_prob, "
                              "mutation_scale, ...); use --set")
        from imrl_jax.evolution.ga import GA

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
