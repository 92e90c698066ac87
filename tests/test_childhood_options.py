"""The childhood options of docs/CHILDHOOD.md and the GA's mean of lives: semantics on hand-made cases.

(Their agreement with the NumPy reference, step by step, is in test_reference.py.)
"""

import math
import os

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from imrl_jax.commands import evolve
from imrl_jax.evolution import ga
from imrl_jax import conditions as C
from imrl_jax.agent import state as S
from imrl_jax.agent import lifetime as L
from imrl_jax.world.arena import Pose
from imrl_jax.config import make_config
from imrl_jax.agent.networks import decode
from imrl_jax.world.env import at


def test_robot_pinned_on_a_wall_is_put_at_a_random_pose_after_n_steps(tiny):
    """A straight driver at 2 cm/step from x = 20 heading west: on the wall (x = 15) from
    its 3rd step (20 -> 18 -> 16 -> 15), so with N = 5 the 7th step (index 6) respawns it."""
    config = tiny("EE-LS", childhood_walls="respawn", wall_respawn_steps=5)
    n = config.num_inputs + 1
    actor = np.zeros((3, 2, n), np.float32)
    actor[:, 1, -1] = 30.0  # speed unit saturated: 2 cm per step, no turn
    agent = decode(config, jnp.asarray(actor.reshape(-1)))
    phase = L.Phase(experts_learn=False, selector_learns=False, intrinsic=False, has_target=False, noisy=False,
                    respawn=True)
    state = L.init_state(config, agent, at(Pose(jnp.array([20.0, 200.0]), jnp.array(math.pi))))
    key = jax.random.key(0)
    _, record = jax.jit(L.simulate, static_argnums=(1, 2, 6))(key, config, phase, config.learning_params(),
                                                              L.childhood_task(config), state, 40)
    respawned = np.flatnonzero(np.asarray(record.respawned))
    assert respawned[0] == 6
    x = np.asarray(record.world.pose.pos[:, 0])
    np.testing.assert_allclose(x[:6], [18, 16, 15, 15, 15, 15], atol=1e-4)
    # The new pose is the step's spawn draw, scaled to the arena.
    draws = S.draw_many(key, 40, config.draw_block, spawn=3)
    r, size = config.robot_radius, config.arena_size
    np.testing.assert_allclose(np.asarray(record.world.pose.pos[6]), r + (size - 2 * r) * np.asarray(draws.spawn[6, :2]),
                               rtol=1e-6)
    np.testing.assert_allclose(float(record.world.pose.heading[6]), 2 * math.pi * float(draws.spawn[6, 2]), rtol=1e-6)
    # Clamped (the default), the same robot stays on the wall.
    clamped = config.replace(childhood_walls="clamp")
    _, held = jax.jit(L.simulate, static_argnums=(1, 2, 6))(key, clamped, phase._replace(respawn=False),
                                                           clamped.learning_params(), L.childhood_task(clamped),
                                                           L.init_state(clamped, agent, at(state.world.pose)), 40)
    np.testing.assert_allclose(np.asarray(held.world.pose.pos[2:, 0]), 15.0)
    assert not np.asarray(held.respawned).any()


def test_paper_childhood_draws_are_unchanged_by_the_respawn_draws():
    """The expert-choice and noise numbers of a block are the same with or without spawn draws."""
    key = jax.random.key(5)
    plain, spawn = L.draw_block(key, 3, 100), L.draw_block(key, 3, 100, spawn=3)
    np.testing.assert_array_equal(plain.u, spawn.u)
    np.testing.assert_array_equal(plain.z, spawn.z)
    assert plain.spawn is None and spawn.spawn.shape == (100, 3)
    assert float(spawn.spawn.min()) >= 0.0 and float(spawn.spawn.max()) < 1.0


def test_childhood_learns_with_its_own_values_and_adulthood_with_the_adult_ones(tiny):
    params = make_config("paper", trace_lambda=0.9, eta_selector_actor=0.5, childhood_eta_selector_critic=0.02,
                         childhood_trace_lambda=0.3).learning_params()
    child = S.phase_params(C.CHILDHOOD, params)
    assert (child.trace_lambda, child.eta_selector_actor, child.eta_selector_critic) == (0.3, 0.01, 0.02)
    assert S.phase_params(C.ADULT_LEARNING_SELECTOR, params) == params


def test_fitness_as_the_mean_of_several_lives(tiny):
    from helpers import SHORT_TASK, hand_experts

    config = tiny("EE-LS", lives_per_fitness=2, population_size=2, num_parents=1, task_steps=300, num_bins=1,
                  tasks=(SHORT_TASK,))
    params = config.learning_params()
    experts = jnp.asarray(hand_experts(config.num_inputs + 1).reshape(-1), jnp.float32)  # they reach the target
    genomes = jnp.stack([experts, experts * 0.5])
    key = jax.random.key(2)
    fitness, performance = jax.jit(ga.evaluate, static_argnums=1)(key, config, params, genomes)
    # The same lives one by one: individual i's lives use keys split(key, (P, N))[i].
    keys = jax.random.split(key, (2, 2)).reshape(-1)
    lives = jax.jit(jax.vmap(lambda k, g: L.live(k, config, params, g)))(keys, jnp.repeat(genomes, 2, axis=0))
    np.testing.assert_allclose(fitness, np.asarray(lives.fitness).reshape(2, 2).mean(1), rtol=1e-6)
    np.testing.assert_allclose(performance, np.asarray(lives.performance).reshape(2, 2, -1).mean(1), rtol=1e-6)
    assert not np.allclose(*np.asarray(lives.fitness).reshape(2, 2)[0])  # two different lives were averaged


def test_extension_runs_written_before_childhood_values_relive_with_their_own_rules():
    """A config.json without the childhood fields learned childhood with the adult values."""
    old = make_config("extension").to_dict()
    for name in ("childhood_trace_lambda", "childhood_eta_selector_actor", "childhood_eta_selector_critic"):
        del old[name]
    old["trace_lambda"] = 0.5
    config = type(make_config()).from_dict(old)
    assert config.childhood_trace_lambda == 0.5
    assert config.childhood_eta_selector_actor == config.eta_selector_actor


@pytest.mark.parametrize("setting, field", [
    ("childhood_walls=bounce", "childhood_walls"),
    ("wall_respawn_steps=0", "wall_respawn_steps"),
    ("childhood_selector_reward=curiosity", "childhood_selector_reward"),
    ("progress_rate=0", "progress_rate"),
    ("childhood_trace_lambda=1", "childhood_trace_lambda"),
    ("lives_per_fitness=-2", "lives_per_fitness"),
])
def test_bad_childhood_settings_exit_2_naming_the_field(tmp_path, capsys, setting, field):
    out = tmp_path / "run"
    code = evolve.main(["--cond", "LE-LS", "--preset", "small", "--set", setting, "--out", str(out), "--quiet"])
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert len(err.splitlines()) == 1 and field in err, err
    assert not os.path.exists(out)


@pytest.mark.parametrize("condition", ["LE-LS", "EE-LS", "EE-ES", "SLE"])
def test_learned_actors_start_with_the_speed_bias_and_evolved_ones_do_not(tiny, condition):
    from imrl_jax.agent import reference

    config = tiny(condition, initial_speed_bias=2.5)
    genome = jax.random.uniform(jax.random.key(4), (config.num_genes,), jnp.float32, -1.0, 1.0)
    actor = np.asarray(decode(config, genome).actor)
    np.testing.assert_allclose(actor, reference.decode(config, np.asarray(genome))["actor"], rtol=1e-6)
    if condition in ("LE-LS", "SLE"):  # learned: zero but the speed unit's bias
        expected = np.zeros_like(actor)
        expected[:, 1, -1] = 2.5
        np.testing.assert_array_equal(actor, expected)
        assert np.all(np.asarray(L.adult_agent(config, decode(config, genome)).actor)[:, 1, -1] == 2.5)
    else:  # evolved: the genome's
        np.testing.assert_array_equal(actor.reshape(-1)[: actor.size], np.asarray(genome)[: actor.size])


def test_childhood_trajectory_lives_the_configs_childhood(tiny):
    """The pictures' childhood (behaviour.childhood_trajectory) has the config's respawns, drawn as breaks."""
    from imrl_jax.analysis import behaviour

    config = tiny("LE-LS", childhood_walls="respawn", wall_respawn_steps=5)
    genome = np.asarray(behaviour.colour_reinforcers(config))
    path = behaviour.childhood_trajectory(jax.random.key(0), config, config.learning_params(), genome, 400)
    assert path.respawned.sum() > 0
    np.testing.assert_array_equal(path.breaks, path.respawned)  # no target in childhood: respawns only
    moved = np.hypot(*(path.pos - path.seen_pos).T)
    assert moved[~path.breaks].max() <= 2.0 + 1e-4 < moved[path.breaks].min()  # only a respawn jumps
