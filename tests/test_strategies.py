"""Search strategies behind init/ask/tell: the evosax adapter (shapes, maximisation, bad names) and the GA by name."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from imrl_jax import search, strategies
from imrl_jax.config import ConfigError, make_config

pytest.importorskip("evosax")


def _config():
    return make_config("paper", condition="EE-LS", population_size=16, num_parents=4)


@pytest.mark.parametrize("name", ["sep_cma_es", "snes"])
def test_an_evosax_strategy_maximises_the_fitness_it_is_told(name):
    """On fitness = -|x - 0.5|^2 the mean moves towards 0.5 in every gene: the adapter maximises."""
    config = _config()
    strategy = strategies.make_strategy(name, config)
    params = strategy.default_params()
    assert float(params.std_init) == pytest.approx(1 / np.sqrt(3))  # the paper's U[-1, 1] start
    state = strategy.init(jax.random.key(0), params)

    def one(state, g):
        key = jax.random.fold_in(jax.random.key(1), g)
        genomes, state = strategy.ask(key, state, params)
        fitness = -jnp.sum((genomes - 0.5) ** 2, axis=1)
        state, _ = strategy.tell(key, genomes, fitness, state, params)
        return state, (genomes.shape, fitness.max())

    first, _ = one(state, 0)
    genomes, _ = strategy.ask(jax.random.key(2), state, params)
    assert genomes.shape == (16, config.num_genes)
    state, (shapes, best) = jax.lax.scan(one, state, jnp.arange(60))
    assert float(best[-1]) > float(best[0])
    mean = np.asarray(strategy.algorithm.get_mean(state))
    assert abs(mean.mean() - 0.5) < 0.15, mean.mean()


def test_strategies_by_name_and_bad_input():
    config = _config()
    assert type(strategies.make_strategy("ga", config)).__name__ == "GA"
    with pytest.raises(ConfigError, match="unknown strategy 'cmaes'"):
        strategies.make_strategy("cmaes", config)
    with pytest.raises(ConfigError, match="strategy snes: sigma is not a parameter"):
        strategies.make_strategy("snes", config, {"sigma": 0.1})
    assert float(strategies.make_strategy("snes", config, {"std_init": 0.2}).default_params().std_init) == \
        pytest.approx(0.2)


def test_an_evosax_strategy_runs_the_shared_generation_step(tiny):
    """search.generation with Sep-CMA-ES: one tiny generation of lives, the state's generation counter moves on."""
    from imrl_jax.lifetime import live

    config = tiny("EE-ES", population_size=4, num_parents=2, task_steps=60, num_bins=1)
    strategy = strategies.make_strategy("sep_cma_es", config)
    params = strategy.default_params()
    state = strategy.init(jax.random.key(0), params)
    state, result = jax.jit(lambda s: search.generation(jax.random.key(3), strategy,
                                                        lambda k, g: live(k, config, config.learning_params(), g),
                                                        s, params, 0))(state)
    assert result.genomes.shape == (4, config.num_genes) and result.fitness.shape == (4,)
    assert int(state.generation_counter) == 1
