"""The selector sweep: a study of one measure of no run, its committed result found where it lies."""

import json
import math
import os

import pytest

from experiments.harness import reproduce
from experiments import selector_sweep as sweep


def test_the_committed_sweep_is_done():
    """Its one stage is done: the committed folder holds result.json, the summary its sweep.json records."""
    stages, scale = sweep.all_stages()
    assert [(s.name, s.kind, s.out_dir, s.needs) for s in stages] == [("measure sweep", "measure", sweep.OUT, ())]
    assert reproduce.stage_done(stages[0], scale) and stages[0].cost == 60 * 3 * 6 * 100_000
    with open(os.path.join(sweep.OUT, "result.json")) as f, open(os.path.join(sweep.OUT, "sweep.json")) as g:
        result = json.load(f)
        assert result == json.load(g)
    assert (result["best"]["trace_lambda"], result["best"]["eta_selector_actor"],
            result["best"]["eta_selector_critic"]) == (0.98, 0.3, 0.001)  # the extension preset's point
    assert round(result["best"]["performance"], 3) == 0.656 and round(result["paper"]["performance"], 3) == 0.100
    command = sweep.SWEEP.stage_command(stages[0])[0]
    assert command[1:] == ["-m", "experiments.selector_sweep", "--out", sweep.OUT, "sweep"]


def test_a_tiny_sweep_writes_its_result_last(tmp_path):
    """Two points of 200-step tasks, one lane each: a row per point, the summary in sweep.json and result.json."""
    out = str(tmp_path / "sweep")
    assert sweep.main(["--out", out, "sweep", "--task-steps", "200", "--seeds", "1", "--lambdas", "0,0.9",
                       "--selector-actor-rates", "0.3", "--selector-critic-rates", "0.01"]) == 0
    assert sorted(os.listdir(out)) == ["result.json", "sweep.csv", "sweep.json", "sweep.png"]
    with open(os.path.join(out, "sweep.csv")) as f:
        assert [line.split(",")[0] for line in f.read().splitlines()] == ["trace_lambda", "0.0000", "0.9000"]
    with open(os.path.join(out, "result.json")) as f:
        result = json.load(f)
    assert result["paper"] is None and result["best"]["trace_lambda"] in (0.0, 0.9)
    assert 0.0 <= result["best"]["performance"] <= 1.0 and result["task_steps"] == 200 and result["seeds"] == 1
    assert result["command"].startswith("python -m experiments.selector_sweep --out ")


def test_a_bad_grid_exits_2(tmp_path, capsys):
    """One line, exit 2 (argparse's usage and error, two lines, before)."""
    assert sweep.main(["--out", str(tmp_path), "sweep", "--lambdas", "0,x"]) == 2
    assert capsys.readouterr().err == "error: argument --lambdas: not a comma-separated list of numbers: '0,x'\n"
    assert not os.listdir(tmp_path)


def _attack(tmp_path, *argv):
    from attack import attack

    return attack(sweep.main, ["--out", "sweep", "sweep", *argv], str(tmp_path))


def _hostile_cases():
    from test_circular_paths import hostile_cases

    return hostile_cases(sweep.parser())


@pytest.mark.parametrize("flag, value", _hostile_cases())
def test_hostile_values_are_refused_or_planned_with_nothing_written(tmp_path, flag, value):
    """Every option of the sweep's parser, every hostile value: one line and exit 2, or a plan; nothing written."""
    from attack import assert_contract

    outcome = _attack(tmp_path, f"{flag}={value}")
    if assert_contract(outcome, flag, "memory", "lanes", argv=[flag, value]) == "planned":
        assert 1 <= outcome.plan.checked["lanes"] and all(
            math.isfinite(v) for point in outcome.plan.checked["grid"] for v in point.values())


@pytest.mark.parametrize("argv, flag", [
    (["--lambdas", "0,nan"], "--lambdas"),  # a NaN rate: lived as NaN, written as the best point before
    (["--selector-actor-rates=-1"], "--selector-actor-rates"),  # below the config's bound: accepted before
    (["--selector-critic-rates", "100"], "--selector-critic-rates"),
    (["--lambdas", "1"], "--lambdas"),  # a trace that never decays
    (["--lambdas", "0,0"], "--lambdas"),  # one point twice
    (["--seeds", "0"], "--seeds"),  # an empty mean: NaN rows before
    (["--seeds", "100000000"], "--seeds: 100,000,000 is above the limit"),
    (["--task-steps", "0"], "--task-steps"),
    (["--turn-gain", "inf"], "--turn-gain"),
    (["--seeds", "10000", "--lambdas", ",".join(str(i / 100) for i in range(99))], "lanes"),
])
def test_bad_sweeps_are_refused_in_one_line(tmp_path, argv, flag):
    from attack import assert_refused

    assert_refused(_attack(tmp_path, *argv), flag, argv=argv)


def test_an_out_holding_another_file_is_refused(tmp_path):
    """The sweep's folder may hold its own files and the study runner's (a stage run again), nothing else."""
    from attack import assert_contract, assert_refused

    (tmp_path / "sweep" / "logs").mkdir(parents=True)
    for name in ("sweep.csv", "manifest.json"):
        (tmp_path / "sweep" / name).write_text("old")
    assert assert_contract(_attack(tmp_path)) == "planned"
    (tmp_path / "sweep" / "notes.txt").write_text("mine")
    assert_refused(_attack(tmp_path), "--out")
