"""The time-scale study: the ceiling stage, and the evolutions planned from its result."""

import json
import os

from experiments import reproduce
from experiments import timescale as study


def _fake_ceiling(out, paper_best):
    skills = dict(zip(study.OPTIONS, (0.7, 0.2, 0.6, 0.3, 0.2, 0.4, 0.1)))  # per-step is never the choice
    paper = {option: paper_best if option == "colour-20" else 0.1 for option in study.OPTIONS}
    rows = [dict(rules=rules, option=option, fitness=value)
            for rules, values in (("paper", paper), ("skills", skills)) for option, value in values.items()]
    os.makedirs(os.path.dirname(study.result_path(out, "ceiling")))
    with open(study.result_path(out, "ceiling"), "w") as f:
        json.dump(dict(rows=rows), f)


def _fake_rates(out, best_option="colour-60"):
    rows = [dict(option=option, trace_lambda=lam, eta_selector_actor=actor, eta_selector_critic=critic,
                 fitness=0.1 + (option == best_option) * 0.5 * (actor == 1.0) * (critic == 0.01) * (lam == 0.9))
            for option in study.RATE_OPTIONS for lam in (0.0, 0.9, 0.98) for actor in (0.3, 1.0) for critic in (0.01,)]
    rows.append(dict(option="per-step", trace_lambda=0.98, eta_selector_actor=0.3, eta_selector_critic=0.001,
                     fitness=0.9))  # per-step is never the option evolved
    os.makedirs(os.path.join(out, "rates"))
    with open(study.result_path(out, "rates"), "w") as f:
        json.dump(dict(rows=rows), f)


def _fake_confirm(out, best_option="colour-60"):
    """The confirmation of _fake_rates' best points: ``best_option`` stays the best in fresh lives."""
    rows = [dict(option=option, trace_lambda=0.9, eta_selector_actor=1.0, eta_selector_critic=0.01,
                 fitness=0.5 if option == best_option else 0.3) for option in study.RATE_OPTIONS]
    rows[0]["fitness"] = 0.9  # per-step is never the option evolved
    os.makedirs(os.path.join(out, "confirm"))
    with open(study.result_path(out, "confirm"), "w") as f:
        json.dump(dict(rows=rows), f)


def test_the_plan_waits_for_the_measures(tmp_path):
    out = str(tmp_path / "timescale")
    ceiling, rates, confirm = study.plan(out)
    assert ceiling.kind == rates.kind == confirm.kind == "measure" and ceiling.cost == 7 * 3 * 8 * 600_000
    assert rates.cost == 5 * (3 * 6 * 3) * 3 * 600_000  # options x grid points x lives x steps
    assert confirm.cost == 5 * 8 * 600_000
    for stage, which in ((ceiling, "ceiling"), (rates, "rates"), (confirm, "confirm")):
        command, env = study.stage_command(stage, out)
        assert command[-4:] == ["experiments.timescale", which, "--out", stage.out_dir] and "PYTHONPATH" in env
    _fake_ceiling(out, paper_best=0.45)
    _fake_rates(out)
    assert len(study.plan(out)) == 3  # the confirmation has not run


def test_evolutions_under_the_best_option(tmp_path):
    out = str(tmp_path / "timescale")
    _fake_ceiling(out, paper_best=0.45)  # the paper's rules still do not compose: skills' evolutions only
    _fake_rates(out)
    _fake_confirm(out)
    stages = study.plan(out)
    assert all(reproduce.stage_done(stage, study.SCREEN) for stage in stages[:3])
    stages = stages[1:]  # the indices below as before the confirmation stage
    assert [s.name for s in stages[2:]] == ["evolve skills+colour-60 LE-LS", "learning test skills+colour-60 LE-LS",
                                            "evolve skills+colour-60 EE-LS", "learning test skills+colour-60 EE-LS"]
    assert reproduce.stage_done(stages[0], study.SCREEN) and reproduce.stage_done(stages[1], study.SCREEN)
    evolve = study.stage_command(stages[2], out)[0]
    assert evolve[evolve.index("--preset") + 1] == "skills"
    sets = [evolve[i + 1] for i, word in enumerate(evolve) if word == "--set"]
    assert sets == ["selector_period=60", "selector_termination=colour", "trace_lambda=0.9", "eta_selector_actor=1.0",
                    "eta_selector_critic=0.01"]  # the confirmed point's rates
    test = study.stage_command(stages[3], out)[0]
    assert test[test.index("imrl_jax.learning_test") + 1] == stages[2].out_dir  # the run's own config
    _fake_ceiling(str(tmp_path / "composes"), paper_best=0.55)
    _fake_rates(str(tmp_path / "composes"))
    _fake_confirm(str(tmp_path / "composes"))
    paper = [s for s in study.plan(str(tmp_path / "composes")) if s.variant.startswith("paper")]
    assert [s.name for s in paper if s.kind == "evolve"] == [f"evolve paper+colour-20 {c}"
                                                            for c in ("LE-LS", "EE-LS", "EE-ES")]
    sets = study.stage_command(paper[0], str(tmp_path / "composes"))[0]
    assert " ".join(sets).count("--set") == 2 and "selector_termination=colour" in sets


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
    assert all(0.0 <= r["fitness"] <= 1.0 for r in rows)
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
    rows = study.measure_confirm(str(out / "confirm"), lives=2, task_steps=200)
    assert [(r["option"], r["trace_lambda"], r["sweep_fitness"]) for r in rows] == [("period-5", 0.9, 0.4)]
    assert 0.0 <= rows[0]["fitness"] <= 1.0
    assert sorted(os.listdir(out / "confirm")) == ["confirm.csv", "result.json"]


def _fake_evolution(folder, best_per_seed):
    """An evolution's history.csv as the report reads it: a row per generation and seed."""
    os.makedirs(folder)
    rows = [f"{g},{seed},{v},0.0,0.0" for seed, curve in enumerate(best_per_seed) for g, v in enumerate(curve)]
    with open(os.path.join(folder, "history.csv"), "w") as f:
        f.write("generation,seed,best,mean,std\n" + "\n".join(rows) + "\n")


def _fake_test(folder, per_run):
    """A finished learning test as the report reads it: steady.json and curve.csv."""
    os.makedirs(folder)
    with open(os.path.join(folder, "steady.json"), "w") as f:
        json.dump(dict(steady_per_run=list(per_run), steady_mean=sum(per_run) / len(per_run), steady_sd=0.0,
                       num_runs=len(per_run), pairs_both_ways=0.5), f)
    with open(os.path.join(folder, "curve.csv"), "w") as f:
        f.write("bin,end_step,mean,sd_over_runs\n0,1000,0.1,0.01\n1,2000,0.3,0.01\n")


def test_report_compares_the_option_with_the_per_step_runs(tmp_path):
    """Hand-made runs of 100 generations: a running option shows its progress; a finished one its claims."""
    reproduction, out = str(tmp_path / "paper"), str(tmp_path / "timescale")
    constant = lambda *values: [[v] * 100 for v in values]  # noqa: E731  one flat curve per seed
    _fake_evolution(os.path.join(reproduction, "skills", "evolve", "LE-LS"), constant(0.8, 0.76))
    _fake_evolution(os.path.join(reproduction, "skills", "evolve", "EE-LS"), constant(0.4, 0.5))
    _fake_evolution(os.path.join(reproduction, "paper", "evolve", "EE-ES"), constant(0.3, 0.4))
    for variant, condition, runs in (("skills", "LE-LS", (0.8, 0.8)), ("skills", "EE-LS", (0.5, 0.5)),
                                     ("skills", "SLE", (0.4, 0.4)), ("paper", "EE-ES", (0.3, 0.3))):
        _fake_test(os.path.join(reproduction, variant, "test", condition), runs)
    _fake_ceiling(out, paper_best=0.45)
    _fake_rates(out)
    _fake_confirm(out)  # colour-60 is evolved
    option = os.path.join(out, "skills+colour-60")
    _fake_evolution(os.path.join(option, "EE-LS", "evolve"), [[0.7] * 40, [0.74] * 40])  # running
    rows = study.measure_evolutions(out, reproduction, summary={})
    assert list(rows) == ["skills", "skills+colour-60"] and rows["skills+colour-60"]["measured"] is None
    assert rows["skills"]["measured"]["claims"][3]["verdict"] == "does not hold"  # 0.45 against 0.78
    text = study.report_table(rows)
    assert "| skills, colour-60 selector | LE-LS | not started | - | - | - | - |" in text
    assert "| skills, colour-60 selector | EE-LS | 2 x 40 of 100, running | - | - | - | - |" in text
    _fake_evolution(os.path.join(option, "LE-LS", "evolve"), constant(0.6, 0.62))  # finished, not yet tested
    rows = study.measure_evolutions(out, reproduction, summary={})
    measured = rows["skills+colour-60"]["measured"]
    assert set(measured["evolution"]) == {"LE-LS", "EE-ES"} and measured["claims"][3]["verdict"] == "n/a"
    text = study.report_table(rows)
    assert "| skills, colour-60 selector | LE-LS | 2 x 100 | 0.610 +- 0.010 | - | 0 | - |" in text
    assert "| skills, colour-60 selector | EE-LS | 2 x 40 of 100, running | - | - | - | - |" in text
    assert "| skills, per-step selector (the paper's) | LE-LS | 2 x 100 | 0.780 +- 0.020 | - | 0 | 0.800 +- 0.000 " \
           "(2 runs) |" in text
    os.remove(os.path.join(option, "EE-LS", "evolve", "history.csv"))
    os.rmdir(os.path.join(option, "EE-LS", "evolve"))
    _fake_evolution(os.path.join(option, "EE-LS", "evolve"), constant(0.7, 0.74))
    _fake_test(os.path.join(option, "LE-LS", "test"), (0.6, 0.6))
    _fake_test(os.path.join(option, "EE-LS", "test"), (0.7, 0.7))
    rows = study.measure_evolutions(out, reproduction, summary={})
    claims = rows["skills+colour-60"]["measured"]["claims"]
    # EE-LS 0.72 against LE-LS 0.61; se = sqrt(0.0002 / 2 + 0.0008 / 2) (sd with ddof 1 over 2 seeds)
    assert claims[3]["verdict"] == "holds" and abs(claims[3]["numbers"]["standard_error"] - 0.0005 ** 0.5) < 1e-9
    assert claims[6]["measured"].startswith("EE-LS > LE-LS > SLE > EE-ES")  # the option's tests beside skills' SLE
    text = study.report_table(rows)
    assert "| skills, colour-60 selector | LE-LS | 2 x 100 | 0.610 +- 0.010 | - | 0 | 0.600 +- 0.000 (2 runs) |" in text
    assert "| 3: EE-LS ends with a higher best fitness than LE-LS. | no: EE-LS 0.450 vs LE-LS 0.780" in text
    document = tmp_path / "TIMESCALE.md"
    document.write_text(f"intro\n{study.REPORT_START}\nSTALE\n{study.REPORT_END}\nend\n")
    assert study.report(out, str(document), reproduction, summary={}) == 0
    written = document.read_text()
    assert "STALE" not in written and "**holds**: EE-LS 0.720 vs LE-LS 0.610" in written
    assert json.loads(open(os.path.join(out, "evolutions.json")).read())["skills+colour-60"]["claims"]["3"][
        "verdict"] == "holds"
    assert os.path.getsize(os.path.join(out, "evolutions.png")) > 0


def test_report_before_the_measurements_is_refused(tmp_path, capsys):
    assert study.main(["--report", "--out", str(tmp_path / "none")]) == 2
    err = capsys.readouterr().err.strip()
    assert "the measurements have not run" in err and "\n" not in err


def test_a_run_evolved_at_other_rates_is_refused(tmp_path, capsys):
    """The folder names the option, not its rates: a run whose config differs from the confirmed point is refused."""
    out = str(tmp_path / "timescale")
    _fake_ceiling(out, paper_best=0.45)
    _fake_rates(out)
    _fake_confirm(out)
    folder = os.path.join(out, "skills+colour-60", "LE-LS", "evolve")
    os.makedirs(folder)
    config = dict(selector_period=60, selector_termination="colour", trace_lambda=0.9, eta_selector_actor=1.0,
                  eta_selector_critic=0.01)
    with open(os.path.join(folder, "config.json"), "w") as f:
        json.dump(dict(config=config), f)
    assert study.mismatched_runs(out) == []
    with open(os.path.join(folder, "config.json"), "w") as f:
        json.dump(dict(config=dict(config, eta_selector_actor=3.0)), f)
    [line] = study.mismatched_runs(out)
    assert "eta_selector_actor=3.0" in line and "eta_selector_actor=1.0" in line
    assert study.main(["--report", "--out", out]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"error: {folder}: evolved with eta_selector_actor=3.0") and "\n" not in err


def test_confirm_before_the_rate_sweep_exits_2(tmp_path, capsys):
    out = str(tmp_path / "timescale" / "confirm")
    assert study.main(["confirm", "--out", out]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: ") and "the rate sweep has not run" in err and "\n" not in err
    assert not os.path.exists(os.path.join(out, "result.json"))
