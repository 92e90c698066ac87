"""The selector sweep: a study of one measure of no run, its committed result found where it lies."""

import json
import os

import pytest

from experiments import reproduce
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
    with pytest.raises(SystemExit) as stop:
        sweep.main(["--out", str(tmp_path), "sweep", "--lambdas", "0,x"])
    assert stop.value.code == 2
    assert "argument --lambdas: not a comma-separated list of numbers: '0,x'" in capsys.readouterr().err
    assert not os.listdir(tmp_path)
