"""Learning tests (Fig. 3b/3c): chunked tests equal whole lives, the statistics, the command line."""

import json
import os
import socket

import jax
import numpy as np
import pytest
from helpers import stop_after_first

from imrl_jax.runs import cli, learning_test_state, rundir
from imrl_jax import conditions
from imrl_jax.commands import learning_test
from imrl_jax.analysis import charts, steady_state
from imrl_jax.evolution.ga import init_population
from imrl_jax.agent.lifetime import live


@pytest.mark.parametrize("condition, options", [("LE-LS", {}), ("SLE", {}),
                                                ("EE-LS", dict(selector_period=7, selector_termination="colour"))],
                         ids=["LE-LS", "SLE", "EE-LS-options"])
def test_chunked_test_equals_one_life(tiny, condition, options):
    """A test run in 2 chunks is the same computation as live() with the test's task length (counts bitwise);
    with the selector's options, an option running across the chunks' boundary goes on."""
    config = tiny(condition, task_steps=400, num_bins=4, **options)
    keys = jax.random.split(jax.random.key(3), 2)
    genomes = np.asarray(init_population(jax.random.key(4), config))[:2]
    params = config.learning_params()
    reaches, selections = learning_test.run_tests(keys, config, params, genomes, num_chunks=2)
    whole = jax.vmap(lambda k, g: live(k, config, params, g))(keys, genomes)
    assert reaches.shape == (2, config.num_tasks, 4)
    np.testing.assert_array_equal(reaches, np.asarray(whole.reward_curve))
    np.testing.assert_array_equal(selections, np.asarray(whole.adult_selections))
    # The window is not trivial: the robots do reach targets in it (SLE's noisy expert at least).
    if condition == "SLE":
        assert reaches.sum() > 0


def test_statistics_by_hand(tiny):
    """Steady state = performance over the final bins, averaged per run; the best run is the highest."""
    config = tiny("EE-LS", task_steps=400, num_bins=4)  # bins of 100 steps
    per_bin_max = np.asarray(config.theoretical_max()) / 4  # reaches per bin at performance 1
    reaches = np.zeros((2, 1, 1, 6, 4))
    reaches[0, ..., 3] = 0.5 * per_bin_max  # run 0: 0.5 in the last bin, 0 before
    reaches[1, ..., 2:] = 0.25 * per_bin_max[:, None]  # run 1: 0.25 in the last two bins
    summary = steady_state.summarise(config, reaches, steady_steps=200)  # last 2 bins
    assert summary["steady_per_run"] == pytest.approx([0.25, 0.25])
    summary = steady_state.summarise(config, reaches, steady_steps=100)  # last bin
    assert summary["steady_per_run"] == pytest.approx([0.5, 0.25])
    assert summary["steady_mean"] == pytest.approx(0.375)
    assert summary["best_run"] == 0 and summary["steady_best_run"] == pytest.approx(0.5)
    assert summary["whole_test_mean"] == pytest.approx((0.5 + 0.5) / 8)
    with pytest.raises(Exception, match="steady_steps"):
        steady_state.steady_bins(config, 150)


def test_command_line(tiny_run, tmp_path, capsys):
    """The best individuals of each seed are tested; outputs agree with each other; reruns are refused."""
    out = str(tmp_path / "test")
    argv = [tiny_run, "--best", "2", "--tests", "2", "--task-steps", "400", "--bins", "4", "--steady-steps", "200",
            "--chunks", "2", "--out", out, "--quiet"]
    capsys.readouterr()
    assert learning_test.main(argv) == 0
    printed = capsys.readouterr()  # --quiet: the summary line alone
    assert printed.err == "" and printed.out.count("\n") == 1 and printed.out.startswith("EE-LS: steady state")
    config, seeds, best = learning_test.load_run(tiny_run, 2)
    with np.load(os.path.join(tiny_run, "final_population.npz")) as data:
        fitness, evaluated = data["fitness"], data["evaluated"]
    for s in range(len(seeds)):
        top = np.sort(fitness[s])[::-1][:2]
        chosen = [np.flatnonzero((evaluated[s] == g).all(1))[0] for g in best[s]]
        np.testing.assert_array_equal(fitness[s][chosen], top)
    with open(os.path.join(out, "steady.json")) as f:
        summary = json.load(f)
    with np.load(os.path.join(out, "curves.npz")) as data:
        reaches = data["reaches"]
    assert reaches.shape == (len(seeds), 2, 2, 6, 4)
    test_config = config.replace(task_steps=400, num_bins=4)
    assert summary["steady_mean"] == pytest.approx(steady_state.summarise(test_config, reaches, 200)["steady_mean"])
    assert (summary["generation"], summary["generations_done"], summary["num_generations"]) == (0, 1, 1)
    assert os.path.exists(os.path.join(out, "learning_curve.png"))
    rows = open(os.path.join(out, "curve.csv")).read().splitlines()
    assert len(rows) == 5 and rows[0].startswith("bin,end_step,mean")

    before = {name: os.path.getmtime(os.path.join(out, name)) for name in os.listdir(out)}
    assert learning_test.main(argv) == 2  # the output already holds a test: refused, nothing touched
    assert "already holds a learning test" in capsys.readouterr().err
    assert before == {name: os.path.getmtime(os.path.join(out, name)) for name in os.listdir(out)}


@pytest.mark.parametrize("how", ["killed", "running"])
def test_a_half_evolved_run_is_refused_or_tested_with_a_warning_and_its_generation_recorded(tiny_run, tmp_path, capsys,
                                                                                            how):
    """A run killed at generation 1 of 3 (or one whose writer still runs) is not tested as if finished."""
    import shutil

    run = str(tmp_path / "run")
    shutil.copytree(tiny_run, run)
    if how == "killed":
        with open(os.path.join(run, "config.json")) as f:
            info = json.load(f)
        info["config"]["num_generations"] = 3
        with open(os.path.join(run, "config.json"), "w") as f:
            json.dump(info, f)
        why = f"{run} has 1 of its 3 generations evaluated"
    else:
        with open(os.path.join(run, ".lock"), "w") as f:  # this process: alive
            json.dump(dict(pid=os.getpid(), host=socket.gethostname(), start=0), f)
        why = f"{run} has 1 of its 1 generations evaluated and is being written by pid {os.getpid()} on " \
              f"{socket.gethostname()}"
    out = tmp_path / "test"
    argv = [run, "--best", "1", "--tests", "1", "--task-steps", "200", "--bins", "2", "--steady-steps", "100",
            "--chunks", "1", "--quiet", "--out", str(out)]
    assert learning_test.main(argv) == 2
    assert capsys.readouterr().err == (f"error: run_dir: {why}: its evolution is unfinished (pass --allow-unfinished "
                                       f"to test generation 0 anyway)\n")
    assert not out.exists()
    assert learning_test.main([*argv, "--allow-unfinished"]) == 0
    assert capsys.readouterr().err == f"warning: {why}: testing generation 0 (steady.json records it)\n"
    with open(out / "steady.json") as f:
        summary = json.load(f)
    assert (summary["generation"], summary["generations_done"], summary["num_generations"]) == \
        (0, 1, 3 if how == "killed" else 1)


def test_an_interrupted_test_goes_on_from_its_first_unfinished_run(tiny_run, tmp_path, monkeypatch, capsys):
    """Stopped after its first run, the same command tests only the others; the results equal an uninterrupted test's."""
    argv = [tiny_run, "--best", "2", "--tests", "1", "--task-steps", "400", "--bins", "4", "--steady-steps", "200",
            "--chunks", "2", "--quiet"]
    whole, cut = tmp_path / "whole", tmp_path / "cut"
    assert learning_test.main([*argv, "--out", str(whole)]) == 0
    num_runs = len(learning_test.load_run(tiny_run, 2)[1])
    assert num_runs >= 2
    real, calls = stop_after_first(monkeypatch, learning_test, "run_tests")
    with pytest.raises(KeyboardInterrupt):
        learning_test.main([*argv, "--out", str(cut)])
    assert sorted(os.listdir(cut / learning_test.PARTIAL)) == ["run_000.npz", "spec.json"]
    assert not (cut / "steady.json").exists()

    # Other settings in the same folder are refused: one line, exit 2, the kept run untouched.
    kept = (cut / learning_test.PARTIAL / "run_000.npz").read_bytes()
    capsys.readouterr()
    assert learning_test.main([*argv[:-1], "--tests", "2", "--quiet", "--out", str(cut)]) == 2
    err = capsys.readouterr().err.strip()
    assert "--out" in err and "other settings" in err and len(err.splitlines()) == 1
    assert (cut / learning_test.PARTIAL / "run_000.npz").read_bytes() == kept

    calls.clear()
    monkeypatch.setattr(learning_test, "run_tests", lambda *a, **k: calls.append(1) or real(*a, **k))
    capsys.readouterr()
    assert learning_test.main([*argv[:-1], "--out", str(cut)]) == 0  # its progress shown
    assert len(calls) == num_runs - 1  # run 0 was not tested again
    lines = capsys.readouterr().err.splitlines()  # what the runs left cost, said before anything compiles
    config = learning_test.load_run(tiny_run, 2)[0].replace(task_steps=400, num_bins=4)
    lives, steps = 2 * 1, 2 * 1 * config.lifetime_steps  # best x tests; a test lives a whole life
    cost = f"testing {num_runs - 1} run(s): {lives} lives a run, {steps:,} lane-steps a run, "
    assert lines[1].startswith(cost) and lines[1].endswith(" GiB of memory (an estimate)"), lines[:3]
    assert lines[0].startswith("EE-LS learning test: ") and "1 run(s) done before" in lines[0]
    with np.load(whole / "curves.npz") as a, np.load(cut / "curves.npz") as b:
        np.testing.assert_array_equal(a["reaches"], b["reaches"])
        np.testing.assert_array_equal(a["selections"], b["selections"])
    summary = json.loads((cut / "steady.json").read_text())
    assert summary["resumed_runs"] == [0]
    assert summary["steady_mean"] == json.loads((whole / "steady.json").read_text())["steady_mean"]
    assert not (cut / learning_test.PARTIAL).exists()


#: A test from scratch of one short life (what an option that is wrongly accepted runs).
TINY_SLE = ["--runs", "1", "--best", "1", "--tests", "1", "--task-steps", "200", "--bins", "2", "--steady-steps", "100",
            "--chunks", "1", "--quiet"]


@pytest.mark.parametrize("argv, message", [
    (["/nonexistent/run"], "/nonexistent/run' is not a directory"),
    (["--cond", "SLE", "--set", "eta_actor=nan"], "eta_actor: must be a finite number"),
    (["--cond", "SLE", "--set", "eta=0.1"], "did you mean eta_actor"),
    (["--cond", "SLE", "--bins", "10", "--chunks", "3"], "--chunks"),
    (["--cond", "SLE", "--task-steps", "1000", "--bins", "10", "--steady-steps", "150"], "steady_steps"),
    (["--cond", "XX"], "--cond"),
    (["--cond", "SLE", "--set", "trace_lambda=2"], "trace_lambda"),
    # Refused before partial/ is made (a step of 1e30 cm divided by zero once the test had begun).
    (["--cond", "SLE", "--set", "max_speed=1e30"], "max_speed: must be in (0, 10000] (got 1e+30)"),
    (["--cond", "SLE", "--set", "target_radius=150"], "target_radius: must be below every task's start-to-target"),
    (["--cond", "SLE", "--cpu-devices", "100000"], "--cpu-devices: 100,000 is above the limit"),
    (["--cond", "SLE", "--best-genomes", "best_genomes.npz", *TINY_SLE], "--best-genomes: only with a run directory"),
    ([], "run_dir"),
])
def test_bad_input(tmp_path, capsys, argv, message):
    """Bad input: one line naming the field or file, exit code 2, nothing written."""
    out = tmp_path / "out"
    assert learning_test.main([*argv, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1
    assert not out.exists()


def test_a_test_that_cannot_fit_in_memory_is_refused(tmp_path, capsys, monkeypatch):
    from imrl_jax.evolution import devices

    monkeypatch.setattr(devices, "available_memory", lambda: 2**30)
    monkeypatch.setattr(devices, "accelerator_memory", lambda: None)
    out = tmp_path / "out"
    assert learning_test.main(["--cond", "SLE", "--runs", "1", "--best", "100", "--tests", "100", "--task-steps", "200",
                               "--bins", "2", "--steady-steps", "100", "--chunks", "1", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: memory: testing 100 x 100 test(s) of 6 tasks a run needs about ") and \
        "but this machine has 1.0 GiB available" in err and len(err.splitlines()) == 1
    assert not out.exists()


def test_the_progress_names_each_runs_chunks_within_it():
    """With --chunks 10 the tenth chunk of a test's first run said "chunk 10 (10/20)", the eleventh "chunk 11"."""
    import io

    from imrl_jax.runs.progress import Progress

    progress = Progress(20, quiet=False, stream=io.StringIO(), unit="chunk", group=("run", 10))
    assert progress.update(10, 0.0, 0.0, 1.0, scores="s").startswith("run 1 chunk 10/10 (10/20) | s")
    assert progress.update(11, 0.0, 0.0, 1.0, scores="s").startswith("run 2 chunk 1/10 (11/20) | s")


def test_a_text_file_as_best_genomes_is_refused_in_one_line_naming_it(tmp_path, capsys):
    """It said the file held "pickled (object) data"; it is not an .npz at all."""
    run, kept = tmp_path / "run", tmp_path / "best_genomes.npz"
    kept.write_text("not arrays\n")
    run.mkdir()
    (run / "config.json").write_text(json.dumps({"config": {"condition": "EE-LS"}, "seeds": [0]}))
    out = tmp_path / "out"
    assert learning_test.main([str(run), "--best-genomes", str(kept), "--out", str(out)]) == 2
    assert capsys.readouterr().err == (f"error: --best-genomes: {kept} is unreadable (not an .npz file of "
                                       f"arrays)\n")
    assert not out.exists()


def test_no_run_directory_is_refused_with_a_hint_naming_every_condition_tested_from_scratch(tmp_path, capsys):
    assert learning_test.main(["--out", str(tmp_path / "out")]) == 2
    assert capsys.readouterr().err == ("error: run_dir: give an evolution's run directory, or --cond SLE or EXT-LS to "
                                       "test learning from scratch\n")


def test_kept_runs_and_their_spec_are_read_bounded(tmp_path):
    """A kept run larger than a run's arrays can be is tested again (not decompressed); a spec.json that is not UTF-8
    is refused in one line naming it."""
    partial = tmp_path / "partial"
    partial.mkdir()
    (partial / "spec.json").write_text(json.dumps({"fingerprint": "f"}))
    np.savez_compressed(partial / "run_000.npz", reaches=np.zeros((10, 6, 1000), np.int32),
                        selections=np.zeros((10, 6, 1000, 3), np.int32))
    warnings = []
    assert learning_test_state.finished_runs(str(partial), "f", 1, warn=warnings.append, limit=10_000) == {}
    assert warnings == [f"warning: {partial / 'run_000.npz'} cannot be read (RunDirError); run 0 is tested again"]
    assert list(learning_test_state.finished_runs(str(partial), "f", 1, warn=warnings.append, limit=10**6)) == [0]
    (partial / "spec.json").write_bytes(b"\xff\xfe")
    with pytest.raises(cli.UsageError, match=r"spec.json cannot be read \(RunDirError\)"):
        learning_test_state.finished_runs(str(partial), "f", 1)


def test_an_empty_out_is_refused(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert learning_test.main(["--cond", "SLE", *TINY_SLE, "--out", ""]) == 2
    assert capsys.readouterr().err == "error: --out: empty path; give a directory\n"
    assert os.listdir(tmp_path) == []


def test_pairs_both_ways_by_hand():
    """Both tasks of a pair at the level count; one of them does not (what a fixed controller gets at best)."""
    performance = np.array([[0.5, 0.3, 0.9, 0.1, 0.0, 0.0],   # pair 1 both ways; pair 2 one way; pair 3 none
                            [0.2, 0.2, 0.2, 0.2, 0.19, 0.8]])  # pairs 1 and 2 (at the level), not 3
    assert steady_state.pairs_both_ways(performance) == pytest.approx(3 / 6)
    assert steady_state.pairs_both_ways(performance, level=0.25) == pytest.approx(1 / 6)


def test_unwritable_out_is_refused_before_testing(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("kept")
    out = blocker / "out"
    argv = ["--cond", "SLE", "--runs", "1", "--best", "1", "--tests", "1", "--task-steps", "200", "--bins", "2",
            "--steady-steps", "100", "--chunks", "1", "--out", str(out)]
    assert learning_test.main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"error: --out: cannot write to {out}") and len(err.splitlines()) == 1
    assert os.listdir(tmp_path) == ["file"]


def test_help(capsys):
    with pytest.raises(SystemExit):
        learning_test.main(["--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "``" not in text and "(default: None)" not in text
    assert "--cond {" + ",".join(conditions.NAMES) + "}" in text and "EXT-LS" in conditions.NAMES
    assert "--quiet no progress lines" in text


def test_the_step_counter_is_shared_so_block_draws_stay_a_branch(tiny):
    """advance gets the step counter as one value for every lane: under vmap the block draw stays a cond.

    Carried per lane it would be batched, and the cond a select that draws a block on every step (3x slower).
    """
    config = tiny("EE-LS", task_steps=400, num_bins=4)
    begin_all, advance_all = learning_test.make_learning_test(config, 2)
    genomes = np.asarray(init_population(jax.random.key(1), config))[:2]
    tests = begin_all(jax.random.split(jax.random.key(0), 2), config.learning_params(), genomes)
    jaxpr = str(jax.make_jaxpr(advance_all)(config.learning_params(), jax.numpy.int32(0), tests))
    assert " cond[" in jaxpr


#: On 2 devices: 3 tests are padded with a copy of the last; the copy changes no real lane.
ODD_COUNTS = """
import jax, jax.numpy as jnp, numpy as np
from imrl_jax.commands import learning_test
from imrl_jax.config import make_config
assert len(jax.devices()) == 2
argv = ["--cond", "SLE", "--runs", "1", "--best", "1", "--tests", "3", "--task-steps", "200", "--bins", "2",
        "--steady-steps", "100", "--chunks", "1", "--set", "target_radius=40", "--quiet", "--out", OUT]
assert learning_test.main(argv) == 0
config = make_config("paper", condition="SLE", target_radius=40).replace(task_steps=200, num_bins=2)
keys = jnp.concatenate([learning_test.test_keys(0, 1, 1, 3), jax.random.split(jax.random.key(7), 1)])
four = learning_test.run_tests(keys, config, config.learning_params(), np.zeros((4, 0), np.float32))  # no padding
with np.load(OUT + "/curves.npz") as data:
    for name, want in zip(("reaches", "selections"), four):
        np.testing.assert_array_equal(data[name].reshape(want[:3].shape), want[:3], err_msg=name)
print("reaches", int(four[0].sum()))
"""


def test_an_odd_number_of_tests_on_two_devices_equals_the_same_tests_unpadded(tmp_path):
    """3 tests on 2 devices (a padding lane) give the reaches and expert use of the same tests among 4 (none)."""
    from helpers import run_python

    done = run_python(f"OUT = {str(tmp_path / 'out')!r}\n" + ODD_COUNTS, devices=2)
    assert done.returncode == 0, done.stderr[-3000:]
    assert int(done.stdout.split()[-1]) > 0, "the check is weak if no test reaches a target"
    assert not (tmp_path / "out" / learning_test.PARTIAL).exists()


def _sle_argv(out):
    return ["--cond", "SLE", "--runs", "1", "--best", "1", "--tests", "2", "--task-steps", "200", "--bins", "2",
            "--steady-steps", "100", "--chunks", "1", "--quiet", "--out", str(out)]


def test_a_locked_out_is_refused_and_a_stale_lock_taken_over(tmp_path, capsys):
    """A live writer (another process) is named and refused; once it is gone, its lock is taken over."""
    import subprocess

    from helpers import write_lock

    out = tmp_path / "out"
    holder = subprocess.Popen(["sleep", "60"])
    try:
        lock = write_lock(str(out), holder.pid)
        assert learning_test.main(_sle_argv(out)) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith("error: --out: ") and f"pid {holder.pid} on " in err and len(err.splitlines()) == 1
        assert sorted(os.listdir(out)) == [".lock"]
    finally:
        holder.kill()
        holder.wait()
    assert learning_test.main(_sle_argv(out)) == 0
    first = capsys.readouterr().err.splitlines()[0]
    assert first == f"warning: {lock}: took over the stale lock of pid {holder.pid} on {socket.gethostname()} (no longer running)"
    assert not os.path.exists(lock) and (out / "steady.json").exists()


def test_an_out_holding_anything_else_is_refused(tmp_path, capsys):
    """Only a new or empty directory, or an unfinished test to go on with: anything else is left alone."""
    out = tmp_path / "out"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    assert learning_test.main(_sle_argv(out)) == 2
    err = capsys.readouterr().err.strip()
    assert err == (f"error: --out: {out} is not empty and holds no unfinished learning test (it holds notes.txt); "
                   f"choose a new or empty directory")
    assert os.listdir(out) == ["notes.txt"]


@pytest.mark.parametrize("argv, message", [
    (["--cond", "SLE", "--task-steps", "2000000000"], "--task-steps: 2,000,000,000 is above the limit of 1,000,000,000"),
    (["--cond", "SLE", "--runs", "20000"], "--runs: 20,000 is above the limit of 10,000"),
    (["--cond", "SLE", "--best", "1000", "--tests", "10000"], "--best x --tests: 10,000,000 is above the limit"),
    (["--cond", "SLE", "--task-steps", "1e9"], "--task-steps: invalid int value: '1e9'"),
    (["--cond", "SLE", "--set", "condition=LE-LS"], "--set condition=LE-LS: condition is set by --cond"),
    (["--cond", "SLE", "--set", "task_steps=500"], "task_steps is set by --task-steps"),
])
def test_absurd_sizes_and_sets_of_options_are_refused(tmp_path, capsys, argv, message):
    out = tmp_path / "out"
    assert learning_test.main([*argv, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: ") and message in err and len(err.splitlines()) == 1
    assert not out.exists()


def test_a_test_smaller_or_shorter_than_the_papers_is_labelled_reduced_scale(tiny):
    config = tiny("EE-LS")
    assert charts.scale_label(config.replace(task_steps=1_000_000), (10, 10, 10)) == ""
    assert charts.scale_label(config.replace(task_steps=1_000_000), (5, 4, 5)) == ", reduced scale (100 tests)"
    assert (charts.scale_label(config.replace(task_steps=20), (10, 10, 10))
            == ", reduced scale (20 cycles)")


def test_set_with_a_run_directory_tests_the_evolved_genomes_under_the_values_set(tiny_run, tmp_path, capsys):
    from attack import assert_refused, attack

    argv = [tiny_run, "--best", "1", "--tests", "1", "--task-steps", "400", "--bins", "4", "--steady-steps", "200",
            "--chunks", "1", "--quiet"]
    planned = attack(learning_test.main, [*argv, "--set", "eta_selector_actor=0.05", "--out", str(tmp_path / "a")],
                     str(tmp_path))
    test = planned.plan.tests[0]
    evolved, _ = learning_test.load_run(tiny_run, 1)[:2]
    assert test.config == evolved.replace(task_steps=400, num_bins=4, eta_selector_actor=0.05)
    assert test.source.endswith(", eta_selector_actor=0.05")
    refused = attack(learning_test.main, [*argv, "--set", "num_experts=2", "--out", str(tmp_path / "b")], str(tmp_path))
    assert_refused(refused, "--set")
    assert refused.stderr == "error: --set: num_experts changes the genome (222 genes evolved, 148 asked)\n"


def test_the_best_genomes_a_report_kept_stand_in_for_a_lost_final_population(tiny_run, tmp_path, capsys):
    import shutil

    config, seeds, best = learning_test.load_run(tiny_run, 2)
    run = tmp_path / "v" / "evolve" / config.condition  # the pipeline's layout: VARIANT/evolve/CONDITION
    run.mkdir(parents=True)
    shutil.copy(os.path.join(tiny_run, "config.json"), run / "config.json")  # no final_population.npz
    kept = tmp_path / "best_genomes.npz"
    np.savez(kept, **{f"v__{config.condition}__genomes": best, f"v__{config.condition}__seeds": np.asarray(seeds)})
    found = rundir.load_kept_best(str(run), str(kept), 1)
    assert found[0] == config and found[1] == seeds
    np.testing.assert_array_equal(found[2], best[:, :1])
    other = tmp_path / "w" / "evolve" / config.condition
    shutil.copytree(run, other)
    assert learning_test.main([str(other), "--best-genomes", str(kept), "--best", "1", "--out", str(tmp_path / "t")]) == 2
    assert capsys.readouterr().err.strip() == (f"error: --best-genomes: {kept} holds no w/{config.condition} (it holds "
                                               f"v/{config.condition})")
    np.savez(kept, **{f"v__{config.condition}__genomes": best})  # the seeds left out
    assert learning_test.main([str(run), "--best-genomes", str(kept), "--best", "1", "--out", str(tmp_path / "t")]) == 2
    assert capsys.readouterr().err.strip() == (f"error: --best-genomes: {kept} holds no v__{config.condition}__seeds "
                                               f"beside v__{config.condition}__genomes")
    assert not (tmp_path / "t").exists()


def test_cpu_devices_are_set_up_before_the_task_set_starts_jax(tmp_path):
    """The task set's checks run JAX: the devices asked for after them would be ignored."""
    from helpers import devices_seen

    args = ["--cond", "SLE", "--task-set", "paper", "--cpu-devices", "2", "--out", str(tmp_path / "test")]
    assert devices_seen("imrl_jax.learning_test", args) == 2
