"""The search study's plan: each strategy evolves each condition under skills, then its best are tested."""

import json

from experiments import search as study


def test_plan_evolves_each_row_with_its_strategy_and_tests_its_own_run():
    rows = [study.BY_NAME["snes-EE-ES"], study.BY_NAME["sep_cma_es-LE-LS"]]
    stages = study.plan(rows)
    assert [s.name for s in stages] == ["evolve snes-EE-ES", "learning test snes-EE-ES",
                                        "evolve sep_cma_es-LE-LS", "learning test sep_cma_es-LE-LS"]
    evolve = study.stage_command(stages[2])[0]
    assert evolve[evolve.index("--strategy") + 1] == "sep_cma_es" and evolve[evolve.index("--cond") + 1] == "LE-LS"
    assert evolve[evolve.index("--preset") + 1] == "skills" and evolve[evolve.index("--seeds") + 1] == "5"
    test = study.stage_command(stages[1])[0]
    assert test[test.index("-m") + 2].endswith("snes/EE-ES/evolve")
    assert stages[0].cost == 5 * 50 * 100 * 6 * 100_000 and stages[2].cost == 5 * 50 * 100 * (150_000 + 600_000)


def test_unknown_rows_are_refused_and_a_strategy_selects_its_rows(capsys):
    assert study.main(["--only", "snes,cma"]) == 2
    assert "unknown strategy or row 'cma'" in capsys.readouterr().err
    assert study.main(["--only", "snes", "--list"]) == 0
    printed = capsys.readouterr().out.splitlines()
    assert len(printed) == 6 and all("snes" in line for line in printed)


def _fake_evolution(folder, best_per_seed):
    """An evolution's history.csv as the report reads it: a row per generation and seed (a short seed: unfinished)."""
    folder.mkdir(parents=True)
    rows = [f"{g},{seed},{v},0.0,0.0" for seed, curve in enumerate(best_per_seed) for g, v in enumerate(curve)]
    (folder / "history.csv").write_text("generation,seed,best,mean,std\n" + "\n".join(rows) + "\n")


def _fake_test(folder, per_run):
    """A finished learning test as the report reads it: steady.json and curve.csv."""
    folder.mkdir(parents=True)
    (folder / "steady.json").write_text(json.dumps(dict(steady_per_run=list(per_run), pairs_both_ways=0.5)))
    (folder / "curve.csv").write_text("bin,end_step,mean,sd_over_runs\n0,1000,0.1,0.01\n1,2000,0.3,0.01\n")


def test_report_measures_each_strategy_and_judges_its_claims(tmp_path):
    """Hand-made GA and SNES runs of 6 generations: final best, plateau, steady state and verdicts; tables, figure."""
    reproduction, out = tmp_path / "paper", tmp_path / "search"
    _fake_evolution(reproduction / "skills" / "evolve" / "LE-LS", [[0.5] + [0.8] * 5, [0.5] + [0.76] * 5])
    _fake_evolution(reproduction / "skills" / "evolve" / "EE-LS", [[0.0, 0.1, 0.2, 0.3, 0.4, 0.5],
                                                                   [0.2, 0.3, 0.4, 0.5, 0.6, 0.7]])
    _fake_evolution(reproduction / "paper" / "evolve" / "EE-ES", [[0.1] * 3 + [0.5] * 3, [0.1] * 3 + [0.3] * 3])
    _fake_test(reproduction / "skills" / "test" / "EE-LS", [0.5, 0.52, 0.48])
    _fake_test(reproduction / "skills" / "test" / "SLE", [0.4, 0.4, 0.4])
    _fake_test(reproduction / "skills" / "test" / "LE-LS", [0.45, 0.45, 0.45])
    _fake_test(reproduction / "paper" / "test" / "EE-ES", [0.1, 0.1, 0.1])
    _fake_evolution(out / "snes" / "EE-LS" / "evolve", [[0.9] * 6, [0.8] * 6])
    _fake_evolution(out / "snes" / "LE-LS" / "evolve", [[0.7] * 6, [0.7] * 6])
    _fake_evolution(out / "snes" / "EE-ES" / "evolve", [[0.3] * 4, [0.3] * 3])  # running: generation 3 half written
    _fake_test(out / "snes" / "EE-LS" / "test", [0.6, 0.7, 0.8])
    summary = tmp_path / "summary.json"  # the GA's relived EE-ES: one circular task of two
    summary.write_text(json.dumps(dict(best_individuals={"paper/EE-ES": dict(stereotypy_per_task=[0.9, 0.5],
                                                                             speed=2.0),
                                                         "skills/EE-LS": dict(fresh_mean_per_seed=[0.3, 0.4])},
                                   colours_followed={"skills/EE-LS": [3, 2, 1, 2]})))
    measured = study.measure(str(out), str(reproduction), str(summary), generations=6)
    rows = {(r["strategy"], r["condition"]): r for r in measured["rows"]}
    assert sorted(rows) == [("ga", "EE-ES"), ("ga", "EE-LS"), ("ga", "LE-LS"),
                            ("snes", "EE-ES"), ("snes", "EE-LS"), ("snes", "LE-LS")]  # Sep-CMA-ES: nothing run
    ee_ls = rows["ga", "EE-LS"]  # seeds' last 5: 0.3 and 0.5; mean curve 0.1..0.6 reaches 0.9 x 0.4 at generation 3
    assert abs(ee_ls["final_best_mean"] - 0.4) < 1e-12 and abs(ee_ls["final_best_sd"] - 0.1) < 1e-12
    assert ee_ls["plateau_generation"] == 3 and rows["ga", "LE-LS"]["plateau_generation"] == 1
    assert abs(rows["ga", "EE-ES"]["final_best_mean"] - 0.28) < 1e-12  # (0.1 + 0.1 + 3 x 0.5) / 5, (0.2 + 0.9) / 5
    assert abs(rows["ga", "LE-LS"]["final_best_sd"] - 0.02) < 1e-12
    assert rows["snes", "EE-ES"]["generations"] == 3 and not rows["snes", "EE-ES"]["finished"]
    assert "final_best_mean" not in rows["snes", "EE-ES"]
    assert abs(rows["snes", "EE-LS"]["steady_mean"] - 0.7) < 1e-12 and rows["snes", "EE-LS"]["test_runs"] == 3
    ga, snes = measured["claims"]["ga"], measured["claims"]["snes"]
    assert ga[1]["verdict"] == "holds"  # plateau LE-LS 1 against 3 and 3
    assert ga[2]["verdict"] == "holds"  # sd 0.02 at most half of 0.1 and of 0.06
    assert ga[3]["verdict"] == "does not hold"  # 0.40 against 0.78
    assert ga[4]["verdict"] == "partly"  # 0.28 / 0.78 = 0.36 not about, one circular task
    assert ga[4]["numbers"]["circular_tasks"] == 1 and ga[4]["path_probe"]
    assert ga[6]["verdict"] == "partly" and ga[6]["numbers"]["pairs_held"] == 5  # SLE 0.40 < LE-LS 0.45: reversed
    # SNES: 0.85 against 0.70, se = sqrt(0.005 / 2) = 0.05 < 0.15 / 2; its EE-ES is running, so claims 1, 2, 4 wait
    assert snes[3]["verdict"] == "holds" and abs(snes[3]["numbers"]["standard_error"] - 0.05) < 1e-12
    assert [snes[n]["verdict"] for n in (1, 2, 4, 6)] == ["n/a"] * 4 and not snes[4]["path_probe"]
    text = study.table(measured)
    assert "| ga | EE-LS | 2 | 6 | 0.400 | 0.100 | 0.350 (0.071) | 3 | 2.00 (0.25) | 3 | 0.500 | 0.016 |" in text
    assert "| ga | LE-LS | 2 | 6 | 0.780 | 0.020 | - | 1 | - | 3 | 0.450 | 0.000 |" in text  # no probe kept
    assert "| snes | EE-ES | 2 | 3 of 6 | - | - | - | - | - | - | - | - |" in text
    assert "| snes | EE-LS | 2 | 6 | 0.850 | 0.050 | - | 0 | - | 3 | 0.700 | 0.082 |" in text  # no population kept
    assert "| snes | **holds** | EE-LS 0.850 vs LE-LS 0.700: d = +0.150, se = 0.050 |" in text
    assert "sep_cma_es" not in text and "0.400 +- 0.000 over 3 runs" in text
    assert study.figure(measured, str(tmp_path / "search.png")) and (tmp_path / "search.png").stat().st_size > 0
    document = tmp_path / "SEARCH.md"
    document.write_text(f"intro\n{study.TABLE_START}\nold\n{study.TABLE_END}\nend\n")
    assert study.report(str(out), str(document), str(reproduction), str(summary)) == 0  # 100 generations: all running
    written = document.read_text()
    assert "old" not in written and written.startswith("intro\n") and written.endswith(f"{study.TABLE_END}\nend\n")
    assert json.loads((out / "report.json").read_text())["claims"]["ga"]["3"]["verdict"] == "n/a"


def test_a_strategys_own_runs_are_relived_for_claim_4_and_probed_for_their_experts(tmp_path, monkeypatch):
    """A strategy's finished EE-ES is relived for claim 4's path (run_path on its run directory): with one circular
    task of six and a fitness ratio of 0.5, the claim holds partly, and the table names the path's source; its
    EE-LS and LE-LS experts are probed (run_probe)."""
    from experiments import relive

    reproduction, out = tmp_path / "paper", tmp_path / "search"
    for condition, value in (("EE-ES", 0.4), ("LE-LS", 0.8), ("EE-LS", 0.5)):
        _fake_evolution(out / "snes" / condition / "evolve", [[value] * 6, [value] * 6])
    asked = []

    def fake_path(run_dir, config_dict=None):
        asked.append(run_dir)
        return dict(stereotypy_per_task=[0.9] + [0.5] * 5, speed=2.0)

    probed = []

    def fake_probe(run_dir, config_dict=None):
        probed.append(run_dir)
        return dict(followed=[[0, 1, 2], [0, -1, 2]])  # 3 colours and 2

    monkeypatch.setattr(relive, "run_path", fake_path)
    monkeypatch.setattr(relive, "run_probe", fake_probe)
    measured = study.measure(str(out), str(reproduction), str(tmp_path / "none.json"), generations=6)
    assert sorted(probed) == [str(out / "snes" / c / "evolve") for c in ("EE-LS", "LE-LS")]  # EE-ES has no learning
    ee_ls = next(r for r in measured["rows"] if r["condition"] == "EE-LS")
    assert (ee_ls["colours_mean"], ee_ls["specialised_share"], ee_ls["probed"]) == (2.5, 0.5, 2)
    claim = measured["claims"]["snes"][4]
    assert asked == [str(out / "snes" / "EE-ES" / "evolve")]
    assert claim["path_probe"] and claim["numbers"]["circular_tasks"] == 1 and claim["verdict"] == "partly"
    assert "path: its relived best EE-ES |" in study.table(measured)


def test_run_path_relives_the_fittest_once_until_the_population_moves_on(tmp_path, monkeypatch):
    """run_path relives the fittest genome of final_population.npz's last generation once and keeps its path in
    path.json; a later generation is relived again; without a population there is nothing to relive."""
    import numpy as np

    from experiments import relive

    calls = []

    def fake_relive(config_dict, best):
        calls.append((best["genomes"][:, 0, 0].tolist(), best["fitness"][:, 0].tolist()))
        return dict(stereotypy_per_task=[0.8] * 6, speed=1.5, seed=1, fitness=0.4, relived_fitness=0.4)

    monkeypatch.setattr(relive, "relive_best", fake_relive)
    assert relive.run_path(str(tmp_path), {"c": 1}) is None
    evaluated = np.arange(2 * 3 * 1, dtype=np.float32).reshape(2, 3, 1)

    def save(generation):
        np.savez(tmp_path / "final_population.npz", evaluated=evaluated, fitness=np.asarray([[0.1, 0.9, 0.5],
                 [0.3, 0.2, 0.4]]), generation=generation, seeds=np.asarray([0, 1]))

    save(5)
    first = relive.run_path(str(tmp_path), {"c": 1})
    assert calls == [([1.0, 5.0], [0.9, 0.4])]  # each seed's fittest
    assert first["stereotypy_per_task"] == [0.8] * 6 and first["best_seed"] == 1 and first["generations"] == 5
    assert relive.run_path(str(tmp_path), {"c": 1}) == first and len(calls) == 1
    save(6)
    assert relive.run_path(str(tmp_path), {"c": 1})["generations"] == 6 and len(calls) == 2
