"""The size-matched controls (MODEL.md "Size-matched controls"): their genomes, and whole lives against the reference."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import EXTENDED, SHORT_TASK, reference_life

from imrl_jax.agent import kernel
from imrl_jax.agent import lifetime as L
from imrl_jax.config import make_config
from imrl_jax.agent.networks import decode, encode

_live = jax.jit(L.live, static_argnums=1)


def _assert_life_matches_reference(config, genome, seed=11):
    """A whole life in JAX (float64) against the NumPy reference: reaches, fitness and every weight at rtol 1e-8."""
    key = jax.random.key(seed)
    result = _live(key, config, config.learning_params(), genome)
    ref = reference_life(config, key, genome)
    np.testing.assert_array_equal(np.asarray(result.reaches), ref["reaches"])
    np.testing.assert_allclose(float(result.fitness), ref["fitness"], rtol=1e-12)
    lives = [(result.agent, ref["childhood_weights"])] + [
        (jax.tree.map(lambda x: x[t], result.adult_agents), ref["task_weights"][t]) for t in range(config.num_tasks)]
    for agent, weights in lives:
        for name, value in agent._asdict().items():
            if value is not None and name in weights:
                np.testing.assert_allclose(np.asarray(value), weights[name], rtol=1e-8, atol=1e-10, err_msg=name)
    return ref


def test_turn_only_actors_have_le_ls_size_and_a_fixed_speed_unit():
    """EE-LS-T: 111 genes, the turn units' weights in expert order; the speed unit 0 but its bias, the config's."""
    config = make_config("paper", condition="EE-LS-T", initial_speed_bias=2.5)
    assert config.num_genes == make_config("paper", condition="LE-LS").num_genes == 111
    genome = jnp.arange(111, dtype=jnp.float32)
    agent = decode(config, genome)
    np.testing.assert_array_equal(agent.actor[1, 0, :2], [37.0, 38.0])  # expert 1's turn unit: genes 37..
    np.testing.assert_array_equal(agent.actor[:, 1, :-1], 0.0)
    np.testing.assert_array_equal(agent.actor[:, 1, -1], 2.5)
    np.testing.assert_array_equal(agent.reinforcer, 0.0)
    np.testing.assert_array_equal(encode(config, agent), genome)
    assert "initial_speed_bias" not in config.spec.ignored_fields()  # it sets the speed
    assert kernel.unsupported(config) is None  # it decodes into the actors only


@pytest.mark.usefixtures("x64")
@pytest.mark.parametrize("rules", [{}, EXTENDED], ids=["paper-rules", "traces-and-rates"])
def test_turn_only_actors_live_as_the_reference_says(tiny, rules):
    """EE-LS-T's whole life (six copies of a 40 cm task, the selector learning) follows the reference in float64."""
    config = tiny("EE-LS-T", tasks=(SHORT_TASK,) * 2, task_steps=400, num_bins=1, initial_speed_bias=3.0, **rules)
    n = config.num_inputs + 1
    turn = 0.05 * np.random.default_rng(3).uniform(-1.0, 1.0, (3, n))
    turn[:, -1] += (0.0, 0.4, -0.4)  # straight ahead, slowly left, slowly right (all at the fixed speed)
    ref = _assert_life_matches_reference(config, jnp.asarray(turn.reshape(-1)))
    assert ref["reaches"].min() > 0, ref["reaches"]  # the straight expert reaches it: a reward to learn from
    np.testing.assert_array_equal(ref["task_weights"][0]["actor"][:, 1, -1], 3.0)  # the speed stays fixed


def test_reinforcer_sized_controls_have_ee_ls_size():
    """LE-LS-2R and LE-LS-Z: 222 genes, the reinforcers first; 2R's second units follow, Z's extra genes go nowhere."""
    size = make_config("paper", condition="EE-LS").num_genes
    genome = jnp.arange(222, dtype=jnp.float32)
    pair = make_config("paper", condition="LE-LS-2R")
    assert pair.num_genes == size == 222
    agent = decode(pair, genome)
    np.testing.assert_array_equal(agent.reinforcer[1, :2], [37.0, 38.0])
    np.testing.assert_array_equal(agent.second_reinforcer[0, :2], [111.0, 112.0])  # the second units follow
    np.testing.assert_array_equal(encode(pair, agent), genome)
    assert kernel.unsupported(pair) is None
    neutral = make_config("paper", condition="LE-LS-Z")
    assert neutral.num_genes == size
    plain = decode(make_config("paper", condition="LE-LS"), genome[:111])
    assert jax.tree.all(jax.tree.map(np.array_equal, decode(neutral, genome), plain))
    assert kernel.unsupported(neutral) is None
    with pytest.raises(ValueError, match="encode: neutral genes are not encoded back"):
        encode(neutral, plain)


def test_two_reinforcer_units_reward_their_mean():
    """r_k = (r1 + r2) / 2 with r = 2 sigmoid(w.x~) - 1: units of activations 0 and log 3 give (0 + 0.5) / 2."""
    from imrl_jax.agent.networks import internal_rewards

    config = make_config("paper", condition="LE-LS-2R")
    agent = decode(config, jnp.zeros(222).at[111 + 36].set(np.log(3.0)))  # expert 0's second unit: its bias
    np.testing.assert_allclose(internal_rewards(agent, jnp.ones(37)), [0.25, 0.0, 0.0], rtol=1e-6)


@pytest.mark.usefixtures("x64")
def test_two_reinforcer_units_live_as_the_reference_says(tiny):
    """LE-LS-2R's whole life (childhood from both units, six tasks) follows the reference; the second units count."""
    config = tiny("LE-LS-2R", childhood_steps=600, task_steps=300, num_bins=1)
    genome = jax.random.uniform(jax.random.key(12), (config.num_genes,), jnp.float64, -1.0, 1.0)
    _assert_life_matches_reference(config, genome)
    other = _live(jax.random.key(11), config, config.learning_params(), genome.at[111:].set(-genome[111:]))
    first = _live(jax.random.key(11), config, config.learning_params(), genome)
    assert not np.allclose(np.asarray(other.agent.actor), np.asarray(first.agent.actor))  # they change childhood


@pytest.mark.usefixtures("x64")
def test_neutral_genes_change_no_life(tiny):
    """LE-LS-Z's whole life follows the reference, and is LE-LS's life of its first 111 genes bitwise."""
    config = tiny("LE-LS-Z", childhood_steps=600, task_steps=300, num_bins=1)
    genome = jax.random.uniform(jax.random.key(12), (config.num_genes,), jnp.float64, -1.0, 1.0)
    ref = _assert_life_matches_reference(config, genome)
    plain = config.replace(condition="LE-LS")
    result = _live(jax.random.key(11), plain, plain.learning_params(), genome[:111])
    np.testing.assert_array_equal(np.asarray(result.reaches), ref["reaches"])
    zeroed = _live(jax.random.key(11), config, config.learning_params(), genome.at[111:].set(0.0))
    assert jax.tree.all(jax.tree.map(np.array_equal, zeroed.agent, result.agent))
