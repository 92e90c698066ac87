"""A study as a table over shared runs (experiments.harness.table): rows find their runs by key, wherever they lie."""

import os

import pytest

from helpers import RESULTS

from experiments.harness.study import SCALES, SCREEN
from experiments.harness.reproduce import stage_done
from experiments.harness.table import Measure, Row, Table, evolution_spec, learning_test_dir
from imrl_jax.runs import runspec


def test_a_row_is_exactly_what_its_command_computes():
    """The goals study's EE-LS-T row has the key of the run its command made (config.json as written)."""
    committed = runspec.RunSpec.from_run_dir(os.path.join(RESULTS, "goals", "EE-LS-T", "evolve"))
    assert evolution_spec(Row("x", "EE-LS-T", "skills"), SCREEN).key() == committed.key()
    assert evolution_spec(Row("x", "EE-LS-T", "faithful"), SCREEN).key() != committed.key()


def test_a_run_another_study_made_is_found_and_shared(tmp_path):
    """A new study asking for EV-LS under skills at the future-work study's sizes gets that study's finished run
    (and its test: one stage for the two rows that ask for it)."""
    table = Table("mine", "docs/MINE.md", 99, rows=(Row("ev", "EV-LS", "skills"), Row("ev-again", "EV-LS", "skills"),
                                                    Row("new", "EV-LS", "skills", ("gamma=0.95",), test=False)),
                  scale=SCREEN, out=str(tmp_path), results=RESULTS)
    stages, _ = table.all_stages()
    shared = os.path.join(RESULTS, "future_work", "EV-LS", "evolve")
    assert [(s.name, s.out_dir, s.needs) for s in stages] == [
        ("evolve ev", shared, None),
        ("learning test ev", os.path.join(RESULTS, "future_work", "EV-LS", "test"), ("evolve ev",)),
        ("evolve new", os.path.join(RESULTS, "runs", evolution_spec(table.rows[2], SCREEN).key(), "evolve"), None)]
    assert stage_done(stages[0], SCREEN) and stage_done(stages[1], SCREEN) and not stage_done(stages[2], SCREEN)
    command = table.stage_command(stages[2])[0]
    assert command[command.index("--set") + 1] == "gamma=0.95" and command[command.index("--out") + 1] == stages[2].out_dir


def test_a_learning_test_sits_beside_its_evolution():
    assert learning_test_dir(os.path.join("r", "runs", "k", "evolve")) == os.path.join("r", "runs", "k", "test")
    paper = os.path.join("r", "paper", "skills")
    assert learning_test_dir(os.path.join(paper, "evolve", "LE-LS")) == os.path.join(paper, "test", "LE-LS")


def test_the_report_reads_what_has_finished(tmp_path):
    """The committed EE-LS-T run measured by the claims' rules; a row not started says so; the figure is drawn."""
    document = tmp_path / "DOC.md"
    document.write_text("before\n<!-- t table: python -m experiments report t -->\nold\n<!-- end of t table -->\nafter\n")
    table = Table("t", str(document), 99, rows=(Row("EE-LS-T", "EE-LS-T", "skills"),
                                               Row("later", "EE-LS-T", "skills", ("gamma=0.95",))),
                  scale=SCREEN, out=str(tmp_path / "out"), results=RESULTS)
    assert table.main(["--report"]) == 0
    text = document.read_text()
    assert text.startswith("before\n<!-- t table") and text.endswith("<!-- end of t table -->\nafter\n")
    assert "| EE-LS-T | EE-LS-T | skills | 5 | 100 of 100 | 0.535 +- 0.028 | 35 | 0.583 +- 0.050 (5 runs) |" in text
    assert "| later | EE-LS-T | skills | - | 0 of 100 | not started | - | - |" in text and "old" not in text
    assert (tmp_path / "out" / "t.png").stat().st_size > 10_000


def test_new_runs_that_differ_only_in_dynamic_values_are_one_sweep(tmp_path, monkeypatch):
    """Three EE-LS rows (a discount and a mutation size apart) are one sweep stage and one test stage, each row's
    run a point found by the key of the row's own command; the LE-LS row is its own stage; once begun, the sweep
    goes on as one; a measure of a row waits for the sweep that makes its run."""
    import json

    from experiments.harness.reproduce import generations_done
    from experiments.harness.study import SCALES

    scale = dict(SCALES["tiny"], task_steps=1000)
    # The stages' commands (subprocesses) compile several programs that each run in moments: XLA's backend
    # optimisations off spare most of their time, and nothing here compares numbers with a run compiled otherwise.
    monkeypatch.setenv("JAX_DISABLE_MOST_OPTIMIZATIONS", "1")
    rows = (Row("a", "EE-LS", "skills", ("target_radius=40",)),
            Row("b", "EE-LS", "skills", ("target_radius=40", "gamma=0.95")),
            Row("c", "EE-LS", "skills", ("target_radius=40", "mutation_scale=0.5")),
            Row("a-again", "EE-LS", "skills", ("target_radius=40",), test=False),
            Row("d", "LE-LS", "skills", test=False))
    results = str(tmp_path / "results")
    measure = Measure("landscape-b", "b", ("--generations", "0,last", "--parents", "2", "--walks", "1", "--mutants",
                                           "2", "--walk-length", "2", "--random", "2", "--lives", "2", "--chunk", "6"))
    table = Table("mine", "docs/MINE.md", 99, rows=rows, scale=scale, out=str(tmp_path / "out"), results=results,
                  measures=(measure,))
    stages, _ = table.all_stages()
    keys = {row.name: evolution_spec(row, scale).key() for row in rows}
    sweep_root = os.path.dirname(table.evolutions()["a"])
    assert [(s.name, s.out_dir, s.needs) for s in stages] == [
        ("evolve a+b+c (one sweep)", sweep_root, None),
        ("learning test a+b+c (one sweep)", learning_test_dir(sweep_root), ("evolve a+b+c (one sweep)",)),
        ("evolve d", os.path.join(results, "runs", keys["d"], "evolve"), None),
        ("measure landscape-b", str(tmp_path / "out" / "measures" / "landscape-b"), ("evolve a+b+c (one sweep)",))]
    assert table.evolutions() == {**{n: os.path.join(sweep_root, keys[n]) for n in "abc"},
                                  "a-again": os.path.join(sweep_root, keys["a"]),
                                  "d": os.path.join(results, "runs", keys["d"], "evolve")}
    command = table.stage_command(stages[0])[0]
    assert command[command.index("--zip") - 4:command.index("--zip")] == [
        "--sweep", "gamma=0.99,0.95,0.99", "--sweep", "mutation_scale=1.0,1.0,0.5"]
    assert table.main([]) == 0
    assert {n: generations_done(d) for n, d in table.evolutions().items()} == dict.fromkeys("abc", 2) | {
        "a-again": 2, "d": 2}
    assert runspec.index(results) == {keys[n]: os.path.relpath(table.evolutions()[n], results) for n in "abcd"}
    assert table.stage_command(table.all_stages()[0][0])[0][3:] == ["--resume", "--out", sweep_root,
                                                                      "--generations", "2"]
    with open(os.path.join(sweep_root, "sweep.json")) as f:
        assert [p["key"] for p in json.load(f)["points"]] == [keys[n] for n in "abc"]
    with open(os.path.join(learning_test_dir(sweep_root), "sweep_tests.json")) as f:  # every point tested
        assert list(json.load(f)["points"]) == [keys[n] for n in "abc"]
    assert stage_done(table.all_stages()[0][1], scale)
    with open(tmp_path / "out" / "measures" / "landscape-b" / "result.json") as f:  # the measure of b's point
        measured = json.load(f)
    assert measured["run"] == table.evolutions()["b"] and measured["condition"] == "EE-LS"
    assert sorted(measured["pieces"]) == ["generation 0, learning", "generation 1, learning",
                                          "random genomes, learning"]


def test_rows_of_a_search_strategy_of_their_own_sizes_and_not_evolved_find_their_committed_runs():
    """The search study's SNES run (its strategy in the key), the reproduction's LE-LS at the paper's sizes, and
    tests from scratch found by their keys: the future-work study's EXT-LS with its noise setting, and the claims
    map's SLE test of skills-bias0 for paper-selector's rules (SLE reads neither the childhood nor the preset's
    selector values, which differ)."""
    from experiments.rule_sets import SELECTOR_SETS
    from experiments.harness.study import SCALES

    table = Table("mine", "docs/MINE.md", 99, scale=SCREEN, out=os.path.join(RESULTS, "future_work"), results=RESULTS,
                  rows=(Row("snes", "EE-LS", "skills", options=("--strategy", "snes")),
                        Row("ga", "EE-LS", "skills", scale=SCALES["paper"]),
                        Row("EXT-LS-whole", "EXT-LS", "skills", ("sle_noise_steps=0",)),
                        Row("sle", "SLE", "paper", SELECTOR_SETS), Row("sle-new", "SLE", "paper", ("gamma=0.95",))))
    assert table.evolutions() == {"snes": os.path.join(RESULTS, "search", "snes", "EE-LS", "evolve"),
                                  "ga": os.path.join(RESULTS, "paper", "skills", "evolve", "EE-LS"),
                                  "EXT-LS-whole": None, "sle": None, "sle-new": None}
    tests = table.tests()
    assert tests["EXT-LS-whole"] == os.path.join(RESULTS, "future_work", "EXT-LS-whole", "test")
    assert tests["sle"] == os.path.join(RESULTS, "claims", "skills-bias0", "test", "SLE")
    assert tests["sle-new"] == os.path.join(RESULTS, "future_work", "sle-new", "test")
    stages, _ = table.all_stages()
    assert [s.name for s in stages] == ["evolve snes", "learning test snes", "evolve ga", "learning test ga",
                                        "learning test EXT-LS-whole", "learning test sle", "learning test sle-new"]
    assert all(stage_done(s, SCREEN) for s in stages[:-1]) and not stage_done(stages[-1], SCREEN)
    assert stages[4].needs == ()
    command = table.stage_command(stages[4])[0]
    assert command[command.index("--cond") + 1] == "EXT-LS" and "sle_noise_steps=0" in command
    assert command[command.index("--runs") + 1] == "5" and "sle_noise_steps=100000" not in command
    snes = table.stage_command(stages[0])[0]
    assert snes[snes.index("--strategy") + 1] == "snes" and snes[-1] == "--resume"
    measured = {m["row"]: m for m in table.measure()}
    assert measured["ga"]["seeds"] == 10 and measured["ga"]["target"] == 100 and "steady_mean" in measured["EXT-LS-whole"]


def test_a_measure_of_no_run_goes_where_it_is_told(tmp_path):
    """A measure that reads no run (a sweep of fixed controllers) has no run argument and its own folder."""
    table = Table("t", "docs/T.md", 99, rows=(), scale=SCREEN, out=str(tmp_path), results=str(tmp_path),
                  measures=(Measure("hand", "", ("hand", "--seeds", "2"), module="experiments.childhood_study",
                                    out=str(tmp_path / "childhood")),
                            Measure("other", "", module="m")))
    stages, _ = table.all_stages()
    assert [(s.name, s.out_dir, s.needs) for s in stages] == [
        ("measure hand", str(tmp_path / "childhood"), ()), ("measure other", str(tmp_path / "measures" / "other"), ())]
    assert table.stage_command(stages[0])[0][1:] == ["-m", "experiments.childhood_study", "--out",
                                                     str(tmp_path / "childhood"), "hand", "--seeds", "2"]


def test_a_row_of_fewer_generations_of_its_own_is_done_at_its_own_length():
    """The childhood study's equal-compute run (2 lives a fitness, 15 generations) is done, though the table's are 30."""
    from experiments.harness.study import SCALES

    scale = dict(SCALES["paper"], seeds=3, generations=30)
    table = Table("t", "docs/T.md", 99, scale=scale, out="unused", results=RESULTS, rows=(
        Row("2lives", "LE-LS", "skills", ("lives_per_fitness=2",), test=False, scale=dict(scale, generations=15)),
        Row("new", "LE-LS", "skills", ("lives_per_fitness=2", "gamma=0.95"), test=False)))
    stages, sizes = table.all_stages()
    assert stages[0].out_dir == os.path.join(RESULTS, "childhood", "evolve", "LE-LS-skills-2lives")
    assert [s.generations for s in stages] == [15, 30] and sizes["generations"] == 30
    assert stage_done(stages[0], sizes) and not stage_done(stages[0]._replace(generations=0), sizes)


def test_a_learning_test_of_its_own_options_waits_for_its_row_and_two_rows_of_one_name_are_refused(tmp_path):
    """A test-kind measure (the novel tasks' learning test on another task set) is done by its steady.json and
    waits for its row's evolution; a name given twice is refused, naming it."""
    table = Table("t", "docs/T.md", 99, scale=SCREEN, out=str(tmp_path), results=RESULTS,
                  rows=(Row("EE-LS-T", "EE-LS-T", "skills"),),
                  measures=(Measure("novel", "EE-LS-T", ("--task-set", "novel"), module="imrl_jax.learning_test",
                                    out=os.path.join(RESULTS, "goals", "EE-LS-T", "test"), kind="test"),))
    stages, _ = table.all_stages()
    assert [(s.name, s.kind, s.needs) for s in stages][-1] == ("test novel", "test", ("evolve EE-LS-T",))
    assert stage_done(stages[-1], SCREEN)  # the folder holds a steady.json
    command = table.stage_command(stages[-1])[0]
    assert command[1:4] == ["-m", "imrl_jax.learning_test", os.path.join(RESULTS, "goals", "EE-LS-T", "evolve")]
    assert command[-2:] == ["--task-set", "novel"]
    with pytest.raises(ValueError, match="table t: two rows or measures are named 'a'"):
        Table("t", "docs/T.md", 99, scale=SCREEN, out=str(tmp_path), rows=(Row("a", "LE-LS", "skills"),) * 2)


def test_rows_of_one_run_make_the_longest_and_a_measure_cannot_take_a_rows_name_or_read_a_test(tmp_path):
    """Two rows of one run asking for 2 and 3 generations: one stage of 3, whose command asks for 3; a test stage
    counts its row's runs; a measure named as a row, or reading a row that is not evolved, is refused."""
    from experiments.harness.study import SCALES

    tiny = SCALES["tiny"]
    table = Table("t", "docs/T.md", 99, scale=tiny, out=str(tmp_path), results=str(tmp_path / "results"),
                  rows=(Row("short", "EE-LS", "skills"), Row("long", "EE-LS", "skills", scale=dict(tiny, generations=3)),
                        Row("sle", "SLE", "skills", scale=dict(tiny, seeds=3))))
    stages, _ = table.all_stages()
    assert [(s.name, s.generations, s.runs) for s in stages] == [
        ("evolve short", 3, 0), ("learning test short", 0, 2), ("learning test sle", 0, 3)]
    command = table.stage_command(stages[0])[0]
    assert command[command.index("--generations") + 1] == "3"
    with pytest.raises(ValueError, match="two rows or measures are named 'short'"):
        Table("t", "docs/T.md", 99, scale=tiny, out=str(tmp_path), rows=table.rows,
              measures=(Measure("short", "short", kind="test"),))
    with pytest.raises(ValueError, match="measure m reads row sle, which is not evolved"):
        Table("t", "docs/T.md", 99, scale=tiny, out=str(tmp_path), rows=table.rows, measures=(Measure("m", "sle"),))


def test_two_folders_of_one_run_are_one_line_and_exit_2(tmp_path, capsys):
    """The same committed run copied twice under a table's results: planning stops with the error naming both."""
    import shutil

    results = tmp_path / "results"
    for copy in ("a", "b"):
        shutil.copytree(os.path.join(RESULTS, "goals", "EE-LS-T", "evolve"), results / copy / "evolve",
                        ignore=shutil.ignore_patterns("checkpoints", "resume_checkpoint", "*.npz", "*.png"))
    table = Table("t", "docs/T.md", 99, scale=SCREEN, out=str(tmp_path / "out"), results=str(results),
                  rows=(Row("EE-LS-T", "EE-LS-T", "skills"),))
    assert table.main([]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and "hold the same run" in err and err.count("\n") == 1
    assert not (tmp_path / "out").exists()


def test_a_measure_of_a_run_of_its_own_finds_it_by_key(tmp_path):
    """A measure on a run that is no row of the table (the future-work study's EV-LS) finds it by its key and waits
    for nothing, as an argument that is such a Row does (the childhood study's probes of the reproductions' runs); a
    folder given by hand is read as it is."""
    table = Table("t", "docs/T.md", 99, scale=SCREEN, out=str(tmp_path), results=RESULTS, rows=(),
                  measures=(Measure("ev", Row("EV-LS", "EV-LS", "skills")), Measure("there", "some/folder"),
                            Measure("args", "", ("evolved", Row("EV-LS", "EV-LS", "skills"),
                                                 Row("cpu", "EE-LS", "paper", scale=SCALES["cpu"]), "--best", "2"))))
    stages, _ = table.all_stages()
    assert [(s.name, s.condition, s.needs) for s in stages] == [("measure ev", "EV-LS", ()), ("measure there", "", ()),
                                                                ("measure args", "", ())]
    assert table.stage_command(stages[0])[0][3] == os.path.join(RESULTS, "future_work", "EV-LS", "evolve")
    assert table.stage_command(stages[1])[0][3] == "some/folder"
    assert table.stage_command(stages[2])[0][5:] == ["evolved", os.path.join(RESULTS, "future_work", "EV-LS", "evolve"),
                                                     os.path.join(RESULTS, "cpu", "paper", "evolve", "EE-LS"), "--best",
                                                     "2"]


def test_a_measure_of_several_rows_runs_names_them_and_waits_for_each(tmp_path):
    """``{ROW}`` arguments are the rows' evolution folders (the childhood study's heritability of four runs): the
    measure waits for each row's evolution, and a name that is no evolved row is refused."""
    table = Table("t", "docs/T.md", 99, scale=SCREEN, out=str(tmp_path), results=RESULTS,
                  rows=(Row("ev", "EV-LS", "skills"), Row("new", "EV-LS", "skills", ("gamma=0.95",), test=False),
                        Row("sle", "SLE", "skills")),
                  measures=(Measure("both", "", ("heritability", "{ev}", "{new}", "--lives", "2"), module="m"),))
    stages, _ = table.all_stages()
    both = next(s for s in stages if s.name == "measure both")
    assert both.needs == ("evolve ev", "evolve new")
    evolutions = table.evolutions()
    assert table.stage_command(both)[0][1:] == ["-m", "m", "--out", str(tmp_path / "measures" / "both"),
                                                "heritability", evolutions["ev"], evolutions["new"], "--lives", "2"]
    assert evolutions["ev"] == os.path.join(RESULTS, "future_work", "EV-LS", "evolve")
    for name, why in (("sle", "not evolved"), ("nothing", "no row")):
        with pytest.raises(ValueError, match=f"measure m reads row {name}, which is {why}"):
            Table("t", "docs/T.md", 99, scale=SCREEN, out=str(tmp_path), rows=table.rows,
                  measures=(Measure("m", "", (f"{{{name}}}",)),))
