"""The studies' shared helpers: markdown rows (experiments.harness.markdown), a history.csv's columns (loading) and a measure's CSV and result.json (study)."""

import json

import numpy as np

from experiments.harness import loading, markdown, study


def test_markdown_rows_and_mean_sd():
    assert markdown.head("row", "steady state") == ["| row | steady state |", "|---|---|"]
    assert markdown.line("", 3, "0.5") == "|  | 3 | 0.5 |"
    assert markdown.table(["a", "b"], [[1, "x"], ["", 0.5]]) == "| a | b |\n|---|---|\n| 1 | x |\n|  | 0.5 |"
    assert markdown.mean_sd(0.8456, 0.0125) == "0.846 +- 0.013" and markdown.mean_sd(2, 0.5, 1) == "2.0 +- 0.5"



def test_history_columns_by_generation_and_seed(tmp_path):
    assert loading.history_columns(str(tmp_path), ["best"]) is None and loading.history_columns(None, ["best"]) is None
    (tmp_path / "history.csv").write_text("generation,seed,best,mean_a\n0,3,0.1,1\n0,1,0.2,2\n1,1,0.4,4\n")
    values = loading.history_columns(str(tmp_path), ["best", "mean_a"])
    assert values.shape == (2, 2, 2) and values[0].tolist() == [[0.2, 2.0], [0.1, 1.0]]  # seeds sorted: 1, 3
    assert values[1, 0].tolist() == [0.4, 4.0] and np.isnan(values[1, 1]).all()  # seed 3 has not written it
    (tmp_path / "history.csv").write_text("generation,seed,best\n")
    assert loading.history_columns(str(tmp_path), ["best"]) is None


def test_a_measure_writes_its_csv_then_its_result(tmp_path):
    out = tmp_path / "ceiling"
    study.write_measure(str(out), "ceiling", [dict(a=1, b=1 / 3), dict(a=2)], "python -m x", 2, lives=8)
    assert (out / "ceiling.csv").read_text() == "a,b\n1,0.33\n2,\n"
    recorded = json.loads((out / "result.json").read_text())
    assert recorded["command"] == "python -m x" and recorded["lives"] == 8 and "git_commit" in recorded
    study.write_measure(str(out), "ceiling", [dict(a=0.125)], "python -m x")
    assert (out / "ceiling.csv").read_text() == "a\n0.125\n"  # floats as they are
