"""Every study that is a table, planned, listed and reported on results made by hand (experiments.harness.table).

Each study module that declares ``TABLE`` is run here against a results folder of its own: first
empty (every stage to run, a report that says so), then with an evolution and a learning test written
by hand for every row (every stage done, the report's table showing exactly the numbers written). Last, what a
report says before and while it relives the best individuals (experiments.harness.relive.Reliving).
"""

import importlib
import json
import os

import numpy as np
import pytest
from helpers import relocated, write_evolution, write_learning_test

from experiments.harness import study as S
from experiments.harness.reproduce import stage_done
from experiments.harness.table import Table, evolution_spec


def table_studies() -> dict[str, Table]:
    """Every study that is a table (its module's ``TABLE``, or one of its ``TABLES``), by its name."""
    found = {}
    for name, entry in S.studies().items():
        module = importlib.import_module(f"experiments.{entry.module}")
        for table in [getattr(module, "TABLE", None), *getattr(module, "TABLES", {}).values()]:
            if isinstance(table, Table) and table.name == name:
                found[name] = table
    return found


TABLES = table_studies()
#: The studies whose report writes the Table's own rows table (the others write tables of their own).
WRITE_ROWS_TABLE = ("goals", "search", "worlds")


def test_every_study_but_two_is_found_as_a_table():
    """The timescale study's rows come from its measures (built when asked) and the selector sweep is one measure:
    every other study is a table this test runs."""
    assert sorted(TABLES) == ["baselines", "childhood", "claims-experts", "claims-screen", "future-work", "goals",
                              "novel-tasks", "reproduction", "reproduction-cpu", "search", "worlds"]


def generic_table(table: Table) -> str | None:
    """The rows' table the report wrote between the table's own markers (None: its report writes one of its own)."""
    text = open(table.document).read()
    start, end = f"<!-- {table.name} table:", f"<!-- end of {table.name} table -->"
    if start not in text or end not in text:
        return None
    text = text[text.index(start):text.index(end)]
    return text if "| row | condition | preset |" in text else None


@pytest.mark.parametrize("name", sorted(TABLES))
def test_a_table_study_plans_lists_and_reports_what_was_made_by_hand(name, tmp_path, capsys):
    table = relocated(TABLES[name], tmp_path)
    stages, scale = table.all_stages()
    measures = {f"{m.kind} {m.name}" for m in table.measures}  # of any kind (a learning test on another task set too)
    row_stages = [s for s in stages if s.name not in measures]  # none in a table of measures alone (the baselines)
    assert bool(row_stages) == bool(table.rows) and not any(stage_done(s, scale) for s in stages)
    assert all(s.out_dir.startswith(str(tmp_path)) for s in stages if s.name in measures)  # its measures moved too
    for stage in stages:
        command = table.stage_command(stage)[0]
        assert command[command.index("--out") + 1] == stage.out_dir
    assert table.main(["--report"]) == 0
    assert generic_table(table) is None or "not started" in generic_table(table)

    made, evolutions, tests = {}, table.evolutions(), table.tests()  # where each row's run and test will be found
    for i, row in enumerate(table.rows):
        made[row.name] = round(0.1 + 0.01 * i, 3), round(0.5 + 0.01 * i, 3)
        sizes = table.scale_of(row)
        evolved = evolutions[row.name]
        if evolved is not None and not os.path.isdir(evolved):  # a run two rows share is written once
            spec, best = evolution_spec(row, sizes), made[row.name][0]
            write_evolution(evolved, [[best] * len(spec.seeds)] * sizes["generations"], seeds=spec.seeds,
                            config=dict(config=spec.config.to_dict(), seeds=list(spec.seeds),
                                        search=json.loads(spec.search)),
                            columns=dict(mean=best / 2, std=0.0, **{f"best_task{t}": best for t in range(1, 7)}))
        if (row.test or evolved is None) and not os.path.isdir(tests[row.name]):
            steady = made[row.name][1]
            write_learning_test(tests[row.name], [steady] * sizes["seeds"], (steady / 2, steady), 10,
                                steady_sd=0.0, pairs_both_ways=0.0, steady_best_run=steady, best_run=0,
                                steady_per_task=[steady] * 6,
                                whole_test_mean=steady / 2, num_best=1, num_tests=1)
    stages, scale = table.all_stages()
    assert all(stage_done(s, scale) == (s.name not in measures) for s in stages)  # the measures still to run
    capsys.readouterr()
    assert table.main(["--report"]) == 0
    measured, text = {m["row"]: m for m in table.measure()}, generic_table(table)
    assert (text is None) == (name not in WRITE_ROWS_TABLE)
    assert (table.evolutions(), table.tests()) == (evolutions, tests)  # found where they were planned
    for row in table.rows:
        first = next(r for r in table.rows if evolutions[r.name] == evolutions[row.name]
                     and tests[r.name] == tests[row.name])  # whose numbers a shared run holds
        m = measured[row.name]
        if row.evolved:
            assert (m["final_mean"], m["final_sd"], m["plateau"]) == (pytest.approx(made[first.name][0]),
                                                                     pytest.approx(0), 0), row
        if row.test or not row.evolved:
            assert (m["steady_mean"], m["steady_sd"]) == (pytest.approx(made[first.name][1]), 0), row
        if text is None:
            continue
        line = next(line for line in text.splitlines() if line.startswith(f"| {row.name} |"))
        assert not row.evolved or f" {made[first.name][0]:.3f} +- 0.000 | 0 |" in line, line
        if row.test or not row.evolved:
            assert f" {made[first.name][1]:.3f} +- 0.000 ({table.scale_of(row)['seeds']} runs) |" in line, line
    if text is not None:
        assert os.path.getsize(os.path.join(table.out, f"{table.name}.png")) > 10_000


# ----------------------------------------------------------------------------- a report says what reliving costs


class _Events:
    """An event sink that keeps what it is given."""

    def __init__(self):
        self.events = []

    def write(self, event):
        self.events.append(event)

    def close(self):
        pass


def test_reliving_says_what_it_costs_before_the_first_compile_then_counts_with_an_eta(tmp_path):
    """The plan line (lives, lane-steps, backend, time at the bench's speed) comes first, a compiling line before each
    part's call, then a progress line after it; from the second part on the ETA is a number."""
    import io
    import re
    import time

    from experiments.harness.relive import Part, Reliving
    from imrl_jax.runs.events import EventLog

    bench = tmp_path / "bench"
    bench.mkdir()
    (bench / "made-up.json").write_text(json.dumps(dict(backend="cpu", lifetimes=[
        dict(individuals=50, lane_steps_per_s=1e6, compile_and_first_run_s=2.0)])))
    stream, sink, seen = io.StringIO(), _Events(), []

    def work(name):  # what the stream held when the part began (its compile would start here)
        seen.append((name, stream.getvalue().splitlines()))
        time.sleep(0.05)
        return name

    parts = [Part("one life", 1, 1000), Part("fresh lives", 10, 2_000_000), Part("probe", 10, 1_000_000)]
    reliving = Reliving(parts, stream=stream, backend="cpu", bench_dir=str(bench), log=EventLog([sink]))
    assert [reliving.run(p, work, p.what) for p in parts] == ["one life", "fresh lives", "probe"]
    lines = stream.getvalue().splitlines()
    # 3,001,000 lane-steps at 1 M/s and 3 compilations of 2 s: 9 s
    assert lines[0].startswith("reliving the best individuals: 3 part(s), 21 lives' worth, 3.0 M lane-steps on cpu")
    assert re.search(r"about 0:00:09 \(ETA\) at the 1.0 M lane-steps/s docs/bench/made-up.json", lines[0]), lines[0]
    assert seen[0] == ("one life", lines[:2]) and lines[1].startswith("part 1/3, one life: compiling")
    assert seen[1] == ("fresh lives", lines[:4]) and lines[3].startswith("part 2/3, fresh lives: compiling")
    assert lines[2].startswith("life 1 (1/21) | part 1/3 done in") and "first life with compilation" in lines[2]
    eta = re.search(r"ETA (\d+):(\d\d):(\d\d) \|", lines[4])
    assert lines[4].startswith("life 11 (11/21)") and eta, lines[4]
    assert lines[6].startswith("life 21 (21/21)") and len(lines) == 7
    # the ETA after part 2: 10 lives left at part 2's 10 lives in ~0.05 s
    etas = [e["eta_s"] for e in sink.events if e["kind"] == "progress"]
    assert etas[0] is None and 0 < etas[1] < 5 and etas[2] == 0


def test_reliving_without_a_measured_speed_says_so():
    import io

    from experiments.harness.relive import Part, Reliving

    stream = io.StringIO()
    Reliving([Part("one life", 1, 1000)], stream=stream, backend="tpu")
    assert "no speed measured on tpu in docs/bench to estimate its time" in stream.getvalue().splitlines()[0]


def test_the_report_says_what_reliving_costs_before_it_relives(tmp_path, monkeypatch, capsys):
    """The reproduction report prints its plan line on stderr before the first life compiles."""
    from experiments import report
    from helpers import tiny_config
    from test_report import _write_results

    table = _write_results(tmp_path / "results", tmp_path / "docs" / "REPRODUCTION.md")
    config = tiny_config("LE-LS")
    entry = dict(genomes=np.zeros((2, 3, config.num_genes), np.float32), fitness=np.zeros((2, 3)),
                 index=np.zeros((2, 3), int), seeds=np.arange(2), generations=8, config=config.to_dict())
    monkeypatch.setattr(report, "update_best_genomes", lambda data: {("paper", "LE-LS"): entry})

    def first_life(*args):
        raise RuntimeError(capsys.readouterr().err)

    monkeypatch.setattr(report, "relive_best", first_life)
    with pytest.raises(RuntimeError) as stopped:
        report.run(table, behaviour=True, baselines_dir=str(tmp_path / "none"))
    lines = str(stopped.value).splitlines()
    # 2 seeds, lives of 400 + 6 x 200 = 1,600 steps: the best life (and 6 x 1,000 steps driven, a 400-step childhood),
    # 20 fresh lives, 6 probed childhoods of 400 steps and 3 experts x 2,400 probe steps each (28 lives' worth)
    assert lines[0].startswith("reliving the best individuals: 3 part(s), 49 lives' worth, 85,600 lane-steps on cpu")
    assert lines[1].startswith("part 1/3, LE-LS (paper, lives of 1,600 steps): the best individual's life") and \
        lines[1].endswith("compiling, then 8,000 lane-steps") and len(lines) == 2


def test_a_kept_relived_result_says_so_and_is_not_lived_again(tmp_path, capsys):
    from experiments.harness.relive import kept

    calls = []
    compute = lambda: calls.append(1) or dict(value=1)  # noqa: E731
    path = str(tmp_path / "fresh.json")
    assert kept(path, dict(k=1), compute)["value"] == 1 and "kept in" not in capsys.readouterr().err
    assert kept(path, dict(k=1), compute)["value"] == 1 and len(calls) == 1
    assert f"kept in {path}: lived by an earlier report" in capsys.readouterr().err


def test_a_study_reports_fresh_lives_say_their_cost_before_they_are_lived(tmp_path, monkeypatch, capsys):
    """run_fresh (the claims, future-work and search reports) says its lives and lane-steps before it lives them."""
    from experiments.harness import relive
    from helpers import tiny_config

    def fake_fresh(config_dict, best, num_lives, seed):
        raise RuntimeError(capsys.readouterr().err)

    monkeypatch.setattr(relive, "fresh_fitness", fake_fresh)
    np.savez(tmp_path / "final_population.npz", evaluated=np.zeros((3, 4, 2), np.float32), fitness=np.zeros((3, 4)),
             generation=7, seeds=np.asarray([4, 5, 6]))
    with pytest.raises(RuntimeError) as stopped:
        relive.run_fresh(str(tmp_path), tiny_config("EE-LS").to_dict(), num_lives=2)
    lines = str(stopped.value).splitlines()
    # 3 seeds x 2 lives of 6 x 200 steps
    assert lines[0].startswith("reliving the best individuals: 1 part(s), 6 lives' worth, 7,200 lane-steps on cpu")
    assert lines[1] == f"part 1/1, {tmp_path}: 2 fresh lives of each of 3 seeds' best: compiling, then 7,200 lane-steps"
    assert len(lines) == 2 and not (tmp_path / relive.FRESH_FILE).exists()
