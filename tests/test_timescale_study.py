"""The time-scale study: its measurements, and the rows planned from their results, found by their keys."""

import json
import os

import pytest
from helpers import RESULTS, write_evolution, write_learning_test

from experiments.harness import reproduce
from experiments import timescale as study
from experiments.harness.table import evolution_spec


def _write(out, name, rows):
    os.makedirs(os.path.join(out, name))
    with open(os.path.join(out, name, "result.json"), "w") as f:
        json.dump(dict(rows=rows), f)


def _fake_ceiling(out, paper_best):
    skills = dict(zip(study.OPTIONS, (0.7, 0.2, 0.6, 0.3, 0.2, 0.4, 0.1)))  # per-step is never the choice
    paper = {option: paper_best if option == "colour-20" else 0.1 for option in study.OPTIONS}
    _write(out, "ceiling", [dict(rules=rules, option=option, fitness=value)
                            for rules, values in (("paper", paper), ("skills", skills)) for option, value in values.items()])


def _fake_rates(out, best_option="colour-60"):
    rows = [dict(option=option, trace_lambda=lam, eta_selector_actor=actor, eta_selector_critic=critic,
                 fitness=0.1 + (option == best_option) * 0.5 * (actor == 1.0) * (critic == 0.01) * (lam == 0.9))
            for option in study.RATE_OPTIONS for lam in (0.0, 0.9, 0.98) for actor in (0.3, 1.0) for critic in (0.01,)]
    rows.append(dict(option="per-step", trace_lambda=0.98, eta_selector_actor=0.3, eta_selector_critic=0.001,
                     fitness=0.9))  # per-step is never the option evolved
    _write(out, "rates", rows)


def _fake_confirm(out, best_option="colour-60", actor=1.0):
    """The confirmation of _fake_rates' best points: ``best_option`` stays the best in fresh lives."""
    rows = [dict(option=option, trace_lambda=0.9, eta_selector_actor=actor, eta_selector_critic=0.01,
                 fitness=0.5 if option == best_option else 0.3) for option in study.RATE_OPTIONS]
    rows[0]["fitness"] = 0.9  # per-step is never the option evolved
    _write(out, "confirm", rows)


def _measured(out, paper_best=0.45, **confirm):
    _fake_ceiling(out, paper_best)
    _fake_rates(out)
    _fake_confirm(out, **confirm)


def test_the_plan_waits_for_the_measures(tmp_path):
    out = str(tmp_path / "timescale")
    stages, scale = study.timescale_table(out, results=str(tmp_path)).all_stages()
    assert scale == study.SCREEN and [s.name for s in stages] == ["measure ceiling", "measure rates", "measure confirm"]
    ceiling, rates, confirm = stages
    assert ceiling.kind == rates.kind == confirm.kind == "measure" and ceiling.cost == 7 * 3 * 8 * 600_000
    assert rates.cost == 5 * (3 * 6 * 3) * 3 * 600_000  # options x grid points x lives x steps
    assert confirm.cost == 5 * 8 * 600_000
    assert (ceiling.needs, rates.needs, confirm.needs) == ((), (), ("measure rates",))  # confirm relives rates' best
    table = study.timescale_table(out, results=str(tmp_path))
    for stage, which in zip(stages, ("ceiling", "rates", "confirm")):
        command, env = table.stage_command(stage)
        assert command[1:] == ["-m", "experiments.timescale", "--out", os.path.join(out, which), which] and env is None
    _fake_ceiling(out, paper_best=0.45)
    _fake_rates(out)
    assert len(study.timescale_table(out, results=str(tmp_path)).all_stages()[0]) == 3  # confirmation not run


def test_evolutions_under_the_best_option(tmp_path):
    out, results = str(tmp_path / "timescale"), str(tmp_path)
    _measured(out)  # the paper's rules still do not compose: skills' evolutions only
    table = study.timescale_table(out, results=results)
    stages, _ = table.all_stages()
    assert all(reproduce.stage_done(stage, study.SCREEN) for stage in stages[:3])
    assert [s.name for s in stages[3:]] == ["evolve skills+colour-60 LE-LS", "learning test skills+colour-60 LE-LS",
                                            "evolve skills+colour-60 EE-LS", "learning test skills+colour-60 EE-LS"]
    assert not any(reproduce.stage_done(stage, study.SCREEN) for stage in stages[3:])
    row = table.rows[0]
    assert stages[3].out_dir == os.path.join(results, "runs", evolution_spec(row, study.SCREEN).key(), "evolve")
    evolve = table.stage_command(stages[3])[0]
    assert evolve[evolve.index("--preset") + 1] == "skills" and evolve[evolve.index("--cond") + 1] == "LE-LS"
    sets = [evolve[i + 1] for i, word in enumerate(evolve) if word == "--set"]
    assert sets == ["selector_period=60", "selector_termination=colour", "trace_lambda=0.9", "eta_selector_actor=1.0",
                    "eta_selector_critic=0.01"]  # the confirmed point's rates
    test = table.stage_command(stages[4])[0]
    assert test[test.index("imrl_jax.learning_test") + 1] == stages[3].out_dir  # the run's own config
    composes = str(tmp_path / "composes")
    _measured(composes, paper_best=0.55)
    table = study.timescale_table(composes, results=results)
    paper = [s for s in table.all_stages()[0] if s.variant.startswith("paper")]
    assert [s.name for s in paper if s.kind == "evolve"] == [f"evolve paper+colour-20 {c}"
                                                            for c in ("LE-LS", "EE-LS", "EE-ES")]
    sets = table.stage_command(paper[0])[0]
    assert " ".join(sets).count("--set") == 2 and "selector_termination=colour" in sets


def test_the_plan_finds_every_committed_run():
    """The committed measurements call for period-10 under skills; its runs are found by key where they lie."""
    stages, scale = study.STUDIES[0].stages()
    assert [s.name for s in stages if not reproduce.stage_done(s, scale)] == []
    assert [s.name for s in stages] == ["measure ceiling", "measure rates", "measure confirm",
                                        "evolve skills+period-10 LE-LS", "learning test skills+period-10 LE-LS",
                                        "evolve skills+period-10 EE-LS", "learning test skills+period-10 EE-LS"]
    folder = os.path.join("experiments", "results", "timescale", "skills+period-10")
    assert study.timescale_table().evolutions() == {f"skills+period-10 {c}": os.path.join(folder, c, "evolve")
                                                    for c in ("LE-LS", "EE-LS")}


def test_a_run_evolved_at_other_rates_is_never_taken_for_the_confirmed_points(tmp_path):
    """The committed runs' folder names the option, not its rates: a confirmation that calls for other rates plans
    a new run under its own key, and the same rates find the committed one."""
    out = str(tmp_path / "timescale")
    _measured(out, best_option="period-10", actor=10.0)
    for name in ("rates", "confirm"):  # the committed point: lambda 0.98, critic 0.01
        path = os.path.join(out, name, "result.json")
        with open(path) as f:
            rows = [dict(r, trace_lambda=0.98) for r in json.load(f)["rows"]]
        with open(path, "w") as f:
            json.dump(dict(rows=rows), f)
    committed = os.path.join(RESULTS, "timescale", "skills+period-10", "LE-LS", "evolve")
    assert study.timescale_table(out, results=RESULTS).evolutions()["skills+period-10 LE-LS"] == committed
    with open(os.path.join(out, "confirm", "result.json"), "w") as f:
        json.dump(dict(rows=[dict(r, eta_selector_actor=3.0) for r in rows]), f)
    table = study.timescale_table(out, results=RESULTS)
    assert table.evolutions()["skills+period-10 LE-LS"] == os.path.join(
        RESULTS, "runs", evolution_spec(table.rows[0], study.SCREEN).key(), "evolve")


def test_ceiling_stage_writes_its_result_last(tmp_path, monkeypatch):
    """A tiny ceiling (one option and rule set: one compilation; 200-step tasks): rows, CSV, figure, result.json."""
    monkeypatch.setattr(study, "OPTIONS", {"period-5": dict(selector_period=5)})
    monkeypatch.setattr(study, "RULES", {"paper": {}})
    out = str(tmp_path / "ceiling")
    rows = study.measure_ceiling(out, lives=2, task_steps=200)
    assert [(r["rules"], r["option"]) for r in rows] == [("paper", "period-5")]
    assert all(0.0 <= r["fitness"] <= 1.0 and 0.0 <= r["last_tenth"] <= 1.5 and 1 / 3 <= r["top_share"] <= 1.0
               for r in rows)
    assert sorted(os.listdir(out)) == ["ceiling.csv", "ceiling.png", "result.json"]
    with open(os.path.join(out, "result.json")) as f:
        assert json.load(f)["rows"] == rows


def test_rate_sweep_writes_its_result_last(tmp_path, monkeypatch):
    """A tiny sweep (one option, 2 points, 200-step tasks): one row per point, the best at the top of the figure."""
    monkeypatch.setattr(study, "RATE_OPTIONS", ("period-5",))
    monkeypatch.setattr(study, "RATE_GRID", dict(trace_lambda=(0.0,), eta_selector_actor=(0.0, 1.0),
                                                 eta_selector_critic=(0.01,)))
    out = str(tmp_path / "rates")
    rows = study.measure_rates(out, lives=2, task_steps=200)
    assert [(r["option"], r["eta_selector_actor"]) for r in rows] == [("period-5", 0.0), ("period-5", 1.0)]
    assert all(0.0 <= r["fitness"] <= 1.0 and r["lives"] == 2 for r in rows)
    assert study.best_rates(rows, "period-5") == max(rows, key=lambda r: r["fitness"])
    assert sorted(os.listdir(out)) == ["rates.csv", "rates.png", "result.json"]


def test_confirmation_relives_each_options_best_point(tmp_path, monkeypatch):
    """One option, its best point from a (fake) sweep, 2 fresh lives of 200-step tasks: one row, result.json last."""
    monkeypatch.setattr(study, "RATE_OPTIONS", ("period-5",))
    out = tmp_path / "timescale"
    (out / "rates").mkdir(parents=True)
    sweep = [dict(option="period-5", trace_lambda=lam, eta_selector_actor=1.0, eta_selector_critic=0.01,
                  fitness=value) for lam, value in ((0.0, 0.2), (0.9, 0.4))]
    (out / "rates" / "result.json").write_text(json.dumps(dict(rows=sweep)))
    assert study.main(["--out", str(out / "confirm"), "confirm", "--lives", "2", "--task-steps", "200"]) == 0
    rows = study.read_measure(str(out), "confirm")
    assert [(r["option"], r["trace_lambda"], r["sweep_fitness"], r["lives"]) for r in rows] == [
        ("period-5", 0.9, 0.4, 2)]
    assert 0.0 <= rows[0]["fitness"] <= 1.0
    assert sorted(os.listdir(out / "confirm")) == ["confirm.csv", "result.json"]


def _fake_evolution(folder, best_per_seed):
    """An evolution of ``best_per_seed[seed][generation]``."""
    write_evolution(folder, list(zip(*best_per_seed)), columns=dict(mean=0.0, std=0.0))


def _fake_test(folder, per_run):
    """A finished learning test."""
    write_learning_test(folder, per_run, steady_sd=0.0, pairs_both_ways=0.5)


def test_report_compares_the_option_with_the_per_step_runs(tmp_path):
    """Hand-made runs of 100 generations: a running option shows its progress; a finished one its claims."""
    reproduction, out = str(tmp_path / "paper"), str(tmp_path / "timescale")
    constant = lambda *values: [[v] * 100 for v in values]  # noqa: E731  one flat curve per seed
    document = tmp_path / "TIMESCALE.md"
    document.write_text(f"intro\n{study.REPORT_START}\nSTALE\n{study.REPORT_END}\nend\n")
    _measured(out)  # colour-60 is evolved
    table = study.timescale_table(out, results=str(tmp_path), reproduction=reproduction, summary={},
                                  document=str(document))
    per_step = table.option_runs()  # the per-step runs alone, where their keys find them under tmp_path
    assert all(folder.startswith(str(tmp_path)) for folder in [*per_step.evolutions.values(), *per_step.tests.values()])
    for condition, curves in (("LE-LS", constant(0.8, 0.76)), ("EE-LS", constant(0.4, 0.5)),
                              ("EE-ES", constant(0.3, 0.4))):
        _fake_evolution(per_step.evolutions[condition], curves)
    for condition, runs in (("LE-LS", (0.8, 0.8)), ("EE-LS", (0.5, 0.5)), ("SLE", (0.4, 0.4)), ("EE-ES", (0.3, 0.3))):
        _fake_test(per_step.tests[condition], runs)
    evolved = {row.condition: table.evolutions()[row.name] for row in table.rows}
    _fake_evolution(evolved["EE-LS"], [[0.7] * 40, [0.74] * 40])  # running
    rows = table.claims()
    assert list(rows) == ["skills", "skills+colour-60"] and rows["skills+colour-60"]["measured"] is None
    assert rows["skills"]["measured"]["claims"][3]["verdict"] == "does not hold"  # 0.45 against 0.78
    text = study.report_table(rows)
    assert "| skills, colour-60 selector | LE-LS | not started | - | - | - | - |" in text
    assert "| skills, colour-60 selector | EE-LS | 2 x 40 of 100, running | - | - | - | - |" in text
    _fake_evolution(evolved["LE-LS"], constant(0.6, 0.62))  # finished, not yet tested
    rows = table.claims()
    measured = rows["skills+colour-60"]["measured"]
    assert set(measured["evolution"]) == {"LE-LS", "EE-ES"} and measured["claims"][3]["verdict"] == "n/a"
    text = study.report_table(rows)
    assert "| skills, colour-60 selector | LE-LS | 2 x 100 | 0.610 +- 0.010 | - | 0 | - |" in text
    assert "| skills, colour-60 selector | EE-LS | 2 x 40 of 100, running | - | - | - | - |" in text
    assert "| skills, per-step selector (the paper's) | LE-LS | 2 x 100 | 0.780 +- 0.020 | - | 0 | 0.800 +- 0.000 " \
           "(2 runs) |" in text
    os.remove(os.path.join(evolved["EE-LS"], "history.csv"))
    os.rmdir(evolved["EE-LS"])
    _fake_evolution(evolved["EE-LS"], constant(0.7, 0.74))
    for condition, per_run in (("LE-LS", (0.6, 0.6)), ("EE-LS", (0.7, 0.7))):
        _fake_test(table.tests()[f"skills+colour-60 {condition}"], per_run)
    rows = table.claims()
    claims = rows["skills+colour-60"]["measured"]["claims"]
    # EE-LS 0.72 against LE-LS 0.61; se = sqrt(0.0002 / 2 + 0.0008 / 2) (sd with ddof 1 over 2 seeds)
    assert claims[3]["verdict"] == "holds" and abs(claims[3]["numbers"]["standard_error"] - 0.0005 ** 0.5) < 1e-9
    assert claims[6]["measured"].startswith("EE-LS > LE-LS > SLE > EE-ES")  # the option's tests beside skills' SLE
    text = study.report_table(rows)
    assert "| skills, colour-60 selector | LE-LS | 2 x 100 | 0.610 +- 0.010 | - | 0 | 0.600 +- 0.000 (2 runs) |" in text
    assert "| 3: EE-LS ends with a higher best fitness than LE-LS. | no: EE-LS 0.450 vs LE-LS 0.780" in text
    assert table.main(["--report"]) == 0
    written = document.read_text()
    assert "STALE" not in written and "**holds**: EE-LS 0.720 vs LE-LS 0.610" in written
    with open(os.path.join(out, "evolutions.json")) as f:
        recorded = json.load(f)
    assert recorded["skills+colour-60"]["claims"]["3"]["verdict"] == "holds"
    assert recorded["skills+colour-60"]["progress"] == {"LE-LS": [100, 2], "EE-LS": [100, 2]}
    assert os.path.getsize(os.path.join(out, "evolutions.png")) > 10_000


def test_report_before_the_measurements_is_refused(tmp_path, capsys):
    assert study.timescale_table(str(tmp_path / "none"), results=str(tmp_path)).main(["--report"]) == 2
    err = capsys.readouterr().err.strip()
    assert "the measurements have not run" in err and "\n" not in err


def test_confirm_before_the_rate_sweep_exits_2(tmp_path, capsys):
    out = str(tmp_path / "timescale" / "confirm")
    assert study.main(["--out", out, "confirm"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: ") and "the rate sweep has not run" in err and "\n" not in err
    assert not os.path.exists(os.path.join(out, "result.json"))


@pytest.mark.parametrize("argv, field", [(["rates", "--lives", "-1"], "--lives"), (["ceiling", "--task-steps", "0"],
                                                                                     "--task-steps")])
def test_a_measurement_of_no_lives_or_steps_exits_2_naming_it(tmp_path, capsys, argv, field):
    """A traceback from deep in the ceiling's program before; now one line naming the option, nothing written."""
    out = tmp_path / "measure"
    assert study.main(["--out", str(out), *argv]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0] == f"error: {field}: must be at least 1 (got {argv[-1]})" and not out.exists()


def _attack(tmp_path, *argv):
    from attack import attack

    return attack(study.main, list(argv), str(tmp_path))


def _hostile_cases():
    from test_circular_paths import hostile_cases

    return hostile_cases(study.measure_parser())


@pytest.mark.parametrize("flag, value", _hostile_cases())
def test_hostile_values_are_refused_or_planned_with_nothing_written(tmp_path, flag, value):
    """Every option of a measurement's parser, every hostile value: one line and exit 2, or a plan; nothing written."""
    from attack import assert_contract

    argv = ["--out", "timescale/ceiling", "ceiling", f"{flag}={value}"]
    outcome = _attack(tmp_path, *argv)
    if assert_contract(outcome, flag, "memory", argv=argv) == "planned":  # only with values in bounds
        checked = outcome.plan.checked
        assert 1 <= checked.get("lives", 1) <= 10_000 and 0 <= checked.get("key", 0) < 2**32
        assert 1 <= checked["task_steps"] <= 10**9 and checked["out_dir"].strip()


def _rates(tmp_path):
    """A rate sweep's result.json beside the confirmation's folder: a point of each option."""
    folder = tmp_path / "timescale" / "rates"
    folder.mkdir(parents=True)
    rows = [dict(option=option, trace_lambda=0.9, eta_selector_actor=1.0, eta_selector_critic=0.01, fitness=0.5)
            for option in study.RATE_OPTIONS]
    (folder / "result.json").write_text(json.dumps(dict(rows=rows)))
    return str(folder / "result.json")


CONFIRM = ("--out", "timescale/confirm", "confirm")


def test_confirm_plans_from_a_sound_rate_sweep(tmp_path):
    from attack import assert_contract

    _rates(tmp_path)
    outcome = _attack(tmp_path, *CONFIRM)
    assert assert_contract(outcome) == "planned" and outcome.plan.checked["out_dir"] == "timescale/confirm"


@pytest.mark.parametrize("how", ["empty", "truncated", "not json", "null", "a list", "NaN", "binary", "removed"])
def test_a_damaged_rate_sweep_is_one_line_naming_it(tmp_path, how):
    """confirm reads rates/result.json: damaged, it is named in one line (a traceback before, for most)."""
    from attack import assert_refused, damage

    damage(_rates(tmp_path), how)
    assert_refused(_attack(tmp_path, *CONFIRM), "rates", argv=[how])


@pytest.mark.parametrize("change", [
    lambda d: d["rows"][0].update(fitness=float("nan")),  # a NaN best: max() then picks arbitrary rates
    lambda d: d["rows"][0].update(fitness="high"),
    lambda d: d["rows"][0].update(eta_selector_actor=-3.0),  # a rate the config refuses
    lambda d: d["rows"][0].pop("trace_lambda"),
    lambda d: d["rows"][0].update(option="period-7"),
    lambda d: d.update(rows=[r for r in d["rows"] if r["option"] != "colour-60"]),  # an option never swept
    lambda d: d.update(rows=[1, 2]),
    lambda d: d.pop("rows"),
], ids=["nan fitness", "text fitness", "rate out of bounds", "no lambda", "unknown option", "option missing",
        "rows not dicts", "no rows"])
def test_a_rate_sweep_of_bad_rows_is_one_line_naming_it(tmp_path, change):
    from attack import assert_refused, edit_json

    edit_json(_rates(tmp_path), change)
    assert_refused(_attack(tmp_path, *CONFIRM), "rates")


def test_a_measurement_into_a_folder_of_other_files_is_refused(tmp_path):
    from attack import assert_contract, assert_refused

    (tmp_path / "m").mkdir()
    (tmp_path / "m" / "ceiling.csv").write_text("old")
    assert assert_contract(_attack(tmp_path, "--out", "m", "ceiling")) == "planned"
    (tmp_path / "m" / "notes.txt").write_text("mine")
    assert_refused(_attack(tmp_path, "--out", "m", "ceiling"), "--out")
