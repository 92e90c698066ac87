"""Every study that is a table, planned, listed and reported on results made by hand (experiments.table).

Each study module that declares ``TABLE`` is run here against a results folder of its own: first
empty (every stage to run, a report that says so), then with an evolution and a learning test written
by hand for every row (every stage done, the report's table showing exactly the numbers written).
"""

import importlib
import json
import os

import pytest
from helpers import relocated, write_evolution, write_learning_test

from experiments import study as S
from experiments.reproduce import stage_done
from experiments.table import Table, evolution_spec


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
WRITE_ROWS_TABLE = ("goals", "search")


def test_every_study_but_two_is_found_as_a_table():
    """The timescale study's rows come from its measures (built when asked) and the selector sweep is one measure:
    every other study is a table this test runs."""
    assert sorted(TABLES) == ["baselines", "childhood", "claims-experts", "claims-screen", "future-work", "goals",
                              "novel-tasks", "reproduction", "reproduction-cpu", "search"]


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
