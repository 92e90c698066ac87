"""Search strategies behind init/ask/tell: the evosax adapter (shapes, maximisation, bad names) and the GA by name."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from imrl_jax.evolution import search, strategies
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


@pytest.mark.parametrize("name", list(strategies.STRATEGIES))
def test_every_strategy_starts_at_the_papers_spread(name):
    """The first population asked has mean 0 and sd 1/sqrt(3), the paper's U[-1, 1] genes (Open-ES: its schedule)."""
    config = make_config("paper", condition="LE-LS", population_size=50, num_parents=10)
    strategy = strategies.make_strategy(name, config)
    params = strategy.default_params()
    genomes, _ = strategy.ask(jax.random.key(1), strategy.init(jax.random.key(0), params), params)
    genomes = np.asarray(genomes)
    assert genomes.shape == (50, config.num_genes)
    # 50 x 111 draws: the sd of the sample sd is about 0.577 / sqrt(2 * 5550) = 0.006
    assert abs(genomes.mean()) < 0.03 and genomes.std() == pytest.approx(1 / np.sqrt(3), abs=0.03), genomes.std()
    if name == "open_es":
        wide = strategies.make_strategy(name, config, {"std_init": 0.2})
        params = wide.default_params()
        genomes, _ = wide.ask(jax.random.key(1), wide.init(jax.random.key(0), params), params)
        assert float(np.asarray(genomes).std()) == pytest.approx(0.2, abs=0.01)


def test_without_evosax_an_evosax_strategy_says_how_to_install_it(tmp_path, capsys, monkeypatch):
    """evosax unimportable: --strategy snes exits 2 with one line naming the extra, writing nothing; the GA runs on."""
    from imrl_jax.commands import evolve

    monkeypatch.setitem(__import__("sys").modules, "evosax.algorithms", None)
    strategies._algorithm.cache_clear()
    try:
        out = tmp_path / "run"
        assert evolve.main([*_evolve_args(1, "snes"), "--out", str(out)]) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith('error: strategy: evosax strategies need the evosax extra: pip install -e ".[evosax]"')
        assert "\n" not in err and not out.exists()
        assert type(strategies.make_strategy("ga", _config())).__name__ == "GA"
    finally:
        strategies._algorithm.cache_clear()


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
    from imrl_jax.agent.lifetime import live

    config = tiny("EE-ES", population_size=4, num_parents=2, task_steps=60, num_bins=1)
    strategy = strategies.make_strategy("sep_cma_es", config)
    params = strategy.default_params()
    state = strategy.init(jax.random.key(0), params)
    state, result = jax.jit(lambda s: search.generation(jax.random.key(3), strategy,
                                                        lambda k, g: live(k, config, config.learning_params(), g),
                                                        s, params, 0))(state)
    assert result.genomes.shape == (4, config.num_genes) and result.fitness.shape == (4,)
    assert int(state.generation_counter) == 1


def _evolve_args(generations, strategy=None, *extra):
    from helpers import evolve_args

    args = evolve_args(seeds=2, population=6, parents=2, task_steps=200, childhood_steps=200, bins=1,
                       generations=generations)
    return args + (["--strategy", strategy] if strategy else []) + list(extra)


def test_evolve_with_an_evosax_strategy_resumes_and_extends_bitwise(tmp_path, capsys):
    """--strategy snes: 2 generations then --resume to 3 end as 3 uninterrupted (the strategy's state checkpointed)."""
    from helpers import assert_same_outputs, outputs

    from imrl_jax.commands import evolve

    whole, split = str(tmp_path / "whole"), str(tmp_path / "split")
    assert evolve.main([*_evolve_args(3, "snes", "--strategy-set", "lr_std_init=0.2"), "--out", whole]) == 0
    assert evolve.main([*_evolve_args(2, "snes", "--strategy-set", "lr_std_init=0.2"), "--out", split]) == 0
    assert evolve.main(["--resume", "--out", split, "--generations", "3", "--quiet"]) == 0
    want = outputs(whole)
    assert_same_outputs(outputs(split), want)
    assert len(want["history.csv"].splitlines()) == 1 + 3 * 2
    assert want["config.json"]["search"] == {"strategy": "snes", "settings": {"lr_std_init": 0.2}}
    assert not np.array_equal(want["evaluated"][:, 0], want["evaluated"][:, 1])  # drawn, not copies
    capsys.readouterr()
    for argv, message in ((["--strategy", "ga"], f"error: --strategy: {split} was evolved with snes (lr_std_init=0.2), "
                                                 f"not ga; resume it with its own (leave out --strategy)"),
                          (["--strategy-set", "lr_std_init=0.3"], "not snes (lr_std_init=0.3)")):
        assert evolve.main(["--resume", "--out", split, "--generations", "4", *argv]) == 2
        err = capsys.readouterr().err.strip()
        assert message in err and "\n" not in err
    assert outputs(split)["history.csv"] == want["history.csv"]  # nothing written by the refused resumes


@pytest.mark.parametrize("argv, message", [
    (["--strategy", "cmaes"], "error: strategy: unknown strategy 'cmaes' (choose from ga, sep_cma_es, cma_es, snes, "
                              "xnes, open_es, pgpe)"),
    (["--strategy", "snes", "--strategy-set", "sigma=1"], "error: strategy snes: sigma is not a parameter"),
    (["--strategy", "snes", "--strategy-set", "std_init"], "error: --strategy-set: expected FIELD=NUMBER, got 'std_init'"),
    (["--strategy", "ga", "--strategy-set", "std_init=1"], "error: --strategy-set: strategy ga's settings are config fields"),
    (["--strategy", "snes", "--strategy-set", "weights=1"],
     "error: strategy snes: weights is not a scalar parameter (choose from std_init, lr_std_init)"),
    (["--strategy", "snes", "--strategy-set", "std_init=nan"], "error: strategy snes: std_init must be a finite number > 0"),
    (["--strategy", "sep_cma_es", "--strategy-set", "std_init=-1"],
     "error: strategy sep_cma_es: std_init must be a finite number > 0, got -1.0"),
    (["--strategy", "open_es", "--strategy-set", "lr_std_init=0.1"],
     "error: strategy open_es: lr_std_init is not a parameter (choose from std_init)"),
])
def test_bad_strategies_exit_2_with_one_line_and_write_nothing(tmp_path, capsys, argv, message):
    from imrl_jax.commands import evolve

    out = tmp_path / "run"
    assert evolve.main([*_evolve_args(1), *argv, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(message) and "\n" not in err, err
    assert not out.exists()


@pytest.mark.slow  # evolve's evosax step runs in the default suite in the resume test above
@pytest.mark.parametrize("name", list(strategies.STRATEGIES))
def test_a_tiny_evolution_with_each_offered_strategy(tiny, name):
    """Two generations of each strategy through evolve's own step equal search.generation run generation by generation:
    the populations asked (bitwise) and their fitness."""
    from imrl_jax.commands import evolve
    from imrl_jax.agent.lifetime import live

    config = tiny("EE-LS", population_size=4, num_parents=2, task_steps=60, num_bins=1, num_generations=2)
    from imrl_jax.evolution.devices import make_mesh, population_sharding

    strategy = strategies.make_strategy(name, config)
    mesh = make_mesh()
    sharding = population_sharding(mesh, 1, config.population_size)
    state = evolve.initial_state(config, [0], sharding, strategy, mesh)
    step = evolve.make_step(config, strategy, sharding)
    keys = evolve.evolution_keys(state.key_data)
    params = config.learning_params()
    populations, search_state, asked, fitness = state.populations, state.search, [], []
    for g in range(2):
        asked.append(np.asarray(populations)[0])  # the genomes generation g lives
        populations, search_state, stats = step(keys, params, populations, search_state, g)
        fitness.append(np.asarray(stats.fitness))
    asked.append(np.asarray(populations)[0])  # asked for generation 2 after generation 1's tell
    # the same by hand: init, then ask, live, tell per generation
    search_params = strategy.default_params()
    hand = strategy.init(jax.random.fold_in(jax.random.key(0), 0), search_params)
    by_hand = []
    for g in range(2):
        hand, result = search.generation(keys[0], strategy, lambda k, genome: live(k, config, params, genome), hand,
                                         search_params, g)
        by_hand.append(np.asarray(result.genomes))
        np.testing.assert_array_equal(np.asarray(result.fitness), fitness[g][0])
    by_hand.append(np.asarray(search.ask(keys[0], strategy, hand, search_params, 2)[0]))
    for g, (got, want) in enumerate(zip(asked, by_hand)):
        assert got.shape == want.shape == (4, config.num_genes) and got.dtype == want.dtype, g
        assert got.tobytes() == want.tobytes(), f"generation {g}'s population differs"
