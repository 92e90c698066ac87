"""The evolve command: run directory, exact resume after SIGKILL, fall-back, bad input."""

import os
import shutil
import signal
import subprocess
import time

import numpy as np
import pytest
from helpers import evolve_args, evolve_command, read_population

from imrl_jax import evolve


def _tiny(seeds="2", task_steps="1000"):
    return evolve_args(seeds=seeds, population=6, parents=2, task_steps=task_steps, bins=2)


TINY = _tiny()


def _outputs(out_dir):
    with open(os.path.join(out_dir, "history.csv")) as f:
        history = f.read()
    return history, read_population(out_dir)


def _assert_same_outputs(a, b):
    history_a, arrays_a = _outputs(a)
    history_b, arrays_b = _outputs(b)
    assert history_a == history_b
    assert set(arrays_a) == set(arrays_b)
    for name in arrays_a:
        np.testing.assert_array_equal(arrays_a[name], arrays_b[name], err_msg=name)


def _cli(args, cwd):
    env = {**os.environ, "JAX_PLATFORMS": "cpu"}
    return subprocess.Popen(evolve_command(args), cwd=cwd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)


@pytest.fixture(scope="module")
def finished_run(tmp_path_factory):
    """An uninterrupted 6-generation run (in this process, through the CLI's main)."""
    out = str(tmp_path_factory.mktemp("runs") / "full")
    assert evolve.main([*TINY, "--generations", "6", "--out", out]) == 0
    return out


def test_run_directory_contents(finished_run):
    names = set(os.listdir(finished_run))
    assert {"config.json", "history.csv", "fitness.png", "final_population.npz", "checkpoints"} <= names
    history, arrays = _outputs(finished_run)
    with open(os.path.join(finished_run, "history.csv"), "rb") as f:
        assert b"\r" not in f.read()  # LF line endings, as every other text file the run writes
    rows = history.strip().splitlines()
    assert rows[0].startswith("generation,seed,best,mean,std,best_task1") and len(rows) == 1 + 6 * 2
    import json

    with open(os.path.join(finished_run, "checkpoints", "6", "meta", "metadata")) as f:
        assert json.load(f)["elapsed_seconds"] > 0  # a resumed run's progress line counts on from it
    assert arrays["evaluated"].shape == (2, 6, 222) and arrays["fitness"].shape == (2, 6)
    last = [row.split(",") for row in rows[-2:]]
    np.testing.assert_allclose([float(r[2]) for r in last], arrays["fitness"].max(1), atol=1e-6)


def test_sigkill_mid_run_then_resume_is_bitwise_identical(finished_run, tmp_path):
    out = str(tmp_path / "killed")
    args = [*TINY, "--generations", "6", "--out", out]
    process = _cli(args, tmp_path)
    checkpoints = os.path.join(out, "checkpoints")
    deadline = time.time() + 120
    try:
        while time.time() < deadline and process.poll() is None:
            if os.path.isdir(os.path.join(checkpoints, "2")):
                break
            time.sleep(0.02)
        assert process.poll() is None, "the run finished before it could be killed"
        process.send_signal(signal.SIGKILL)
    finally:
        process.kill()
        process.communicate()
    done = sorted(int(d) for d in os.listdir(checkpoints) if d.isdigit())
    assert 2 <= done[-1] < 6
    resumed = _cli([*args, "--resume"], tmp_path)
    stdout, stderr = resumed.communicate(timeout=300)
    assert resumed.returncode == 0, stderr
    assert "resuming" in stderr
    _assert_same_outputs(out, finished_run)


def test_corrupt_checkpoint_falls_back_to_the_previous_one(finished_run, tmp_path, capsys):
    import shutil

    out = str(tmp_path / "corrupt")
    shutil.copytree(finished_run, out)
    latest = os.path.join(out, "checkpoints", "6")
    for root, _, files in os.walk(os.path.join(latest, "state")):
        for name in files:  # truncate every data file of the newest checkpoint
            with open(os.path.join(root, name), "r+b") as f:
                f.truncate(max(0, os.path.getsize(os.path.join(root, name)) // 3))
    assert evolve.main([*TINY, "--generations", "6", "--out", out, "--resume"]) == 0
    err = capsys.readouterr().err
    assert "checkpoints/6 is unreadable" in err and "resuming" in err and "(5 of 6 done" in err
    _assert_same_outputs(out, finished_run)


def test_finished_run_extended_is_bitwise_an_uninterrupted_longer_run(tmp_path, capsys):
    import json

    args = evolve_args(seeds=1, population=4, parents=2, task_steps=200, bins=1)
    longer, extended = str(tmp_path / "three"), str(tmp_path / "two_then_three")
    assert evolve.main([*args, "--generations", "3", "--out", longer]) == 0
    assert evolve.main([*args, "--generations", "2", "--out", extended]) == 0
    assert evolve.main([*args, "--generations", "3", "--out", extended, "--resume"]) == 0
    assert "(2 of 3 done" in capsys.readouterr().err
    _assert_same_outputs(extended, longer)
    with open(os.path.join(extended, "config.json")) as f:
        info = json.load(f)
    assert info["config"]["num_generations"] == 3 and info["extended"][0]["num_generations"] == [2, 3]
    before = _snapshot(extended)
    for generations, message in (("2", "num_generations is 2 but the run used 3"), ("1", "may only grow it")):
        assert evolve.main([*args, "--generations", generations, "--out", extended, "--resume"]) == 2
        err = capsys.readouterr().err.strip()
        assert message in err and err.startswith("error: ") and len(err.splitlines()) == 1
    assert _snapshot(extended) == before


def test_resume_accepts_other_compute_choices_and_ignored_fields_listing_every_real_difference(
        finished_run, tmp_path, capsys):
    """scan_unroll is how, not what; EE-LS never reads eta_actor: neither blocks a resume. Model changes are all named."""
    out = str(tmp_path / "copy")
    shutil.copytree(finished_run, out)
    assert evolve.main([*TINY, "--generations", "6", "--out", out, "--resume", "--set", "scan_unroll=2",
                        "--set", "eta_actor=0.5"]) == 0
    _assert_same_outputs(out, finished_run)
    capsys.readouterr()
    assert evolve.main([*_tiny(task_steps="500"), "--generations", "6", "--out", out, "--resume",
                        "--set", "gamma=0.5"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "task_steps is 500" in err and "gamma is 0.5" in err


def _snapshot(out_dir):
    files = {}
    for root, _, names in os.walk(out_dir):
        for name in names:
            path = os.path.join(root, name)
            with open(path, "rb") as f:
                files[os.path.relpath(path, out_dir)] = f.read()
    return files


@pytest.mark.parametrize("args, message", [
    (TINY, "already holds a run"),
    ([*_tiny(task_steps="500"), "--resume"], "task_steps is 500 but the run used 1000"),
    ([*_tiny(seeds="3"), "--resume"], "seeds [0, 1, 2] differ"),
])
def test_bad_input_exits_2_and_changes_nothing(finished_run, capsys, args, message):
    before = _snapshot(finished_run)
    assert evolve.main([*args, "--generations", "6", "--out", finished_run]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and err.startswith("error: ") and len(err.splitlines()) == 1
    assert _snapshot(finished_run) == before


@pytest.mark.parametrize("args, message", [
    (["--cond", "SLE"], "SLE is not evolved"),
    (["--cond", "XYZ"], "unknown condition"),
    (["--cond", "EE-LS", "--population", "55"], "population_size: must be a multiple"),
    (["--cond", "EE-LS", "--population", "7"], "num_parents: cannot exceed population_size=7"),
    (["--cond", "EE-LS", "--childhood-steps", "-5"], "childhood_steps"),
    (["--cond", "EE-LS", "--seeds", "0"], "--seeds"),
    (["--cond", "EE-LS", "--resume"], "holds no run to resume"),
])
def test_bad_arguments(tmp_path, capsys, args, message):
    out = str(tmp_path / "new")
    assert evolve.main([*args, "--out", out]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1
    assert not os.path.exists(out)


@pytest.mark.parametrize("args, message", [
    (["--set", "eta_actor=nan"], "eta_actor: must be a finite number"),
    (["--set", "eta_actor=inf"], "eta_actor: must be a finite number"),
    (["--set", "noise_std=-inf"], "noise_std: must be a finite number"),
    (["--set", "max_speed=inf"], "max_speed: must be a finite number"),
    (["--set", "max_turn_deg=0"], "max_turn_deg: must be in (0, 180]"),
    (["--set", "eta=0.1"], "did you mean eta_actor or eta_evaluator"),
    (["--set", "trace_lamda=0.9"], "did you mean trace_lambda?"),
    (["--set", "bogus=1"], "fields: condition, num_experts"),
    (["--keep", "0"], "--keep: must be at least 1"),
])
def test_bad_values_exit_2_naming_the_field(tmp_path, capsys, args, message):
    out = str(tmp_path / "new")
    assert evolve.main(["--cond", "EE-LS", "--preset", "small", *args, "--out", out]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and err.startswith("error: ") and len(err.splitlines()) == 1
    assert not os.path.exists(out)


def test_unwritable_out_exits_2_naming_it(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("kept")
    for out in (blocker / "run", blocker):
        assert evolve.main(["--cond", "EE-LS", "--preset", "small", "--out", str(out)]) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith("error: --out: ") and str(out) in err and len(err.splitlines()) == 1
    assert os.listdir(tmp_path) == ["file"] and blocker.read_text() == "kept"


def test_read_only_out_exits_2(tmp_path, capsys, monkeypatch):
    """A folder the process may not write in (a read-only file system, an immutable folder) is refused up front."""
    import tempfile

    def refuse(*args, **kwargs):
        raise OSError(30, "Read-only file system")

    monkeypatch.setattr(tempfile, "TemporaryFile", refuse)
    out = tmp_path / "new"
    assert evolve.main(["--cond", "EE-LS", "--preset", "small", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert err == f"error: --out: cannot write to {out} ({tmp_path}: Read-only file system)"
    assert not out.exists()


def test_help_shows_each_default_once_and_no_none(capsys):
    with pytest.raises(SystemExit):
        evolve.main(["--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "(default: None)" not in text and "(default: False)" not in text
    assert text.count("default: runs/COND") == 1 and "(default: 3)" in text
    assert "(default: the preset's; paper 100, small 10)" in text


def test_progress_line_names_generations_from_0_and_leaves_compilation_out():
    import io

    from imrl_jax.progress import Progress

    stream = io.StringIO()
    progress = Progress(4, done=2, stream=stream, first_index=0, elapsed=100.0)
    first = progress.update(3, 0.5, 0.1, 1e6, scores="best fitness: max over seeds 0.5000")
    second = progress.update(4, 0.5, 0.1, 2e6, scores="best fitness: max over seeds 0.5000")
    assert first.startswith("gen 2 (3/4) | best fitness: max over seeds 0.5000 | 0:01:40 elapsed")
    assert "with compilation" in first and "ETA" not in first and "lane-steps" not in first
    assert second.startswith("gen 3 (4/4)") and "ETA 0:00:00" in second and "2.00 M lane-steps/s" in second
    assert stream.getvalue().splitlines() == [first, second]


def test_unreadable_checkpoint_reason_is_one_short_line():
    from imrl_jax.checkpoint import unreadable_reason

    error = ValueError('DATA_LOSS: Error reading "/runs/x/checkpoints/6/state/manifest.ocdbt": '
                       '<tensorstore.KvStore object at 0x7f3a2c1d9e70> failed\n  with more words ' + "x " * 200
                       + "[source locations='tensorstore/kvstore/ocdbt/io.cc:123']")
    reason = unreadable_reason(error, "/runs/x/checkpoints/6")
    assert "0x7f" not in reason and "source locations" not in reason and "\n" not in reason
    assert reason.startswith('DATA_LOSS: Error reading "state/manifest.ocdbt": (an object) failed with more words')
    assert len(reason) <= 164 and reason.endswith(" ...")
