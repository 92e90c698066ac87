"""The Pallas step kernel (kernel.py) against the XLA step.

On CPU the kernel runs in Pallas's interpreter: in float64 it must give the XLA program's
events exactly and its weights to rounding. That it lowers to a Triton kernel for a GPU is
checked by lowering for CUDA (compiling it needs a GPU).
"""

import dataclasses
import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import EXTENDED, SHORT_TASK, assert_trees_close, hand_experts

from imrl_jax.agent import kernel as K
from imrl_jax.agent import kernel_layout as KL
from imrl_jax import conditions as C
from imrl_jax.agent import lifetime as L
from imrl_jax.world.arena import Pose
from imrl_jax.agent.networks import decode
from imrl_jax.world.env import at

STEPS = 2000


def test_round_even_rounds_half_to_even():
    x = jnp.array([-2.5, -1.5, -0.5, 0.5, 1.5, 2.5, 2.4999998, 2.5000002, -3.7, 7.0, 1e6 + 0.5])
    np.testing.assert_array_equal(np.asarray(K.round_even(x)), np.asarray(jnp.round(x)))


#: The childhood options of docs/CHILDHOOD.md, with a short wall wait so that respawns happen.
OPTIONS = dict(childhood_walls="respawn", wall_respawn_steps=5, childhood_selector_reward="progress",
               progress_rate=0.05, initial_speed_bias=2.0)


@pytest.mark.usefixtures("x64")
# The plain childhood and SLE's horizon are slow: childhood-options and SLE run the same branches and more.
@pytest.mark.parametrize("condition, options", [pytest.param("LE-LS", {}, marks=pytest.mark.slow), ("LE-LS", OPTIONS),
                                               ("EE-LS", {}), pytest.param("SLE", {}, marks=pytest.mark.slow),
                                               pytest.param("SLE-horizon", {}, marks=pytest.mark.slow),
                                               pytest.param("LE-LS", dict(OPTIONS, selector_period=4,
                                                                          selector_termination="colour"),
                                                            marks=pytest.mark.slow),
                                               ("EE-LS", dict(selector_period=3))],
                         ids=["childhood", "childhood-options", "adult-LS", "SLE", "SLE-noise-horizon",
                              "childhood-selector-options", "adult-selector-options"])
def test_phase_in_pieces_matches_xla(tiny, condition, options):
    """A phase run by the kernel in two pieces, against XLA in one: every branch of the step.

    Childhood (intrinsic rewards, noise, walls; also respawns and the progress reward), a
    learning selector, and a single learning expert (one expert, noise; also with its noise
    over the first half only, sle_noise_steps), the adult phases with reaches and timeouts; the
    selector's options carried from one piece to the next (the option that runs, in the kernel's layout).
    """
    horizon = STEPS // 2 if condition.endswith("-horizon") else STEPS
    condition = condition.removesuffix("-horizon")
    config = tiny(condition, tasks=(SHORT_TASK,), childhood_steps=STEPS, task_steps=STEPS, num_bins=8,
                  **EXTENDED, **options)
    params = config.learning_params()
    n = config.num_inputs + 1
    if condition == "LE-LS":
        agent = decode(config, jax.random.uniform(jax.random.key(7), (3 * n,), jnp.float64, -1.0, 1.0))
        phase, task = L.childhood_phase(config), L.childhood_task(config, jnp.float64)
        pose = Pose(jnp.array([40.0, 60.0]), jnp.array(math.pi))  # heading into the west wall
    else:
        agent = L.adult_agent(config, decode(config, jnp.zeros((config.num_genes,), jnp.float64)))
        if condition == "EE-LS":
            agent = agent._replace(actor=jnp.asarray(hand_experts(n)))
        phase, task = C.get(condition).adult, L.task_spec(config, 0, jnp.float64)
        pose = task.start
    state = L.for_phase(config, phase, L.init_state(config, agent, at(pose)))
    pallas = config.replace(step_kernel="pallas")

    @jax.jit
    def both(key, state):
        whole = L.run_phase(key, config, phase, params, task, state, STEPS, horizon)
        # 750 + 1250 steps: the second piece starts mid-way through a block of draws.
        first = L.run_phase(key, pallas, phase, params, task, state, 750, horizon, 3)
        second = L.run_phase(key, pallas, phase, params, task, first[0], 1250, horizon, 5)
        return whole, (second[0], jax.tree.map(lambda a, b: jnp.concatenate([a, b]), first[1], second[1]))

    (xla_state, xla_curves), (kernel_state, kernel_curves) = both(jax.random.key(1), state)
    for name in L.Curves._fields:
        np.testing.assert_array_equal(np.asarray(getattr(kernel_curves, name)),
                                      np.asarray(getattr(xla_curves, name)), err_msg=name)
    assert_trees_close(kernel_state, xla_state, rtol=1e-9, atol=1e-9, cast=np.float64)
    if condition != "LE-LS":
        assert int(xla_curves.reaches.sum()) > 0 and int(xla_curves.timeouts.sum()) > 0
    else:  # every expert takes control
        assert np.all(np.asarray(xla_curves.selections).sum(0) > 0)
        assert (int(np.asarray(xla_curves.respawns).sum()) > 0 if options else xla_curves.respawns is None)


@pytest.mark.slow
@pytest.mark.usefixtures("x64")
def test_life_matches_xla(tiny):
    """A whole LE-LS life (childhood, six tasks vmapped) with step_kernel="pallas", against XLA."""
    config = tiny("LE-LS", childhood_steps=1200, task_steps=300, num_bins=3, **EXTENDED)
    params = config.learning_params()
    genome = jax.random.uniform(jax.random.key(12), (config.num_genes,), jnp.float64, -1.0, 1.0)
    live = jax.jit(L.live, static_argnums=1)
    xla = live(jax.random.key(11), config, params, genome)
    pallas = live(jax.random.key(11), config.replace(step_kernel="pallas"), params, genome)
    for name in ("reaches", "timeouts", "reward_curve", "adult_selections", "childhood_selections"):
        np.testing.assert_array_equal(np.asarray(getattr(pallas, name)), np.asarray(getattr(xla, name)),
                                      err_msg=name)
    for name in ("agent", "adult_agents"):
        assert_trees_close(getattr(pallas, name), getattr(xla, name), rtol=1e-9, atol=1e-9, name=name)
    assert int(xla.timeouts.sum()) > 0 and np.count_nonzero(xla.childhood_selections) == 3 * 3


#: Every model beyond the paper's on the kernel, one program: all the genome's optional parts, the selector's options
#: (ending at a colour come into view), the childhood options; five experts (Triton pads them to eight rows).
EVERYTHING = dict(genome=("reinforcer", "second_reinforcer", "expressed", "parameters", "childhood_length"))
EVERYTHING_OPTIONS = dict(num_experts=5, selector_period=4, selector_termination="colour", **OPTIONS)


@pytest.fixture
def everything():
    """A row of one's own whose genome holds every part the paper's LE-LS lacks (the table's rows take them apart)."""
    row = C.register(dataclasses.replace(C.get("LE-LS-PC"), name="LE-LS-everything", **EVERYTHING))
    yield row
    del C.CONDITIONS[row.name]


def _lives_agree(config, genomes, key=11):
    """Whole lives of ``genomes`` (vmapped: each lane its own genes) with the kernel and the XLA step: every event
    equal, weights to 1e-9 (float64). Returns the XLA step's lives."""
    params = config.learning_params()

    def lives(config):
        keys = jax.random.split(jax.random.key(key), genomes.shape[0])
        return jax.jit(jax.vmap(lambda k, g: L.live(k, config, params, g)))(keys, genomes)

    xla, pallas = lives(config), lives(config.replace(step_kernel="pallas"))
    for name in ("reaches", "timeouts", "reward_curve", "adult_selections", "childhood_selections"):
        np.testing.assert_array_equal(np.asarray(getattr(pallas, name)), np.asarray(getattr(xla, name)),
                                      err_msg=name)
    for name in ("agent", "adult_agents"):
        assert_trees_close(getattr(pallas, name), getattr(xla, name), rtol=1e-9, atol=1e-9, name=name)
    return xla


@pytest.mark.usefixtures("x64")
# Observing by points in the default suite: its layout by hand, pack/unpack and lowering (below); its lives slow.
@pytest.mark.parametrize("retina", ["entries", pytest.param("points", marks=pytest.mark.slow)])
def test_every_model_lives_on_the_kernel_as_on_the_xla_step(tiny, everything, retina):
    """Two lanes, each its own second reinforcers, expressed experts, learning values and childhood length, with
    the selector on its own time-scale: whole lives, the kernel (observing either way) against the XLA step."""
    config = tiny(everything.name, tasks=(SHORT_TASK,), childhood_steps=600, task_steps=300, num_bins=3, **EXTENDED,
                  kernel_retina=retina, **EVERYTHING_OPTIONS)
    genomes = jax.random.uniform(jax.random.key(12), (2, config.num_genes), jnp.float64, -1.0, 1.0)
    k, n = 5, config.num_inputs + 1
    genomes = genomes.at[:, 2 * k * n:2 * k * n + k].set(jnp.array([[0.5, -0.3, 0.8, -0.9, 0.1],
                                                                    [-0.5, 0.3, 0.8, 0.9, -0.1]]))
    genomes = genomes.at[:, -1].set(jnp.array([0.0, 0.6]))  # childhood stops at step 300 and 480 of 600
    agents = jax.vmap(lambda g: decode(config, g))(genomes)
    assert agents.params.eta_actor[0] != agents.params.eta_actor[1]  # each lane learns at its own rates
    xla = _lives_agree(config, genomes)
    assert xla.reaches.sum() > 0
    used = np.asarray(xla.childhood_selections).sum(1) > 0
    np.testing.assert_array_equal(used, [[1, 0, 1, 0, 1], [0, 1, 1, 1, 0]])  # the expressed experts only


@pytest.mark.usefixtures("x64")
@pytest.mark.parametrize("case", [
    "EV-LS-diff:period",
    pytest.param("EV-LS", marks=pytest.mark.slow),
    pytest.param("LE-LS-N", marks=pytest.mark.slow),
    pytest.param("LE-LS-P", marks=pytest.mark.slow),
    pytest.param("LE-LS-PC", marks=pytest.mark.slow),
    pytest.param("LE-LS-2R", marks=pytest.mark.slow),
    pytest.param("LE-LS:period", marks=pytest.mark.slow),
    pytest.param("LE-LS:colour", marks=pytest.mark.slow),
    pytest.param("EE-ES:colour", marks=pytest.mark.slow),
    pytest.param("SLE:period", marks=pytest.mark.slow),
    pytest.param("EXT-LS:colour", marks=pytest.mark.slow),
])
def test_each_row_lives_on_the_kernel_as_on_the_xla_step(tiny, case):
    """Each row of the condition table beyond the paper's (and the selector's options, "ROW:termination") alone."""
    condition, _, termination = case.partition(":")
    options = dict(selector_period=4, selector_termination=termination) if termination else {}
    config = tiny(condition, tasks=(SHORT_TASK,), childhood_steps=600, task_steps=300, num_bins=3, **EXTENDED,
                  **options)
    genomes = jax.random.uniform(jax.random.key(12), (2, config.num_genes), jnp.float64, -1.0, 1.0)
    xla = _lives_agree(config, genomes)
    assert xla.reaches.sum() > 0


def test_kernel_lowers_to_triton_for_gpu(tiny):
    """Childhood (with its options), adulthood and SLE kernels, vmapped over lanes, lower to Triton for CUDA."""
    config = tiny("LE-LS", childhood_steps=400, task_steps=200, num_bins=2, **OPTIONS)
    params = config.learning_params()

    def lanes(key, genome):
        agent = decode(config, genome)
        child = L.init_state(config, agent, at(Pose(jnp.array([40.0, 60.0]), jnp.array(math.pi))))
        child, _ = K.run_phase(key, config, L.childhood_phase(config), params, L.childhood_task(config), child,
                               config.childhood_steps, interpret=False)
        adult = L.task_start(config, child.agent, 0)
        adult = K.run_phase(key, config, C.ADULT_LEARNING_SELECTOR, params, L.task_spec(config, 0), adult,
                            config.task_steps, interpret=False)
        # One expert (SLE): its choice is computed, not a constant (Triton's loop cannot return one).
        single = L.task_start(sle, L.adult_agent(sle, decode(sle, jnp.zeros((0,)))), 0)
        return adult, K.run_phase(key, sle, C.ADULT_SINGLE_EXPERT, params, L.task_spec(sle, 0), single,
                                  sle.task_steps, interpret=False)

    sle = tiny("SLE", task_steps=200, num_bins=2)
    keys = jax.random.split(jax.random.key(0), 6).reshape(2, 3)
    genomes = jnp.zeros((2, 3, config.num_genes))
    text = jax.jit(jax.vmap(jax.vmap(lanes))).trace(keys, genomes).lower(lowering_platforms=("cuda",)).as_text()
    assert text.count("__gpu$xla.gpu.triton") == 3


@pytest.mark.parametrize("case", ["everything", "everything/points", "EV-LS-diff:period", "EV-LS:colour",
                                  "EE-ES:colour", "EXT-LS:period", "SLE/points"])
def test_every_model_lowers_to_triton_for_gpu(tiny, everything, monkeypatch, case):
    """Whole lives of each model beyond the paper's, vmapped over lanes, lower to one Triton kernel a phase (also
    observing by points, "/points")."""
    monkeypatch.setattr(K, "_interpret", lambda: False)  # what a GPU runs, lowered on the CPU
    case, _, retina = case.partition("/")
    condition, _, termination = case.partition(":")
    options = dict(kernel_retina=retina or "entries")
    if condition == "everything":
        condition = everything.name
        options.update(EVERYTHING_OPTIONS)
    elif termination:
        options.update(selector_period=4, selector_termination=termination)
    config = tiny(condition, childhood_steps=400, task_steps=200, num_bins=2, step_kernel="pallas", **options)
    params = config.learning_params()
    keys = jax.random.split(jax.random.key(0), 3)
    genomes = jnp.zeros((3, config.num_genes))
    lives = jax.jit(jax.vmap(lambda k, g: L.live(k, config, params, g)))
    text = lives.trace(keys, genomes).lower(lowering_platforms=("cuda",)).as_text()
    assert text.count("__gpu$xla.gpu.triton") == 1 + config.spec.has_childhood


def test_observing_by_points_puts_the_columns_colour_major(tiny):
    """kernel_retina="points": column c x 16 + p holds colour c of point p (x~'s entry 3 p + c), the bias column 48;
    the layout's rows give each point's offsets once and each column's colour (3 where it holds none)."""
    config = tiny("LE-LS", kernel_retina="points")
    cols = KL.columns(config)
    assert cols.shape == (64,) and KL.columns(tiny("LE-LS")).tolist() == list(range(37)) + [-1] * 27
    assert cols[[0, 1, 11, 16, 17, 32, 43, 48]].tolist() == [0, 3, 33, 1, 4, 2, 35, 36]
    assert (cols[12:16] == -1).all() and (cols[49:] == -1).all() and sorted(cols[cols >= 0]) == list(range(37))
    layout = np.asarray(KL.retina_layout(config))
    assert layout[0, :12].tolist() == [17.0] * 6 + [21.0] * 6 and layout[0, 12:].tolist() == [0.0] * 52
    assert layout[1, :6].tolist() == [-10.0, -6.0, -2.0, 2.0, 6.0, 10.0]
    assert layout[2, [0, 11, 12, 16, 32, 43, 44, 48]].tolist() == [0.0, 0.0, 3.0, 1.0, 2.0, 2.0, 3.0, 3.0]
    assert layout[3].nonzero()[0].tolist() == [48]


@pytest.mark.parametrize("retina", ["entries", "points"])
def test_a_state_packed_and_unpacked_is_itself(tiny, retina):
    """pack then unpack gives the phase state back exactly (every weight, trace, observation and option), with the
    second reinforcers laid out alike (the kernel's columns in either order)."""
    config = tiny("LE-LS-2R", selector_period=4, kernel_retina=retina)
    genome = jax.random.uniform(jax.random.key(3), (config.num_genes,), jnp.float32, -1.0, 1.0)
    state = L.init_state(config, decode(config, genome), at(L.task_spec(config, 0).start))
    noise = iter(jax.random.split(jax.random.key(4), 64))
    state = jax.tree.map(lambda x: jax.random.normal(next(noise), x.shape, x.dtype)
                         if jnp.issubdtype(x.dtype, jnp.floating) else x, state)._replace(t=jnp.int32(5))
    back = KL.unpack(KL.pack(state, config), state, state.block, config)
    assert jax.tree.all(jax.tree.map(lambda a, b: bool(jnp.array_equal(a, b)), back, state))
    second = np.asarray(KL.fixed(state.agent, config).second_reinforcer)
    cols = KL.columns(config)
    np.testing.assert_array_equal(second[:3, cols >= 0], np.asarray(state.agent.second_reinforcer)[:, cols[cols >= 0]])


def test_a_phase_option_the_kernel_does_not_implement_is_refused(monkeypatch):
    """A later rule's phase option that the kernel lacks gets a one-line error, not wrong results (here the
    evolved evaluators' option, taken out of the kernel's list)."""
    from imrl_jax.config import ConfigError, make_config

    K.check_supported(C.get("EV-LS").childhood)  # implemented: no error
    monkeypatch.setattr(K, "SUPPORTED", tuple(f for f in K.SUPPORTED if f != "evaluation"))
    with pytest.raises(ConfigError, match="does not implement the phase option evaluation='discounted'"):
        K.check_supported(C.get("EV-LS").childhood)
    assert "evaluation='discounted'" in K.unsupported(make_config("small", condition="EV-LS"))
