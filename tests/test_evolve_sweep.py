"""``evolve --sweep``: a sweep's points are runs of their own, equal to single runs, resumable and extensible."""

import csv
import json
import os
import shutil
import signal
import subprocess
import time

import numpy as np
import pytest
from helpers import assert_same_outputs, evolve_args, evolve_command, outputs

from imrl_jax.commands import evolve, evolve_sweep
from imrl_jax.runs.runspec import RunSpec

#: EE-LS at a tiny scale; a 40 cm target makes reaches common, so fitness is not all 0.
BASE = evolve_args(seeds=2, population=6, parents=2, task_steps=1000, bins=2) + ["--set", "target_radius=40"]
SWEEP = ["--sweep", "eta_selector_actor=0.01,0.3", "--sweep", "mutation_scale=0.5,1"]
POINTS = [dict(eta_selector_actor=a, mutation_scale=m) for a in (0.01, 0.3) for m in (0.5, 1.0)]


def _point_dirs(root):
    with open(os.path.join(root, "sweep.json")) as f:
        return {json.dumps(p["settings"], sort_keys=True): os.path.join(root, p["key"]) for p in json.load(f)["points"]}


@pytest.fixture(scope="module")
def finished_sweep(tmp_path_factory):
    """An uninterrupted sweep of 4 points x 2 seeds x 4 generations."""
    out = str(tmp_path_factory.mktemp("sweeps") / "full")
    assert evolve.main([*BASE, *SWEEP, "--generations", "4", "--out", out]) == 0
    return out


def test_each_point_is_a_run_of_its_own_named_by_its_key(finished_sweep):
    dirs = _point_dirs(finished_sweep)
    assert [json.loads(k) for k in dirs] == [json.loads(json.dumps(p, sort_keys=True)) for p in POINTS]
    for settings, point_dir in dirs.items():
        spec = RunSpec.from_run_dir(point_dir)
        assert os.path.basename(point_dir) == spec.key()
        for field, value in json.loads(settings).items():
            assert getattr(spec.config, field) == value
        assert {"config.json", "history.csv", "fitness.png", "final_population.npz", "checkpoints"} <= set(
            os.listdir(point_dir))
    with open(os.path.join(finished_sweep, "sweep.csv")) as f:
        rows = list(csv.DictReader(f))
    assert [r["key"] for r in rows] == [os.path.basename(d) for d in dirs.values()]
    for row in rows:  # the recorded best of the last generations (at most 5: all 4 here), mean over seeds
        best = np.loadtxt(os.path.join(finished_sweep, row["key"], "history.csv"), delimiter=",", skiprows=1,
                          usecols=2).reshape(4, 2)
        assert float(row["best_last5_mean"]) == pytest.approx(best.mean(0).mean(), abs=1e-6)
        assert int(row["generations"]) == 4
    assert len({r["best_last5_mean"] for r in rows}) > 1  # the points differ


def test_a_point_equals_the_single_run_of_its_settings_bitwise(finished_sweep, tmp_path):
    single = str(tmp_path / "single")
    assert evolve.main([*BASE, "--generations", "4", "--set", "eta_selector_actor=0.3", "--set", "mutation_scale=0.5",
                        "--out", single]) == 0
    point = _point_dirs(finished_sweep)[json.dumps(dict(eta_selector_actor=0.3, mutation_scale=0.5), sort_keys=True)]
    assert_same_outputs(outputs(point), outputs(single))
    assert RunSpec.from_run_dir(single).key() == os.path.basename(point)


def test_killed_resumed_and_extended_sweep_equals_the_uninterrupted_one(finished_sweep, tmp_path):
    """Killed after generation 1, resumed to 3, one point extended alone to 4, then the sweep to 4: bitwise."""
    out = str(tmp_path / "killed")
    process = subprocess.Popen(evolve_command([*BASE, *SWEEP, "--generations", "3", "--out", out]),
                               env={**os.environ, "JAX_PLATFORMS": "cpu"}, stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True)
    deadline = time.time() + 200
    try:
        while time.time() < deadline and process.poll() is None:
            if os.path.isfile(os.path.join(out, "sweep.csv")):  # written after every point's checkpoint
                break
            time.sleep(0.02)
        assert process.poll() is None, "the sweep finished before it could be killed"
        process.send_signal(signal.SIGKILL)
    finally:
        process.kill()
        process.communicate()
    dirs = _point_dirs(out)
    assert evolve.main(["--resume", "--out", out, "--quiet"]) == 0
    for point_dir in dirs.values():
        assert int(np.load(os.path.join(point_dir, "final_population.npz"))["generation"]) == 3
    alone = list(dirs.values())[1]
    assert evolve.main(["--resume", "--out", alone, "--generations", "4", "--quiet"]) == 0
    assert evolve.main(["--resume", "--out", out, "--generations", "4", "--quiet"]) == 0
    want = _point_dirs(finished_sweep)
    for settings, point_dir in dirs.items():
        got, expected = outputs(point_dir), outputs(want[settings])
        assert_same_outputs(got, expected)
        assert got["config.json"]["config"]["num_generations"] == 4
    with open(os.path.join(out, "sweep.json")) as f:
        assert json.load(f)["config"]["num_generations"] == 4


@pytest.mark.parametrize("args, message", [
    (["--sweep", "population_size=4,6"], "--sweep: population_size is static (it changes the program's shapes or "
                                         "loop lengths): evolve once per value; sweepable: "),
    (["--sweep", "task_steps=100,200"], "--sweep: task_steps is static"),
    (["--sweep", "gama=0.9,0.99"], "--sweep: unknown field 'gama' (sweepable: "),
    (["--sweep", "gamma=0.9,x"], "--sweep: gamma: expected numbers separated by commas (got '0.9,x')"),
    (["--sweep", "gamma"], "--sweep: expected FIELD=V1,V2,... (got 'gamma')"),
    (["--sweep", "gamma="], "--sweep: expected FIELD=V1,V2,... (got 'gamma=')"),
    (["--sweep", "gamma=0.9,,0.99"], "--sweep: gamma: expected numbers separated by commas (got '0.9,,0.99')"),
    (["--sweep", "gamma=0.9", "--sweep", "gamma=0.8"], "--sweep: gamma is given twice"),
    (["--sweep", "gamma=0.9,0.8", "--sweep", "trace_lambda=0.1", "--zip"],
     "--zip: every --sweep needs as many values (gamma: 2, trace_lambda: 1)"),
    (["--sweep", "eta=0.1,-1"], "--sweep: eta_actor: must be in [0, 10] (got -1.0)"),
    (["--sweep", "childhood_trace_lambda=0.1,0.2"],
     "--sweep: childhood_trace_lambda=0.2 and childhood_trace_lambda=0.1 are the same run (childhood_trace_lambda: not "
     "read by EE-LS)"),
    (["--sweep", "gamma=0.9", "--strategy", "snes"], "--strategy: a sweep evolves with the paper's GA"),
    (["--sweep", "gamma=0.9", "--strategy-set", "std_init=1"], "--strategy-set: a sweep evolves with the paper's GA"),
    (["--zip"], "--zip: only with --sweep"),
])
def test_bad_sweeps_exit_2_in_one_line_and_write_nothing(tmp_path, capsys, args, message):
    out = tmp_path / "sweep"
    assert evolve.main([*BASE, *args, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"error: {message}") and "\n" not in err, err
    assert not out.exists()


def test_a_finished_sweep_is_refused_without_resume_and_its_points_must_match(finished_sweep, tmp_path, capsys):
    copy = str(tmp_path / "copy")
    shutil.copytree(finished_sweep, copy)
    before = sorted(os.listdir(copy))
    assert evolve.main([*BASE, *SWEEP, "--generations", "4", "--out", copy]) == 2
    assert "already holds a sweep (sweep.json); pass --resume" in capsys.readouterr().err
    assert evolve.main(["--resume", "--out", copy, "--sweep", "gamma=0.9,0.99"]) == 2
    assert "--sweep: the points differ from the sweep's" in capsys.readouterr().err
    assert sorted(os.listdir(copy)) == before


def test_parse_takes_the_product_or_the_values_in_step():
    assert evolve_sweep.parse(["gamma=0.9,0.99", "eta=0.1,0.3"]) == [
        dict(gamma=0.9, eta=0.1), dict(gamma=0.9, eta=0.3), dict(gamma=0.99, eta=0.1), dict(gamma=0.99, eta=0.3)]
    assert evolve_sweep.parse(["gamma=0.9,0.99", "eta=0.1,0.3"], zipped=True) == [
        dict(gamma=0.9, eta=0.1), dict(gamma=0.99, eta=0.3)]


def test_a_sweeps_learning_test_tests_every_point_as_its_own_test_would(finished_sweep, tmp_path, capsys):
    """``learning_test SWEEP`` tests each point into OUT/KEY (one program for all), each bitwise the point's own."""
    from imrl_jax.commands import learning_test

    lengths = ["--best", "2", "--tests", "1", "--task-steps", "400", "--bins", "2", "--steady-steps", "200",
               "--chunks", "1", "--quiet"]
    out = tmp_path / "tests"
    assert learning_test.main([finished_sweep, "--out", str(out), *lengths]) == 0
    dirs = _point_dirs(finished_sweep)
    with open(out / "sweep_tests.json") as f:
        summary = json.load(f)["points"]
    assert list(summary) == [os.path.basename(d) for d in dirs.values()]
    point = list(dirs.values())[2]
    alone = tmp_path / "alone"
    assert learning_test.main([point, "--out", str(alone), *lengths]) == 0
    with np.load(out / os.path.basename(point) / "curves.npz") as a, np.load(alone / "curves.npz") as b:
        assert a["reaches"].tobytes() == b["reaches"].tobytes() and a["reaches"].sum() > 0
    assert summary[os.path.basename(point)]["steady_mean"] == json.loads((alone / "steady.json").read_text())[
        "steady_mean"]
    capsys.readouterr()
    assert learning_test.main([finished_sweep, "--out", str(out), *lengths]) == 0  # done: each point said so
    assert capsys.readouterr().out.count("tested before (steady.json)") == 4
    assert learning_test.main([finished_sweep, "--out", str(out), *lengths, "--tests", "2"]) == 2  # not mixed in
    assert "holds a test of other settings: num_tests 1 (asked 2)" in capsys.readouterr().err
    # another model (--set) is refused too, though every size is as asked; nothing is written
    before = {p: p.stat().st_mtime_ns for p in out.rglob("*")}
    assert learning_test.main([finished_sweep, "--out", str(out), *lengths, "--set", "gamma=0.5"]) == 2
    assert "holds a test of other settings: gamma 0.99 (asked 0.5)" in capsys.readouterr().err
    assert {p: p.stat().st_mtime_ns for p in out.rglob("*")} == before


def test_a_sweep_that_cannot_go_on_together_or_differs_is_refused_and_nothing_changes(finished_sweep, tmp_path,
                                                                                        capsys):
    """A point without a checkpoint (the others have theirs: starting again would throw them away), another base
    config, and one checkpoint a point (points killed a generation apart could not go on) are each refused."""
    copy = str(tmp_path / "copy")
    shutil.copytree(finished_sweep, copy)
    point = list(_point_dirs(copy).values())[1]
    shutil.rmtree(os.path.join(point, "checkpoints"))
    before = {os.path.join(d, f): os.path.getmtime(os.path.join(d, f)) for d, _, fs in os.walk(copy) for f in fs}
    assert evolve.main(["--resume", "--out", copy, "--generations", "5", "--quiet"]) == 2
    err = capsys.readouterr().err
    assert f"--resume: point {os.path.basename(point)} (eta_selector_actor=0.01, mutation_scale=1) has no readable " \
           f"checkpoint (its checkpoints: none)" in err and err.count("\n") == 1
    assert evolve.main(["--resume", "--out", finished_sweep, "--set", "gamma=0.5", "--quiet"]) == 2
    assert "--resume: the config differs from the sweep's in" in capsys.readouterr().err
    assert evolve.main([*BASE, *SWEEP, "--keep", "1", "--out", str(tmp_path / "new")]) == 2
    assert capsys.readouterr().err.startswith("error: --keep: a sweep keeps at least 2 checkpoints a point")
    after = {os.path.join(d, f): os.path.getmtime(os.path.join(d, f)) for d, _, fs in os.walk(copy) for f in fs}
    assert after == before and not (tmp_path / "new").exists()


# ------------------------------------------------------------ refusals, planned before anything is written

def _made_sweep(root, settings=(dict(gamma=0.5), dict(gamma=0.9)), generations=8, steps=((6, 7, 8), (6, 7, 8)),
                extended=None):
    """A sweep's folder as a sweep leaves it (sweep.json, each point's config.json, checkpoint folders of ``steps``),
    made without running it; ``extended``: (point index, generations) of a point resumed alone that far."""
    from imrl_jax.config import make_config

    config = make_config("small", condition="EE-LS", num_generations=generations, population_size=4, num_parents=2,
                         task_steps=200, childhood_steps=200, num_bins=1)
    seeds = [0, 1]
    points = evolve_sweep.make_points(config, seeds, list(settings))
    os.makedirs(root)
    with open(os.path.join(root, "sweep.json"), "w") as f:
        json.dump(evolve_sweep.sweep_record(config, seeds, points), f)
    for i, (p, saved) in enumerate(zip(points, steps)):
        if extended is not None and extended[0] == i:
            p = p._replace(config=p.config.replace(num_generations=extended[1]))
        for step in saved:
            os.makedirs(os.path.join(root, p.key, "checkpoints", str(step), "state"))
        with open(os.path.join(root, p.key, "config.json"), "w") as f:
            json.dump(evolve_sweep.point_record(p, seeds), f)
    return points


def test_a_sweep_resume_past_a_point_resumed_alone_is_refused_in_one_line_and_nothing_is_written(tmp_path):
    """Refused after it had rewritten sweep.json to 16 generations and added "extended" to every point's config.json."""
    from attack import assert_refused, attack

    root = str(tmp_path / "sweep")
    points = _made_sweep(root, steps=((6, 7, 8), (12, 13, 14)), extended=(1, 14))
    outcome = attack(evolve.main, ["--resume", "--out", root, "--generations", "16"], root)
    assert_refused(outcome, points[1].key)
    assert "was resumed alone to generation 14" in outcome.stderr and "none of 8 or fewer" in outcome.stderr
    assert f"--out {os.path.join(root, 'KEY')} --generations 14" in outcome.stderr
    # the same sweep whose points all hold generation 8 goes on from there
    other = str(tmp_path / "together")
    _made_sweep(other, steps=((6, 7, 8), (8,)))
    outcome = attack(evolve.main, ["--resume", "--out", other, "--generations", "16"], other)
    assert outcome.planned and outcome.plan.common == 8 and not outcome.changed


def test_a_sweep_resume_with_an_unwritable_tensorboard_folder_is_refused_and_nothing_is_written(tmp_path):
    pytest.importorskip("tensorboardX")
    from attack import assert_refused, attack

    root = str(tmp_path / "sweep")
    _made_sweep(root)
    with open(os.path.join(root, "tensorboard"), "w") as f:
        f.write("a file where the folder goes")
    outcome = attack(evolve.main, ["--resume", "--out", root, "--generations", "16", "--log", "tensorboard"], root)
    assert_refused(outcome, "--log tensorboard")


def test_values_equal_in_float32_are_one_point_and_minus_0_is_0_in_its_key(tmp_path):
    from attack import assert_refused, attack

    from imrl_jax.config import make_config

    base = [*BASE, "--generations", "2", "--out", str(tmp_path / "s")]
    for values in ("-0,0", "1e-320,0", "0.9,0.900000001"):
        outcome = attack(evolve.main, [*base, "--sweep", f"gamma={values}"], str(tmp_path))
        assert_refused(outcome, "gamma")
        assert f"--sweep: gamma: {values.replace(',', ' and ')} are one value in float32" in outcome.stderr
    for value in ("nan", "inf", "-inf", "1e39"):
        assert_refused(attack(evolve.main, [*base, "--sweep", f"gamma=0.5,{value}"], str(tmp_path)), "gamma")
    outcome = attack(evolve.main, [*base, "--sweep", "gamma=-0,0.900000001"], str(tmp_path))
    assert outcome.planned and not outcome.changed
    zero, point = outcome.plan.points
    assert zero.settings == {"gamma": 0.0} and np.copysign(1.0, zero.settings["gamma"]) == 1.0
    assert point.settings == {"gamma": 0.9}  # the float32 0.900000001 is, as the shortest decimal that gives it
    config = make_config("small", condition="EE-LS", population_size=6, num_parents=2, task_steps=1000, num_bins=2,
                         target_radius=40.0, num_generations=2)
    assert zero.key == RunSpec.make(config.replace(gamma=0.0), [0, 1]).key()  # what a study asking for 0 looks up
    assert point.key == RunSpec.make(config.replace(gamma=0.9), [0, 1]).key()


def test_set_of_a_swept_field_is_refused_not_dropped(tmp_path):
    from attack import assert_refused, attack

    base = [*BASE, "--generations", "2", "--out", str(tmp_path / "s")]
    assert_refused(attack(evolve.main, [*base, "--sweep", "gamma=0.5,0.9", "--set", "gamma=0.3"], str(tmp_path)),
                   "--set gamma=0.3")
    assert_refused(attack(evolve.main, [*base, "--sweep", "eta=0.1,0.2", "--set", "eta_actor=0.3"], str(tmp_path)),
                   "--set eta_actor=0.3")
    root = str(tmp_path / "made")
    _made_sweep(root)
    assert_refused(attack(evolve.main, ["--resume", "--out", root, "--set", "gamma=0.3"], root), "--set gamma=0.3")


def test_sweep_csv_prints_values_round_trip_exact():
    from imrl_jax.runs.checkpoint import RunState, empty_history
    from imrl_jax.config import make_config

    config = make_config("small", condition="EE-LS")
    settings = [dict(gamma=float(np.float32(0.1))), dict(gamma=float(np.nextafter(np.float32(0.1), np.float32(1))))]
    points = evolve_sweep.make_points(config, [0], settings)
    state = RunState(np.asarray(0), None, None, None, None, empty_history(config.num_generations, 1, 6))
    rows = list(csv.DictReader(evolve_sweep.summary_csv(points, [state, state]).splitlines()))
    assert [float(r["gamma"]) for r in rows] == [s["gamma"] for s in settings]  # were both "0.1"


def test_a_sweep_of_no_points_is_refused_in_one_line(tmp_path):
    from attack import assert_refused, attack, edit_json

    root = str(tmp_path / "sweep")
    _made_sweep(root)
    edit_json(os.path.join(root, "sweep.json"), lambda saved: saved.update(points=[]))
    assert_refused(attack(evolve.main, ["--resume", "--out", root], root), "sweep.json")
    for hostile in ([{"settings": {"gamma": "x"}, "key": "k"}], [{"settings": {"bogus": 1}, "key": "k"}], [1]):
        edit_json(os.path.join(root, "sweep.json"), lambda saved: saved.update(points=hostile))
        assert_refused(attack(evolve.main, ["--resume", "--out", root], root), "sweep.json")
    from imrl_jax.config import make_config

    with pytest.raises(evolve_sweep.UsageError, match="at least one point"):  # a sweep.json of none, or run()'s
        evolve_sweep.plan(make_config("small", condition="EE-LS"), str(tmp_path / "new"), [0], [])


def test_a_sweep_whose_records_outgrow_the_memory_is_refused_before_any_folder(tmp_path):
    """--generations 1000000 --seeds 1000 passed the estimate and failed at 36 GB, after writing 1,000 point folders."""
    from attack import assert_refused, attack

    huge = ["--cond", "EE-LS", "--preset", "small", "--generations", "1000000", "--seeds", "1000"]
    outcome = attack(evolve.main, [*huge, "--sweep", "gamma=0.5,0.9", "--out", str(tmp_path / "s")], str(tmp_path))
    assert_refused(outcome, "memory")
    assert "GiB of per-generation records" in outcome.stderr and "use fewer generations or seeds" in outcome.stderr


def test_a_resume_whose_checkpoints_cannot_be_read_is_refused_before_anything_is_written(tmp_path, capsys):
    """The restore runs after the lock and before any write: sweep.json and the points' config.json as they were."""
    from attack import tree

    root = str(tmp_path / "sweep")
    _made_sweep(root)  # checkpoint folders orbax cannot read
    before = tree(root)
    assert evolve.main(["--resume", "--out", root, "--generations", "16", "--quiet"]) == 2
    err = [line for line in capsys.readouterr().err.splitlines() if not line.startswith("warning: ")]
    assert len(err) == 1 and err[0].startswith("error: --resume: point ") and "has no readable checkpoint" in err[0]
    assert tree(root) == before


def test_ctrl_c_in_a_sweeps_checkpoint_ends_in_one_line_without_orbaxs_thread_traceback(tmp_path, monkeypatch,
                                                                                        capsys):
    """Ctrl-C while a sweep saved a point: one of orbax's threads ended with its traceback after the one line."""
    import threading

    from imrl_jax.runs import checkpoint

    real, saves, hooks = checkpoint.Checkpointer.save, [], []
    orbax_code = compile("def work():\n    raise RuntimeError('a write of orbax cut short')\n",
                         os.path.join(os.sep, "site-packages", "orbax", "checkpoint", "write.py"), "exec")

    def save(self, state, meta):
        saves.append(self.directory)
        if len(saves) < 2:
            return real(self, state, meta)
        hooks.append(getattr(threading.excepthook, "drops_failed_reads", False))  # orbax's thread ends silenced
        namespace = {}
        exec(orbax_code, namespace)
        thread = threading.Thread(target=namespace["work"])
        thread.start()
        thread.join()
        raise KeyboardInterrupt  # in the second point's save of generation 0

    monkeypatch.setattr(checkpoint.Checkpointer, "save", save)
    out = str(tmp_path / "stopped")
    assert evolve.main([*BASE, *SWEEP, "--generations", "2", "--out", out]) == 130
    assert hooks == [True]
    assert capsys.readouterr().err == (f"interrupted in generation 1 (1 of 2 done, 0 checkpointed); resume with: "
                                       f"python -m imrl_jax.evolve --resume --out {out}\n")


@pytest.mark.parametrize("how", ["empty", "truncated", "not json", "null", "a list", "NaN", "binary"])
def test_a_damaged_sweep_json_is_one_line_naming_it_for_every_command_that_reads_it(tmp_path, how):
    """sweep.json damaged every way: a resume of the sweep and a learning test of it refuse naming it, nothing
    written (the points' own files as they were)."""
    from attack import assert_refused, attack, damage

    from imrl_jax.commands import learning_test

    root = str(tmp_path / "sweep")
    _made_sweep(root)
    damage(os.path.join(root, "sweep.json"), how)
    assert_refused(attack(evolve.main, ["--resume", "--out", root], str(tmp_path)), "sweep.json",
                   argv=["evolve --resume", how])
    tests = ["--best", "1", "--tests", "1", "--task-steps", "400", "--bins", "2", "--steady-steps", "200", "--chunks",
             "1", "--out", str(tmp_path / "tests")]
    assert_refused(attack(learning_test.main, [root, *tests], str(tmp_path)), "sweep.json", argv=["learning_test", how])
