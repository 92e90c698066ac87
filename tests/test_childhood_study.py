"""The childhood study as a table: its committed evolutions and measures are found, its report regenerates
docs/CHILDHOOD.md's evolutions table, and its measures' command refuses bad input in one line, exit 2."""

import dataclasses
import os

import pytest
from helpers import ROOT

from experiments import childhood_study as study
from experiments.harness.reproduce import stage_done


@pytest.fixture
def in_root(monkeypatch):
    monkeypatch.chdir(ROOT)  # the table's folders are relative to the repository's root


def test_every_committed_run_and_measure_is_found(in_root):
    """0 stages left: the seven evolutions by their key where the study made them, each measure by its result.json."""
    stages, scale = study.TABLE.all_stages()
    assert [s for s in stages if not stage_done(s, scale)] == []
    evolutions = {s.variant: s.out_dir for s in stages if s.kind == "evolve"}
    assert evolutions == {name: os.path.join(study.OUT, "evolve", name) for name in study.EVOLUTIONS}
    assert [s.generations for s in stages if s.kind == "evolve"] == [30, 30, 30, 30, 15, 30, 30]
    measures = {s.variant: s for s in stages if s.kind == "measure"}
    assert len(measures) == 15 and measures["evolved_skills"].needs == ("evolve LE-LS-skills",)
    command = study.TABLE.stage_command(measures["evolved_skills"])[0]
    assert command[1:] == ["-m", study.MODULE, evolutions["LE-LS-skills"], "--out",
                           os.path.join(study.OUT, "measures", "evolved_skills"), "evolved"]
    command = study.TABLE.stage_command(measures["evolved_cpu"])[0]
    assert [os.path.relpath(r, study.RESULTS) for r in command[-4:]] == [
        os.path.join("cpu", v, "evolve", c) for v, c in (("paper", "LE-LS"), ("extension", "LE-LS"),
                                                         ("paper", "EE-LS"), ("extension", "EE-LS"))]
    rows = study.read_rows(measures["evolved_cpu"].out_dir)  # the committed CSV its result.json names
    assert len(rows) == 200 and rows[0]["run"] == "LE-LS" and rows[0]["fitness"] == pytest.approx(0.2068)
    # the heritability measure names four of the study's rows ({ROW}): it waits for them and reads their runs
    heritable = ("LE-LS-skills", "LE-LS-extension", "LE-LS-skills-no-speed-bias", "LE-LS-skills-2lives")
    assert measures["heritability"].needs == tuple(f"evolve {name}" for name in heritable)
    command = study.TABLE.stage_command(measures["heritability"])[0]
    assert command[command.index("heritability") + 1:] == [evolutions[name] for name in heritable]
    # the committed measure's rows are each run's best, seed by seed and rank by rank, as best_of_run gives them
    committed = [r for r in study.read_rows(measures["heritability"].out_dir) if r["run"] == "LE-LS-skills"]
    _, genomes, best = study.best_of_run(evolutions["LE-LS-skills"], 10)
    assert len(genomes) == len(best) == len(committed) == 30
    assert [(b["seed"], b["rank"]) for b in best] == [(s, k) for s in range(3) for k in range(1, 11)]
    assert [b["fitness"] for b in best] == pytest.approx([r["fitness"] for r in committed], abs=5e-5)


def test_the_report_regenerates_the_evolutions_table(in_root, tmp_path):
    """Section 5's numbers from the committed histories and probes; the figures from the committed CSVs."""
    document = tmp_path / "CHILDHOOD.md"
    document.write_text("<!-- childhood table: python -m experiments report childhood -->\nold\n"
                        "<!-- end of childhood table -->\n")
    os.symlink(os.path.abspath(os.path.join(study.OUT, "measures")), tmp_path / "measures")
    table = dataclasses.replace(study.TABLE, document=str(document), out=str(tmp_path))
    assert table.report() == 0
    text = document.read_text()
    assert "| LE-LS, `skills` | 0.771 (0.785, 0.748, 0.780) | 0.54-0.89 | 0 / 0 / 28 / 2 |" in text
    assert "| LE-LS, `extension` | 0.418 (0.414, 0.415, 0.424) | 0.34-0.48 | 0 / 2 / 18 / 10 |" in text
    assert ("| LE-LS, `skills`, fitness the mean of 2 lives, 15 generations (equal compute) | 0.753 (0.745, 0.771, "
            "0.742) | 0.63-0.86 | 0 / 2 / 25 / 3 |") in text
    assert ("| LE-LS, `extension` + `initial_speed_bias=4` | 0.705 (0.710, 0.792, 0.611) | 0.00-0.90: seed 2 solves "
            "task 1 at 0.00 | 5 / 14 / 11 / 0 |") in text
    assert text.count("\n| ") == 8 and "old" not in text
    for name in ("evolve", "hand", "hand_fast"):
        assert (tmp_path / f"{name}.png").stat().st_size > 20_000


def test_a_measure_writes_its_csv_then_its_result(tmp_path):
    out = tmp_path / "measures" / "probe"
    assert study.finish(str(out), [dict(run="a", seed=0, fitness=0.25), dict(run="b", seed=1, fitness=1 / 3)]) == 0
    assert (out / "probe.csv").read_text() == "run,seed,fitness\na,0,0.2500\nb,1,0.3333\n"
    assert study.read_rows(str(out)) == [dict(run="a", seed=0.0, fitness=0.25), dict(run="b", seed=1.0, fitness=0.3333)]


@pytest.mark.parametrize("argv, field", [
    (["hand", "--rules", "bogus"], "--rules"),
    (["hand", "--walls", "bounce", "--lengths", "300", "--seeds", "1"], "childhood_walls"),
    (["bogus"], "stage"),
    (["hand", "evolved"], "stage"),
    (["evolved", "/nonexistent/run"], "not a run directory"),
    (["evolved"], "runs"),
    (["ceiling", "--lives", "0"], "--lives: must be at least 1"),  # wrote nan fitness before, exit 0
    (["hand", "--seeds", "0"], "--seeds: must be at least 1"),
])
def test_bad_input_exits_2_naming_it(tmp_path, capsys, monkeypatch, argv, field):
    monkeypatch.setattr("imrl_jax.evolution.devices.use_host_cores", lambda count=None: None)  # leave the suite's devices
    out = tmp_path / "study"
    code = study.main(argv + ["--out", str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and field in err[-1] and len(err) == 1
    assert not out.exists()


#: The stage each option is read by, and its command line before the option (a run first, where it reads runs).
STAGE_OF = {"--lengths": "hand", "--walls": "hand", "--rewards": "hand", "--rules": "hand", "--respawn-steps": "hand",
            "--speed-bias": "hand", "--seeds": "hand", "--task-steps": "ceiling", "--biases": "speed",
            "--preset": "speed", "--best": "evolved", "--individuals": "random", "--lives": "heritability",
            "--key": "ceiling", "--out": "ceiling"}


def fake_run(folder, seeds=2, population=4, fitness=None):
    """A finished evolution's config.json and final_population.npz (no lives: written by hand)."""
    import json

    import numpy as np
    from helpers import tiny_config

    config = tiny_config(population_size=population)
    os.makedirs(folder)
    with open(os.path.join(folder, "config.json"), "w") as f:
        json.dump(dict(config=config.to_dict(), seeds=list(range(seeds))), f)
    rng = np.random.default_rng(0)
    np.savez(os.path.join(folder, "final_population.npz"), generation=np.int64(1),
             evaluated=rng.uniform(-1, 1, (seeds, population, config.num_genes)).astype(np.float32),
             fitness=rng.uniform(0, 1, (seeds, population)).astype(np.float32) if fitness is None else fitness)
    return str(folder)


def _attack(tmp_path, *argv):
    from attack import attack

    return attack(study.main, list(argv), str(tmp_path))


def _hostile_cases():
    from test_circular_paths import hostile_cases

    from experiments.childhood_measures import measure_parser
    from experiments.childhood_study import measures

    cases = hostile_cases(measure_parser(measures()))
    assert {flag for flag, _ in cases} == set(STAGE_OF)  # a new option is given its stage here
    from attack import HOSTILE_TEXTS

    return cases + [("RUN", value) for value in HOSTILE_TEXTS]  # the positional: the runs a stage reads


@pytest.mark.parametrize("flag, value", _hostile_cases())
def test_hostile_values_are_refused_or_planned_with_nothing_written(tmp_path, monkeypatch, flag, value):
    """Every option of the measures' parser under the stage that reads it, every hostile value, and every hostile run
    word: one line and exit 2, or a plan; nothing written."""
    from attack import assert_contract

    monkeypatch.setattr("imrl_jax.evolution.devices.use_host_cores", lambda count=None: None)  # leave the suite's devices
    run = fake_run(tmp_path / "run")
    if flag == "RUN":
        argv = [value, "--out", "m/evolved", "evolved", "--best", "2"]
    else:
        stage = STAGE_OF[flag]
        argv = ([run] if stage in ("evolved", "heritability") else []) + ["--out", f"m/{stage}", stage,
                                                                          "--best", "2", f"{flag}={value}"]
    outcome = _attack(tmp_path, *argv)
    named = (flag, "runs", "memory", "lives at once") + ((value,) if flag == "RUN" and value.strip() else ())
    if assert_contract(outcome, *named, argv=argv) == "planned":
        args = outcome.plan.checked["args"]
        assert args.lives is None or 1 <= args.lives <= 10_000
        assert 0 <= args.key < 2**32 and 1 <= args.best <= 4
        assert all(os.path.isfile(os.path.join(r, "config.json")) for r in args.runs)


@pytest.mark.parametrize("name", ["config.json", "final_population.npz"])
@pytest.mark.parametrize("how", ["empty", "truncated", "not json", "null", "a list", "NaN", "binary", "removed"])
def test_a_damaged_run_is_one_line_naming_its_file(tmp_path, monkeypatch, name, how):
    """evolved and heritability read a run's config.json and final_population.npz: damaged, one line names it."""
    from attack import assert_refused, damage

    monkeypatch.setattr("imrl_jax.evolution.devices.use_host_cores", lambda count=None: None)
    run = fake_run(tmp_path / "run")
    damage(os.path.join(run, name), how)
    for stage in ("evolved", "heritability"):
        assert_refused(_attack(tmp_path, run, "--out", "m/probe", stage, "--best", "2"), name, "config.json",
                       argv=[name, how, stage])


@pytest.mark.parametrize("case", ["nan fitness", "genes of another width", "best above the population"])
def test_a_run_of_bad_arrays_is_refused(tmp_path, monkeypatch, case):
    """NaN fitness would rank arbitrary genomes as the best; a genome of another width would be decoded as garbage."""
    import numpy as np
    from attack import assert_refused

    monkeypatch.setattr("imrl_jax.evolution.devices.use_host_cores", lambda count=None: None)
    run = fake_run(tmp_path / "run", fitness=np.full((2, 4), np.nan, np.float32) if case == "nan fitness" else None)
    if case == "genes of another width":
        path = os.path.join(run, "final_population.npz")
        with np.load(path) as data:
            arrays = dict(data)
        np.savez(path, **dict(arrays, evaluated=arrays["evaluated"][..., :-1]))
    best = "5" if case == "best above the population" else "2"
    assert_refused(_attack(tmp_path, run, "--out", "m/probe", "evolved", "--best", best), "run", "--best")


def test_a_measure_into_a_folder_of_other_files_is_refused(tmp_path, monkeypatch):
    from attack import assert_contract, assert_refused

    monkeypatch.setattr("imrl_jax.evolution.devices.use_host_cores", lambda count=None: None)
    (tmp_path / "ceiling").mkdir()
    (tmp_path / "ceiling" / "ceiling.csv").write_text("old")
    assert assert_contract(_attack(tmp_path, "--out", "ceiling", "ceiling")) == "planned"
    (tmp_path / "ceiling" / "notes.txt").write_text("mine")
    assert_refused(_attack(tmp_path, "--out", "ceiling", "ceiling"), "--out")


def _kept_run(tmp_path, fitness="finite"):
    """A reproduction's run folder (RESULTS/VARIANT/evolve/COND) with no population: its best in best_genomes.npz."""
    import json

    import numpy as np
    from helpers import tiny_config

    config = tiny_config()
    run = tmp_path / "results" / "paper" / "evolve" / "LE-LS"
    run.mkdir(parents=True)
    (run / "config.json").write_text(json.dumps(dict(config=config.to_dict(), seeds=[0, 1])))
    arrays = dict(paper__LE__genomes=np.zeros((2, 3, config.num_genes), np.float32), paper__LE__seeds=np.arange(2))
    if fitness != "none":
        arrays["paper__LE__fitness"] = np.full((2, 3), np.nan if fitness == "nan" else 0.5, np.float32)
    np.savez(tmp_path / "results" / "best_genomes.npz", **{k.replace("__LE__", "__LE-LS__"): v for k, v in arrays.items()})
    return str(run)


@pytest.mark.parametrize("fitness", ["finite", "nan", "none", "file removed"])
def test_a_reproductions_kept_best_is_read_checked(tmp_path, monkeypatch, fitness):
    """A run with no population is measured from its reproduction's best_genomes.npz: a NaN or missing fitness there,
    or no such file, is one line naming the run (a traceback or arbitrary ranks before)."""
    from attack import assert_contract, assert_refused

    monkeypatch.setattr("imrl_jax.evolution.devices.use_host_cores", lambda count=None: None)
    run = _kept_run(tmp_path, fitness)
    if fitness == "file removed":
        os.remove(tmp_path / "results" / "best_genomes.npz")
    outcome = _attack(tmp_path, run, "--out", "m/probe", "evolved", "--best", "2")
    if fitness == "finite":
        assert assert_contract(outcome) == "planned"
    else:
        assert_refused(outcome, run)
