"""The JAX lifetime against the plain NumPy reference, given the same random draws.

Both run in float64 here, so they agree to ~1e-9 step after step; every window holds the
events that matter (target reaches with resets, timeouts, wall contacts), and every
condition is checked with the paper's rules and with the learning extensions (traces,
other per-network rates).
"""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import EXTENDED, SHORT_TASK, hand_experts, reference_life

from imrl_jax import conditions as C
from imrl_jax.agent import state as S
from imrl_jax.agent import lifetime as L
from imrl_jax.agent import reference
from imrl_jax.world.arena import Pose
from imrl_jax.agent.networks import Agent, decode
from imrl_jax.world.env import at

STEPS = 2000
PAPER = {}
#: The childhood options of docs/CHILDHOOD.md (static: they change the program).
CHILDHOOD_OPTIONS = dict(childhood_walls="respawn", wall_respawn_steps=5, childhood_selector_reward="progress",
                         progress_rate=0.05)


def _to_numpy(agent: Agent) -> dict:
    return {name: np.asarray(value, np.float64) for name, value in agent._asdict().items() if value is not None}


def _assert_weights_close(jax_agent: Agent, ref: dict):
    for name, value in jax_agent._asdict().items():
        if value is not None and name in ref:  # "expressed" and "params" only where a condition has them
            np.testing.assert_allclose(np.asarray(value), ref[name], rtol=1e-8, atol=1e-10, err_msg=name)


def _compare_phase(config, phase, phase_name, agent, pose, task_index, params, seed=0, learning_steps=None):
    key = jax.random.key(seed)
    draws = S.draw_many(key, STEPS, config.draw_block, spawn=S.spawn_draws(config, phase))
    task = L.childhood_task(config, jnp.float64) if task_index is None else L.task_spec(config, task_index, jnp.float64)
    state = L.init_state(config, agent, at(pose))
    final, record = jax.jit(L.simulate, static_argnums=(1, 2, 6))(key, config, phase, params, task, state, STEPS)
    ref = reference.run_phase(config.replace(**params._asdict()), phase_name, _to_numpy(agent),
                              (float(pose.pos[0]), float(pose.pos[1]), float(pose.heading)),
                              np.asarray(draws.u), np.asarray(draws.z), task=task_index,
                              spawn=None if draws.spawn is None else np.asarray(draws.spawn),
                              learning_steps=learning_steps)
    np.testing.assert_array_equal(np.asarray(record.k), ref["k"])
    np.testing.assert_array_equal(np.asarray(record.reached), ref["reached"])
    np.testing.assert_array_equal(np.asarray(record.timeout), ref["timeout"])
    np.testing.assert_array_equal(np.asarray(record.respawned), ref["respawned"])
    np.testing.assert_allclose(np.asarray(record.world.pose.pos[:, 0]), ref["x"], atol=1e-8)
    np.testing.assert_allclose(np.asarray(record.world.pose.pos[:, 1]), ref["y"], atol=1e-8)
    np.testing.assert_allclose(np.asarray(record.world.pose.heading), ref["heading"], atol=1e-8)
    _assert_weights_close(final.agent, ref["weights"])
    pos = np.asarray(record.world.pose.pos)
    r = config.robot_radius
    walls = np.sum((pos <= r + 1e-9) | (pos >= config.arena_size - r - 1e-9))
    return dict(reaches=int(ref["reached"].sum()), timeouts=int(ref["timeout"].sum()), walls=int(walls),
                switches=int(np.sum(ref["k"][1:] != ref["k"][:-1])), respawns=int(ref["respawned"].sum()),
                agent=final.agent)


@pytest.mark.usefixtures("x64")
@pytest.mark.parametrize("options", [{}, CHILDHOOD_OPTIONS], ids=["paper-childhood", "respawn-and-progress"])
@pytest.mark.parametrize("rules", [PAPER, EXTENDED], ids=["paper-rules", "traces-and-rates"])
def test_childhood_matches_reference(tiny, rules, options):
    config = tiny("LE-LS", childhood_steps=STEPS, **options)
    params = config.replace(**rules).learning_params()
    n = config.num_inputs + 1
    genome = jax.random.uniform(jax.random.key(7), (3 * n,), jnp.float64, -1.0, 1.0)
    agent = decode(config, genome)
    pose = Pose(jnp.array([40.0, 60.0]), jnp.array(math.pi))  # heading into the west wall
    events = _compare_phase(config, L.childhood_phase(config), "childhood", agent, pose, None, params)
    assert events["walls"] > 0 and events["switches"] > 100
    assert (events["respawns"] > 0) == bool(options), events


@pytest.mark.usefixtures("x64")
@pytest.mark.parametrize("condition, form", [("EV-LS", "discounted"), ("EV-LS-diff", "difference")])
def test_evolved_evaluators_childhood_matches_reference(tiny, condition, form):
    """The actors learn from the change of their fixed, evolved evaluations; the evaluators stay as evolved."""
    config = tiny(condition, childhood_steps=STEPS, **CHILDHOOD_OPTIONS)
    params = config.replace(**EXTENDED).learning_params()
    genome = jax.random.uniform(jax.random.key(7), (config.num_genes,), jnp.float64, -1.0, 1.0)
    agent = decode(config, genome)
    phase = L.childhood_phase(config)
    assert phase.evaluation == form and config.num_genes == 111
    pose = Pose(jnp.array([40.0, 60.0]), jnp.array(math.pi))  # heading into the west wall
    events = _compare_phase(config, phase, phase, agent, pose, None, params)
    assert events["walls"] > 0 and events["switches"] > 100 and events["respawns"] > 0
    np.testing.assert_array_equal(events["agent"].evaluator, agent.evaluator)  # innate: never learns
    assert np.abs(np.asarray(events["agent"].actor - agent.actor)).max() > 1e-3  # the actors learned
    assert np.abs(np.asarray(events["agent"].selector_actor)).max() > 1e-3  # and the selector, from that surprise


@pytest.mark.usefixtures("x64")
def test_hierarchy_on_extrinsic_reward_matches_reference(tiny):
    """EXT-LS: from scratch, the experts (while in control) and the selector all learn from the task's reward."""
    config = tiny("EXT-LS", tasks=(SHORT_TASK,), task_steps=STEPS, num_bins=1, initial_speed_bias=3.0)
    params = config.replace(**EXTENDED).learning_params()
    task = L.task_spec(config, 0, jnp.float64)
    agent = L.adult_agent(config, decode(config, jnp.zeros((0,), jnp.float64)))
    events = _compare_phase(config, config.spec.adult, config.spec.adult, agent, task.start, 0, params)
    assert events["reaches"] > 0 and events["timeouts"] > 0 and events["switches"] > 100, events
    for network in ("actor", "evaluator", "selector_actor", "selector_critic"):
        assert np.abs(np.asarray(getattr(events["agent"], network) - getattr(agent, network))).max() > 1e-4, network


@pytest.mark.usefixtures("x64")
@pytest.mark.parametrize("rules", [PAPER, EXTENDED], ids=["paper-rules", "traces-and-rates"])
@pytest.mark.parametrize("condition", ["EE-LS", "EE-ES", "SLE"])
def test_adult_phase_matches_reference(tiny, condition, rules):
    config = tiny(condition, tasks=(SHORT_TASK,), task_steps=STEPS, num_bins=1)
    params = config.replace(**rules).learning_params()
    n = config.num_inputs + 1
    if condition == "SLE":
        agent = L.adult_agent(config, decode(config, jnp.zeros((0,), jnp.float64)))
        phase, name = C.ADULT_SINGLE_EXPERT, "sle"
    else:
        agent = decode(config, jnp.zeros((config.num_genes,), jnp.float64))
        agent = agent._replace(actor=jnp.asarray(hand_experts(n)))
        if condition == "EE-ES":
            selector = jax.random.uniform(jax.random.key(3), (3, n), jnp.float64, -1.0, 1.0)
            agent = agent._replace(selector_actor=selector)
            phase, name = C.ADULT_EVOLVED_SELECTOR, "adult-es"
        else:
            phase, name = C.ADULT_LEARNING_SELECTOR, "adult-ls"
    task = L.task_spec(config, 0, jnp.float64)
    events = _compare_phase(config, phase, name, agent, task.start, 0, params)
    assert events["reaches"] > 0 and events["timeouts"] > 0 and events["walls"] > 0, events


@pytest.mark.usefixtures("x64")
@pytest.mark.parametrize("condition", ["LE-LS-N", "LE-LS-P", "LE-LS-PC"])
def test_evolved_traits_match_reference_step_by_step(tiny, condition):
    """The future-work rows step by step: childhood with the evolved traits, then LE-LS-N's adulthood.

    LE-LS-N: expert 1 is not expressed (never chosen, never learns); LE-LS-P: the decoded rates and
    discount drive learning; LE-LS-PC: learning and noise stop at the evolved childhood length (half)."""
    config = tiny(condition, childhood_steps=STEPS, task_steps=STEPS, tasks=(SHORT_TASK,), num_bins=1,
                  **CHILDHOOD_OPTIONS)
    genome = jax.random.uniform(jax.random.key(7), (config.num_genes,), jnp.float64, -1.0, 1.0)
    if condition == "LE-LS-N":
        genome = genome.at[-3:].set(jnp.asarray([0.5, -0.3, 0.8]))
    if condition == "LE-LS-PC":
        genome = genome.at[-1].set(0.0)  # u = 0.5: learning for the first half of the childhood
    agent = decode(config, genome)
    params = config.learning_params() if agent.params is None else agent.params
    learning_steps = None if agent.childhood_length is None else int(agent.childhood_length)
    assert learning_steps in (None, STEPS // 2)
    pose = Pose(jnp.array([40.0, 60.0]), jnp.array(math.pi))  # heading into the west wall
    events = _compare_phase(config, L.childhood_phase(config), "childhood", agent, pose, None, params,
                            learning_steps=learning_steps)
    assert events["walls"] > 0 and events["switches"] > 100 and events["respawns"] > 0, events
    assert np.abs(np.asarray(events["agent"].actor - agent.actor)).max() > 1e-3  # its own learning occurred
    if condition == "LE-LS-P":  # the evolved values, not the config's, are the ones that learned
        assert not np.isclose(float(params.eta_actor), config.eta_actor)
    if condition != "LE-LS-N":
        return
    np.testing.assert_array_equal(events["agent"].actor[1], agent.actor[1])  # never in control: never learned
    n = config.num_inputs + 1
    adult = L.adult_agent(config, events["agent"])._replace(actor=jnp.asarray(hand_experts(n)))
    task = L.task_spec(config, 0, jnp.float64)
    events = _compare_phase(config, config.spec.adult, "adult-ls", adult, task.start, 0, params)
    assert events["reaches"] > 0 and events["timeouts"] > 0 and events["switches"] > 20, events


_live = jax.jit(L.live, static_argnums=1)


@pytest.mark.usefixtures("x64")
@pytest.mark.parametrize("rules", [PAPER, EXTENDED], ids=["paper-rules", "traces-and-rates"])
@pytest.mark.parametrize("condition", ["LE-LS", "EE-LS", "EE-ES", "SLE", "EV-LS", "EXT-LS"])
def test_whole_life_matches_reference(tiny, condition, rules):
    """live(): childhood, key splitting, selector resets, six tasks, fitness."""
    # The rules are dynamic values (params): both variants share one compiled life.
    program = tiny(condition, childhood_steps=600, task_steps=300, num_bins=1)
    config = program.replace(**rules)
    params = config.learning_params()
    key = jax.random.key(11)
    genome = jax.random.uniform(jax.random.key(12), (config.num_genes,), jnp.float64, -1.0, 1.0)
    if condition in ("EE-LS", "EE-ES"):  # good experts make reaches likely
        n = config.num_inputs + 1
        genome = genome.at[: 6 * n].set(jnp.asarray(hand_experts(n)).reshape(-1))
    result = _live(key, program, params, genome)

    ref = reference_life(config, key, genome)
    np.testing.assert_array_equal(np.asarray(result.reaches), ref["reaches"])
    np.testing.assert_allclose(float(result.fitness), ref["fitness"], rtol=1e-12)
    _assert_weights_close(result.agent, ref["childhood_weights"])
    for t in range(config.num_tasks):
        _assert_weights_close(jax.tree.map(lambda x: x[t], result.adult_agents), ref["task_weights"][t])


def test_float32_lifetime_tracks_float64_reference(tiny):
    """The default float32 program follows the float64 reference for 2,000 steps."""
    config = tiny("EE-LS", tasks=(SHORT_TASK,), task_steps=STEPS, num_bins=1)
    params = config.learning_params()
    n = config.num_inputs + 1
    agent = decode(config, jnp.zeros((config.num_genes,)))._replace(actor=jnp.asarray(hand_experts(n), jnp.float32))
    task = L.task_spec(config, 0)
    key = jax.random.key(0)
    final, record = jax.jit(L.simulate, static_argnums=(1, 2, 6))(
        key, config, C.ADULT_LEARNING_SELECTOR, params, task, L.init_state(config, agent, at(task.start)), STEPS)
    draws = S.draw_many(key, STEPS, config.draw_block)
    ref = reference.run_phase(config, "adult-ls", _to_numpy(agent), (300.0, 200.0, 0.0),
                              np.asarray(draws.u, np.float64), np.asarray(draws.z, np.float64), task=0)
    np.testing.assert_array_equal(np.asarray(record.k), ref["k"])
    np.testing.assert_array_equal(np.asarray(record.reached), ref["reached"])
    np.testing.assert_allclose(np.asarray(record.world.pose.pos[:, 0]), ref["x"], atol=1e-3)
    np.testing.assert_allclose(np.asarray(record.world.pose.pos[:, 1]), ref["y"], atol=1e-3)
    for name, value in final.agent._asdict().items():
        if value is not None:
            np.testing.assert_allclose(np.asarray(value), ref["weights"][name], rtol=1e-4, atol=1e-5, err_msg=name)
    assert ref["reached"].sum() > 0


@pytest.mark.usefixtures("x64")
def test_sle_noise_horizon_matches_reference(tiny):
    """sle_noise_steps: SLE's noise anneals over a fixed number of steps, then stays 0."""
    config = tiny("SLE", task_steps=300, num_bins=1, sle_noise_steps=100)
    params = config.learning_params()
    key = jax.random.key(11)
    genome = jnp.zeros((0,), jnp.float64)
    result = _live(key, config, params, genome)
    ref = reference_life(config, key, genome)
    np.testing.assert_array_equal(np.asarray(result.reaches), ref["reaches"])
    for t in range(config.num_tasks):
        _assert_weights_close(jax.tree.map(lambda x: x[t], result.adult_agents), ref["task_weights"][t])
    whole = _live(key, config.replace(sle_noise_steps=0), params, genome)  # noise over all 300 steps
    assert not np.allclose(np.asarray(whole.adult_agents.actor), np.asarray(result.adult_agents.actor))


#: A selector on its own time-scale (docs/TIMESCALE.md): options of 7 steps, or until a colour comes into view
#: (at most 25 steps).
TIMESCALES = {"period-7": dict(selector_period=7), "colour-25": dict(selector_period=25, selector_termination="colour")}


@pytest.mark.usefixtures("x64")
@pytest.mark.parametrize("timescale", TIMESCALES.values(), ids=TIMESCALES)
def test_childhood_options_match_reference(tiny, timescale):
    """Semi-Markov TD in childhood: the selector learns once per option from the surprise summed over it."""
    config = tiny("LE-LS", childhood_steps=STEPS, **CHILDHOOD_OPTIONS, **timescale)
    params = config.replace(**EXTENDED).learning_params()
    genome = jax.random.uniform(jax.random.key(7), (config.num_genes,), jnp.float64, -1.0, 1.0)
    agent = decode(config, genome)
    pose = Pose(jnp.array([40.0, 60.0]), jnp.array(math.pi))  # heading into the west wall
    events = _compare_phase(config, L.childhood_phase(config), "childhood", agent, pose, None, params)
    assert events["walls"] > 0 and events["respawns"] > 0 and 20 < events["switches"] < STEPS / 7, events
    assert np.abs(np.asarray(events["agent"].selector_actor)).max() > 1e-3  # the selector learned


@pytest.mark.usefixtures("x64")
@pytest.mark.parametrize("rules", [PAPER, EXTENDED], ids=["paper-rules", "traces-and-rates"])
@pytest.mark.parametrize("timescale", TIMESCALES.values(), ids=TIMESCALES)
def test_adult_options_match_reference(tiny, timescale, rules):
    """Semi-Markov TD in adulthood: the reward summed and discounted over the option, gamma^tau to its length."""
    config = tiny("EE-LS", tasks=(SHORT_TASK,), task_steps=STEPS, num_bins=1, **timescale)
    params = config.replace(**rules).learning_params()
    n = config.num_inputs + 1
    agent = decode(config, jnp.zeros((config.num_genes,), jnp.float64))._replace(actor=jnp.asarray(hand_experts(n)))
    task = L.task_spec(config, 0, jnp.float64)
    events = _compare_phase(config, C.ADULT_LEARNING_SELECTOR, "adult-ls", agent, task.start, 0, params)
    assert events["reaches"] > 0 and events["timeouts"] > 0 and events["switches"] > 20, events
    assert np.abs(np.asarray(events["agent"].selector_critic)).max() > 1e-4


@pytest.mark.usefixtures("x64")
def test_evolved_selector_keeps_its_choice_for_the_period(tiny):
    """EE-ES with options: nothing learns, and the expert changes only where an option ends."""
    config = tiny("EE-ES", tasks=(SHORT_TASK,), task_steps=STEPS, num_bins=1, selector_period=7)
    n = config.num_inputs + 1
    selector = jax.random.uniform(jax.random.key(3), (3, n), jnp.float64, -1.0, 1.0)
    agent = decode(config, jnp.zeros((config.num_genes,), jnp.float64))._replace(
        actor=jnp.asarray(hand_experts(n)), selector_actor=selector)
    task = L.task_spec(config, 0, jnp.float64)
    key = jax.random.key(0)
    final, record = jax.jit(L.simulate, static_argnums=(1, 2, 6))(
        key, config, C.ADULT_EVOLVED_SELECTOR, config.learning_params(), task, L.init_state(config, agent, at(task.start)),
        STEPS)
    events = _compare_phase(config, C.ADULT_EVOLVED_SELECTOR, "adult-es", agent, task.start, 0,
                            config.learning_params())
    k, ended = np.asarray(record.k), np.asarray(record.reached | record.timeout)
    # Hand-counted: an option starts at step 0 and after every trial end, and lasts 7 steps at most.
    since = 0
    for t in range(1, STEPS):
        since = 0 if ended[t - 1] or since + 1 >= 7 else since + 1
        if since:
            assert k[t] == k[t - 1], t
    assert events["switches"] > 20 and events["reaches"] > 0, events
