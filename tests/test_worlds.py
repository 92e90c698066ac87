"""A world behind its interface (imrl_jax/world/base.py): the arena is one, and a life reaches it only through it."""

import dataclasses
import inspect

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from imrl_jax.agent import lifetime as L
from imrl_jax.agent import state as S
from imrl_jax.world import base, env as E, worlds


def test_the_arena_is_a_world():
    config = E.Config()
    for name, member in inspect.getmembers(base.World, inspect.isfunction):
        assert callable(getattr(E.ARENA, name)), name
    for name, member in inspect.getmembers(base.Env, inspect.isfunction):
        assert callable(getattr(E.ARENA.make_env(config), name)), name
    assert E.ARENA.num_inputs(config) == 36 and E.ARENA.actions(config) == base.Actions(base.CONTINUOUS, 2)
    assert E.ARENA.num_tasks(config) == 6 and E.ARENA.num_spawn_draws == 3
    np.testing.assert_allclose(E.ARENA.max_reaches(config), config.theoretical_max(), rtol=1e-6)
    assert worlds.world_of(config) is E.ARENA and worlds.WORLDS == {"arena": E.ARENA, "xland": "imrl_jax.world.xland"}


def test_a_respawn_draws_the_world_s_count_of_numbers_and_a_flag_is_refused():
    key = jax.random.key(0)
    assert S.draw_block(key, 0, 8, spawn=3).spawn.shape == (8, 3)
    assert S.draw_block(key, 0, 8).spawn is None
    with pytest.raises(TypeError, match="number of draws"):
        S.draw_block(key, 0, 8, spawn=True)


@dataclasses.dataclass(frozen=True)
class HalfAsHard(E.Arena):
    """The arena, whose tasks allow twice the reaches: the same lives score half."""

    def max_reaches(self, config, dtype=jnp.float32):
        return 2 * super().max_reaches(config, dtype)


@dataclasses.dataclass(frozen=True)
class Blind(E.Arena):
    """The arena seen as nothing: an agent that observes only its world's observe sees zeros."""

    def make_env(self, config, has_target=True, respawn=False):
        return BlindEnv(config, has_target, respawn)


@dataclasses.dataclass(frozen=True)
class BlindEnv(E.Environment):
    def observe(self, state):
        return jnp.zeros_like(super().observe(state))


def test_a_life_reaches_the_world_only_through_it(tiny, monkeypatch):
    """Performance is reaches over the world's max_reaches, and the agent sees only what its env observes."""
    config = tiny("LE-LS", task_steps=300, childhood_steps=300, num_bins=2)
    genome = jax.random.uniform(jax.random.key(1), (config.num_genes,), minval=-1.0, maxval=1.0)
    # The world is read when a life is traced: each life its own function, traced anew (clearing jax's caches
    # would make every later test in this process compile again).
    life = lambda: jax.jit(lambda *args: L.live(*args), static_argnums=1)  # noqa: E731
    key, params = jax.random.key(2), config.learning_params()
    plain = life()(key, config, params, genome)
    monkeypatch.setitem(worlds.WORLDS, "arena", HalfAsHard())
    half = life()(key, config, params, genome)
    np.testing.assert_array_equal(half.reaches, plain.reaches)
    np.testing.assert_allclose(half.performance, plain.performance / 2, rtol=1e-6)
    monkeypatch.setitem(worlds.WORLDS, "arena", Blind())
    blind = life()(key, config, params, genome)
    # Seeing nothing, every perceptron reads only its bias: the reinforcers pay the same reward everywhere.
    assert not np.array_equal(np.asarray(blind.agent.actor), np.asarray(plain.agent.actor))
    np.testing.assert_array_equal(np.asarray(blind.agent.actor)[..., :-1], 0.0)


def _xland_config(tiny, **settings):
    pytest.importorskip("xminigrid")  # the worlds extra (not in the minimum environment)
    return worlds.configure(tiny("LE-LS", childhood_steps=300, task_steps=200), "xland", **settings)


def test_a_config_moves_into_another_world_with_its_sizes(tiny):
    from imrl_jax.config import Config
    from imrl_jax.runs import runspec

    config = _xland_config(tiny, arm_length=5)
    assert (config.world, config.world_settings, config.world_inputs, config.world_actions) == (
        "xland", (("arm_length", 5),), 55, 5)
    assert config.num_inputs == 55 and config.num_actor_units == 5 and config.num_genes == 3 * 56
    assert Config.from_dict(config.to_dict()) == config  # config.json's lists of pairs read back
    arena = worlds.configure(config, "arena")
    assert arena == tiny("LE-LS", childhood_steps=300, task_steps=200)
    # A world's name and settings are part of a run's key; the arena's keys are as before worlds.
    keys = {runspec.RunSpec(c, (0,)).key for c in (arena, config, _xland_config(tiny))}
    assert len(keys) == 3 and "world" not in runspec.model(arena) and runspec.model(config)["world"] == "xland"


@pytest.mark.parametrize("change, field", [
    (dict(world="nowhere", world_inputs=5, world_actions=2), "world: unknown world 'nowhere'"),
    (dict(world_settings=(("arm_length", 9),), world_inputs=0, world_actions=0, world="arena"), "world_settings"),
    (dict(world_settings=(("colour", 1),)), "world_settings: unknown setting 'colour'"),
    (dict(world_settings=(("task_set", "paper"),)), "world_settings: task_set"),
    (dict(world_settings=(("arm_length", 1),)), "world_settings: XLandSettings.arm_length"),
    (dict(world_inputs=36), "world_inputs: 36 inputs and 5 actions are not world xland's"),
    (dict(condition="EE-LS-T"), "condition: EE-LS-T evolves the arena's actor_turn"),
    (dict(condition="LE-LS-P"), "condition: LE-LS-P evolves the arena's parameters"),
])
def test_a_world_a_config_cannot_live_in_is_refused_naming_the_field(tiny, change, field):
    from imrl_jax.config import ConfigError

    config = _xland_config(tiny)
    with pytest.raises(ConfigError) as refused:
        worlds.world_of(dataclasses.replace(config, **change))
    assert str(refused.value).startswith(field)


def test_a_discrete_action_is_drawn_in_proportion_to_its_unit_and_is_the_largest_without_noise():
    from imrl_jax import conditions as C

    output = jnp.asarray([0.1, 0.6, 0.2, 0.05, 0.05])
    z = jax.random.normal(jax.random.key(4), (20_000, 2))
    drawn = jax.vmap(lambda zz: L.choose_action(C.CHILDHOOD, output, zz))(z)
    np.testing.assert_allclose(np.bincount(np.asarray(drawn), minlength=5) / 20_000, output / output.sum(), atol=0.01)
    assert int(L.choose_action(C.CHILDHOOD._replace(noisy=False), output, z[0])) == 1


def test_a_life_in_another_world_learns_its_discrete_actions(tiny):
    """LE-LS in XLand: childhood moves the experts' actors (one unit per action, the selector's rule), every
    step's action is one of the world's, and the kernel refuses the world."""
    from imrl_jax import conditions as C
    from imrl_jax.agent import kernel
    from imrl_jax.config import ConfigError

    config = _xland_config(tiny)
    genome = jax.random.uniform(jax.random.key(0), (config.num_genes,), minval=-1.0, maxval=1.0)
    life = jax.jit(L.live, static_argnums=1)(jax.random.key(1), config, config.learning_params(), genome)
    assert life.agent.actor.shape == (3, 5, 56) and np.all(np.isfinite(np.asarray(life.agent.actor)))
    assert np.abs(np.asarray(life.agent.actor)).sum() > 0 and 0.0 <= float(life.fitness) <= 1.0
    world = worlds.world_of(config)
    agent = L.decode(config, genome)
    start = world.make_env(config, False, False).reset(jax.random.key(2), world.childhood_task(config))
    _, record = L.simulate(jax.random.key(3), config, C.CHILDHOOD._replace(respawn=False), config.learning_params(),
                           world.childhood_task(config), S.init_state(config, agent, start), 50)
    assert record.world.position.shape == (50, 2)  # the world's own state, recorded
    assert "world xland" in kernel.unsupported(config)
    with pytest.raises(ConfigError, match="world xland"):
        kernel.run_phase(jax.random.key(0), config, C.CHILDHOOD, config.learning_params(), None, None, 10)


@pytest.mark.parametrize("item", ["world=xland", "world_inputs=55", "world_actions=5"])
def test_the_world_is_not_set_field_by_field(item):
    """A config's world fields are set together (worlds.configure): --set of one is refused before anything runs."""
    from imrl_jax.config import WORLD_FIELDS
    from imrl_jax.runs import cli

    with pytest.raises(cli.UsageError, match="the world is not set field by field"):
        cli.parse_sets([item])
    assert not set(WORLD_FIELDS) & set(cli.settable_fields())


def test_a_run_whose_config_names_an_impossible_world_is_refused_naming_its_file(tmp_path):
    import json

    from imrl_jax.config import Config
    from imrl_jax.runs import rundir

    saved = Config().to_dict()
    saved.update(world="nowhere", world_inputs=5, world_actions=2)  # each field valid alone; no such world
    (tmp_path / "config.json").write_text(json.dumps({"config": saved, "seeds": [0]}))
    with pytest.raises(rundir.RunDirError, match=r"config.json is unreadable \(world: unknown world 'nowhere'"):
        rundir.read_config(str(tmp_path))


def test_evolved_actors_in_another_world_have_a_row_per_action(tiny):
    """EE-ES in XLand: the genome holds K actors of one unit per action and the selector; a genome's actor genes
    are the agent's actors as they are, and nothing learns in its life."""
    from imrl_jax.agent import networks

    config = worlds.configure(tiny("EE-ES", task_steps=200), "xland")
    assert config.num_genes == 3 * 5 * 56 + 3 * 56  # the actors, then the selector
    genome = jax.random.uniform(jax.random.key(0), (config.num_genes,), minval=-1.0, maxval=1.0)
    agent = networks.decode(config, genome)
    np.testing.assert_array_equal(np.asarray(agent.actor), np.asarray(genome[:3 * 5 * 56]).reshape(3, 5, 56))
    np.testing.assert_array_equal(np.asarray(networks.encode(config, agent)), np.asarray(genome))
    life = jax.jit(L.live, static_argnums=1)(jax.random.key(1), config, config.learning_params(), genome)
    np.testing.assert_array_equal(np.asarray(life.agent.actor), np.asarray(agent.actor))
    assert 0.0 <= float(life.fitness) <= 1.0


def test_evolve_lives_in_the_world_its_command_line_names_and_resumes_there(tmp_path, capsys):
    """``evolve --world xland``: config.json records the world; ``--resume`` keeps it (a resume ending bitwise as an
    uninterrupted run is the command's, tests/test_evolve.py); a resume naming another world is refused, the run as
    it was."""
    pytest.importorskip("xminigrid")
    from imrl_jax.commands import evolve
    from imrl_jax.runs.rundir import read_config

    line = ["--cond", "LE-LS", "--world", "xland", "--world-set", "arm_length=3", "--preset", "small", "--population",
            "4", "--parents", "2", "--childhood-steps", "60", "--task-steps", "40", "--bins", "2", "--quiet"]
    run = str(tmp_path / "run")
    assert evolve.main([*line, "--generations", "1", "--out", run]) == 0
    config = read_config(run)[0]
    assert (config.world, config.world_settings, config.world_inputs) == ("xland", (("arm_length", 3),), 55)
    assert evolve.main(["--resume", "--out", run, "--generations", "2", "--quiet"]) == 0
    assert read_config(run)[0] == config.replace(num_generations=2)
    with open(f"{run}/history.csv") as f:
        assert {row.split(",")[0] for row in f.read().splitlines()[1:]} == {"0", "1"}  # both generations, in xland
    before = {name: open(f"{run}/{name}", "rb").read() for name in ("config.json", "history.csv")}
    capsys.readouterr()
    assert evolve.main(["--resume", "--out", run, "--world", "arena", "--generations", "3"]) == 2
    assert "error:" in capsys.readouterr().err
    assert before == {name: open(f"{run}/{name}", "rb").read() for name in before}


# ----------------------------------------------------------------------------- a world of one's own


@pytest.fixture
def own_worlds(monkeypatch):
    """worlds.WORLDS as a copy the test may register into, and notebooks/ importable (corridor_world.py)."""
    from helpers import ROOT

    monkeypatch.setattr(worlds, "WORLDS", dict(worlds.WORLDS))
    monkeypatch.syspath_prepend(f"{ROOT}/notebooks")
    return worlds.WORLDS


def test_a_world_is_registered_under_a_free_name_only(own_worlds):
    from imrl_jax.config import ConfigError

    worlds.register("blind", Blind())
    worlds.register("blind", Blind())  # the same world again (a notebook run twice)
    assert own_worlds["blind"] == Blind() and worlds.make("blind") == Blind()
    for name, world in (("blind", HalfAsHard()), ("arena", Blind()), ("xland", "corridor_world")):
        with pytest.raises(ValueError, match=f"register: the name '{name}' is taken by another world"):
            worlds.register(name, world)
    with pytest.raises(ValueError, match="an identifier"):
        worlds.register("two words", Blind())
    with pytest.raises(ConfigError, match="registered as an object"):
        worlds.make("blind", (("view", 4),))


def test_the_corridor_world_implements_the_interface_and_a_controller_solves_its_tasks(own_worlds, tiny):
    """notebooks/corridor_world.py (docs/WORLDS.md, "A world of one's own"): every method, an observation of
    num_inputs numbers, and a controller that turns towards the goal and walks reaches each task's max_reaches."""
    import corridor_world as cw
    from imrl_jax.config import ConfigError

    worlds.register("corridor", "corridor_world")
    config = worlds.configure(tiny("LE-LS", childhood_steps=300, task_steps=200), "corridor")
    world = worlds.world_of(config)
    assert world == cw.Corridor() and (config.num_inputs, config.num_actor_units, config.num_genes) == (9, 2, 30)
    for name, _ in inspect.getmembers(base.World, inspect.isfunction):
        assert callable(getattr(world, name)), name
    for name, _ in inspect.getmembers(base.Env, inspect.isfunction):
        assert callable(getattr(world.make_env(config), name)), name
    env, open_env = world.make_env(config), world.make_env(config, has_target=False, respawn=True)
    start = env.reset(None, world.task(config, 0))
    np.testing.assert_array_equal(env.observe(start), [1, 0, 0] * 3)  # cell 1 facing right: red, red, red
    wide = worlds.world_of(worlds.configure(config, "corridor", view=5))
    assert wide.make_env(config).observe(start).shape == (wide.num_inputs(config),) == (15,)
    child = open_env.reset(jax.random.key(0), world.childhood_task(config))
    assert open_env.observe(child).shape == (world.num_inputs(config),)

    def reaches(index):
        params = world.task(config, index)  # a traced index

        def step(state, _):
            away = (params.goal - state.position) * state.facing < 0
            return env.transition(state, jnp.where(away, cw.TURN, cw.FORWARD).astype(jnp.int32), params)

        return jax.lax.scan(step, env.reset(None, params), None, config.task_steps)[1].reached.sum()

    found = jax.jit(jax.vmap(reaches))(jnp.arange(world.num_tasks(config)))
    np.testing.assert_allclose(found, world.max_reaches(config), atol=1)
    assert np.all(np.asarray(found) >= 20)  # 200 steps, shortest solutions of 2 to 10 steps

    def turning(state, u):  # childhood: turning round never moves, so a random start follows stuck_steps turns
        return open_env.transition(state, jnp.int32(cw.TURN), world.childhood_task(config), u)

    _, events = jax.lax.scan(turning, child, jax.random.uniform(jax.random.key(1), (45, world.num_spawn_draws)))
    assert np.flatnonzero(events.respawned).tolist() == [19, 39] and not events.reached.any()
    with pytest.raises(ConfigError, match="world_settings: CorridorSettings"):
        worlds.configure(config, "corridor", cells="rgx")
    # A name its SETTINGS lack is refused by worlds.make for every world, listing what it may set.
    with pytest.raises(ConfigError, match=r"^world_settings: unknown setting 'width' of world corridor \(settable: "):
        worlds.configure(config, "corridor", width=3)

    @dataclasses.dataclass(frozen=True)
    class Miscounted(cw.Corridor):
        def num_inputs(self, config=None):  # one more than it observes: refused before any life
            return 10

    worlds.register("miscounted", Miscounted())
    with pytest.raises(ConfigError, match=r"world_inputs: world miscounted observes an array of shape \(9,\), not"):
        worlds.configure(config, "miscounted")


def test_a_learning_tests_performance_is_reaches_over_the_worlds_own_maximum(tiny):
    """A test's performance per bin divides by the world's own most reaches per task (XLand's differ by task), not
    the arena's: reaching a task's maximum in every bin is 1 in every task."""
    pytest.importorskip("xminigrid")
    from imrl_jax.analysis.steady_state import performance_curve
    from imrl_jax.evolution.sweeps import normalised_curve

    config = worlds.configure(tiny("LE-LS", task_steps=2_800, num_bins=2), "xland")
    most = np.asarray(worlds.world_of(config).max_reaches(config))
    np.testing.assert_array_equal(worlds.task_maxima(config), most)
    assert len(set(most.tolist())) > 1  # the tasks' shortest solutions differ
    full = np.repeat(most[:, None] / 2, 2, axis=1)
    np.testing.assert_allclose(performance_curve(config, full), 1.0)
    np.testing.assert_allclose(normalised_curve(config, full), 1.0)
    arena = tiny("LE-LS", task_steps=2_800, num_bins=2)
    np.testing.assert_array_equal(worlds.task_maxima(arena), np.asarray(arena.theoretical_max()))
