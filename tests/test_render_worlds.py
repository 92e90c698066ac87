"""``python -m imrl_jax.render`` of a run in another world (XLand): a still and an animation drawn from the
recorded life, and the options a still has no use for refused."""

import json
import os

import jax
import numpy as np
import pytest
from PIL import Image

from helpers import tiny_config

pytest.importorskip("xminigrid")  # the worlds extra (not in the minimum environment)

from imrl_jax.agent import lifetime as L  # noqa: E402
from imrl_jax.agent.networks import decode  # noqa: E402
from imrl_jax.agent.state import init_state  # noqa: E402
from imrl_jax.analysis import xland_figures as X  # noqa: E402
from imrl_jax.commands import render  # noqa: E402
from imrl_jax.world import worlds, xland  # noqa: E402


def _config():
    return worlds.configure(tiny_config("EE-LS", task_steps=60, num_bins=1, population_size=2), "xland")


@pytest.fixture(scope="module")
def xland_run(tmp_path_factory):
    """A run directory in XLand, its genomes random."""
    return _run_dir(tmp_path_factory.mktemp("xland") / "run", _config())


def test_a_still_and_an_animation_of_a_life_in_xland(xland_run, tmp_path, capsys):
    png, gif = tmp_path / "life.png", tmp_path / "life.gif"
    assert render.main([xland_run, "--task", "2", "--steps", "20", "--out", str(png)]) == 0
    assert "a still of task 2" in capsys.readouterr().out
    summary = render.run(xland_run, 2, str(gif), steps=20, every=5)
    with Image.open(png) as image:
        assert image.format == "PNG"
    with Image.open(gif) as image:
        assert image.format == "GIF" and image.n_frames == 4 == summary["frames"]
    assert sorted(os.listdir(tmp_path)) == ["life.gif", "life.png"]  # the temporary files are gone
    assert summary["index"] == 1 and summary["fitness"] == 0.1


def test_the_drawing_is_the_recorded_life():
    """The path joins the positions simulate recorded (a restart's jump left out), the agent is on the last one
    pointing its way, and the room is drawn as the world's state has it (an opened door, a picked key)."""
    config = _config()
    world = worlds.world_of(config)
    agent = decode(config, jax.random.uniform(jax.random.key(3), (config.num_genes,), minval=-1.0, maxval=1.0))
    key, params, steps = jax.random.key(4), config.learning_params(), 40
    life = X.task_life(key, config, params, agent, 1, steps)
    task = world.task(config, 1)
    start = world.make_env(config).reset(None, task)
    _, record = L.simulate(key, config, config.spec.adult, params, task, init_state(config, agent, start), steps,
                           config.task_steps)
    recorded = np.concatenate([np.asarray(start.position)[None], np.asarray(record.world.position)])
    np.testing.assert_array_equal(life.position, recorded)

    fig = X.plot_life(config, life, task=1)
    room_ax = fig.axes[0]
    (path,) = room_ax.collections[2:]  # after the cells' vertical and horizontal lines
    drawn = sorted(tuple(map(tuple, s)) for s in path.get_segments())
    breaks = np.asarray(record.reached | record.timeout | record.respawned)
    expected = sorted(((float(c0), float(r0)), (float(c1), float(r1)))
                      for (r0, c0), (r1, c1), b in zip(recorded[:-1], recorded[1:], breaks) if not b)
    assert drawn == expected and len(drawn) == steps - breaks.sum()
    assert any(a != b for a, b in drawn)  # the agent moved
    (triangle,) = room_ax.patches
    tip = triangle.get_xy()[0]
    (row, col), direction = recorded[-1], int(np.asarray(record.world.direction)[-1])
    np.testing.assert_allclose(tip, np.array([col, row]) + 0.38 * X.AHEAD[direction])

    grid = xland.room(world.settings)
    door, key_cell = (tuple(np.argwhere(grid[..., 0] == t)[0]) for t in (X.DOOR_CLOSED, X.KEY))
    changed = grid.copy()
    changed[door] = (X.DOOR_OPEN, X.GREEN)
    changed[key_cell] = (X.FLOOR, 7)  # picked up: xminigrid leaves plain floor
    before, after = X.room_pixels(grid), X.room_pixels(changed)
    px = X.CELL_PX

    def cell(image, rc):
        return image[rc[0] * px:(rc[0] + 1) * px, rc[1] * px:(rc[1] + 1) * px]

    assert not np.array_equal(cell(before, door), cell(after, door))
    np.testing.assert_array_equal(cell(after, key_cell), np.broadcast_to(X.PLAIN_RGB, (px, px, 3)))
    assert np.isclose(cell(before, key_cell), X.KEY_RGB).all(-1).any()  # the key's yellow
    same = np.ones(grid.shape[:2], bool)
    same[door] = same[key_cell] = False
    for rc in zip(*np.nonzero(same)):
        np.testing.assert_array_equal(cell(before, rc), cell(after, rc))
    # The still draws the room of the last state, a frame the room of its step.
    life = life._replace(grid=life.grid.copy())
    life.grid[-1] = changed
    for t, drawn_grid in ((None, changed), (0, grid)):
        image = X.plot_life(config, life, task=1, t=t).axes[0].images[0].get_array()
        np.testing.assert_array_equal(image, X.room_pixels(drawn_grid))


@pytest.mark.parametrize("flag", ["--every", "--fps"])
def test_a_still_refuses_an_animations_options(xland_run, tmp_path, capsys, flag):
    out = tmp_path / "x.png"
    assert render.main([xland_run, "--task", "1", "--out", str(out), flag, "2"]) == 2
    assert capsys.readouterr().err == f"error: {flag}: x.png is a still, it has no frames (leave {flag} out, " \
                                      "or write a .gif)\n"
    assert os.listdir(tmp_path) == []


def _run_dir(path, config):
    """A run directory as evolve leaves one (config.json, final_population.npz) of two random genomes."""
    path.mkdir()
    (path / "config.json").write_text(json.dumps({"config": config.to_dict(), "seeds": [0]}))
    genomes = np.asarray(jax.random.uniform(jax.random.key(0), (1, 2, config.num_genes), minval=-1.0, maxval=1.0))
    np.savez(path / "final_population.npz", generation=1, evaluated=genomes, fitness=np.array([[0.0, 0.1]]))
    return str(path)


def test_a_world_is_drawn_only_in_its_formats(tmp_path, capsys):
    """The arena has no still (its render is as it was); render looks each world's drawing up in one table."""
    arena = _run_dir(tmp_path / "arena", tiny_config("EE-LS", population_size=2))
    assert render.main([arena, "--task", "1", "--out", str(tmp_path / "a.png")]) == 2
    assert capsys.readouterr().err == "error: --out: a life in world arena is drawn as .gif or .mp4, not .png\n"
    assert set(render.DRAWERS) == set(worlds.WORLDS) and os.listdir(tmp_path) == ["arena"]
