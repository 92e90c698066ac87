"""The benchmark command's input checks (the measurements themselves are not timed in tests)."""

import pytest

from imrl_jax.commands import bench


@pytest.mark.parametrize("argv, field", [
    (["--lanes", "1,x"], "--lanes"),
    (["--lanes", "0"], "--lanes"),
    (["--lifetime-lanes", ""], "--lifetime-lanes"),
    (["--lifetime-lanes", "300,-6"], "--lifetime-lanes"),
    (["--steps", "0"], "--steps"),
    (["--lifetime-task-steps", "15"], "--lifetime-task-steps"),
    (["--kernel", "xla,triton"], "--kernel"),
    (["--cpu-devices", "100000"], "--cpu-devices: 100,000 is above the limit"),
    (["--sweep-points", "-1"], "--sweep-points: must be in 0..1000"),
])
def test_bad_input_exits_2_naming_the_field(argv, field, capsys):
    assert bench.main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"error: {field}") and "\n" not in err


def test_json_path_that_is_a_directory_is_refused(tmp_path, capsys):
    assert bench.main(["--json", str(tmp_path)]) == 2
    assert "--json" in capsys.readouterr().err


def test_json_path_under_a_file_is_refused_before_measuring(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("kept")
    assert bench.main(["--json", str(blocker / "out.json")]) == 2
    assert "--json" in capsys.readouterr().err
    assert blocker.read_text() == "kept"


def test_help_shows_defaults(capsys):
    with pytest.raises(SystemExit):
        bench.main(["--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "(default: 1,50,300,3000)" in text and "(default: 1000)" in text and "(default: None)" not in text


@pytest.mark.slow
def test_the_sweep_benchmark_times_both_programs_on_the_same_generation():
    result = bench.sweep_benchmark(2, num_seeds=1, task_steps=20, pairs=1, log=lambda text: None)
    assert result["points"] == 2 and result["single_generation_s"] > 0 and result["sweep_generation_s"] > 0
    assert result["ratio"] == pytest.approx(result["sweep_generation_s"] / (2 * result["single_generation_s"]))
