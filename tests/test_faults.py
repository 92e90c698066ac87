"""Fault injection (slow; run by hand, docs/TESTING.md): kills, corrupted files and a full disk lose nothing.

    IMRL_FAULT_KILLS=10 python -m pytest -m slow tests/test_faults.py   # kills per command (20 in all)

SIGKILL at random moments (seeded) of an evolution and of a learning test, each followed
by the resume a user would type, must end bitwise as the uninterrupted command; every file
of a checkpoint (and of a learning test's ``partial/``) corrupted in turn must fall back to
an older one and end the same, or exit 2 with one line; a full disk must give one line,
exit 1, and resume to the same result once there is room.
"""

import contextlib
import json
import os
import random
import shutil
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from helpers import assert_same_outputs, evolve_args, evolve_command, outputs

from imrl_jax.commands import evolve, learning_test

pytestmark = pytest.mark.slow

KILLS = int(os.environ.get("IMRL_FAULT_KILLS", "10"))
ENV = {**os.environ, "JAX_PLATFORMS": "cpu"}
EVOLUTION = evolve_args(seeds=2, population=6, parents=2, task_steps=1000, bins=2, generations=6)
TEST_OPTIONS = ["--best", "2", "--tests", "2", "--task-steps", "2000", "--bins", "8", "--steady-steps", "1000",
                "--chunks", "4", "--quiet"]


def _learning_test_command(run_dir, out):
    return [sys.executable, "-m", "imrl_jax.learning_test", run_dir, *TEST_OPTIONS, "--out", out]


def _assert_same_evolution(out, want):
    assert_same_outputs(outputs(out), outputs(want))


def _assert_same_test(out, want):
    """A learning test's curve.csv and every array of its curves.npz, bitwise."""
    with open(os.path.join(out, "curve.csv")) as f, open(os.path.join(want, "curve.csv")) as g:
        assert f.read() == g.read()
    with np.load(os.path.join(out, "curves.npz")) as got, np.load(os.path.join(want, "curves.npz")) as wanted:
        assert set(got.files) == set(wanted.files)
        for name in wanted.files:
            np.testing.assert_array_equal(got[name], wanted[name], err_msg=name)


def _timed(command):
    start = time.perf_counter()
    done = subprocess.run(command, env=ENV, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    return time.perf_counter() - start


def _kill_and_resume(first, resume, seconds, rng):
    """Start ``first`` and SIGKILL it after a random time in [0, ``seconds``], then ``resume()`` the same way, until
    one finishes; returns the kills (each hit a running process). Every command's stderr is free of tracebacks."""
    kills, command = 0, first
    while True:
        process = subprocess.Popen(command, env=ENV, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        if kills < KILLS:
            with contextlib.suppress(subprocess.TimeoutExpired):
                process.wait(timeout=rng.uniform(0.0, seconds))
            if process.poll() is None:
                process.send_signal(signal.SIGKILL)
                kills += 1
        _, err = process.communicate(timeout=600)
        assert "Traceback" not in err, err
        if process.returncode == 0:
            return kills
        assert process.returncode == -signal.SIGKILL, err
        command = resume()


def _killed_until(kills_wanted, start, check, seconds, rng):
    """Runs made by ``start(i)`` (first command, resume) killed at random moments until ``kills_wanted`` kills
    landed; each run that finishes is checked against the uninterrupted one; returns (kills, runs)."""
    kills = runs = 0
    while kills < kills_wanted:
        first, resume, out = start(runs)
        kills += _kill_and_resume(first, resume, seconds, rng)
        check(out)
        runs += 1
    return kills, runs


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """The uninterrupted evolution and learning test, and how long each took as a subprocess."""
    root = tmp_path_factory.mktemp("reference")
    run, test = str(root / "run"), str(root / "test")
    evolution_seconds = _timed(evolve_command([*EVOLUTION, "--out", run]))
    test_seconds = _timed(_learning_test_command(run, test))
    return dict(run=run, test=test, evolution_seconds=evolution_seconds, test_seconds=test_seconds)


def test_kills_at_random_moments_lose_nothing(reference, tmp_path):
    rng = random.Random(2007)

    def evolution(i):
        out = str(tmp_path / f"run{i}")
        first = evolve_command([*EVOLUTION, "--out", out])

        def resume():  # what a user types: the run's own directory, or the first command if none was recorded yet
            recorded = os.path.exists(os.path.join(out, "config.json"))
            return evolve_command(["--resume", "--out", out, "--quiet"]) if recorded else first

        return first, resume, out

    def test(i):
        command = _learning_test_command(reference["run"], str(tmp_path / f"test{i}"))
        return command, lambda: command, str(tmp_path / f"test{i}")

    kills, runs = _killed_until(KILLS, evolution, lambda out: _assert_same_evolution(out, reference["run"]),
                                reference["evolution_seconds"], rng)
    test_kills, test_runs = _killed_until(KILLS, test, lambda out: _assert_same_test(out, reference["test"]),
                                          reference["test_seconds"], rng)
    print(f"\n{kills} kills of {runs} evolution(s) and {test_kills} of {test_runs} learning test(s) survived, "
          f"each finished run bitwise the uninterrupted one")
    assert kills == test_kills == KILLS


def _corrupt(path, how):
    size = os.path.getsize(path)
    if how == "truncated":
        with open(path, "r+b") as f:
            f.truncate(size // 3)
    elif how == "bit-flipped":
        with open(path, "r+b") as f:
            data = bytearray(f.read())
            for i in range(0, len(data), 7):
                data[i] ^= 0x10
            f.seek(0)
            f.write(data)
    elif how == "garbage":
        with open(path, "wb") as f:
            f.write(bytes(random.Random(size).randrange(256) for _ in range(max(size, 16))))
    else:  # emptied
        open(path, "wb").close()


def _files(folder):
    return sorted(os.path.relpath(os.path.join(root, name), folder)
                  for root, _, names in os.walk(folder) for name in names)


@pytest.mark.parametrize("how", ["truncated", "garbage", "emptied"])
def test_every_checkpoint_file_corrupted_falls_back_or_exits_2(reference, tmp_path, capsys, how):
    newest = os.path.join("checkpoints", "6")
    names = [os.path.join(newest, name) for name in _files(os.path.join(reference["run"], newest))]
    names += ["config.json", "history.csv", "final_population.npz"]
    outcomes = {}
    for i, name in enumerate(names):
        out = str(tmp_path / f"run{i}")
        shutil.copytree(reference["run"], out)
        _corrupt(os.path.join(out, name), how)
        code = evolve.main(["--resume", "--out", out, "--generations", "6", "--quiet"])
        err = capsys.readouterr().err.strip()
        if code == 0:
            _assert_same_evolution(out, reference["run"])
            outcomes[name] = "same result"
        else:
            assert code == 2 and err.startswith("error: ") and "\n" not in err, (name, code, err)
            assert os.path.join(out, name).replace(out, "") in err.replace(out, "") or "config" in err, (name, err)
            outcomes[name] = "exit 2"
    print(f"\n{how}: {len(outcomes)} files: " + json.dumps(outcomes, indent=1))
    assert outcomes["config.json"] == "exit 2"
    assert all(outcome == "same result" for name, outcome in outcomes.items() if name != "config.json")


@pytest.mark.parametrize("how", ["truncated", "bit-flipped"])
def test_a_fall_back_in_a_fresh_process_prints_one_line_and_no_traceback(reference, tmp_path, how):
    """As a user runs it: orbax's failed reads of the damaged checkpoint, left unawaited in its threads, printed 5 to 15
    "Event loop is closed" tracebacks beside the one-line warning (and the fall-back itself was right)."""
    newest = os.path.join("checkpoints", "6")
    names = [os.path.join(newest, name) for name in _files(os.path.join(reference["run"], newest))
             if name.startswith("state")]
    outcomes = {}
    for i, name in enumerate(names):
        out = str(tmp_path / f"run{i}")
        shutil.copytree(reference["run"], out)
        _corrupt(os.path.join(out, name), how)
        done = subprocess.run(evolve_command(["--resume", "--out", out, "--quiet"]), env=ENV, capture_output=True,
                              text=True, timeout=600)
        assert done.returncode == 0 and "Traceback" not in done.stderr, (name, done.stderr[-3000:])
        assert len(done.stderr.splitlines()) <= 1, (name, done.stderr)  # the warning, if the damage was read
        _assert_same_evolution(out, reference["run"])
        outcomes[name] = done.stderr.strip()[:60] or "read as it was"
    print(f"\n{how}: {len(outcomes)} files: " + json.dumps(outcomes, indent=1))


@pytest.mark.parametrize("how", ["truncated", "garbage", "emptied"])
def test_a_learning_tests_kept_runs_corrupted_are_run_again_or_exit_2(reference, tmp_path, capsys, monkeypatch, how):
    from imrl_jax.runs import learning_test_state as lt

    out = str(tmp_path / "test")
    with monkeypatch.context() as patch:  # a test interrupted before its outputs: every run kept in partial/
        patch.setattr(lt.shutil, "rmtree", lambda path: None)
        assert learning_test.main([reference["run"], *TEST_OPTIONS, "--out", out]) == 0
    _assert_same_test(out, reference["test"])
    for name in lt.OUTPUTS:
        os.remove(os.path.join(out, name))
    outcomes = {}
    for i, name in enumerate(_files(os.path.join(out, lt.PARTIAL))):
        copy = str(tmp_path / f"test{i}")
        shutil.copytree(out, copy)
        _corrupt(os.path.join(copy, lt.PARTIAL, name), how)
        code = learning_test.main([reference["run"], *TEST_OPTIONS, "--out", copy])
        err = capsys.readouterr().err.strip()
        if code == 0:
            _assert_same_test(copy, reference["test"])
            outcomes[name] = "same result"
        else:
            assert code == 2 and err.startswith("error: ") and "\n" not in err and name in err, (name, code, err)
            outcomes[name] = "exit 2"
    print(f"\n{how}: {len(outcomes)} files: " + json.dumps(outcomes, indent=1))
    # docs/TESTING.md: an unreadable spec.json exits 2 naming it; a kept run that cannot be read is tested again
    assert outcomes == {"spec.json": "exit 2", "run_000.npz": "same result", "run_001.npz": "same result"}


def _mount_tmpfs(path, size):
    os.makedirs(path, exist_ok=True)
    done = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", path], capture_output=True)
    return done.returncode == 0


def test_a_full_disk_is_one_line_exit_1_and_resumes_to_the_same_result(reference, tmp_path):
    disk = str(tmp_path / "disk")
    if not _mount_tmpfs(disk, "160k"):
        pytest.skip("mounting a small tmpfs needs root")
    try:
        out = os.path.join(disk, "run")
        full = subprocess.run(evolve_command([*EVOLUTION, "--out", out]), env=ENV, capture_output=True, text=True,
                              timeout=600)
        err = full.stderr.strip()
        assert full.returncode == 1, err
        assert len(err.splitlines()) == 1 and os.strerror(28) in err and f"--resume --out {out}" in err, err
        assert [name for name in _files(out) if ".tmp-" in name] == []
        subprocess.run(["mount", "-o", "remount,size=64m", disk], check=True)  # room again
        resumed = subprocess.run(evolve_command(["--resume", "--out", out, "--quiet"]), env=ENV, capture_output=True,
                                 text=True, timeout=600)
        assert resumed.returncode == 0, resumed.stderr
        _assert_same_evolution(out, reference["run"])
    finally:
        subprocess.run(["umount", disk], capture_output=True)
