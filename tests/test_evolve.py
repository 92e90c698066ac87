"""The evolve command: run directory, exact resume after SIGKILL, fall-back, bad input."""

import os
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
    rows = history.strip().splitlines()
    assert rows[0].startswith("generation,seed,best,mean,std,best_task1") and len(rows) == 1 + 6 * 2
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
    assert "checkpoints/6 is unreadable" in err and "resuming" in err and "after generation 5" in err
    _assert_same_outputs(out, finished_run)


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
    ([*_tiny(task_steps="500"), "--resume"], "config field task_steps is 500"),
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
