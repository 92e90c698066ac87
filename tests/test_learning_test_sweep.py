"""The learning test's plan: every check before anything is written (a sweep's points, ``--out``, hostile values and
files), a sweep's record written last, its generation stated, and the default lengths following the run's preset.

Runs and sweeps are written by hand (no evolution) and the tests themselves are replaced by a stand-in that writes a
test's ``steady.json`` as the real one does: nothing here compiles.
"""

import json
import os
import shutil

import numpy as np
import pytest
from attack import (HOSTILE_FILE_BYTES, HOSTILE_INTS, HOSTILE_TEXTS, assert_contract, assert_refused, attack, damage,
                    edit_json, tree)
from helpers import tiny_config

from imrl_jax.commands import learning_test
from imrl_jax.runs import rundir
from imrl_jax.config import make_config
from imrl_jax.commands.learning_test_sweep import SWEEP_TESTS

#: The lengths of a tiny test of a hand-made run (its tasks of 200 cycles in 2 bins).
LENGTHS = ["--best", "2", "--tests", "1", "--task-steps", "400", "--bins", "2", "--steady-steps", "200",
           "--chunks", "1", "--quiet"]
#: The points of the hand-made sweep: key -> gamma (no key a prefix of another: a message names one).
POINTS = {"a-0.9": 0.9, "b-0.95": 0.95, "c-0.99": 0.99}
KEYS = tuple(POINTS)


def write_run(folder, config, generation=None, seeds=(0, 1), genes=None):
    """A finished run directory of ``config`` (its population random), at ``generation`` (default: its last)."""
    os.makedirs(folder, exist_ok=True)
    with open(os.path.join(folder, "config.json"), "w") as f:
        json.dump({"config": config.to_dict(), "seeds": list(seeds)}, f)
    rng = np.random.default_rng(0)
    shape = (len(seeds), config.population_size)
    np.savez(os.path.join(folder, "final_population.npz"),
             generation=np.int64(config.num_generations if generation is None else generation),
             evaluated=rng.normal(size=shape + (genes or config.num_genes,)).astype(np.float32),
             fitness=rng.random(shape).astype(np.float32))
    return str(folder)


def write_sweep(folder, base=None):
    """A finished sweep of three points (gamma), as ``evolve --sweep`` lays it out."""
    base = base or tiny_config("EE-LS", num_generations=2)
    points = [dict(key=key, settings=dict(gamma=gamma)) for key, gamma in POINTS.items()]
    os.makedirs(folder)
    with open(os.path.join(folder, "sweep.json"), "w") as f:
        json.dump(dict(config=base.to_dict(), seeds=[0, 1], points=points), f)
    for p in points:
        write_run(os.path.join(folder, p["key"]), base.replace(**p["settings"]))
    return str(folder)


@pytest.fixture
def sweep(tmp_path):
    return write_sweep(tmp_path / "sweep")


@pytest.fixture
def stand_in(monkeypatch):
    """Tests replaced by one that writes the summary the real test writes (from its sizes), numbers made up."""
    tested = []

    def _test_runs(config, genomes, out_dir, num_tests, steady_steps, num_chunks, seed, quiet, source, command, evolved,
                   log):
        tested.append(out_dir)
        summary = dict(condition=config.condition, source=source, num_runs=genomes.shape[0], num_best=genomes.shape[1],
                       num_tests=num_tests, task_steps=config.task_steps, num_bins=config.num_bins,
                       steady_steps=steady_steps, seed=seed, **evolved, steady_mean=0.5 + len(tested) / 100,
                       steady_sd=0.1, steady_best_run=0.6, whole_test_mean=0.3, config=config.to_dict())
        rundir.write_atomic(os.path.join(out_dir, "steady.json"), json.dumps(summary).encode())
        return summary

    monkeypatch.setattr(learning_test, "_test_runs", _test_runs)
    return tested


def test_a_sweeps_test_states_the_generation_and_repeats_each_points_steady_json(sweep, tmp_path, stand_in):
    out = str(tmp_path / "tests")
    assert learning_test.main([sweep, *LENGTHS, "--out", out]) == 0
    assert stand_in == [os.path.join(out, key) for key in KEYS]
    record = json.loads(open(os.path.join(out, SWEEP_TESTS)).read())
    assert record["generation"] == 1 and record["test"]["task_steps"] == 400
    for key in KEYS:
        steady = json.loads(open(os.path.join(out, key, "steady.json")).read())
        assert steady["generation"] == 1 and steady["generations_done"] == 2
        assert {name: record["points"][key][name] for name in ("generation", "steady_mean")} == \
            {name: steady[name] for name in ("generation", "steady_mean")}
    assert learning_test.main([sweep, *LENGTHS, "--out", out]) == 0  # every point tested before: none again
    assert len(stand_in) == 3


@pytest.mark.parametrize("record", ["kept", "never written"])
def test_a_refused_sweep_test_writes_nothing(sweep, tmp_path, stand_in, record):
    """One point's test folder deleted and other --task-steps: it tested and wrote that point with the new settings,
    then refused the next; now every point is checked first and the refusal names a point's folder."""
    out = str(tmp_path / "tests")
    assert learning_test.main([sweep, *LENGTHS, "--out", out]) == 0
    shutil.rmtree(os.path.join(out, KEYS[0]))
    if record == "never written":  # an interrupted sweep's test: its record is written last
        os.remove(os.path.join(out, SWEEP_TESTS))
    argv = [sweep, *LENGTHS, "--task-steps", "800", "--bins", "4", "--out", out]
    outcome = attack(learning_test.main, argv, str(tmp_path))
    assert_refused(outcome, os.path.join(out, KEYS[0]) if record == "kept" else os.path.join(out, KEYS[1]))
    if record == "never written":
        assert "task_steps 400 (asked 800)" in outcome.stderr


def test_a_sweeps_record_that_disagrees_with_its_points_is_refused_with_its_repair(sweep, tmp_path, stand_in):
    out = str(tmp_path / "tests")
    assert learning_test.main([sweep, *LENGTHS, "--out", out]) == 0
    record = os.path.join(out, SWEEP_TESTS)
    kept = open(record, "rb").read()
    edit_json(os.path.join(out, KEYS[1], "steady.json"), lambda s: s.update(steady_mean=0.125))
    outcome = attack(learning_test.main, [sweep, *LENGTHS, "--out", out], str(tmp_path))
    assert_refused(outcome, record)
    assert "disagree (steady_mean)" in outcome.stderr and f"remove {record}" in outcome.stderr
    for how in ("not json", "a list", "truncated"):
        damage(record, how)
        assert_refused(attack(learning_test.main, [sweep, *LENGTHS, "--out", out], str(tmp_path)), record)
        open(record, "wb").write(kept)
    edit_json(record, lambda r: r["points"].update({"../x": {}}))
    assert_refused(attack(learning_test.main, [sweep, *LENGTHS, "--out", out], str(tmp_path)), record)
    os.remove(record)  # the repair: the record written anew from the points' tests
    assert learning_test.main([sweep, *LENGTHS, "--out", out]) == 0
    assert json.loads(open(record).read())["points"][KEYS[1]]["steady_mean"] == 0.125


def test_a_sweeps_record_is_written_last(sweep, tmp_path, stand_in, monkeypatch):
    """Interrupted at its second point, a sweep's test leaves no record; the same command goes on and writes it."""
    out = str(tmp_path / "tests")
    real = learning_test._test_runs

    def stop_at_second(*args):
        if len(stand_in) == 1:
            raise KeyboardInterrupt
        return real(*args)

    monkeypatch.setattr(learning_test, "_test_runs", stop_at_second)
    with pytest.raises(KeyboardInterrupt):
        learning_test.main([sweep, *LENGTHS, "--out", out])
    monkeypatch.setattr(learning_test, "_test_runs", real)
    assert not os.path.exists(os.path.join(out, SWEEP_TESTS)) and len(stand_in) == 1
    assert not os.path.exists(os.path.join(out, rundir.LOCK))
    assert learning_test.main([sweep, *LENGTHS, "--out", out]) == 0
    assert len(stand_in) == 3 and os.path.exists(os.path.join(out, SWEEP_TESTS))


def test_a_point_extended_alone_is_refused_unless_mixed_generations_are_allowed(sweep, tmp_path, stand_in):
    point = os.path.join(sweep, KEYS[1])
    config = rundir.load_run(point).config
    write_run(point, config.replace(num_generations=4))  # evolved on alone to 4 of 4; the others 2 of 2
    out = str(tmp_path / "tests")
    outcome = attack(learning_test.main, [sweep, *LENGTHS, "--out", out], str(tmp_path))
    assert_refused(outcome, "--allow-mixed-generations")
    assert f"({KEYS[0]}, {KEYS[2]}: 2; {KEYS[1]}: 4)" in outcome.stderr
    assert learning_test.main([sweep, *LENGTHS, "--allow-mixed-generations", "--out", out]) == 0
    record = json.loads(open(os.path.join(out, SWEEP_TESTS)).read())
    assert record["generation"] is None
    assert [record["points"][key]["generation"] for key in KEYS] == [1, 3, 1]


def test_a_sweeps_out_holding_anything_else_is_refused(sweep, tmp_path, stand_in):
    out = tmp_path / "tests"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    assert_refused(attack(learning_test.main, [sweep, *LENGTHS, "--out", str(out)], str(tmp_path)), "notes.txt")
    (out / "notes.txt").unlink()
    (out / KEYS[0]).write_text("a file named as a point")
    assert_refused(attack(learning_test.main, [sweep, *LENGTHS, "--out", str(out)], str(tmp_path)), KEYS[0])
    (out / KEYS[0]).unlink()
    (out / KEYS[0]).mkdir()
    (out / KEYS[0] / "notes.txt").write_text("mine")
    assert_refused(attack(learning_test.main, [sweep, *LENGTHS, "--out", str(out)], str(tmp_path)), "notes.txt")
    assert_refused(attack(learning_test.main, [sweep, *LENGTHS, "--out", sweep], str(tmp_path)), sweep)


def test_a_sweeps_keys_that_are_paths_are_refused(sweep, tmp_path):
    edit_json(os.path.join(sweep, "sweep.json"), lambda s: s["points"][0].update(key="../escape"))
    outcome = attack(learning_test.main, [sweep, *LENGTHS, "--out", str(tmp_path / "tests")], str(tmp_path))
    assert_refused(outcome, "sweep.json")
    edit_json(os.path.join(sweep, "sweep.json"), lambda s: s.update(points=[]))
    assert_refused(attack(learning_test.main, [sweep, "--out", str(tmp_path / "t")], str(tmp_path)), "sweep.json")


def test_a_single_tests_out_holding_anything_else_is_refused(tmp_path):
    """Beside its outputs an unfinished test's --out holds partial/ (its spec and kept runs) and tensorboard/ alone."""
    run = write_run(tmp_path / "run", tiny_config("EE-LS", num_generations=2))
    out = tmp_path / "test"
    (out / "partial").mkdir(parents=True)
    (out / "partial" / "spec.json").write_text("{}")
    (out / "tensorboard").mkdir()
    assert attack(learning_test.main, [run, *LENGTHS, "--out", str(out)], str(tmp_path)).planned
    (out / "partial" / "notes.txt").write_text("mine")
    assert_refused(attack(learning_test.main, [run, *LENGTHS, "--out", str(out)], str(tmp_path)), "notes.txt")
    (out / "partial" / "notes.txt").unlink()
    shutil.rmtree(out / "partial")
    (out / "partial").write_text("a file")
    assert_refused(attack(learning_test.main, [run, *LENGTHS, "--out", str(out)], str(tmp_path)), str(out))


def test_damaged_runs_are_refused_in_one_line(tmp_path):
    config = tiny_config("EE-LS", num_generations=2)
    wide = write_run(tmp_path / "wide", config, genes=config.num_genes + 1)
    assert_refused(attack(learning_test.main, [wide, *LENGTHS, "--out", str(tmp_path / "t")], str(tmp_path)),
                   "final_population.npz")
    nan = write_run(tmp_path / "nan", config)
    with np.load(os.path.join(nan, "final_population.npz")) as data:
        arrays = dict(data)
    arrays["evaluated"][..., 0] = np.nan
    np.savez(os.path.join(nan, "final_population.npz"), **arrays)
    assert_refused(attack(learning_test.main, [nan, *LENGTHS, "--out", str(tmp_path / "t")], str(tmp_path)),
                   "final_population.npz")
    run = tmp_path / "v" / "evolve" / "EE-LS"  # the best genomes a report kept, NaN
    write_run(run, config)
    kept = tmp_path / "best_genomes.npz"
    np.savez(kept, **{"v__EE-LS__genomes": np.full((2, 2, config.num_genes), np.nan, np.float32),
                      "v__EE-LS__seeds": np.arange(2)})
    assert_refused(attack(learning_test.main, [str(run), "--best-genomes", str(kept), *LENGTHS, "--out",
                                               str(tmp_path / "t")], str(tmp_path)), "--best-genomes")
    for name in ("config.json", "final_population.npz"):
        for how in HOSTILE_FILE_BYTES:
            run = write_run(tmp_path / f"run-{name}-{how.replace(' ', '_')}", config)
            damage(os.path.join(run, name), how)
            outcome = attack(learning_test.main, [run, *LENGTHS, "--out", str(tmp_path / "t")], str(tmp_path))
            assert_refused(outcome, name, argv=[name, how])


#: Every option given a value, and the names its refusal may give (the option, or the field it sets).
INT_OPTIONS = {"--best": ("--best",), "--tests": ("--tests", "--best x --tests"), "--task-steps": ("--task-steps",),
               "--bins": ("--bins", "--chunks"), "--steady-steps": ("--steady-steps",), "--chunks": ("--chunks",),
               "--seed": ("--seed",), "--runs": ("--runs",), "--cpu-devices": ("--cpu-devices",)}


@pytest.mark.parametrize("source", ["run", "scratch"])
@pytest.mark.parametrize("option", list(INT_OPTIONS))
def test_hostile_values_of_every_size_are_refused_or_planned_and_nothing_is_written(tmp_path, option, source):
    """Out of bounds, past 32 and 64 bits, not integers: one line naming the option, exit 2, nothing written; or a
    plan (a value that is allowed), nothing written before it is carried out."""
    run = write_run(tmp_path / "run", tiny_config("EE-LS", num_generations=2))
    head = ([run, *(["--best", "2"] if option != "--best" else [])] if source == "run" else ["--cond", "SLE"])
    for value in HOSTILE_INTS:  # the other lengths their defaults: the run's, or the preset's
        argv = [*head, f"{option}={value}", "--quiet", "--out", str(tmp_path / "test")]
        seen = assert_contract(attack(learning_test.main, argv, str(tmp_path)), *INT_OPTIONS[option], argv=argv)
        # below the least, past 64 bits, not an integer: never a test
        assert seen == "refused" or value not in ("-1", "18446744073709551616", "1.5", "nan", ""), argv


@pytest.mark.parametrize("option", ["--set", "--task-set", "--out", "--log", "--cond", "--register"])
def test_hostile_texts_of_every_text_option_are_refused_or_planned_and_nothing_is_written(tmp_path, option):
    run = write_run(tmp_path / "run", tiny_config("EE-LS", num_generations=2))
    for value in HOSTILE_TEXTS:
        out = [] if option == "--out" else ["--out", str(tmp_path / "test")]
        argv = [run, *LENGTHS, f"{option}={value}", *out]
        outcome = attack(learning_test.main, argv, str(tmp_path))
        if assert_contract(outcome, option, "run_dir", argv=argv) == "planned" and option == "--out":
            assert outcome.plan.tests[0].out_dir == value, argv


@pytest.mark.parametrize("how", list(HOSTILE_FILE_BYTES))
def test_damaged_best_genomes_are_refused_in_one_line(tmp_path, how):
    config = tiny_config("EE-LS", num_generations=2)
    run = tmp_path / "v" / "evolve" / "EE-LS"
    write_run(run, config)
    kept = tmp_path / "best_genomes.npz"
    np.savez(kept, **{"v__EE-LS__genomes": np.zeros((2, 2, config.num_genes), np.float32),
                      "v__EE-LS__seeds": np.arange(2)})
    damage(str(kept), how)
    argv = [str(run), "--best-genomes", str(kept), *LENGTHS, "--out", str(tmp_path / "test")]
    assert_refused(attack(learning_test.main, argv, str(tmp_path)), "--best-genomes", argv=argv)


@pytest.mark.parametrize("preset, lengths", [("paper", (1_000_000, 100, 100_000, 10)), ("small", (50_000, 10, 5_000, 10))])
def test_the_default_lengths_follow_the_runs_preset(tmp_path, preset, lengths):
    """The paper's test is 10 x its evolution's tasks, in its bins, the steady state its last tenth: a small run's test
    follows its own lengths (it tested at the paper's, 6 minutes); the paper's defaults are as they were."""
    run = write_run(tmp_path / "run", make_config(preset, condition="EE-LS", num_generations=1))
    outcome = attack(learning_test.main, [run, "--out", str(tmp_path / "test")], str(tmp_path))
    assert outcome.planned, outcome.stderr
    test = outcome.plan.tests[0]
    assert (test.config.task_steps, test.config.num_bins, test.steady_steps, test.num_chunks) == lengths
    scratch = attack(learning_test.main, ["--cond", "SLE", "--preset", preset, "--out", str(tmp_path / "s")],
                     str(tmp_path)).plan.tests[0]
    assert (scratch.config.task_steps, scratch.config.num_bins, scratch.steady_steps) == lengths[:3]
    given = attack(learning_test.main, [run, "--task-steps", "4000", "--bins", "4", "--out", str(tmp_path / "test")],
                   str(tmp_path)).plan.tests[0]
    assert (given.config.task_steps, given.config.num_bins, given.steady_steps, given.num_chunks) == (4000, 4, 1000, 4)


def test_nothing_is_written_around_a_planned_test(tmp_path):
    """The plan of a test that would run writes nothing, neither --out nor its lock."""
    run = write_run(tmp_path / "run", tiny_config("EE-LS", num_generations=2))
    before = tree(str(tmp_path))
    outcome = attack(learning_test.main, [run, *LENGTHS, "--out", str(tmp_path / "test")], str(tmp_path))
    assert outcome.planned and not outcome.changed and tree(str(tmp_path)) == before
