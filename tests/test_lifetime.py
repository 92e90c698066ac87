"""Contract tests of lifetimes: shapes, dtypes, one compile, vmapped = single, scan = loop, invariants."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import assert_trees_close, random_genomes

from imrl_jax import conditions as C
from imrl_jax.agent import lifetime as L
from imrl_jax.config import CONDITIONS
from imrl_jax.agent.networks import decode, encode
from imrl_jax.world.env import at


# The future-work rows' lives follow the NumPy reference (test_reference.py); their contracts are slow.
@pytest.mark.parametrize("condition", [c if c in C.PAPER else pytest.param(c, marks=pytest.mark.slow)
                                       for c in CONDITIONS])
def test_population_shapes_dtypes_and_single_compile(tiny, condition):
    config = tiny(condition)
    evaluate = L.make_evaluate(config)
    params = config.learning_params()
    result = evaluate(jax.random.key(0), params, random_genomes(config, 3))
    again = evaluate(jax.random.key(1), params, random_genomes(config, 3, seed=1))
    assert evaluate._cache_size() == 1  # new keys and genomes reuse the compiled program
    k = config.num_lane_experts
    tasks, bins = config.num_tasks, config.num_bins
    assert result.fitness.shape == (3,) and result.fitness.dtype == jnp.float32
    assert result.performance.shape == (3, tasks)
    assert result.reaches.shape == (3, tasks) and result.reaches.dtype == jnp.int32
    assert result.reward_curve.shape == (3, tasks, bins)
    assert result.adult_selections.shape == (3, tasks, bins, k)
    assert result.childhood_selections.shape == (3, bins, k)
    assert result.adult_agents.actor.shape == (3, tasks, k, 2, config.num_inputs + 1)
    # Every adult step has exactly one expert in control; counts add up.
    np.testing.assert_array_equal(result.adult_selections.sum((-1, -2)), config.task_steps)
    np.testing.assert_array_equal(result.reward_curve.sum(-1), result.reaches)
    np.testing.assert_allclose(result.fitness, result.performance.mean(-1), rtol=1e-6)
    best = np.array(config.theoretical_max(), np.float32)
    np.testing.assert_allclose(result.performance, result.reaches / best, rtol=1e-6)
    if condition == "LE-LS":
        np.testing.assert_array_equal(result.childhood_selections.sum((-1, -2)), config.childhood_steps)
    assert again.fitness.shape == (3,)


def test_vmapped_population_equals_single_lives(tiny):
    config = tiny("LE-LS")
    params = config.learning_params()
    genomes = random_genomes(config, 2)
    key = jax.random.key(3)
    batch = L.make_evaluate(config)(key, params, genomes)
    keys = jax.random.split(key, 2)
    single = jax.jit(L.live, static_argnums=1)
    for i in range(2):
        one = single(keys[i], config, params, genomes[i])
        np.testing.assert_array_equal(one.reaches, batch.reaches[i])
        np.testing.assert_array_equal(one.childhood_selections, batch.childhood_selections[i])
        np.testing.assert_allclose(one.agent.actor, batch.agent.actor[i], rtol=1e-6, atol=1e-7)


def test_binned_phase_equals_step_by_step_loop(tiny):
    """run_phase (scan of scans with counts) = simulate (records) = a Python loop of steps."""
    config = tiny("EE-LS", task_steps=60, num_bins=3)
    params = config.learning_params()
    agent = decode(config, random_genomes(config, 1)[0])
    task = L.task_spec(config, 2)
    state = L.init_state(config, L.adult_agent(config, agent), at(task.start))
    key = jax.random.key(5)
    phase = C.ADULT_LEARNING_SELECTOR

    binned_state, curves = jax.jit(L.run_phase, static_argnums=(1, 2, 6))(
        key, config, phase, params, task, state, 60)
    sim_state, records = jax.jit(L.simulate, static_argnums=(1, 2, 6))(key, config, phase, params, task, state, 60)
    step = jax.jit(L.step, static_argnums=(1, 2, 5))
    loop_state = state
    ks = []
    for _ in range(60):
        loop_state, record = step(key, config, phase, params, task, 60, loop_state)
        ks.append(int(record.k))

    np.testing.assert_array_equal(np.asarray(records.k), ks)
    for a, b in [(binned_state, sim_state), (sim_state, loop_state)]:
        assert_trees_close(a, b, rtol=1e-6, atol=1e-6)
    np.testing.assert_array_equal(curves.selections.sum(0), np.bincount(ks, minlength=3))
    np.testing.assert_array_equal(curves.reaches, np.asarray(records.reached).reshape(3, 20).sum(1))


def test_frozen_parts_stay_frozen(tiny):
    """EE-ES learns nothing; EE-LS and LE-LS adulthood leaves the experts as they were."""
    params = tiny().learning_params()
    for condition in ("EE-ES", "EE-LS", "LE-LS"):
        config = tiny(condition)
        genome = random_genomes(config, 1)[0]
        result = jax.jit(L.live, static_argnums=1)(jax.random.key(0), config, params, genome)
        for t in range(config.num_tasks):
            np.testing.assert_array_equal(result.adult_agents.actor[t], result.agent.actor)
            np.testing.assert_array_equal(result.adult_agents.evaluator[t], result.agent.evaluator)
        if condition == "EE-ES":
            np.testing.assert_array_equal(encode(config, result.adult_agents._replace(
                actor=result.adult_agents.actor[0], selector_actor=result.adult_agents.selector_actor[0])), genome)
        else:
            # Rewards are the selector's only signal from zero weights: it moves iff it was rewarded.
            moved = np.abs(np.asarray(result.adult_agents.selector_critic)).sum(-1) > 0
            np.testing.assert_array_equal(moved, np.asarray(result.reaches) > 0)
        if condition == "LE-LS":
            assert np.abs(np.asarray(result.agent.actor)).sum() > 0  # childhood trained the experts


def test_decode_encode_roundtrip(tiny):
    for condition in ("LE-LS", "EE-LS", "EE-ES"):
        config = tiny(condition)
        genome = random_genomes(config, 1)[0]
        assert genome.shape == ({"LE-LS": 111, "EE-LS": 222, "EE-ES": 333}[condition],)
        np.testing.assert_array_equal(encode(config, decode(config, genome)), genome)
    with pytest.raises(ValueError, match="genome"):
        decode(tiny("LE-LS"), jnp.zeros(5))


def test_lifetime_memory_does_not_grow_with_length(tiny):
    """The compiled life needs the same memory (to a few bytes) for 1,000 and 100,000 steps per task."""
    params = tiny().learning_params()
    sizes = []
    for steps in (1_000, 100_000):
        config = tiny("LE-LS", childhood_steps=1_500 * steps // 1_000, task_steps=steps, num_bins=100)
        genome = jnp.zeros((config.num_genes,))
        compiled = jax.jit(L.live, static_argnums=1).lower(jax.random.key(0), config, params, genome).compile()
        memory = compiled.memory_analysis()
        sizes.append(memory.temp_size_in_bytes + memory.output_size_in_bytes)
    # Keeping even one float per step would add 2.4 MB at this length; loop shapes may differ by bytes.
    assert abs(sizes[1] - sizes[0]) < 4096, sizes


def test_select_follows_pseudo_probabilities():
    s = jnp.array([0.2, 0.6, 0.2])  # cumulative 0.2, 0.8, 1.0
    picks = [int(L.select(jnp.float32(u), s)) for u in (0.0, 0.19, 0.21, 0.79, 0.81, 0.999)]
    assert picks == [0, 0, 1, 1, 2, 2]
    u = jax.random.uniform(jax.random.key(0), (20_000,))
    counts = np.bincount(np.asarray(jax.vmap(L.select, (0, None))(u, s)), minlength=3) / 20_000
    np.testing.assert_allclose(counts, [0.2, 0.6, 0.2], atol=0.015)


def test_paper_length_life_runs_on_cpu():
    """A whole 750,000-step LE-LS life (150,000 childhood + 6 x 100,000) in one program."""
    from imrl_jax.config import make_config

    config = make_config("paper", condition="LE-LS")
    genome = jax.random.uniform(jax.random.key(0), (config.num_genes,), minval=-1.0, maxval=1.0)
    result = jax.jit(L.live, static_argnums=1)(jax.random.key(1), config, config.learning_params(), genome)
    assert int(result.childhood_selections.sum()) == 150_000
    np.testing.assert_array_equal(result.adult_selections.sum((-1, -2)), 100_000)
    assert result.reward_curve.shape == (6, 100)
    assert np.isfinite(np.asarray(result.agent.actor)).all()


@pytest.mark.slow  # a compute field (COMPUTE_FIELDS): the default suite keeps to the model
def test_unrolling_the_step_loop_changes_nothing(tiny):
    """scan_unroll is a speed knob: 1 and 3 steps per loop iteration give the same life."""
    params = tiny().learning_params()
    genome = random_genomes(tiny("LE-LS"), 1)[0]
    lives = [jax.jit(L.live, static_argnums=1)(jax.random.key(2), tiny("LE-LS", scan_unroll=u), params, genome)
             for u in (1, 3)]
    np.testing.assert_array_equal(lives[0].reaches, lives[1].reaches)
    np.testing.assert_array_equal(lives[0].childhood_selections, lives[1].childhood_selections)
    jax.tree.map(np.testing.assert_array_equal, lives[0].adult_agents,
                 lives[1].adult_agents)
