"""The evolve command: run directory, exact resume after SIGKILL, fall-back, bad input."""

import errno
import os
import shutil
import signal
import socket
import subprocess
import sys
import time

import numpy as np
import pytest
from helpers import evolve_args, evolve_command, interruptible_command, read_population, snapshot

from imrl_jax.commands import evolve
from imrl_jax.world import tasks
from imrl_jax.config import make_config


def _tiny(seeds="2", task_steps="1000"):
    return evolve_args(seeds=seeds, population=6, parents=2, task_steps=task_steps, bins=2)


TINY = _tiny()
LOUD = [a for a in TINY if a != "--quiet"]  # the same run, its notes printed


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


def test_sigkill_mid_run_then_resume_is_bitwise_identical(finished_run, tmp_path, capsys):
    """A second writer is refused while the first runs; killed, the first's lock is stale and --resume takes it over."""
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
        for second in (["--resume", "--out", out], args):  # this process: another writer
            assert evolve.main(second) == 2
            err = capsys.readouterr().err.strip()
            assert err == (f"error: --out: {out} is being written by pid {process.pid} on {socket.gethostname()}; "
                           f"wait for it to end or stop it")
        process.send_signal(signal.SIGKILL)
    finally:
        process.kill()
        process.communicate()  # reaped: its pid is gone
    done = sorted(int(d) for d in os.listdir(checkpoints) if d.isdigit())
    assert 2 <= done[-1] < 6
    assert os.path.exists(os.path.join(out, ".lock"))
    resumed = _cli(["--resume", "--out", out, "--quiet"], tmp_path)
    stdout, stderr = resumed.communicate(timeout=300)
    assert resumed.returncode == 0, stderr
    assert stderr.strip() == (f"warning: {os.path.join(out, '.lock')}: took over the stale lock of pid {process.pid} "
                              f"on {socket.gethostname()} (no longer running)")
    assert not os.path.exists(os.path.join(out, ".lock"))
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
    assert evolve.main([*LOUD, "--generations", "6", "--out", out, "--resume"]) == 0
    err = capsys.readouterr().err
    assert "checkpoints/6 is unreadable" in err and "resuming" in err and "(5 of 6 done" in err
    _assert_same_outputs(out, finished_run)
    lines = err.splitlines()  # what the generation left will cost, then its compilation, before its line
    cost = [i for i, line in enumerate(lines) if line.startswith("evolving EE-LS: 2 seed(s) x 6 individuals x 1 "
                                                                  "generation(s): 12 lives a generation, ")]
    assert len(cost) == 1 and "lane-steps a generation" in lines[cost[0]]
    assert "about 0:00:0" in lines[cost[0]] and os.path.join("docs", "bench", "cpu-2core.json") in lines[cost[0]]
    assert lines[cost[0] + 1].startswith("compiling the generation") and lines[cost[0] + 2].startswith("gen 5 (6/6)")
    import jax

    from imrl_jax.evolution.devices import memory_needed  # the memory the plan's check estimated: lanes and the records
    from imrl_jax.runs.run_state import history_bytes

    config = evolve.read_config(out)[0]
    gib = memory_needed(config, 12, jax.device_count(), history_bytes(config, 2)) / 2**30
    assert f"; at most about {gib:.1f} GiB of memory (an estimate); step_kernel=xla" in lines[cost[0]]


@pytest.mark.parametrize("damage", ["array metadata", "largest data file"])
def test_a_fall_back_says_one_line_and_no_traceback(finished_run, tmp_path, damage):
    """orbax's reads of the damaged checkpoint fail in its threads and left unawaited: in a fresh process (as a user
    runs it) their errors printed 5 to 15 tracebacks ("Event loop is closed") beside the one-line warning."""
    import shutil

    out = str(tmp_path / "corrupt")
    shutil.copytree(finished_run, out)
    state = os.path.join(out, "checkpoints", "6", "state")
    if damage == "array metadata":
        path = os.path.join(state, "array_metadatas", "process_0")
    else:
        data = [os.path.join(root, name) for root, _, names in os.walk(state) for name in names
                if os.path.basename(root) == "d"]
        path = max(data, key=os.path.getsize)
    with open(path, "r+b") as f:
        f.truncate(os.path.getsize(path) // 3)
    done = subprocess.run(evolve_command(["--resume", "--out", out, "--quiet"]), capture_output=True, text=True,
                          env={**os.environ, "JAX_PLATFORMS": "cpu"}, timeout=300)
    assert done.returncode == 0, done.stderr
    lines = done.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"warning: checkpoint {os.path.join(out, 'checkpoints', '6')} is "
                                                   f"unreadable (") and lines[0].endswith("trying an older one"), \
        "\n".join(lines[:6] + ["..."] + lines[-4:])  # in full: which channel printed a traceback, if one did
    _assert_same_outputs(out, finished_run)


def test_asyncio_drops_the_unretrieved_errors_of_orbax_reads_and_no_other(caplog):
    """A read of a damaged checkpoint leaves an orbax task whose error no one retrieves; when it is collected, asyncio
    logged it as an 80-line traceback beside the one-line warning (seen in the test above, now and then). The filter
    drops exactly those, of a task or a future: an error raised in orbax's code, not one of ours; so does the hook of
    a thread's end; each is installed once (with the unraisable hook, in _silence_failed_reads)."""
    import logging
    import threading

    from imrl_jax.runs import checkpoint

    namespace = {}
    exec(compile("def read():\n    raise ValueError('truncated shard')\n",
                 os.path.join(os.sep, "site-packages", "orbax", "checkpoint", "serialization.py"), "exec"), namespace)
    errors = []
    for raising in (namespace["read"], lambda: int("not a number")):
        try:
            raising()
        except ValueError as error:
            errors.append(error)
    logger, ended = logging.getLogger("asyncio"), []
    thread_hook, unraisable_hook = threading.excepthook, sys.unraisablehook
    threading.excepthook = lambda args: ended.append(args.exc_value)  # what reaches the hook it wraps
    checkpoint._silence_failed_reads()
    checkpoint._silence_failed_reads()
    installed = [f for f in logger.filters if isinstance(f, checkpoint._UnretrievedReads)]
    try:
        assert len(installed) == 1 and threading.excepthook.drops_failed_reads
        with caplog.at_level(logging.ERROR, logger="asyncio"):
            for what in ("Task", "Future"):
                for error in errors:
                    logger.error(f"{what} exception was never retrieved\nfuture: <{what} finished>",
                                 exc_info=(type(error), error, error.__traceback__))
            logger.error("another asyncio error", exc_info=(type(errors[0]), errors[0], errors[0].__traceback__))
        assert [(r.getMessage().split("\n")[0], r.exc_info[1]) for r in caplog.records] == [
            ("Task exception was never retrieved", errors[1]), ("Future exception was never retrieved", errors[1]),
            ("another asyncio error", errors[0])]
        for target in (namespace["read"], lambda: int("not a number")):
            thread = threading.Thread(target=target, name="reader")
            thread.start()
            thread.join()
        assert [str(e) for e in ended] == ["invalid literal for int() with base 10: 'not a number'"]
    finally:
        for f in installed:
            logger.removeFilter(f)
        threading.excepthook, sys.unraisablehook = thread_hook, unraisable_hook


@pytest.mark.slow  # 50 s; the default suite extends a finished run in tests/test_strategies.py (the same path)
def test_finished_run_extended_is_bitwise_an_uninterrupted_longer_run(tmp_path, capsys):
    import json

    args = evolve_args(seeds=1, population=4, parents=2, task_steps=200, bins=1)
    longer, extended = str(tmp_path / "three"), str(tmp_path / "two_then_three")
    assert evolve.main([*args, "--generations", "3", "--out", longer]) == 0
    assert evolve.main([*args, "--generations", "2", "--out", extended]) == 0
    assert evolve.main([*args[:-1], "--generations", "3", "--out", extended, "--resume"]) == 0  # not --quiet
    assert "(2 of 3 done" in capsys.readouterr().err
    _assert_same_outputs(extended, longer)
    with open(os.path.join(extended, "config.json")) as f:
        info = json.load(f)
    assert info["config"]["num_generations"] == 3 and info["extended"][0]["num_generations"] == [2, 3]
    before = snapshot(extended)
    for generations, message in (("2", "num_generations is 2 but the run used 3"), ("1", "may only grow it")):
        assert evolve.main([*args, "--generations", generations, "--out", extended, "--resume"]) == 2
        err = capsys.readouterr().err.strip()
        assert message in err and err.startswith("error: ") and len(err.splitlines()) == 1
    assert snapshot(extended) == before


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


@pytest.mark.parametrize("args, message", [
    (TINY, "already holds a run"),
    ([*_tiny(task_steps="500"), "--resume"], "task_steps is 500 but the run used 1000"),
    ([*_tiny(seeds="3"), "--resume"], "seeds [0, 1, 2] differ"),
])
def test_bad_input_exits_2_and_changes_nothing(finished_run, capsys, args, message):
    before = snapshot(finished_run)
    assert evolve.main([*args, "--generations", "6", "--out", finished_run]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and err.startswith("error: ") and len(err.splitlines()) == 1
    assert snapshot(finished_run) == before


@pytest.mark.parametrize("args, message", [
    (["--cond", "SLE"], "SLE is not evolved"),
    (["--cond", "EXT-LS"], "EXT-LS is not evolved (it learns each task from scratch)"),
    (["--cond", "LE-LS-N", "--set", "num_experts=0"], "num_experts: must be a positive integer (got 0)"),
    (["--cond", "XYZ"], "unknown condition"),
    (["--cond", "EE-LS", "--population", "55"], "population_size: must be a multiple"),
    (["--cond", "EE-LS", "--population", "7"], "num_parents: cannot exceed population_size=7"),
    (["--cond", "EE-LS", "--childhood-steps", "-5"], "childhood_steps"),
    (["--cond", "EE-LS", "--seeds", "0"], "--seeds"),
    (["--cond", "EE-LS", "--resume"], "holds no run to resume"),
    (["--resume"], "holds no run to resume"),
    ([], "--cond: required (or --resume --out RUN"),
    (["--cond", "EE-LS", "--generations", "1e12"], "--generations: invalid int value: '1e12'"),
    (["--cond", "EE-LS", "--generations", "2147483648"], "--generations: 2,147,483,648 is above the limit of 1,000,000"),
    (["--cond", "EE-LS", "--seeds", "20000"], "--seeds: 20,000 is above the limit of 10,000"),
    (["--cond", "EE-LS", "--task-steps", "2000000000"], "--task-steps: 2,000,000,000 is above the limit of 1,000,000,000"),
    (["--cond", "EE-LS", "--seeds", "1000", "--population", "5000"], "--seeds x --population: 5,000,000 is above"),
    (["--cond", "EE-LS", "--first-seed", "-5"], "--first-seed: must be 0 or more (got -5)"),
    (["--cond", "EE-LS", "--set", "condition=LE-LS"], "--set condition=LE-LS: condition is set by --cond; use --cond"),
    (["--cond", "EE-LS", "--set", "num_generations=5"], "num_generations is set by --generations"),
])
def test_bad_arguments(tmp_path, capsys, args, message):
    out = str(tmp_path / "new")
    assert evolve.main([*args, "--out", out]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: ") and message in err and len(err.splitlines()) == 1
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
    # A target radius at or above a task's length scored negative fitness; a step of 1e30 cm divided by zero after
    # config.json was written; an unroll of 100,000 and a thousand experts exhausted the machine's memory.
    (["--set", "target_radius=150"], "target_radius: must be below every task's start-to-target distance (task 6: "
                                     "69.3 cm) (got 150.0)"),
    (["--set", "target_radius=500"], "target_radius: must be below every task's start-to-target distance"),
    (["--set", "target_radius=1e30"], "target_radius: must be in (0, 10000] (got 1e+30)"),
    (["--set", "max_speed=1e30"], "max_speed: must be in (0, 10000] (got 1e+30)"),
    (["--set", "max_speed=25"], "max_speed: must be at most 2 x target_radius = 20 cm"),
    (["--set", "scan_unroll=100000"], "scan_unroll: must be in [1, 64] (got 100000)"),
    (["--set", "kernel_retina=pixels"], "kernel_retina: must be one of entries, points (got 'pixels')"),
    (["--set", "num_experts=1000"], "num_experts: must be in [1, 64] (got 1000)"),
    (["--set", "line_half_width=25"], "line_half_width: must be below edge_length / 2 = 20"),
    (["--set", "arena_size=20"], "edge_length: must be at most arena_size=20"),
    (["--set", "draw_block=100000000"], "draw_block: must be in [1, 10_000]"),
    (["--set", "eta_actor=1e30"], "eta_actor: must be in [0, 10]"),
    (["--cpu-devices", "100000"], "--cpu-devices: 100,000 is above the limit of"),
    (["--cpu-devices", "-1"], "--cpu-devices: must be 0 (one per core) or more"),
])
def test_bad_values_exit_2_naming_the_field(tmp_path, capsys, args, message):
    out = str(tmp_path / "new")
    assert evolve.main(["--cond", "EE-LS", "--preset", "small", *args, "--out", out]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and err.startswith("error: ") and len(err.splitlines()) == 1
    assert not os.path.exists(out)


def test_a_run_that_cannot_fit_in_memory_is_refused_before_anything_is_written(tmp_path, capsys, monkeypatch):
    """A thousand experts took a 24 GB machine down: the memory a run needs is estimated before it starts."""
    from imrl_jax.evolution import devices

    monkeypatch.setattr(devices, "available_memory", lambda: 2**30)  # a machine with 1 GiB free
    monkeypatch.setattr(devices, "accelerator_memory", lambda: None)
    out = tmp_path / "run"
    assert evolve.main(["--cond", "EE-LS", "--preset", "small", "--seeds", "100", "--population", "100",
                        "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: memory: evolving 100 seed(s) x 100 individuals needs about 1.6 GiB (10,000 lives at "
                          "once of 0.11 MiB each, 3 experts, ") and err.endswith(
        "devices; an estimate) but this machine has 1.0 GiB available; use fewer seeds, a smaller population, fewer "
        "bins or experts\n") and len(err.splitlines()) == 1
    assert not out.exists()
    config = make_config("small", condition="EE-LS")
    assert devices.lane_bytes(config.replace(num_experts=6)) > devices.lane_bytes(config)  # grows with what a lane holds
    assert devices.lane_bytes(config.replace(num_bins=100, task_steps=5000)) > devices.lane_bytes(config)


@pytest.mark.parametrize("out", ["", " "])
def test_an_empty_out_is_refused_not_taken_for_the_default(tmp_path, capsys, monkeypatch, out):
    monkeypatch.chdir(tmp_path)
    assert evolve.main(["--cond", "EE-LS", "--preset", "small", "--out", out]) == 2
    assert capsys.readouterr().err == "error: --out: empty path; give a directory\n"
    assert os.listdir(tmp_path) == []  # not runs/EE-LS


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

    from imrl_jax.runs.progress import Progress

    stream = io.StringIO()
    progress = Progress(4, done=2, stream=stream, first_index=0, elapsed=100.0)
    first = progress.update(3, 0.5, 0.1, 1e6, scores="best fitness: max over seeds 0.5000")
    second = progress.update(4, 0.5, 0.1, 2e6, scores="best fitness: max over seeds 0.5000")
    assert first.startswith("gen 2 (3/4) | best fitness: max over seeds 0.5000 | 0:01:40 elapsed")
    assert "with compilation" in first and "ETA" not in first and "lane-steps" not in first
    assert second.startswith("gen 3 (4/4)") and "ETA 0:00:00" in second and "2.00 M lane-steps/s" in second
    assert stream.getvalue().splitlines() == [first, second]


def test_unreadable_checkpoint_reason_is_one_short_line():
    from imrl_jax.runs.checkpoint import unreadable_reason

    error = ValueError('DATA_LOSS: Error reading "/runs/x/checkpoints/6/state/manifest.ocdbt": '
                       '<tensorstore.KvStore object at 0x7f3a2c1d9e70> failed\n  with more words ' + "x " * 200
                       + "[source locations='tensorstore/kvstore/ocdbt/io.cc:123']")
    reason = unreadable_reason(error, "/runs/x/checkpoints/6")
    assert "0x7f" not in reason and "source locations" not in reason and "\n" not in reason
    assert reason.startswith('DATA_LOSS: Error reading "state/manifest.ocdbt": (an object) failed with more words')
    assert len(reason) <= 164 and reason.endswith(" ...")


def test_resume_needs_only_out_and_extends_only_with_generations(finished_run, tmp_path, capsys):
    """--resume --out uses the run's own config and seeds; the preset's generations do not extend it; --quiet is quiet."""
    out = str(tmp_path / "copy")
    shutil.copytree(finished_run, out)
    def text(name):
        with open(os.path.join(out, name)) as f:
            return f.read()

    history, config_json = text("history.csv"), text("config.json")
    capsys.readouterr()
    assert evolve.main([*TINY, "--out", out, "--resume"]) == 0  # small's 10 generations are not asked for
    captured = capsys.readouterr()
    assert captured.err == "" and captured.out.startswith("EE-LS: generations 0-5 x 2 seed(s) done")
    assert evolve.main(["--resume", "--out", out]) == 0
    assert f"{out} is finished (6 of 6 generations): its outputs are rewritten" in capsys.readouterr().err
    assert (text("history.csv"), text("config.json")) == (history, config_json)  # not extended
    _assert_same_outputs(out, finished_run)
    before = snapshot(out)
    assert evolve.main(["--resume", "--out", out, "--population", "8", "--bins", "1", "--set", "gamma=0.5"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and all(f"{field} is " in err for field in ("population_size", "num_bins", "gamma"))
    assert snapshot(out) == before


def test_resume_with_a_preset_is_refused_naming_only_real_differences_not_the_condition(finished_run, capsys):
    """--resume --preset skills said the condition differed (the preset's LE-LS), which the user never typed."""
    before = snapshot(finished_run)
    assert evolve.main(["--resume", "--out", finished_run, "--preset", "skills"]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"error: --resume: the config differs from the run's in {finished_run}: ")
    assert "condition" not in err and "initial_speed_bias" not in err and "task_steps is 100000" in err
    assert snapshot(finished_run) == before


def test_resume_after_the_checkpoints_were_removed_says_so_even_when_quiet(finished_run, tmp_path, capsys):
    import shutil

    out = str(tmp_path / "run")
    shutil.copytree(finished_run, out)
    shutil.rmtree(os.path.join(out, "checkpoints"))
    assert evolve.main(["--resume", "--out", out, "--quiet"]) == 0
    err = capsys.readouterr().err
    assert err == (f"warning: {os.path.join(out, 'checkpoints')} holds no checkpoint, but {out} records 6 generation(s) "
                   f"done: starting again from generation 0 (the same generations again, bitwise)\n")
    _assert_same_outputs(out, finished_run)


def test_a_directory_holding_no_run_is_refused(tmp_path, capsys):
    """Its files could have the names of a run's outputs (history.csv): nothing is written there."""
    out = tmp_path / "mine"
    out.mkdir()
    (out / "history.csv").write_text("my own")
    assert evolve.main([*TINY, "--generations", "1", "--out", str(out)]) == 2
    assert capsys.readouterr().err.strip() == (f"error: --out: {out} is not empty and holds no run (no config.json; "
                                               f"it holds history.csv); choose a new or empty directory")
    assert snapshot(str(out)) == {"history.csv": b"my own"}


def test_notes_and_warnings(finished_run, tmp_path, capsys):
    """A field the condition never reads is noted (not under --quiet); more devices than cores are warned of."""
    out = str(tmp_path / "copy")
    shutil.copytree(finished_run, out)
    cores = os.cpu_count() + 1
    warning = (f"warning: --cpu-devices {cores} is more than this machine's {cores - 1} cores: the devices share them "
               f"(no faster, likely slower)")
    options = ["--resume", "--out", out, "--set", "eta_actor=0.5", "--cpu-devices", str(cores)]
    assert evolve.main(options) == 0
    assert capsys.readouterr().err.splitlines()[:2] == [
        warning, "note: --set eta_actor=0.5: EE-LS does not read eta_actor (it changes nothing)"]
    assert evolve.main([*options, "--quiet"]) == 0
    assert capsys.readouterr().err.splitlines() == [warning]


def test_the_gpu_kernel_off_a_gpu_is_warned_about(monkeypatch):
    import jax

    from imrl_jax.runs.cli import device_warnings
    from imrl_jax.config import make_config

    monkeypatch.setattr(jax, "default_backend", lambda: "cpu")  # as on a CPU host, whichever this one is
    assert device_warnings(make_config("small", condition="EE-LS")) == []
    assert device_warnings(make_config("small", condition="EE-LS", step_kernel="pallas")) == [
        "warning: step_kernel=pallas without a GPU (backend cpu): the kernel runs in Pallas's interpreter, several "
        "times slower than step_kernel=xla"]


def test_ctrl_c_stops_with_one_line_and_exit_code_130(tmp_path):
    out = str(tmp_path / "stopped")
    env = {**os.environ, "JAX_PLATFORMS": "cpu"}
    process = subprocess.Popen(interruptible_command("imrl_jax.evolve", [*TINY, "--generations", "50", "--out", out]),
                               cwd=tmp_path, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.time() + 120
    try:
        while time.time() < deadline and process.poll() is None and not os.path.isdir(os.path.join(out, "checkpoints",
                                                                                                    "1")):
            time.sleep(0.02)
        assert process.poll() is None, "the run ended before it could be interrupted"
        process.send_signal(signal.SIGINT)
        stdout, stderr = process.communicate(timeout=60)
    finally:
        process.kill()
        process.communicate()
    assert process.returncode == 130, stderr
    assert stdout == "" and len(stderr.splitlines()) == 1, stderr
    assert stderr.startswith("interrupted in generation ") and " checkpointed); resume with: python -m " \
        f"imrl_jax.evolve --resume --out {out}\n" in stderr
    assert not os.path.exists(os.path.join(out, ".lock"))


def test_a_full_disk_mid_run_is_one_line_exit_1_and_resumable(tmp_path, monkeypatch, capsys):
    """history.csv cannot be written after generation 1: one line naming it, no temporary file left; --resume writes it."""
    from imrl_jax.runs import rundir

    out = tmp_path / "full"
    out.mkdir()  # an empty directory is as good as a new one
    out = str(out)
    args = evolve_args(seeds=1, population=4, parents=2, task_steps=200, bins=1, generations=2)
    writes = []

    class FullDisk:
        def __init__(self, file):
            self.file = file

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            self.file.close()

        def write(self, data):
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    def open_on_a_full_disk(path, *a, **k):
        file = open(path, *a, **k)
        if os.path.basename(path).startswith("history.csv.tmp-"):
            writes.append(path)
            if len(writes) == 2:
                return FullDisk(file)
        return file

    monkeypatch.setattr(rundir, "open", open_on_a_full_disk, raising=False)
    assert evolve.main([*args, "--out", out]) == 1
    err = capsys.readouterr().err.strip()
    assert err == (f"error: cannot write {os.path.join(out, 'history.csv')} ({os.strerror(errno.ENOSPC)}) after "
                   f"generation 1 (2 generation(s) checkpointed); free space or fix permissions, then resume with: "
                   f"python -m imrl_jax.evolve --resume --out {out}")
    assert [name for _, _, names in os.walk(out) for name in names if ".tmp-" in name] == []
    assert ".lock" not in os.listdir(out)
    monkeypatch.undo()
    assert evolve.main(["--resume", "--out", out, "--quiet"]) == 0  # checkpointed, it is finished: outputs written
    with open(os.path.join(out, "history.csv")) as f:
        assert len(f.read().splitlines()) == 1 + 2


def test_cpu_devices_are_set_up_before_the_task_set_starts_jax(tmp_path):
    """The task set's checks run JAX: the devices asked for after them would be ignored (and --coordinator refused)."""
    args = [*evolve_args(seeds=2), "--task-set", "paper", "--cpu-devices", "2", "--out", str(tmp_path / "run")]
    from helpers import devices_seen

    assert devices_seen("imrl_jax.evolve", args) == 2


def test_the_task_set_is_checked_against_the_geometry_the_command_line_sets(tmp_path, capsys, monkeypatch):
    """Paper tasks 3 and 6 have their targets 69.3 cm from their starts: within a 70 cm target radius. A set of
    longer tasks takes that radius (it is checked against the tasks the run will have, not the ones they replace)."""
    from attack import assert_refused, attack

    out = tmp_path / "run"
    args = [*evolve_args(seeds=1), "--task-set", "paper", "--set", "target_radius=70", "--out", str(out)]
    refused = attack(evolve.main, args, str(tmp_path))
    assert_refused(refused, "--task-set")
    assert refused.stderr == ("error: --task-set: paper: target_radius: must be below every task's "
                              "start-to-target distance (task 6: 69.3 cm) (got 70.0)\n")
    planned = attack(evolve.main, [*evolve_args(seeds=1), "--task-set", "novel", "--set", "target_radius=70", "--out",
                                   str(out)], str(tmp_path))
    assert planned.planned and not planned.changed
    assert planned.plan.config.target_radius == 70 and planned.plan.config.tasks == tasks.novel_tasks()


def test_a_checkpoint_that_records_no_strategy_is_taken_for_the_gas(tmp_path):
    """Checkpoints made before --strategy existed hold no "search": resuming one with another strategy is refused."""
    from imrl_jax.config import make_config
    from imrl_jax.runs.progress import Progress
    from imrl_jax.evolution.strategies import Evosax

    class Restores:  # a checkpoint of such a run (its state does not matter before the strategy is checked)
        directory = str(tmp_path)

        def restore_latest(self, template, warn):
            return template, {"generation": 1}

    config = make_config("small", condition="EE-LS")
    strategy = Evosax("snes", config.population_size, config.num_genes)
    with pytest.raises(evolve.UsageError) as error:
        evolve._restore(config, str(tmp_path), [0], strategy, None, Restores(), Progress(1, quiet=True), None, True)
    assert str(error.value) == ("--strategy: the checkpoint was made by {'strategy': 'ga', 'settings': {}}, not "
                                "{'strategy': 'snes', 'settings': {}}")


def test_search_states_of_more_than_a_thousand_arrays_come_back_in_order():
    """Their leaves are saved as "000", "001", ...: "1000" sorts before "101" as text."""
    from imrl_jax.runs.checkpoint import RunState, _saved, _search_from_saved

    leaves = [np.float32(i) for i in range(1001)]
    saved = _saved(RunState(np.asarray(1), None, None, None, None, None, search=leaves))
    assert [float(x) for x in _search_from_saved(leaves, saved["search"])] == list(range(1001))


def test_the_options_build_the_config_seeds_and_search_without_running_anything():
    """evolve_options holds the command line; evolve keeps its names (experiments/harness/table.py keys rows with them)."""
    from imrl_jax.commands import evolve_options
    from imrl_jax.evolution.strategies import describe

    assert (evolve.parser, evolve.build_config, evolve.build_strategy) == (
        evolve_options.parser, evolve_options.build_config, evolve_options.build_strategy)
    args = evolve_options.parser().parse_args(["--cond", "EE-ES", "--preset", "small", "--seeds", "3", "--first-seed",
                                               "5", "--population", "8", "--set", "trace_lambda=0.5"])
    config, seeds = evolve_options.build_config(args)
    assert (config.condition, config.population_size, config.trace_lambda, config.num_generations, seeds) == (
        "EE-ES", 8, 0.5, 10, [5, 6, 7])
    saved = (config.replace(num_generations=4), [5, 6, 7])  # resuming: what the command line leaves out is the run's
    resumed, resumed_seeds = evolve_options.build_config(evolve_options.parser().parse_args(["--resume"]), saved)
    assert (resumed.num_generations, resumed.population_size, resumed_seeds) == (4, 8, [5, 6, 7])
    assert describe(evolve_options.build_strategy(args, config)) == {"strategy": "ga", "settings": {}}


@pytest.mark.parametrize("argv, message", [
    (["--cond", "NOPE"], "--cond: unknown condition 'NOPE' (choose from LE-LS, EE-LS, EE-ES"),
    (["--resume"], "--resume: give the run to continue with --out RUN"),
    ([], "--cond: required (or --resume --out RUN to continue a run with its own config)"),
])
def test_the_condition_check_names_the_option(argv, message):
    from imrl_jax.commands import evolve_options

    with pytest.raises(evolve.UsageError) as error:
        evolve_options.check_condition(evolve_options.parser().parse_args(argv))
    assert str(error.value).startswith(message)


# ------------------------------------------------------------ refusals, planned before anything is written

def _made_run(root, seeds=(0, 1)):
    """A run's folder as a run that never reached its first checkpoint leaves it (config.json), made without running."""
    import json

    config = make_config("small", condition="EE-LS", population_size=4, num_parents=2, task_steps=200, num_bins=1)
    os.makedirs(root)
    with open(os.path.join(root, "config.json"), "w") as f:
        json.dump({"config": config.to_dict(), "seeds": list(seeds)}, f)


def test_the_main_plans_then_executes_and_writes_nothing_before(tmp_path):
    from attack import attack

    out = str(tmp_path / "run")
    outcome = attack(evolve.main, [*TINY, "--generations", "2", "--out", out], str(tmp_path))
    assert outcome.planned and outcome.code == 0 and not outcome.changed and not os.path.exists(out)
    assert isinstance(outcome.plan, evolve.RunPlan) and outcome.plan.seeds == [0, 1]


@pytest.mark.parametrize("args", [["--first-seed", "18446744073709551616"], ["--first-seed", "4294967295", "--seeds",
                                  "2"], ["--seeds", "18446744073709551616"], ["--first-seed", "-1"]])
def test_seeds_past_32_bits_are_refused_in_one_line(tmp_path, args):
    from attack import assert_refused, attack

    assert_refused(attack(evolve.main, [*TINY, *args, "--out", str(tmp_path / "run")], str(tmp_path)), "--seeds",
                   "--first-seed")


def test_a_run_recording_seeds_past_32_bits_is_refused_in_one_line(tmp_path):
    from attack import assert_refused, attack

    root = str(tmp_path / "run")
    for seeds in ([2**64], [2**32]):
        shutil.rmtree(root, ignore_errors=True)
        _made_run(root, seeds)
        assert_refused(attack(evolve.main, ["--resume", "--out", root], root), "--seeds")


def test_a_run_whose_records_outgrow_the_memory_is_refused(tmp_path):
    """--generations 1000000 --seeds 1000 passed the estimate and failed at 36 GB after writing config.json."""
    from attack import assert_refused, attack

    huge = ["--cond", "EE-LS", "--preset", "small", "--generations", "1000000", "--seeds", "1000"]
    outcome = attack(evolve.main, [*huge, "--out", str(tmp_path / "run")], str(tmp_path))
    assert_refused(outcome, "memory")
    assert "GiB of per-generation records" in outcome.stderr


def test_a_resume_with_an_unwritable_tensorboard_folder_is_refused_and_nothing_is_written(tmp_path):
    pytest.importorskip("tensorboardX")
    from attack import assert_refused, attack

    root = str(tmp_path / "run")
    _made_run(root)
    with open(os.path.join(root, "tensorboard"), "w") as f:
        f.write("a file where the folder goes")
    assert_refused(attack(evolve.main, ["--resume", "--out", root, "--log", "tensorboard"], root), "--log tensorboard")
    new = str(tmp_path / "new" / "run")  # a new run: its folder would be made, nothing is made to check it
    outcome = attack(evolve.main, [*TINY, "--out", new, "--log", "tensorboard"], str(tmp_path))
    assert outcome.planned and not outcome.changed


def test_the_time_a_run_will_take_is_read_from_the_benchmarks_speeds(tmp_path):
    """The speed measured nearest the run's lives on this backend; none measured there: said, no time made up."""
    import json

    from imrl_jax.runs import progress

    folder = tmp_path / "bench"
    folder.mkdir()
    (folder / "cpu.json").write_text(json.dumps({"backend": "cpu", "lifetimes": [
        {"individuals": 50, "lane_steps_per_s": 2e6}, {"individuals": 500, "lane_steps_per_s": 8e6},
        {"individuals": 40, "lane_steps_per_s": float("nan")}]}))
    (folder / "broken.json").write_text("{not json")
    (folder / "gpu.json").write_text(json.dumps({"backend": "gpu", "lifetimes": [{"individuals": 40}]}))
    assert progress.measured_speed("cpu", 40, str(folder)) == (2e6, os.path.join("docs", "bench", "cpu.json"))
    assert progress.measured_speed("cpu", 400, str(folder))[0] == 8e6
    assert progress.measured_speed("gpu", 40, str(folder)) is None
    assert progress.measured_speed("cpu", 40, str(tmp_path / "none")) is None
    # Another world: its agent's adult rate from bench --world's section (the arena's lives are not its speed)
    (folder / "world-xland.json").write_text(json.dumps({"backend": "cpu", "world": {"name": "xland", "settings": {},
        "rows": [{"phase": "LE-LS childhood", "lanes": 50, "agent_lane_steps_per_s": 1e5},
                 {"phase": "LE-LS/EE-LS adulthood", "lanes": 50, "agent_lane_steps_per_s": 3e5},
                 {"phase": "LE-LS/EE-LS adulthood", "lanes": 300, "agent_lane_steps_per_s": 6e5}]}}))
    assert progress.measured_speed("cpu", 40, str(folder), world="xland") == (
        3e5, os.path.join("docs", "bench", "world-xland.json"))
    assert progress.measured_speed("cpu", 250, str(folder), world="xland")[0] == 6e5
    assert progress.measured_speed("cpu", 40, str(folder), world="corridor") is None
    assert progress.measured_speed("cpu", 40, str(folder)) == (2e6, os.path.join("docs", "bench", "cpu.json"))
    assert progress.cost_line("x", 50, 10**7, 20, "tpu").endswith("; no speed measured on tpu in docs/bench to "
                                                                  "estimate its time")
    line = progress.cost_line("x", 50, 10**7, 20, "cpu")
    assert line.startswith("x: 50 lives a generation, 10.0 M lane-steps a generation, 200.0 M in all; about 0:00:")
    assert progress.cost_line("x", 50, 10**7, 20, "tpu", memory=3 * 2**30).endswith(
        "; at most about 3.0 GiB of memory (an estimate)")


@pytest.mark.parametrize("search", [[1], "ga", {"strategy": 1, "settings": {}}, {"strategy": "ga"}, None])
def test_a_run_recording_a_search_of_no_strategy_is_refused_naming_its_config_json(tmp_path, search):
    from attack import assert_refused, attack, edit_json

    root = str(tmp_path / "run")
    _made_run(root)
    edit_json(os.path.join(root, "config.json"), lambda saved: saved.update(search=search))
    assert_refused(attack(evolve.main, ["--resume", "--out", root], root), "config.json")


def test_a_resume_whose_checkpoints_cannot_be_read_is_refused_before_anything_is_written(tmp_path, capsys):
    """The restore runs after the lock and before any write: no TensorBoard folder, config.json as it was."""
    pytest.importorskip("tensorboardX")
    from attack import tree

    root = str(tmp_path / "run")
    _made_run(root)
    os.makedirs(os.path.join(root, "checkpoints", "3", "state"))  # a checkpoint orbax cannot read
    before = tree(root)
    assert evolve.main(["--resume", "--out", root, "--generations", "12", "--log", "tensorboard"]) == 2
    err = [line for line in capsys.readouterr().err.splitlines() if not line.startswith("warning: ")]
    assert err == [f"error: --resume: no readable checkpoint in {os.path.join(root, 'checkpoints')}"]
    assert tree(root) == before
