"""The future-work study's table (each row's run found by its key, or tested from scratch), its measures and
verdicts on hand-made runs, its report of the committed runs, and the evolved values evolve records."""

import dataclasses
import json
import math
import os
import shutil

import pytest
from helpers import ROOT, write_evolution, write_learning_test

from experiments import future_work as study
from experiments.harness.reproduce import stage_done
from experiments.harness.study import SCALES
from imrl_jax.conditions import EVOLVED_FIELDS


def _stages(*names):
    """The study's stages of the rows ``names``, by name."""
    stages, _ = study.TABLE.all_stages()
    return {s.name: s for s in stages if s.variant in names}


def test_every_committed_run_is_found_by_its_key(monkeypatch):
    """Nothing to run: each row finds its committed evolution and learning test, the reproduction's at its sizes."""
    monkeypatch.chdir(ROOT)
    stages, scale = study.all_stages()
    assert len(stages) == 34 and [s.name for s in stages if not stage_done(s, scale)] == []
    evolutions = study.TABLE.evolutions()
    assert evolutions["EV-LS"] == os.path.join(study.OUT, "EV-LS", "evolve") and evolutions["EXT-LS"] is None
    assert evolutions["skills EE-ES"] == os.path.join("experiments", "results", "paper", "paper", "evolve", "EE-ES")
    tests = study.TABLE.tests()
    assert tests["EXT-LS-whole"] == os.path.join(study.OUT, "EXT-LS-whole", "test")
    assert tests["skills SLE-whole"] == os.path.join("experiments", "results", "claims", "skills-sle-test", "test", "SLE")
    assert tests["faithful SLE"] == os.path.join("experiments", "results", "paper", "faithful", "test", "SLE")
    assert set(study.ABOUT) == {r.name for r in study.TABLE.rows}


def test_the_table_evolves_the_evolved_rows_and_tests_the_others_from_scratch():
    stages = _stages("EV-LS", "EXT-LS-whole", "LE-LS-N6")
    assert list(stages) == ["evolve EV-LS", "learning test EV-LS", "learning test EXT-LS-whole",
                            "evolve LE-LS-N6", "learning test LE-LS-N6"]
    evolve = study.TABLE.stage_command(stages["evolve LE-LS-N6"])[0]
    assert evolve[evolve.index("--cond") + 1] == "LE-LS-N" and "num_experts=6" in evolve
    scratch = study.TABLE.stage_command(stages["learning test EXT-LS-whole"])[0]
    assert scratch[scratch.index("--cond") + 1] == "EXT-LS" and "sle_noise_steps=0" in scratch
    assert "sle_noise_steps=100000" not in scratch and scratch[scratch.index("--runs") + 1] == "5"
    test = study.TABLE.stage_command(stages["learning test EV-LS"])[0]
    assert test[test.index("-m") + 2].endswith("EV-LS/evolve")  # the learning test reads its own evolution
    # EV-LS lives a childhood, EXT-LS does not: costs in lane-steps at the paper's lengths.
    assert stages["evolve EV-LS"].cost == 5 * 50 * 100 * (150_000 + 6 * 100_000)
    assert stages["learning test EXT-LS-whole"].cost == 5 * 5 * 4 * 6 * 1_000_000
    reproduction = study.TABLE.stage_command(_stages("skills LE-LS")["evolve skills LE-LS"])[0]
    assert reproduction[reproduction.index("--seeds") + 1] == str(SCALES["paper"]["seeds"]) == "10"


def test_the_fixed_six_experts_rows_are_the_claims_studys_runs_found_by_key():
    from experiments import claims_study
    from imrl_jax.runs.cli import parse_sets
    from imrl_jax.config import make_config

    evolutions, tests = study.TABLE.evolutions(), study.TABLE.tests()
    claim8 = claims_study.experts_runs(claims_study.EXPERTS_TABLE)
    for name, rule in (("LE-LS-6", "skills"), ("LE-LS-6-faithful", "paper-selector")):
        evolved, tested, _ = claim8[rule, "LE-LS", 6]
        assert (evolutions[name], tests[name]) == (evolved, tested)
        assert evolved == os.path.join(claims_study.OUT, rule, "experts6", "evolve", "LE-LS")
    assert evolutions["LE-LS-N6"] == os.path.join(study.OUT, "LE-LS-N6", "evolve")
    # under faithful: the claims study's paper-selector run of 6 experts, whose lives are the same
    faithful = next(r for r in study.TABLE.rows if r.name == "LE-LS-6-faithful")
    screened = claims_study.config_of(claims_study.BY_NAME["paper-selector"], "LE-LS", num_experts=6)
    ours = make_config(faithful.preset, condition="LE-LS", **parse_sets(list(faithful.sets)))
    assert ours.model_differences(screened) == []


def test_the_faithful_rows_run_under_the_faithful_preset():
    stages = _stages("EV-LS-faithful", "EXT-LS-faithful")
    assert list(stages) == ["evolve EV-LS-faithful", "learning test EV-LS-faithful", "learning test EXT-LS-faithful"]
    evolve = study.TABLE.stage_command(stages["evolve EV-LS-faithful"])[0]
    assert evolve[evolve.index("--preset") + 1] == "faithful" and evolve[evolve.index("--cond") + 1] == "EV-LS"
    scratch = study.TABLE.stage_command(stages["learning test EXT-LS-faithful"])[0]
    assert scratch[scratch.index("--preset") + 1] == "faithful" and "sle_noise_steps=0" in scratch
    names = [r.name for r in study.TABLE.rows]
    assert names.index("EV-LS-faithful") > names.index("LE-LS-6")


def test_an_unknown_option_is_refused(capsys):
    assert study.main(["--only", "EV-LS"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: unrecognized arguments: --only") and err.count("\n") == 1


def test_traits_of_a_hand_made_genome():
    import numpy as np

    from imrl_jax.agent import networks
    from imrl_jax.config import make_config

    config = make_config("skills", condition="LE-LS-P")
    genome = np.zeros(config.num_genes, np.float32)  # every parameter gene 0: u = 0.5 of its range
    values = dict(zip(networks.trait_names(config), np.asarray(networks.traits(config, genome))))
    assert values["eta_actor"] == pytest.approx(1e-2) and values["noise_std"] == pytest.approx(0.5)
    assert values["gamma"] == pytest.approx(1 - 10 ** -1.75) and values["initial_speed_bias"] == pytest.approx(2.0)
    config = make_config("skills", condition="LE-LS-N", num_experts=4)
    genome = np.zeros(config.num_genes, np.float32)
    genome[-4:] = [0.5, -0.2, 0.1, -0.9]  # the expression genes come last: experts 1 and 3 expressed
    assert np.asarray(networks.traits(config, genome)).tolist() == [2, 0, 1, 0, 0]
    assert networks.trait_names(make_config("skills", condition="LE-LS")) == ()
    config = make_config("skills", condition="LE-LS-PC")  # the last gene chooses the childhood's length
    names = networks.trait_names(config)
    assert names == EVOLVED_FIELDS + ("childhood_length",)
    values = np.asarray(networks.traits(config, np.zeros(config.num_genes, np.float32)))
    assert values[-1] == config.childhood_steps / 2 and values[-2] == pytest.approx(2.0)  # and the speed bias


def test_the_traits_figure_has_a_panel_for_each_evolved_value():
    import numpy as np

    from imrl_jax.agent import networks
    from imrl_jax.config import make_config
    from imrl_jax.analysis.charts import plot_traits

    config = make_config("skills", condition="LE-LS-PC")
    names = networks.trait_names(config)
    traits = np.tile(np.asarray(networks.traits(config, np.zeros(config.num_genes, np.float32)))[:, None], 2)
    fig = plot_traits(config, names, np.broadcast_to(traits, (3, 2) + traits.shape))
    titles = [" ".join(ax.get_title().split()) for ax in fig.axes]
    assert len(titles) == len(names) and titles[-1] == "childhood_length (steps)"
    # One legend for the figure, with the paper's value (drawn where skills differs from it, as for trace_lambda).
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert labels == ["population mean", "the best's", "the preset's value", "the paper's value",
                      "the longest (childhood_steps)"]


@pytest.mark.slow
def test_history_records_the_evolved_values_and_they_survive_a_resume(tmp_path):
    import csv

    import jax
    import numpy as np
    from helpers import evolve_args, read_population

    from imrl_jax.commands import evolve
    from imrl_jax.agent import networks
    from imrl_jax.config import make_config

    out = str(tmp_path / "run")
    args = evolve_args("LE-LS-P", seeds=2, population=4, parents=2, task_steps=100, childhood_steps=100, bins=1)
    assert evolve.main([*args, "--generations", "2", "--out", out]) == 0
    with open(f"{out}/history.csv") as f:
        before = list(csv.DictReader(f))
    assert evolve.main(["--resume", "--out", out, "--generations", "3", "--quiet"]) == 0
    with open(f"{out}/history.csv") as f:
        rows = list(csv.DictReader(f))
    assert rows[:4] == before  # the first generations' values came back from the checkpoint as written
    config = make_config("small", condition="LE-LS-P")
    arrays = read_population(out)
    values = np.asarray(jax.vmap(jax.vmap(lambda g: networks.traits(config, g)))(arrays["evaluated"]))
    best = arrays["fitness"].argmax(1)
    for s in range(2):
        row = rows[4 + s]
        assert row["generation"] == "2"
        for t, name in enumerate(networks.trait_names(config)):
            assert float(row[f"mean_{name}"]) == pytest.approx(values[s, :, t].mean(), rel=1e-5)
            assert float(row[f"best_{name}"]) == pytest.approx(values[s, best[s], t], rel=1e-5)
    assert os.path.getsize(f"{out}/traits.png") > 10_000


def test_record_traits_and_their_history_columns_by_hand():
    import numpy as np

    from imrl_jax.commands import evolve
    from imrl_jax.runs.checkpoint import empty_history

    traits = np.full((2, 1, 2, 2), np.nan, np.float32)
    values = np.asarray([[[1.0, 10.0], [3.0, 30.0], [2.0, 20.0]]])  # 1 seed x 3 individuals x 2 traits
    traits = evolve.record_traits(traits, 0, np.asarray([[0.1, 0.5, 0.2]]), values)
    np.testing.assert_allclose(traits[0, 0], [[2.0, 3.0], [20.0, 30.0]])  # (mean, the best's) per trait
    assert np.isnan(traits[1]).all()
    text = evolve.history_csv(empty_history(2, 1, 6), 1, [7], traits, ("a", "b"))
    header, row = text.splitlines()
    assert header.endswith(",mean_a,best_a,mean_b,best_b") and row.endswith(",2,3,20,30")


def _fake_evolution(folder, best, planned, traits=None):
    """An evolution of ``best[seed][generation]``, its traits ``traits[name] = (mean, best's)`` each [seed][generation],
    planned for ``planned`` generations."""
    columns = dict(mean=0.1, std=0.01, **{f"{which}_{n}": list(zip(*t[i])) for n, t in (traits or {}).items()
                                          for i, which in enumerate(("mean", "best"))})
    write_evolution(folder, list(zip(*best)), dict(config=dict(num_generations=planned)), columns)


def _fake_test(folder, per_run, sle_noise_steps=None):
    """A finished learning test (SLE's: its noise's horizon in its config)."""
    write_learning_test(folder, per_run, pairs_both_ways=0.5,
                        **({} if sle_noise_steps is None else dict(config=dict(sle_noise_steps=sle_noise_steps))))


#: Every row the report shows, by name, as the table and SLE's tests describe it.
ROWS = {r.name: r for r in study.TABLE.rows}


def _fake_study(tmp_path):
    """The reproduction's LE-LS, EE-LS and tests, and the study's LE-LS-6, LE-LS-N6, LE-LS-P, a running EV-LS, EXT-LS,
    each row's folders ``ROW/evolve`` and ``ROW/test`` (the reproduction's evolutions in ``paper/VARIANT/evolve``);
    and the reproduction report's summary."""
    reproduction = {"skills LE-LS": tmp_path / "paper" / "skills" / "evolve" / "LE-LS",
                    "skills EE-LS": tmp_path / "paper" / "skills" / "evolve" / "EE-LS"}
    row = lambda name, kind: reproduction[name] if kind == "evolve" and name in reproduction else tmp_path / name / kind  # noqa: E731
    _fake_evolution(row("skills LE-LS", "evolve"), [[0.2, 0.4, 0.6, 0.6, 0.6], [0.4, 0.6, 0.8, 0.8, 0.8]], 5)
    _fake_evolution(row("skills EE-LS", "evolve"), [[0.5] * 5, [0.7] * 5], 5)
    _fake_test(row("skills LE-LS", "test"), [0.8, 0.9])
    _fake_test(row("skills SLE", "test"), [0.3, 0.5], sle_noise_steps=100_000)
    _fake_test(row("skills EE-ES", "test"), [0.4, 0.4, 0.4])
    _fake_test(row("faithful SLE", "test"), [0.2, 0.2], sle_noise_steps=0)
    _fake_evolution(row("LE-LS-6", "evolve"), [[0.5] * 5, [0.6] * 5], 5)
    share = lambda k: ([{3: [0, 0.5, 1, 1, 1], 6: [1, 0.5, 0, 0, 0]}.get(k, [0] * 5)] * 2, [[0] * 5] * 2)  # noqa: E731
    _fake_evolution(row("LE-LS-N6", "evolve"), [[0.7] * 5, [0.8] * 5], 5, dict(
        expressed_experts=([[6, 5, 4, 4, 3], [6, 5, 4, 4, 5]], [[6, 4, 4, 3, 3], [6, 5, 4, 3, 3]]),
        **{f"share_{k}_experts": share(k) for k in range(1, 7)}))
    _fake_evolution(row("LE-LS-P", "evolve"), [[0.6] * 5] * 2, 5, dict(  # the last generation's values count
        gamma=([[0.5] * 4 + [0.95], [0.5] * 4 + [0.97]], [[0.5] * 4 + [0.98], [0.5] * 4 + [0.99]]),
        eta_actor=([[0.5] * 4 + [0.02], [0.5] * 4 + [0.04]], [[0.5] * 4 + [0.01], [0.5] * 4 + [0.03]])))
    _fake_evolution(row("EV-LS", "evolve"), [[0.1, 0.2]], 100)  # still running
    _fake_test(row("EXT-LS", "test"), [0.6, 0.7, 0.8])
    summary = dict(best_individuals={"skills/LE-LS": dict(fresh_mean_per_seed=[0.5, 0.6])})  # its fresh lives
    return (ROWS, {n: str(row(n, "evolve")) if r.evolved else None for n, r in ROWS.items()},
            {n: str(row(n, "test")) for n in ROWS}, summary, str(tmp_path / "paper"))


def test_measure_reads_every_finished_row_and_the_reproductions(tmp_path):
    """Hand-made runs: final best, its sd and plateau; steady states; (c)'s last values; (d)'s experts and fitness."""
    measured = study.measure(*_fake_study(tmp_path))
    rows = {r["name"]: r for r in measured["rows"]}
    assert list(rows) == ["skills LE-LS", "skills EE-LS", "skills EE-ES", "skills SLE", "skills SLE-whole",
                          "faithful LE-LS", "faithful SLE", *(r.name for r in study.TABLE.rows[7:])]
    assert rows["faithful LE-LS"]["evolution"] is None and rows["faithful SLE"]["test"]["runs"] == 2
    le_ls = rows["skills LE-LS"]["evolution"]  # seeds' means of 5 generations: 2.4 / 5 and 3.4 / 5
    assert le_ls["final_best"] == pytest.approx(0.58) and le_ls["final_best_sd"] == pytest.approx(0.1)
    assert le_ls["plateau_generation"] == 2  # the mean curve 0.3, 0.5, 0.7: 0.7 >= 0.9 x 0.58 first at generation 2
    assert (le_ls["fresh"], le_ls["fresh_sd"]) == pytest.approx((0.55, 0.005 ** 0.5))  # the summary's, ddof 1
    assert rows["skills EE-ES"]["evolution"] is None and rows["skills EE-ES"]["test"]["runs"] == 3
    assert rows["EV-LS"]["evolution"]["finished"] is False and "final_best" not in rows["EV-LS"]["evolution"]
    assert rows["EXT-LS"]["test"]["steady_mean"] == pytest.approx(0.7)
    assert rows["EXT-LS"]["test"]["steady_sd"] == pytest.approx((0.02 / 3) ** 0.5)  # ddof 0
    assert rows["EXT-LS"]["about"] == study.ABOUT["EXT-LS"]  # only the references say how their SLE's noise went
    evolved = measured["learning_values"]["evolved"]
    assert evolved["LE-LS-PC"] is None and set(evolved["LE-LS-P"]) == {"gamma", "eta_actor"}
    gamma = evolved["LE-LS-P"]["gamma"]
    assert (gamma["mean"], gamma["best"]) == pytest.approx((0.96, 0.985))
    assert gamma["best_per_seed"] == pytest.approx([0.98, 0.99])
    assert measured["learning_values"]["hand"]["skills"]["trace_lambda"] == 0.98
    assert measured["learning_values"]["hand"]["paper"]["childhood_length"] == 150_000
    assert measured["learning_values"]["hand"]["faithful"]["trace_lambda"] == 0.98
    assert measured["learning_values"]["hand"]["faithful"]["initial_speed_bias"] == 0.0  # paper's
    assert evolved["LE-LS-P-faithful"] is None
    first, last = measured["experts"][0]["generations"]  # generations 0 and the last, 4
    assert (first["generation"], first["mean"], first["shares"][6]) == (0, 6.0, 1.0)
    assert (last["generation"], last["mean"], last["best"], last["shares"][3]) == (4, 4.0, 3.0, 1.0)
    assert measured["experts"][1]["generations"] is None and measured["experts"][1]["compared"] == []
    assert rows["LE-LS-N6"]["colours"] is None and "colours" not in rows["skills LE-LS"]  # no population to probe
    against_6, against_3 = measured["experts"][0]["compared"]
    assert against_6["name"] == "LE-LS-6" and against_6["difference"] == pytest.approx(0.2)
    assert against_6["standard_error"] == pytest.approx(0.005 ** 0.5)  # sqrt(0.005 / 2 + 0.005 / 2)
    assert against_3["difference"] == pytest.approx(0.17) and against_3["standard_error"] == pytest.approx(0.0125 ** 0.5)


def test_colour_sets_count_the_colours_each_probed_genome_follows():
    from imrl_jax.analysis.relive import expressed_followed

    # an expert left out by its genome follows nothing, whatever its untrained actor does alone
    assert expressed_followed([2, 2, 0, 1], [1, 0, 1, 0]) == [2, -1, 0, -1]
    assert expressed_followed([2, -1, 0]) == [2, -1, 0]
    sets = study.colour_sets([[2, -1, 0, -1], [0, 2, -1, -1], [1, -1, -1, -1], [-1] * 4, [2, 2, -1, -1]])
    assert sets["genomes"] == 5 and sets["experts_following"] == pytest.approx((2 + 2 + 1 + 0 + 2) / 5)
    assert sets["sets"] == {"red + blue": 2, "blue": 1, "green": 1, "none": 1}  # most often first, then by name
    assert sets["colours"] == pytest.approx((2 + 2 + 1 + 0 + 1) / 5)  # distinct: [2, 2] follows one colour
    assert study.colour_sets(None) is None and study.colour_sets([]) is None
    lines = study._colour_lines([dict(name="LE-LS-N6", colours=sets), dict(name="EV-LS", colours=None)])
    assert lines[-1] == "| LE-LS-N6 | 5 | 1.40 | 1.20 | red + blue 2, blue 1, green 1, none 1 |"
    assert study._colour_lines([dict(name="EV-LS", colours=None)]) == []


def test_table_shows_finished_running_and_not_run_rows(tmp_path):
    text = study.table(study.measure(*_fake_study(tmp_path)))
    for line in ("| skills LE-LS | LE-LS | the reproduction's LE-LS | 2 x 5 | 0.580 | 0.100 | 0.550 (0.071) | 2 | "
                 "0.850 +- 0.050 | 2 |",
                 "| skills EE-LS | EE-LS | the reproduction's EE-LS | 2 x 5 | 0.600 | 0.100 | - | 0 | not run yet | - |",
                 "| skills EE-ES | EE-ES | the reproduction's EE-ES | - | not run yet | - | - | - | 0.400 +- 0.000 | 3 |",
                 "| skills SLE | SLE | the reproduction's SLE, noise over 100,000 cycles | not evolved | - | - | - | - | "
                 "0.400 +- 0.100 | 2 |",
                 "| skills SLE-whole | SLE | the claims study's SLE (skills-sle-test) | not evolved | - | - | - | - | "
                 "not run yet | - |",
                 f"| EV-LS | EV-LS | {study.ABOUT['EV-LS']} | 1 x 2 of 100 | running | - | - | - | not run yet "
                 "| - |",
                 f"| EXT-LS | EXT-LS | {study.ABOUT['EXT-LS']} | not evolved | - | - | - | - | 0.700 +- 0.082 | 3 |",
                 "| gamma | 0.99 | 0.99 | 0.99 | 0.96 | 0.985 | not run yet | not run yet | not run yet | not run yet |",
                 "| eta_actor | 0.01 | 0.01 | 0.01 | 0.03 | 0.02 | not run yet | not run yet | not run yet | not run yet |",
                 "| trace_lambda | 0.98 | 0 | 0.98 | - | - | not run yet | not run yet | not run yet | not run yet |",
                 "| childhood_length | 150,000 | 150,000 | 150,000 | - | - | not run yet | not run yet | not run yet | "
                 "not run yet |",
                 "| faithful SLE | SLE | the reproduction's SLE, noise over the whole test | not evolved | - | - | - | - | "
                 "0.200 +- 0.000 | 2 |",
                 "LE-LS-N6-faithful: not run yet.",
                 "| 0 | 6.00 | 6.00 | 0.000 | 0.000 | 0.000 | 0.000 | 0.000 | 1.000 |",
                 "| 4 | 4.00 | 3.00 | 0.000 | 0.000 | 1.000 | 0.000 | 0.000 | 0.000 |",
                 "| against LE-LS-6 | 0.750 | 0.550 | 2 | +0.200 | 0.071 |",
                 "| against skills LE-LS | 0.750 | 0.580 | 2 | +0.170 | 0.112 |"):
        assert line in text.splitlines(), line
    empty = study.table(study.measure(ROWS, dict.fromkeys(ROWS), dict.fromkeys(ROWS, str(tmp_path / "no")), {}))
    assert "LE-LS-N6: not run yet." in empty.splitlines() and "| 2 x 5 |" not in empty
    assert "LE-LS-N6-faithful: not run yet." in empty.splitlines()


def test_the_report_of_the_committed_runs_is_the_documents(tmp_path, monkeypatch, capsys):
    """The report of the committed runs writes the committed tables and report.json, and a figure per question;
    with nothing finished, every panel says so."""
    monkeypatch.chdir(ROOT)
    out = tmp_path / "out"
    out.mkdir()
    for name in ("EXT-LS", "EXT-LS-whole", "EXT-LS-faithful"):  # the tests from scratch, in the table's folder
        os.symlink(os.path.abspath(os.path.join(study.OUT, name)), out / name)
    document = tmp_path / "FUTURE_WORK.md"
    document.write_text(f"intro\n{study.TABLE_START}\nold\n{study.TABLE_END}\nend\n")
    (tmp_path / "reproduction").mkdir()  # the reproduction's report beside the document, as in docs/
    shutil.copy(os.path.join("docs", "reproduction", "summary.json"), tmp_path / "reproduction")
    assert dataclasses.replace(study.TABLE, document=str(document), out=str(out)).report() == 0
    with open(study.DOCUMENT) as f:
        committed = f.read()
    tables = committed[committed.index(study.TABLE_START):committed.index(study.TABLE_END)]
    assert document.read_text() == f"intro\n{tables}{study.TABLE_END}\nend\n"
    assert "| EV-LS | EV-LS | (a) evolved evaluators, gamma V(x_t) - V(x_{t-1}) | 5 x 100 | 0.766 |" in tables
    with open(out / "report.json") as f, open(os.path.join(study.OUT, "report.json")) as g:
        written, saved = json.load(f), json.load(g)
    assert written["verdicts"] == saved["verdicts"] and written["learning_values"] == saved["learning_values"]
    assert [r["evolution"] for r in written["rows"]] == [r["evolution"] for r in saved["rows"]]
    assert all(os.path.getsize(out / f"question_{q}.png") > 10_000 for q in "abcd")
    assert "20 of 20 rows have finished stages" in capsys.readouterr().out
    nothing = study.measure(ROWS, dict.fromkeys(ROWS), dict.fromkeys(ROWS, str(tmp_path / "no")), {})
    assert all(os.path.getsize(study.figure(nothing, q, str(tmp_path / f"{q}.png"))) > 5_000 for q in "abcd")


def test_criteria_are_easier_when_much_faster_and_higher():
    """(a): LE-LS plateaus at 7 against EE-LS's 50 (<= 25) and ends 0.34 higher (se 0.051): easier; EV-LS at 30
    (> 25) and 0.1 higher with se 0.071 (< 2 se): not easier."""
    from imrl_jax.analysis import further_claims

    actors = dict(plateau=50, final_per_seed=[0.4, 0.5], fresh=0.4, genes=222)
    le_ls = dict(plateau=7, final_per_seed=[0.8, 0.78], fresh=0.7, genes=111)
    ev_ls = dict(plateau=30, final_per_seed=[0.5, 0.6], fresh=None, genes=111)
    both = further_claims.claim_criteria_easier({"LE-LS": le_ls, "EV-LS": ev_ls}, actors)
    assert both["verdict"] == "partly" and both["numbers"]["compared"]["LE-LS"]["much_faster"]
    assert both["numbers"]["compared"]["LE-LS"]["standard_error"] == pytest.approx(0.0026 ** 0.5)
    assert not both["numbers"]["compared"]["EV-LS"]["higher"]
    assert "LE-LS (111 genes): plateau 7, final 0.790, fresh 0.700; d = +0.340 +- 0.051 (easier)" in both["measured"]
    assert further_claims.claim_criteria_easier({"LE-LS": le_ls}, actors)["verdict"] == "holds"
    assert further_claims.claim_criteria_easier({"EV-LS": ev_ls}, actors)["verdict"] == "does not hold"
    assert further_claims.claim_criteria_easier({"LE-LS": le_ls}, None)["verdict"] == "n/a"


def test_motivation_is_needed_when_skills_learn_much_faster_and_end_higher():
    """(b): from the start 0.5 (LE-LS's first bin) the level is 0.5 + 0.9 x (0.6 - 0.5) = 0.59; LE-LS reaches it at
    2,000 cycles, EXT-LS at 4,000 (2x): much faster, and 0.85 against 0.6 is in order; with EXT-LS at 0.6 by 2,000
    only the steady state differs; an EXT-LS that ends below LE-LS's start never reaches a level."""
    from imrl_jax.analysis import further_claims

    steps = [1000, 2000, 3000, 4000]
    skilled = dict(steps=steps, mean=[0.5, 0.8, 0.85, 0.85], per_run=[0.84, 0.86])
    extrinsic = dict(steps=steps, mean=[0.1, 0.3, 0.5, 0.6], per_run=[0.59, 0.61])
    claim = further_claims.claim_motivation_needed(extrinsic, skilled, dict(per_run=[0.4, 0.4]))
    assert claim["verdict"] == "holds" and claim["numbers"]["cycles"] == {"LE-LS": 2000, "EXT-LS": 4000}
    assert claim["numbers"]["level"] == pytest.approx(0.59) and claim["numbers"]["against_flat"] == "in order"
    # At chance and below where LE-LS starts (as at 0.03 against 0.32): it never reaches; LE-LS reaches 0.5 + 0.9 x
    # (0.85 - 0.5) = 0.815 at 3,000 cycles.
    flat = dict(steps=steps, mean=[0.02, 0.03, 0.0, 0.0], per_run=[0.0, 0.0])
    claim = further_claims.claim_motivation_needed(flat, skilled)
    assert claim["verdict"] == "holds" and claim["numbers"]["cycles"] == {"LE-LS": 3000, "EXT-LS": None}
    assert claim["numbers"]["level"] == pytest.approx(0.815) and "EXT-LS never" in claim["measured"]
    # Neither above the start: no speed to compare; only the steady states (in order) count.
    stuck = dict(skilled, mean=[0.5, 0.5, 0.5, 0.5], per_run=[0.5, 0.5])
    claim = further_claims.claim_motivation_needed(flat, stuck)
    assert claim["numbers"]["level"] is None and claim["verdict"] == "partly"
    quick = dict(extrinsic, mean=[0.1, 0.6, 0.6, 0.6])
    assert further_claims.claim_motivation_needed(quick, skilled)["verdict"] == "partly"
    level = dict(quick, per_run=[0.84, 0.86])  # as high and as fast: the hierarchy alone is enough
    assert further_claims.claim_motivation_needed(dict(level, mean=[0.5, 0.8, 0.85, 0.85]), skilled)["verdict"] == \
        "does not hold"
    assert further_claims.claim_motivation_needed(None, skilled)["verdict"] == "n/a"


def test_map_positions_and_which_hand_values_evolution_finds():
    """(c): positions in the genes' ranges by hand (MODEL.md's maps), then trace_lambda evolved nearer skills'
    0.98 and the speed bias nearer the paper's 0: partly; gamma, the same in both, is not judged."""
    from imrl_jax.analysis import further_claims

    assert further_claims.map_position("gamma", 0.99) == pytest.approx(0.4)  # log10(0.01) = -2 in [-3, -0.5]
    assert further_claims.map_position("trace_lambda", 0.0) == 1.0 and further_claims.map_position("eta_actor", 1e-6) == 0.0
    assert further_claims.map_position("eta_selector_actor", 0.3) == pytest.approx((4 + math.log10(0.3)) / 4)
    assert further_claims.map_position("initial_speed_bias", 4.0) == pytest.approx(0.75)
    skills = dict(trace_lambda=0.98, initial_speed_bias=4.0, gamma=0.99, childhood_length=150_000.0)
    paper = dict(skills, trace_lambda=0.0, initial_speed_bias=0.0)
    claim = further_claims.claim_hand_values(dict(trace_lambda=[0.97, 0.99], initial_speed_bias=[0.5, 1.0], gamma=[0.9],
                                          childhood_length=[100_000, 120_000]), skills, paper)
    assert claim["verdict"] == "partly"
    assert claim["numbers"]["nearer"] == {"trace_lambda": "skills", "initial_speed_bias": "paper"}
    assert "childhood length 110,000 of 150,000" in claim["measured"]
    assert further_claims.claim_hand_values(dict(trace_lambda=[0.98]), skills, paper)["verdict"] == "holds"
    assert further_claims.claim_hand_values(dict(gamma=[0.9]), skills, paper)["verdict"] == "n/a"  # nothing to tell apart
    assert further_claims.claim_hand_values({}, skills, paper)["verdict"] == "n/a"


def test_three_experts_are_enough_when_evolution_keeps_about_three_and_more_do_not_pay():
    """(d): 3.5 kept is about three; 0.81 against 0.79 is +0.02 with se 0.014 (< 2 se): no gain."""
    from imrl_jax.analysis import further_claims

    claim = further_claims.claim_three_enough([3, 4], [0.8, 0.82], [0.78, 0.8], [0.6, 0.6])
    assert claim["verdict"] == "holds" and claim["numbers"]["standard_error"] == pytest.approx(0.0002 ** 0.5)
    assert claim["numbers"]["difference_six"] == pytest.approx(0.21)
    assert further_claims.claim_three_enough([4, 5], [0.8, 0.82], [0.78, 0.8])["verdict"] == "partly"
    assert further_claims.claim_three_enough([4, 5], [0.9, 0.92], [0.78, 0.8])["verdict"] == "does not hold"
    assert further_claims.claim_three_enough(None, [0.9], [0.8])["verdict"] == "n/a"


def test_the_report_judges_each_question_from_its_rows(tmp_path):
    """The hand-made study: (d) holds (its best keep 3 experts; 0.75 against 0.58 is +0.17 with se 0.112); (a)
    does not hold so far (LE-LS 0.58 against EE-LS 0.60, plateau 2 against 0), EV-LS still running; (c) has
    nothing to tell apart (gamma and eta_actor are the same under skills and the paper)."""
    measured = study.measure(*_fake_study(tmp_path))
    verdicts = {(v["question"], v["rules"]): v for v in measured["verdicts"]}
    assert len(verdicts) == len(study.JUDGED)
    d = verdicts["d", "skills"]
    assert d["verdict"] == "holds" and d["numbers"]["kept"] == 3.0 and d["numbers"]["difference"] == pytest.approx(0.17)
    a = verdicts["a", "skills"]
    assert a["verdict"] == "does not hold" and a["missing"] == ["EV-LS", "EV-LS-diff"]
    assert verdicts["c", "skills"]["verdict"] == "n/a" and verdicts["d", "faithful"]["verdict"] == "n/a"
    b = verdicts["b", "skills, noise over 100,000 cycles"]  # 0.85 against 0.70: d 0.15 < 2 x 0.076; 0.63 not reached
    assert b["verdict"] == "does not hold" and b["numbers"]["order"] == "tied"
    assert b["numbers"]["against_flat"] == "in order"
    text = study.table(measured).splitlines()
    assert any(line.startswith("| (a) Evolving criteria") and "**does not hold** so far (not finished: EV-LS, "
               "EV-LS-diff)" in line for line in text)
    assert any(line.startswith("| (d) Three experts are enough") and "| **holds** |" in line for line in text)
