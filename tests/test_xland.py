"""The XLand world (imrl_jax.world.xland) and its hand-written controllers (imrl_jax.analysis.xland_controllers)."""

import subprocess
import sys

import pytest

pytest.importorskip("xminigrid")

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402
from xminigrid.core.constants import Colors, Tiles  # noqa: E402

from helpers import ROOT  # noqa: E402
from imrl_jax.analysis import xland_controllers  # noqa: E402
from imrl_jax.config import Config  # noqa: E402
from imrl_jax.world import xland  # noqa: E402
from imrl_jax.world.base import DISCRETE  # noqa: E402

#: The smallest room: 9 x 9, the hub at (4, 4), the door at (4, 2), the key at (6, 6).
SMALL = xland.XLandSettings(arm_length=3)
CONFIG = Config()
FORWARD, RIGHT, LEFT, PICK_UP, TOGGLE = range(5)  # action indices of the default settings


def small(**changes) -> xland.XLand:
    return xland.XLand(xland.XLandSettings(**{"arm_length": 3, **changes}))


def test_world_interface_sizes():
    world = small()
    assert world.name == "xland" and world.num_spawn_draws == 2
    assert world.num_inputs(CONFIG) == 3 * 3 * (3 + 3) + 1 == 55
    assert world.actions(CONFIG) == (DISCRETE, 5)
    assert world.num_tasks(CONFIG) == 6
    # the room's corridors: 3 red, 3 green (one the door), 3 blue (one the key), the hub, walls elsewhere
    grid = xland.room(SMALL)
    assert grid.shape == (9, 9, 2)
    assert tuple(grid[4, 2]) == (Tiles.DOOR_CLOSED, Colors.GREEN) and tuple(grid[6, 6]) == xland.KEY_TILE
    assert len(xland.free_cells(SMALL)) == 1 + 4 + 3 + 3  # floor: hub, red, green less the door, blue less the key


def test_observation_on_a_hand_built_state():
    world, env = small(), small().make_env(CONFIG)
    at_hub = env.at(xland.room(SMALL), (4, 4), xland.UP)  # walls ahead, green on the left, blue on the right
    x = np.asarray(env.observe(at_hub))
    assert x.shape == (world.num_inputs(CONFIG),) and x.dtype == np.float32
    cells = x[:-1].reshape(3, 3, 6)  # far row first, left to right; red, green, blue, blocked, door, key
    np.testing.assert_array_equal(cells[:2, :, 3], 1)  # two rows of wall ahead
    np.testing.assert_array_equal(cells[:2, :, :3], 0)
    np.testing.assert_array_equal(cells[2], [[0, 1, 0, 0, 0, 0], [0, 0, 0, 0, 0, 0], [0, 0, 1, 0, 0, 0]])
    assert x[-1] == 0
    facing_door = np.asarray(env.observe(env.at(xland.room(SMALL), (4, 3), xland.LEFT))).reshape(-1)[:-1]
    np.testing.assert_array_equal(facing_door.reshape(3, 3, 6)[1, 1], [0, 1, 0, 0, 1, 0])  # a green closed door
    facing_key = env.at(xland.room(SMALL), (5, 6), xland.DOWN)
    np.testing.assert_array_equal(np.asarray(env.observe(facing_key)).reshape(-1)[:-1].reshape(3, 3, 6)[1, 1],
                                  [0, 0, 0, 0, 0, 1])  # the yellow key: its colour is not encoded
    holding = facing_key._replace(pocket=jnp.asarray(xland.KEY_TILE, jnp.uint8))
    assert np.asarray(env.observe(holding))[-1] == 1


def test_hand_computed_transitions():
    env, params = small().make_env(CONFIG), small().task(CONFIG, 0)
    step = jax.jit(env.transition)
    at_hub = env.at(xland.room(SMALL), (4, 4), xland.UP)
    state, events = step(at_hub, jnp.int32(FORWARD), params)  # a wall ahead: no move
    np.testing.assert_array_equal(state.position, (4, 4))
    assert int(state.trial_step) == 1 and int(state.still) == 1 and not bool(events.reached)
    state, _ = step(state, jnp.int32(RIGHT), params)
    assert int(state.direction) == xland.RIGHT
    state, _ = step(state, jnp.int32(FORWARD), params)  # onto the blue path
    np.testing.assert_array_equal(state.position, (4, 5))
    assert int(state.still) == 0
    facing_key = env.at(xland.room(SMALL), (5, 6), xland.DOWN)
    state, _ = step(facing_key, jnp.int32(PICK_UP), params)
    np.testing.assert_array_equal(state.pocket, xland.KEY_TILE)
    assert tuple(np.asarray(state.grid[6, 6])) == (Tiles.FLOOR, Colors.BLACK)
    state, _ = step(env.at(xland.room(SMALL), (4, 3), xland.LEFT), jnp.int32(TOGGLE), params)
    assert int(state.grid[4, 2, 0]) == Tiles.DOOR_OPEN


@pytest.mark.parametrize("task_set", ["xland", "xland-novel"])
def test_shortest_solutions_reach_on_their_last_step_and_restart_the_trial(task_set):
    world = small(task_set=task_set)
    env = world.make_env(CONFIG)
    step = jax.jit(env.transition)
    for index, task in enumerate(xland.tasks(world.settings)):
        params = world.task(CONFIG, index)
        state = env.reset(None, params)
        reached = []
        for action in xland.shortest_solution(world.settings, task):
            state, events = step(state, jnp.int32(action), params)
            reached.append(bool(events.reached))
        assert reached == [False] * (len(reached) - 1) + [True], (task_set, index)
        np.testing.assert_array_equal(state.position, task.start)  # back at the start, the room as it began
        assert int(state.trial_step) == 0 and int(state.pocket[0]) == Tiles.EMPTY
        np.testing.assert_array_equal(state.grid, xland.room(world.settings))
    np.testing.assert_array_equal(world.max_reaches(CONFIG), CONFIG.task_steps // world.shortest())
    assert world.shortest().min() >= 2


def test_timeout_restarts_the_trial():
    world = small(trial_timeout=5)
    env, params = world.make_env(CONFIG), world.task(CONFIG, 2)  # the green end, facing the door
    step = jax.jit(env.transition)
    state = env.reset(None, params)
    state, _ = step(state, jnp.int32(TOGGLE), params)  # nothing ahead to toggle yet: one step on
    for _ in range(3):
        state, events = step(state, jnp.int32(FORWARD), params)
        assert not bool(events.timeout)
    assert int(state.grid[4, 2, 0]) == Tiles.DOOR_CLOSED  # the door ahead
    state, events = step(state, jnp.int32(TOGGLE), params)  # the fifth step opens it and times out
    assert bool(events.timeout) and not bool(events.reached)
    np.testing.assert_array_equal(state.position, xland.tasks(world.settings)[2].start)
    np.testing.assert_array_equal(state.grid, xland.room(world.settings))  # closed again
    assert int(state.trial_step) == 0


def test_childhood_never_reaches_and_respawns_when_stuck():
    world = small(stuck_steps=4)
    open_env = world.make_env(CONFIG, has_target=False)
    childhood = world.childhood_task(CONFIG)
    assert jax.tree.structure(childhood) == jax.tree.structure(world.task(CONFIG, 0))
    # task 1's solution, driven in childhood: its goal is passed, nothing is reached, nothing restarts
    task = xland.tasks(world.settings)[0]
    state = open_env.at(xland.room(SMALL), task.start, task.direction)
    step = jax.jit(open_env.transition)
    for action in xland.shortest_solution(world.settings, task) * 3:
        state, events = step(state, jnp.int32(action), childhood)
        assert not bool(events.reached | events.timeout | events.respawned)
    assert int(state.trial_step) == 3 * len(xland.shortest_solution(world.settings, task))
    respawning = world.make_env(CONFIG, has_target=False, respawn=True)
    state = respawning.reset(jax.random.key(0), childhood)
    assert tuple(np.asarray(state.position)) in {tuple(c) for c in xland.free_cells(SMALL)}
    spawn = jnp.asarray([0.99, 0.3])  # the last floor cell, facing right
    step = jax.jit(respawning.transition)
    for i in range(4):
        state, events = step(state, jnp.int32(LEFT), childhood, spawn)  # turning: not moving
        assert bool(events.respawned) == (i == 3) and not bool(events.reached)
    np.testing.assert_array_equal(state.position, xland.free_cells(SMALL)[-1])
    assert int(state.direction) == 1 and int(state.still) == 0


def test_jit_vmap_over_8_lanes_equals_a_loop():
    world = small(trial_timeout=7, stuck_steps=3)
    num_lanes, num_steps = 8, 12
    actions = jax.random.randint(jax.random.key(3), (num_steps, num_lanes), 0, 5)
    spawns = jax.random.uniform(jax.random.key(4), (num_steps, num_lanes, world.num_spawn_draws))
    for has_target, respawn in ((True, False), (False, True)):
        env = world.make_env(CONFIG, has_target, respawn)
        params = [world.task(CONFIG, i % 6) if has_target else world.childhood_task(CONFIG) for i in range(num_lanes)]
        stacked = jax.tree.map(lambda *p: jnp.stack(p), *params)
        keys = jax.random.split(jax.random.key(5), num_lanes)
        states = jax.vmap(env.reset)(keys, stacked)
        vstep = jax.jit(jax.vmap(env.transition))
        step, observe, vobserve = jax.jit(env.transition), jax.jit(env.observe), jax.jit(jax.vmap(env.observe))
        singles = [env.reset(keys[i], params[i]) for i in range(num_lanes)]
        for t in range(num_steps):
            states, events = vstep(states, actions[t], stacked, spawns[t])
            for i in range(num_lanes):
                singles[i], one = step(singles[i], actions[t, i], params[i], spawns[t, i])
                for a, b in zip(jax.tree.leaves((states, events)), jax.tree.leaves((singles[i], one))):
                    np.testing.assert_array_equal(a[i], b)
            np.testing.assert_array_equal(vobserve(states), np.stack([observe(s) for s in singles]))


def test_controllers_compose_every_task_and_no_fixed_behaviour_does():
    world, num_steps = small(), 300
    result = xland_controllers.scores(world, CONFIG, num_steps, num_seeds=2)
    np.testing.assert_array_equal(result["composition"], 1.0)  # every shortest solution, back to back
    for name in ("cycle", "random", "follower"):
        assert result[name].max() < 0.1, (name, result[name])
    novel = xland_controllers.composition_reaches(small(task_set="xland-novel"), CONFIG, num_steps)
    assert np.all(np.asarray(novel) > 0)


def test_settings_are_checked_and_the_extra_is_named_when_missing():
    with pytest.raises(ValueError, match="arm_length"):
        xland.XLandSettings(arm_length=2)
    with pytest.raises(ValueError, match="view_size"):
        xland.XLandSettings(view_size=4)
    with pytest.raises(ValueError, match="stuck_steps"):
        xland.XLandSettings(stuck_steps=0)
    with pytest.raises(ValueError, match="xland-novel"):
        xland.tasks(xland.XLandSettings(task_set="nope"))
    code = "import sys; sys.modules['xminigrid'] = None; import imrl_jax.world.xland"
    run = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True)
    assert run.returncode != 0 and "pip install -e '.[worlds]'" in run.stderr
