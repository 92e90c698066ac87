"""A selector on its own time-scale (docs/TIMESCALE.md): option ends, one-step options, bad values."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import EXTENDED, SHORT_TASK, evolve_args, hand_experts

from imrl_jax import conditions as C
from imrl_jax.commands import evolve
from imrl_jax.agent import lifetime as L
from imrl_jax.agent import timescale
from imrl_jax.world.arena import Pose
from imrl_jax.config import ConfigError
from imrl_jax.agent.networks import decode
from imrl_jax.agent.state import Previous
from imrl_jax.world.env import at


def _xb(points):
    """x~ with the given (point, colour) pairs seen, and the bias."""
    x = np.zeros(37)
    for point, colour in points:
        x[3 * point + colour] = 1.0
    x[-1] = 1.0
    return jnp.asarray(x)


def _prev(valid=True, terminal=False):
    return Previous(jnp.int32(1), jnp.zeros(2), jnp.zeros(2), jnp.zeros(3), jnp.bool_(valid), jnp.bool_(terminal))


def test_option_ends_by_hand(tiny):
    """A colour coming into view ends a "colour" option; one already seen, or one leaving, does not."""
    config = tiny("EE-LS", selector_period=10, selector_termination="colour")
    option = timescale.init_option(3, 37, jnp.float32)._replace(steps=jnp.int32(3))
    red_here, red_there, red_and_green = _xb([(0, 0)]), _xb([(5, 0), (6, 0)]), _xb([(0, 0), (11, 1)])
    ends = lambda now, before, **kw: bool(timescale.ends(config, option, _prev(**kw), now, before))  # noqa: E731
    assert not ends(red_there, red_here)  # red moved across the retina: no new colour
    assert ends(red_and_green, red_here)  # green came into view: a junction
    assert not ends(red_here, red_and_green)  # green left the view
    assert ends(red_here, red_here, valid=False) and ends(red_here, red_here, terminal=True)  # a trial ended
    assert ends(red_here, red_here) is False
    assert bool(timescale.ends(config, option._replace(steps=jnp.int32(9)), _prev(), red_here, red_here))  # 10 steps
    period = config.replace(selector_termination="period")
    assert not bool(timescale.ends(period, option, _prev(), red_and_green, red_here))  # "period" ignores colours
    np.testing.assert_array_equal(timescale.colours_seen(red_and_green), [1.0, 1.0, 0.0])


@pytest.mark.usefixtures("x64")
@pytest.mark.parametrize("phase_name", ["childhood", "adulthood"])
def test_one_step_options_are_the_papers_rules(tiny, phase_name):
    """Options forced at every step (period 1) learn exactly as the paper's per-step selector."""
    steps = 1500
    if phase_name == "childhood":
        config = tiny("LE-LS", childhood_steps=steps, childhood_walls="respawn", wall_respawn_steps=5,
                      childhood_selector_reward="progress", progress_rate=0.05)
        agent = decode(config, jax.random.uniform(jax.random.key(7), (config.num_genes,), jnp.float64, -1.0, 1.0))
        phase, task = L.childhood_phase(config), L.childhood_task(config, jnp.float64)
        pose = Pose(jnp.array([40.0, 60.0]), jnp.array(math.pi))
    else:
        config = tiny("EE-LS", tasks=(SHORT_TASK,), task_steps=steps, num_bins=1)
        agent = decode(config, jnp.zeros((config.num_genes,), jnp.float64))._replace(actor=jnp.asarray(hand_experts(37)))
        phase, task = C.ADULT_LEARNING_SELECTOR, L.task_spec(config, 0, jnp.float64)
        pose = task.start
    params = config.replace(**EXTENDED).learning_params()
    start = L.init_state(config, agent, at(pose))
    assert start.option is None  # period 1: the paper's path
    run = jax.jit(L.simulate, static_argnums=(1, 2, 6))
    key = jax.random.key(0)
    paper, paper_steps = run(key, config, phase, params, task, start, steps)
    forced = start._replace(option=timescale.init_option(3, 37, jnp.float64))  # options, each of one step
    option, option_steps = run(key, config, phase, params, task, forced, steps)
    np.testing.assert_array_equal(option_steps.k, paper_steps.k)
    assert int(np.sum(np.diff(np.asarray(paper_steps.k)) != 0)) > 100
    for name in ("actor", "evaluator", "selector_actor", "selector_critic"):
        np.testing.assert_allclose(getattr(option.agent, name), getattr(paper.agent, name), rtol=1e-10, atol=1e-12,
                                   err_msg=name)
    assert np.abs(np.asarray(paper.agent.selector_critic)).max() > 1e-4


@pytest.mark.parametrize("changes, field", [
    (dict(selector_period=0), "selector_period"),
    (dict(selector_period=2.5), "selector_period"),
    (dict(selector_termination="junction"), "selector_termination"),
])
def test_bad_timescale_values_name_the_field(tiny, changes, field):
    with pytest.raises(ConfigError, match=f"^{field}:"):
        tiny("EE-LS", **changes)


def test_bad_timescale_value_on_the_command_line_exits_2(tmp_path, capsys):
    out = tmp_path / "run"
    code = evolve.main([*evolve_args(generations=1), "--set", "selector_period=-3", "--out", str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and err[0].count("selector_period") >= 1, err
    assert not out.exists()


def test_sle_ignores_the_selector_timescale(tiny):
    """One expert has nothing to choose: the fields are ignored (a resume under other values is allowed)."""
    assert {"selector_period", "selector_termination"} <= C.CONDITIONS["SLE"].ignored_fields()
    assert "selector_period" not in C.CONDITIONS["EE-ES"].ignored_fields()  # its evolved selector chooses options
    assert tiny("SLE").model_differences(tiny("SLE", selector_period=9)) == []
