"""The condition table: genome sizes and layout, the fields each condition ignores, a new condition as one row."""

import dataclasses
import json
import os

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import reference_life
from imrl_jax import conditions
from imrl_jax.agent import lifetime as L
from imrl_jax.agent import reference
from imrl_jax import config as config_module
from imrl_jax.agent import state as S
from imrl_jax.config import ConfigError, Task, make_config
from imrl_jax.agent.networks import decode, encode

#: A target 40 cm ahead, off the floor's lattice: a robot driving straight from the lattice's exact points
#: meets retina points exactly 3 cm from a line, where the reference and JAX may see different colours.
TASK = Task(start=(300.25, 200.5), heading_deg=1.0, target=(340.25, 201.2))
#: A value other than the paper's for every field some condition ignores (all valid together with the rest).
OTHER_VALUES = dict(selector_period=4, selector_termination="colour", childhood_steps=90, childhood_walls="respawn", wall_respawn_steps=3,
                    childhood_selector_reward="progress", progress_rate=0.5, childhood_trace_lambda=0.5,
                    childhood_eta_selector_actor=0.3, childhood_eta_selector_critic=0.2, eta_actor=0.3,
                    eta_evaluator=0.2, initial_speed_bias=2.0, eta_selector_actor=0.4, eta_selector_critic=0.25,
                    trace_lambda=0.6, gamma=0.5, noise_std=0.9, sle_noise_steps=10, population_size=60,
                    num_generations=5, num_parents=5, mutation_prob=0.5, mutation_scale=2.0, init_scale=2.0,
                    num_elites=1, lives_per_fitness=2, num_experts=4)


def test_genome_sizes_and_layout_follow_the_table():
    """111, 222, 333 and 0 genes (37 weights per network and expert); decode puts each network in its place."""
    sizes = {name: make_config("paper", condition=name).num_genes for name in conditions.NAMES}
    assert sizes == {"LE-LS": 111, "EE-LS": 222, "EE-ES": 333, "SLE": 0, "EV-LS": 111, "EV-LS-diff": 111,
                     "LE-LS-P": 122, "LE-LS-PC": 123, "LE-LS-N": 114, "EXT-LS": 0,
                     "EE-LS-T": 111, "LE-LS-2R": 222, "LE-LS-Z": 222}
    assert make_config("paper", condition="EXT-LS").num_lane_experts == 3
    evaluators = decode(make_config("paper", condition="EV-LS"), jnp.arange(111, dtype=jnp.float32))
    np.testing.assert_array_equal(evaluators.evaluator[2, :2], [74.0, 75.0])  # expert 2's evaluator: genes 74..
    np.testing.assert_array_equal(evaluators.reinforcer, 0.0)
    config = make_config("paper", condition="EE-ES")
    genome = jnp.arange(333, dtype=jnp.float32)
    agent = decode(config, genome)
    np.testing.assert_array_equal(agent.actor[1, 0, :3], [74.0, 75.0, 76.0])  # expert 1, turn unit: genes 74..
    np.testing.assert_array_equal(agent.selector_actor[0, :2], [222.0, 223.0])  # the selector follows the actors
    np.testing.assert_array_equal(agent.reinforcer, 0.0)
    np.testing.assert_array_equal(encode(config, agent), genome)
    assert make_config("paper", condition="SLE", num_experts=5).num_lane_experts == 1


def test_unknown_condition_names_the_field():
    with pytest.raises(ConfigError, match="condition: must be one of LE-LS, EE-LS, EE-ES, SLE"):
        make_config("paper", condition="XX")
    with pytest.raises(ValueError, match="unknown condition 'XX'"):
        conditions.get("XX")


def test_every_number_of_the_config_is_bounded_and_a_value_past_a_bound_is_refused_naming_the_field():
    config = make_config("paper")
    bounded = config_module.bounds()
    numbers = {f.name for f in dataclasses.fields(config)
               if isinstance(getattr(config, f.name), (int, float, tuple)) and f.name not in ("tasks", "world_settings")}
    assert numbers == set(bounded)
    refused = 0
    for name, bound in bounded.items():
        value = getattr(config, name)
        assert all(bound.holds(v) for v in (value if isinstance(value, tuple) else (value,))), name
        step = 1 if isinstance(value, int) else 1.0
        for past in (bound.lo if bound.lo_open else bound.lo - step, bound.hi if bound.hi_open else bound.hi + step):
            wrong = tuple(past for _ in value) if isinstance(value, tuple) else past
            with pytest.raises(ConfigError) as error:
                config.replace(**{name: wrong})
            assert str(error.value).startswith(f"{name}: must be ") and error.value.field == name, str(error.value)
            refused += 1
    assert refused == 2 * len(bounded) == 86


def test_the_derived_bounds_refuse_a_model_that_means_nothing():
    config = make_config("paper")
    for changes, message in [
        (dict(target_radius=69.3), "target_radius: must be below every task's start-to-target distance (task 6: 69.3"),
        (dict(max_speed=20.5), "max_speed: must be at most 2 x target_radius = 20 cm"),
        (dict(edge_length=401.0), "edge_length: must be at most arena_size=400"),
        (dict(tiling_origin=(160.0, 401.0)), "tiling_origin: must be a point (x, y) in the arena"),
        (dict(line_half_width=20.0), "line_half_width: must be below edge_length / 2 = 20"),
        (dict(colour_tie_tolerance=0.5, line_half_width=0.5), "colour_tie_tolerance: must be below line_half_width"),
        (dict(robot_radius=200.0), "robot_radius: the robot must fit in the arena"),
        (dict(tasks=(Task((10.0, 10.0), 0.0, (500.0, 10.0)),)), "tasks: task 1: target: (500, 10) is off the floor"),
    ]:
        with pytest.raises(ConfigError) as error:
            config.replace(**changes)
        assert str(error.value).startswith(message), str(error.value)
        assert str(error.value).split(":")[0] in config_module.DERIVED_BOUNDS
    # A trip takes a step at least: the theoretical maximum is finite for every config the bounds let through.
    assert config.replace(target_radius=69.28, max_speed=138.56).steps_per_trip() == (1,) * 6


def _reference_life(config, genome, seed=0):
    """One whole life in the NumPy reference with draws from NumPy (the same for every config of these sizes)."""
    rng = np.random.default_rng(seed)
    child = max(config.childhood_steps, OTHER_VALUES["childhood_steps"])
    u, z, spawn = rng.random(child), rng.standard_normal((child, 2)), rng.random((child, 3))
    task_u, task_z = rng.random((config.num_tasks, config.task_steps)), rng.standard_normal(
        (config.num_tasks, config.task_steps, 2))
    return reference.live(config, genome, (120.0, 180.0, 0.7), u[:config.childhood_steps], z[:config.childhood_steps],
                          task_u, task_z, childhood_spawn=spawn[:config.childhood_steps])


def _genome(config):
    genome = np.random.default_rng(1).uniform(-1.0, 1.0, config.num_genes)
    if "actor" in config.spec.genome:  # experts that drive straight at 2 and 1 cm a step: targets are reached
        n = config.num_inputs + 1
        actors = np.zeros((3, 2, n))
        actors[:, 1, -1] = (6.0, 0.0, 6.0)
        genome[:6 * n] = actors.reshape(-1)
    if "actor_turn" in config.spec.genome:  # turn units 0: straight ahead at the fixed speed
        genome[:3 * (config.num_inputs + 1)] = 0.0
    return genome


def _same_life(a, b) -> bool:
    same = np.array_equal(a["reaches"], b["reaches"]) and np.array_equal(a["performance"], b["performance"])
    for wa, wb in zip([a["childhood_weights"], *a["task_weights"]], [b["childhood_weights"], *b["task_weights"]]):
        same &= all(np.array_equal(wa[name], wb[name]) for name in reference.WEIGHT_KEYS)
    return bool(same)


@pytest.mark.parametrize("name", conditions.NAMES)
def test_a_field_the_condition_ignores_changes_no_life(name):
    """Every field in ``ignored_fields`` leaves the reference's life bitwise as it is; a field it reads does not."""
    config = make_config("paper", condition=name, childhood_steps=60, task_steps=60, num_bins=1,
                         tasks=(TASK, TASK), num_experts=3)
    genome = _genome(config)
    base = _reference_life(config, genome)
    assert base["reaches"].sum() > 0  # something happens for the ignored fields to disturb
    ignored = config.spec.ignored_fields()
    assert ignored <= set(OTHER_VALUES), sorted(ignored - set(OTHER_VALUES))
    for field in sorted(ignored):
        changed = config.replace(**{field: OTHER_VALUES[field]})
        assert _same_life(base, _reference_life(changed, genome)), field
        assert config.model_differences(changed) == []
    # A field every condition reads: the test can fail.
    slower = config.replace(max_speed=1.5)
    assert not _same_life(base, _reference_life(slower, genome))
    assert config.model_differences(slower) == ["max_speed"]


def test_compute_fields_are_not_model_differences():
    config = make_config("paper", condition="LE-LS")
    assert config.model_differences(config.replace(step_kernel="pallas", kernel_retina="points", scan_unroll=4)) == []
    assert config.model_differences(config.replace(draw_block=50)) == ["draw_block"]  # it sets the random stream


@pytest.fixture
def evolved_selector_that_learns():
    """A condition of one's own: EE-ES's genome (actors and selector), but the selector learns on from it."""
    row = conditions.register(dataclasses.replace(conditions.get("EE-ES"), name="EE-ES-learning",
                                                  adult=conditions.ADULT_LEARNING_SELECTOR,
                                                  description="evolved actors and initial selector; it learns"))
    yield row
    del conditions.CONDITIONS[row.name]


#: A module of one's own holding a row (EE-LS under another name: it compiles as fast).
ROWS_MODULE = """
import dataclasses

from imrl_jax import conditions

ROW = dataclasses.replace(conditions.get("EE-LS"), name="EE-LS-mine", description="EE-LS, registered from a module")
"""


def test_a_registered_row_works_with_every_command(tmp_path, monkeypatch, capsys):
    """evolve, its resume, learning_test and render take a row of one's own with --register (each a fresh table)."""
    import sys

    from imrl_jax.commands import evolve, learning_test, render

    (tmp_path / "my_rows.py").write_text(ROWS_MODULE)
    monkeypatch.chdir(tmp_path)

    def forget():  # as a new process would start: the table without the row
        conditions.CONDITIONS.pop("EE-LS-mine", None)
        sys.modules.pop("my_rows", None)

    run, test, gif = str(tmp_path / "run"), str(tmp_path / "test"), str(tmp_path / "best.gif")
    evolution = ["--cond", "EE-LS-mine", "--preset", "small", "--population", "4", "--parents", "2", "--generations",
                 "1", "--task-steps", "200", "--bins", "1", "--quiet", "--out", run]
    try:
        assert evolve.main(evolution) == 2
        err = capsys.readouterr().err
        assert err.startswith("error: --cond: unknown condition 'EE-LS-mine' (choose from LE-LS, EE-LS") and \
            err.endswith("or add a row with --register MODULE:ATTRIBUTE)\n") and not os.path.exists(run)
        assert evolve.main([*evolution, "--register", "my_rows:ROW"]) == 0
        with open(os.path.join(run, "config.json")) as f:
            assert json.load(f)["register"] == ["my_rows:ROW"]
        forget()
        resume = ["--resume", "--out", run, "--generations", "2", "--quiet"]
        assert evolve.main(resume) == 2
        assert capsys.readouterr().err == (f"error: {run}/config.json: condition 'EE-LS-mine' is not a row of the "
                                           f"condition table; add it with --register my_rows:ROW\n")
        assert evolve.main([*resume, "--register", "my_rows:ROW"]) == 0
        forget()
        options = ["--best", "1", "--tests", "1", "--task-steps", "200", "--bins", "2", "--steady-steps", "100",
                   "--chunks", "1", "--quiet", "--out", test]
        assert learning_test.main([run, *options]) == 2 and not os.path.exists(test)
        assert learning_test.main([run, *options, "--register", "my_rows:ROW"]) == 0
        with open(os.path.join(test, "steady.json")) as f:
            assert json.load(f)["condition"] == "EE-LS-mine"
        forget()
        assert render.main([run, "--task", "1", "--steps", "2", "--out", gif]) == 2 and not os.path.exists(gif)
        assert render.main([run, "--task", "1", "--steps", "2", "--out", gif, "--register", "my_rows:ROW"]) == 0
        assert os.path.getsize(gif) > 0
    finally:
        forget()


@pytest.mark.parametrize("spec, message", [
    ("my_rows", "--register my_rows: expected MODULE:ATTRIBUTE, e.g. --register my_rows:ROWS"),
    ("no_such_module:ROW", "--register no_such_module:ROW: cannot import no_such_module (ModuleNotFoundError: No "
                           "module named 'no_such_module')"),
    ("my_rows:NOTHING", "--register my_rows:NOTHING: my_rows has no attribute NOTHING"),
    ("my_rows:NAME", "--register my_rows:NAME: NAME is not a conditions.Condition or a list of them"),
    ("my_rows:TAKEN", "--register my_rows:TAKEN: condition: 'EE-LS' is already a row of the table"),
    # a name that would put runs outside runs/ (runs/../../x) or in runs/ itself
    ("my_rows:UP", "--register my_rows:UP: condition: '../../x' is not a name (letters, digits, and - _ . + inside, "
                   "at most 64 characters)"),
    ("my_rows:EMPTY", "--register my_rows:EMPTY: condition: '' is not a name (letters, digits, and - _ . + inside, "
                      "at most 64 characters)"),
    ("my_rows:NO_GENES", "--register my_rows:NO_GENES: condition EE-NONE: evolved, but its genome encodes no network "
                         "(give genome parts, or evolved=False to test it from scratch)"),
    ("exits:ROW", "--register exits:ROW: cannot import exits (SystemExit: 3)"),
])
def test_a_bad_register_is_one_line(tmp_path, monkeypatch, capsys, spec, message):
    import sys

    from imrl_jax.commands import evolve

    (tmp_path / "my_rows.py").write_text("import dataclasses\nfrom imrl_jax import conditions\nNAME = 'x'\n"
                                         "TAKEN = dataclasses.replace(conditions.get('EE-ES'), name='EE-LS')\n"
                                         "UP = dataclasses.replace(conditions.get('EE-ES'), name='../../x')\n"
                                         "EMPTY = dataclasses.replace(conditions.get('EE-ES'), name='')\n"
                                         "NO_GENES = dataclasses.replace(conditions.get('EE-ES'), name='EE-NONE', "
                                         "genome=())\n")
    (tmp_path / "exits.py").write_text("raise SystemExit(3)\n")  # a module that exits: one line, not a silent exit
    monkeypatch.chdir(tmp_path)
    for module in ("my_rows", "exits"):
        monkeypatch.delitem(sys.modules, module, raising=False)
    from attack import attack

    out = tmp_path / "run"  # attacked: were the row accepted, its plan would not be carried out
    outcome = attack(evolve.main, ["--register", spec, "--cond", "EE-LS", "--out", str(out)], str(tmp_path))
    assert outcome.code == 2 and outcome.stderr == f"error: {message}\n" and not outcome.changed
    assert not out.exists() and conditions.CONDITIONS["EE-LS"].genome == ("actor",)


@pytest.mark.usefixtures("x64")
def test_a_new_condition_is_one_row(tiny, evolved_selector_that_learns):
    """A registered row lives in JAX as the reference says, with no other change to the engine."""
    config = tiny("EE-ES-learning", tasks=(TASK, TASK), task_steps=200, num_bins=1)
    assert config.num_genes == 333 and config.lifetime_steps == 2 * 200
    genome = jnp.asarray(_genome(config))
    key = jax.random.key(11)
    result = jax.jit(L.live, static_argnums=1)(key, config, config.learning_params(), genome)
    keys = L.lifetime_keys(key, config.num_tasks)
    tasks = jax.vmap(S.draw_many, (0, None, None))(keys.tasks, config.task_steps, config.draw_block)
    ref = reference.live(config, np.asarray(genome), (0.0, 0.0, 0.0), np.zeros(0), np.zeros((0, 2)),
                         np.asarray(tasks.u), np.asarray(tasks.z))
    np.testing.assert_array_equal(np.asarray(result.reaches), ref["reaches"])
    assert ref["reaches"].sum() > 0
    evolved = decode(config, genome).selector_actor
    learned = result.adult_agents.selector_actor[0]
    assert not np.allclose(learned, evolved)  # the evolved selector learned on (EE-ES's would not)
    np.testing.assert_allclose(learned, ref["task_weights"][0]["selector_actor"], rtol=1e-10, atol=1e-12)
    with pytest.raises(ValueError, match="already a row"):
        conditions.register(evolved_selector_that_learns)


def test_register_refuses_an_unknown_network():
    row = dataclasses.replace(conditions.get("LE-LS"), name="LE-XX", genome=("reinforcers",))
    with pytest.raises(ValueError, match="'reinforcers' is not a network"):
        conditions.register(row)
    assert "LE-XX" not in conditions.CONDITIONS


@pytest.mark.usefixtures("x64")
def test_an_unexpressed_expert_is_never_chosen_and_never_learns(tiny):
    """LE-LS-N: expression genes (+, -, +, -) leave experts 1 and 3 out of childhood and tasks; JAX agrees with
    the reference step by step over a whole life."""
    config = tiny("LE-LS-N", num_experts=4, childhood_steps=600, task_steps=300, num_bins=1)
    n = config.num_inputs + 1
    assert config.num_genes == 4 * n + 4
    genome = jax.random.uniform(jax.random.key(12), (config.num_genes,), jnp.float64, -1.0, 1.0)
    genome = genome.at[-4:].set(jnp.asarray([0.5, -0.3, 0.8, -0.9]))
    agent = decode(config, genome)
    np.testing.assert_array_equal(agent.expressed, [1.0, 0.0, 1.0, 0.0])
    np.testing.assert_array_equal(decode(config, genome.at[-4:].set(-0.5).at[-2].set(-0.1)).expressed,
                                  [0.0, 0.0, 1.0, 0.0])  # none positive: the largest gene's expert is expressed
    key = jax.random.key(11)
    result = jax.jit(L.live, static_argnums=1)(key, config, config.learning_params(), genome)
    assert int(result.childhood_selections[:, [1, 3]].sum()) == 0 and int(result.adult_selections[..., [1, 3]].sum()) == 0
    assert int(result.childhood_selections[:, 0].sum()) > 0 and int(result.childhood_selections[:, 2].sum()) > 0
    np.testing.assert_array_equal(result.agent.actor[1], agent.actor[1])  # never in control: never learned
    assert not np.array_equal(result.agent.actor[0], agent.actor[0])
    ref = reference_life(config, key, genome)
    np.testing.assert_array_equal(np.asarray(result.reaches), ref["reaches"])
    for name in ("actor", "evaluator", "selector_actor"):
        np.testing.assert_allclose(np.asarray(getattr(result.agent, name)), ref["childhood_weights"][name],
                                   rtol=1e-8, atol=1e-10, err_msg=name)
        np.testing.assert_allclose(np.asarray(getattr(result.adult_agents, name)[2]), ref["task_weights"][2][name],
                                   rtol=1e-8, atol=1e-10, err_msg=name)


def test_evolved_learning_parameters_decode_by_their_maps():
    """LE-LS-P: gene 0 is a rate of 0.01; -0.2 a discount of 0.99; 1 a trace decay of 0; 0.5 a speed bias of 4."""
    config = make_config("paper", condition="LE-LS-P")
    assert config.num_genes == 111 + len(conditions.EVOLVED_PARAMETERS) == 122
    genes = {name: 0.0 for name in conditions.EVOLVED_FIELDS}
    genes.update(gamma=-0.2, trace_lambda=1.0, initial_speed_bias=0.5, noise_std=-0.4, eta_selector_actor=3.0)
    genome = jnp.concatenate([jnp.zeros(111), jnp.asarray([genes[f] for f in conditions.EVOLVED_FIELDS])])
    agent = decode(config, genome)
    np.testing.assert_allclose(agent.params.gamma, 0.99, rtol=1e-6)
    np.testing.assert_allclose(agent.params.trace_lambda, 0.0, atol=1e-7)
    np.testing.assert_allclose(agent.params.eta_actor, 0.01, rtol=1e-6)
    np.testing.assert_allclose(agent.params.eta_selector_actor, 1.0, rtol=1e-6)  # clipped at the top of its range
    np.testing.assert_allclose(agent.params.noise_std, 0.3, rtol=1e-6)
    np.testing.assert_allclose(agent.actor[:, 1, -1], 4.0, rtol=1e-6)
    assert float(agent.params.progress_rate) == pytest.approx(config.progress_rate)  # not evolved: the config's
    assert set(conditions.EVOLVED_FIELDS) <= config.spec.ignored_fields()


@pytest.mark.usefixtures("x64")
def test_an_individual_learns_with_its_evolved_parameters(tiny):
    """A whole LE-LS-P life in JAX agrees with the reference run with the decoded values as its config's."""
    config = tiny("LE-LS-P", childhood_steps=600, task_steps=300, num_bins=1)
    genome = jax.random.uniform(jax.random.key(12), (config.num_genes,), jnp.float64, -1.0, 1.0)
    key = jax.random.key(11)
    result = jax.jit(L.live, static_argnums=1)(key, config, config.learning_params(), genome)
    ref = reference_life(config, key, genome)
    np.testing.assert_array_equal(np.asarray(result.reaches), ref["reaches"])
    for name in ("actor", "evaluator", "selector_actor", "selector_critic"):
        np.testing.assert_allclose(np.asarray(getattr(result.agent, name)), ref["childhood_weights"][name],
                                   rtol=1e-8, atol=1e-10, err_msg=name)
    # The config's own rates would have given another childhood: the evolved ones were used.
    plain = jax.jit(L.live, static_argnums=1)(key, config.replace(condition="LE-LS"), config.learning_params(),
                                              genome[:111])
    assert not np.allclose(np.asarray(plain.agent.actor), np.asarray(result.agent.actor))


@pytest.mark.usefixtures("x64")
def test_an_evolved_childhood_length_stops_learning_and_noise_at_its_end(tiny):
    """LE-LS-PC: a whole life in JAX agrees with the reference, whose childhood of 600 steps with learning for
    300 ends with the weights of its first 300 steps (nothing learns afterwards); a longer one learns more."""


    config = tiny("LE-LS-PC", childhood_steps=600, task_steps=300, num_bins=1)
    genome = np.array(jax.random.uniform(jax.random.key(12), (config.num_genes,), jnp.float64, -1.0, 1.0))
    genome[-1] = 0.0  # u = 0.5: learning for the first 300 steps of 600
    assert float(decode(config, jnp.asarray(genome)).childhood_length) == 300
    key = jax.random.key(11)
    result = jax.jit(L.live, static_argnums=1)(key, config, config.learning_params(), jnp.asarray(genome))
    ref = reference_life(config, key, genome)
    np.testing.assert_array_equal(np.asarray(result.reaches), ref["reaches"])
    for name in ("actor", "evaluator", "selector_actor", "selector_critic"):
        np.testing.assert_allclose(np.asarray(getattr(result.agent, name)), ref["childhood_weights"][name],
                                   rtol=1e-8, atol=1e-10, err_msg=name)
    # In the reference: 600 steps learning for 300 end with the weights of the first 300 steps alone.
    weights = reference.decode(config, genome)
    weights.pop("childhood_length")
    weights.pop("parameters")
    rng = np.random.default_rng(0)
    u, z = rng.random(600), rng.standard_normal((600, 2))
    whole = reference.run_phase(config, "childhood", weights, (200.0, 200.0, 0.3), u, z, learning_steps=300)
    first = reference.run_phase(config, "childhood", weights, (200.0, 200.0, 0.3), u[:300], z[:300], phase_steps=600)
    for name in ("actor", "evaluator", "selector_actor", "selector_critic"):
        np.testing.assert_array_equal(whole["weights"][name], first["weights"][name], err_msg=name)
        assert not np.array_equal(first["weights"][name], weights[name]), name  # it did learn in the first 300
    genome[-1] = 1.0  # all 600 steps
    longer = jax.jit(L.live, static_argnums=1)(key, config, config.learning_params(), jnp.asarray(genome))
    assert not np.allclose(np.asarray(longer.agent.actor), np.asarray(result.agent.actor))
