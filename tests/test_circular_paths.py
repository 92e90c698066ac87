"""A robot that repeats one action (claim 4's circular path): hand-computed trips, a loop over the environment, the summary."""

import math
import os

import numpy as np
import pytest

from experiments import circular_paths as study
from imrl_jax.analysis import controllers
from imrl_jax.config import Task, make_config
from imrl_jax.world.env import make_env, task_spec


def _one_edge_config():
    """One task: the target is the next vertex straight ahead, 40 cm along a red edge."""
    s = 20 * math.sqrt(3)
    return make_config("paper", tasks=(Task(start=(140.0, 200 - s), heading_deg=0.0, target=(180.0, 200 - s)),))


def test_straight_ahead_reaches_at_the_theoretical_maximum():
    """40 cm at 2 cm a step: within 10 cm after ceil(30 / 2) = 15 steps, a trip every 15 steps; half speed every 30."""
    config = _one_edge_config()
    assert config.steps_per_trip() == (15,)
    performance = controllers.constant_performance(config, np.array([[0.5, 1.0], [0.5, 0.5], [1.0, 1.0]]), 600)
    assert np.allclose(np.asarray(performance)[:, 0], [1.0, 0.5, 0.0])  # the full turn circles on the spot (r 3.8 cm)


def test_constant_action_follows_the_environment_step_by_step():
    """The scanned, vmapped measure equals a Python loop over the environment's own transition."""
    config, steps = make_config("paper"), 400
    action = np.array([0.51, 1.0], np.float32)  # task 1's best arc: reaches within 400 steps
    arena = make_env(config)
    for task_index in (0, 1):
        task = task_spec(config, task_index)
        state, reaches = arena.at(task.start), 0
        for _ in range(steps):
            state, events = arena.transition(state, action, task)
            reaches += int(events.reached)
        expected = reaches / (steps / config.steps_per_trip()[task_index])
        got = float(controllers.constant_performance(config, action[None], steps)[0, task_index])
        assert abs(got - expected) < 1e-6, (task_index, got, expected)
        assert (reaches > 0) == (task_index == 0)  # the arc that serves task 1 misses task 2's target


def test_summary_on_hand_made_performance():
    grid = np.array([[0.4, 1.0], [0.5, 1.0], [0.6, 1.0]])
    performance = np.array([[0.9, 0.0, 0.2, 0.0],   # mean 0.275
                            [0.3, 0.3, 0.3, 0.3],   # mean 0.3
                            [0.0, 0.8, 0.0, 0.7]])  # mean 0.375: the best single action
    summary = study.summarise(grid, performance, pairs=((0, 1), (2, 3)))
    assert summary["one_action"]["turn"] == 0.6 and abs(summary["one_action"]["performance"] - 0.375) < 1e-12
    assert [t["performance"] for t in summary["per_task"]] == [0.9, 0.8, 0.3, 0.7]
    assert summary["per_pair"][0]["turn"] == 0.4 and summary["per_pair"][0]["performance"] == [0.9, 0.0]
    assert summary["per_pair"][1]["turn"] == 0.6  # 0.0 + 0.7 beats 0.3 + 0.3 and 0.2 + 0.0
    assert abs(summary["one_action_per_pair"] - (0.9 + 0.7) / 4) < 1e-12


def test_bad_task_steps_exit_2(capsys, tmp_path):
    assert study.main(["--out", str(tmp_path / "c"), "--task-steps", "0"]) == 2
    assert capsys.readouterr().err.strip() == "error: --task-steps: must be at least 1 (got 0)"
    assert not (tmp_path / "c").exists()


def test_the_committed_summary_is_what_the_committed_grid_holds():
    """claims/circles/result.json's numbers (docs/CLAIMS.md, claim 4) from its circles.csv (4 decimals)."""
    import json
    import os

    from helpers import ROOT

    folder = os.path.join(ROOT, study.OUT)
    table = np.loadtxt(os.path.join(folder, "circles.csv"), delimiter=",", skiprows=1)
    assert np.allclose(table[:, :2], study.actions())
    summary = study.summarise(table[:, :2], table[:, 2:8])
    with open(os.path.join(folder, "result.json")) as f:
        committed = json.load(f)
    assert committed["actions"] == 6006 and committed["task_steps"] == study.TASK_STEPS
    assert abs(summary["one_action"]["performance"] - committed["one_action"]["performance"]) < 1e-4
    assert summary["one_action"]["turn"] == committed["one_action"]["turn"] == 0.487
    assert abs(summary["one_action_per_pair"] - committed["one_action_per_pair"]) < 1e-4
    assert np.allclose([t["performance"] for t in summary["per_task"]],
                       [t["performance"] for t in committed["per_task"]], atol=1e-4)
    assert abs(committed["per_task"][0]["performance"] - 0.9792) < 1e-4  # the document's 0.979


def hostile_cases(parser, skip=()):
    """(flag, value) for every option of ``parser`` and every hostile value of its type (tests/attack.py)."""
    from attack import HOSTILE_FLOATS, HOSTILE_INTS, HOSTILE_TEXTS

    kinds = {int: HOSTILE_INTS, float: HOSTILE_FLOATS}
    return [(action.option_strings[-1], value) for action in parser._actions
            if action.option_strings and action.option_strings[-1] not in ("--help", *skip)
            for value in kinds.get(action.type, HOSTILE_TEXTS)]


@pytest.mark.parametrize("flag, value", hostile_cases(study.parser()))
def test_hostile_values_are_refused_or_planned_with_nothing_written(tmp_path, flag, value):
    """Every option of the measure's parser, every hostile value: one line and exit 2, or a plan; nothing written."""
    from attack import assert_contract, attack

    argv = ["--out", "circles", f"{flag}={value}"]
    outcome = attack(study.main, argv, str(tmp_path))
    if assert_contract(outcome, flag, "memory", argv=argv) == "planned":  # a sane value only
        assert outcome.plan.checked["task_steps"] >= 1 and outcome.plan.checked["out"].strip()


def test_an_out_holding_another_file_is_refused(tmp_path):
    """The measure's folder may hold its own files (a measure run again), nothing else."""
    from attack import assert_contract, assert_refused, attack

    (tmp_path / "circles").mkdir()
    (tmp_path / "circles" / "notes.txt").write_text("mine")
    assert_refused(attack(study.main, ["--out", "circles"], str(tmp_path)), "--out")
    os.remove(tmp_path / "circles" / "notes.txt")
    (tmp_path / "circles" / "circles.csv").write_text("old")
    assert assert_contract(attack(study.main, ["--out", "circles"], str(tmp_path))) == "planned"


def test_a_grid_too_large_for_memory_is_refused(tmp_path):
    """1e9 steps per task keeps 36 TB of reach flags: refused before a compile (was an allocation failure)."""
    from attack import assert_refused, attack

    assert_refused(attack(study.main, ["--out", "c", "--task-steps", "1000000000"], str(tmp_path)), "memory")


@pytest.mark.parametrize("out", ["a\x00b", "a\nb", "/", "//"])
def test_an_out_no_folder_can_be_made_of_is_refused(tmp_path, out):
    """A NUL (a ValueError when the folder is made, after the lives) or the root: refused before anything is done."""
    from attack import assert_refused, attack

    assert_refused(attack(study.main, ["--out", out], str(tmp_path)), "--out")
