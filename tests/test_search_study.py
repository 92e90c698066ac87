"""The search study as a table: each strategy evolves each condition under skills, then its best are tested; the
GA's rows are the reproduction's runs; the claims are judged per strategy."""

import json
import os

import numpy as np
import pytest
from helpers import ROOT, relocated, write_evolution, write_learning_test

from experiments import search as study
from experiments.harness.reproduce import stage_done
from experiments.harness.table import evolution_spec
from imrl_jax.analysis.claims import final_best, plateau_generation

RESULTS = os.path.join("experiments", "results")


@pytest.fixture
def at_root(monkeypatch):
    """The study's folders are relative to the repository's root, where its commands run."""
    monkeypatch.chdir(ROOT)


def test_the_plan_finds_every_committed_run_and_evolves_each_row_with_its_strategy(at_root):
    stages, scale = study.all_stages()
    assert len(stages) == 18 and [s for s in stages if not stage_done(s, scale)] == []  # nothing left to run
    evolutions = study.TABLE.evolutions()
    assert evolutions["ga-EE-LS"] == os.path.join(RESULTS, "paper", "skills", "evolve", "EE-LS")
    assert evolutions["ga-EE-ES"] == os.path.join(RESULTS, "paper", "paper", "evolve", "EE-ES")  # shared by presets
    assert evolutions["snes-LE-LS"] == os.path.join(RESULTS, "search", "snes", "LE-LS", "evolve")
    assert study.TABLE.tests()["sep_cma_es-EE-ES"] == os.path.join(RESULTS, "search", "sep_cma_es", "EE-ES", "test")
    by_name = {s.name: s for s in stages}
    evolve = study.TABLE.stage_command(by_name["evolve sep_cma_es-LE-LS"])[0]
    assert evolve[evolve.index("--strategy") + 1] == "sep_cma_es" and evolve[evolve.index("--cond") + 1] == "LE-LS"
    assert evolve[evolve.index("--preset") + 1] == "skills" and evolve[evolve.index("--seeds") + 1] == "5"
    assert "--strategy" not in study.TABLE.stage_command(by_name["evolve ga-LE-LS"])[0]
    test = study.TABLE.stage_command(by_name["learning test snes-EE-ES"])[0]
    assert test[test.index("-m") + 2] == os.path.join(RESULTS, "search", "snes", "EE-ES", "evolve")
    assert by_name["evolve snes-EE-ES"].cost == 5 * 50 * 100 * 6 * 100_000
    assert by_name["evolve sep_cma_es-LE-LS"].cost == 5 * 50 * 100 * (150_000 + 600_000)
    assert [study.strategy_of(r) for r in study.TABLE.rows[::3]] == ["ga", "sep_cma_es", "snes"]


def _row(strategy, condition, best_per_seed=None, per_run=None, generations=6):
    """A measured row as the report builds it, from hand-made curves (a seed per list) and a test's runs."""
    row = dict(strategy=strategy, condition=condition, generations=0, finished=False)
    if best_per_seed is not None:
        best = np.asarray([c[:min(map(len, best_per_seed))] for c in best_per_seed]).T
        final = final_best(best)
        row.update(generations=len(best), seeds=best.shape[1], finished=len(best) >= generations)
        if row["finished"]:
            row.update(final_best_mean=float(final.mean()), final_best_sd=float(final.std()),
                       final_best_per_seed=list(final), plateau_generation=plateau_generation(best.mean(1)))
    if per_run is not None:
        row.update(steady_mean=float(np.mean(per_run)), steady_sd=float(np.std(per_run)), test_runs=len(per_run),
                   steady_per_run=list(per_run))
    return row


def test_the_claims_are_judged_per_strategy_on_finished_evolutions_only():
    """Hand-made GA and SNES rows of 6 generations: the verdicts and the tables."""
    rows = [_row("ga", "EE-LS", [[0.0, 0.1, 0.2, 0.3, 0.4, 0.5], [0.2, 0.3, 0.4, 0.5, 0.6, 0.7]], [0.5, 0.52, 0.48]),
            _row("ga", "EE-ES", [[0.1] * 3 + [0.5] * 3, [0.1] * 3 + [0.3] * 3], [0.1, 0.1, 0.1]),
            _row("ga", "LE-LS", [[0.5] + [0.8] * 5, [0.5] + [0.76] * 5], [0.45, 0.45, 0.45]),
            _row("snes", "EE-LS", [[0.9] * 6, [0.8] * 6], [0.6, 0.7, 0.8]),
            _row("snes", "EE-ES", [[0.3] * 4, [0.3] * 3]),  # running: generation 3 half written
            _row("snes", "LE-LS", [[0.7] * 6, [0.7] * 6])]
    ee_ls = rows[0]  # seeds' last 5: 0.3 and 0.5; mean curve 0.1..0.6 reaches 0.9 x 0.4 at generation 3
    assert abs(ee_ls["final_best_mean"] - 0.4) < 1e-12 and ee_ls["plateau_generation"] == 3
    paths = {"ga": dict(stereotypy_per_task=[0.9, 0.5], speed=2.0)}  # the GA's EE-ES: one circular task of two
    claims = study.judge(study.COMPARED, rows, [0.4, 0.4, 0.4], paths)
    ga, snes = claims["ga"], claims["snes"]
    assert ga[1]["verdict"] == "holds"  # plateau LE-LS 1 against 3 and 3
    assert ga[2]["verdict"] == "holds"  # sd 0.02 at most half of 0.1 and of 0.06
    assert ga[3]["verdict"] == "does not hold"  # 0.40 against 0.78
    assert ga[4]["verdict"] == "partly"  # 0.28 / 0.78 = 0.36 not about, one circular task
    assert ga[4]["numbers"]["circular_tasks"] == 1 and ga[4]["path_probe"]
    assert ga[6]["verdict"] == "partly" and ga[6]["numbers"]["pairs_held"] == 5  # SLE 0.40 < LE-LS 0.45: reversed
    # SNES: 0.85 against 0.70, se = sqrt(0.005 / 2) = 0.05 < 0.15 / 2; its EE-ES is running, so claims 1, 2, 4 wait
    assert snes[3]["verdict"] == "holds" and abs(snes[3]["numbers"]["standard_error"] - 0.05) < 1e-12
    assert [snes[n]["verdict"] for n in (1, 2, 4, 6)] == ["n/a"] * 4 and not snes[4]["path_probe"]
    rows[0].update(fresh_mean=0.35, fresh_sd=0.0707, colours_mean=2.0, specialised_share=0.25)
    sle = dict(steady_mean=0.4, steady_sd=0.0, test_runs=3)
    text = study.table(dict(rows=rows, claims=claims, sle=sle))
    assert "| ga | EE-LS | 0.350 (0.071) | 2.00 (0.25) |" in text and "| ga | LE-LS | - | - |" in text  # none kept
    assert "| snes | **holds** | EE-LS 0.850 vs LE-LS 0.700: d = +0.150, se = 0.050 |" in text
    assert "path: the GA's relived best EE-ES |" in text and "path: not measured |" in text
    assert "sep_cma_es" not in text and "0.400 +- 0.000 over 3 runs" in text


def test_the_report_measures_the_committed_runs_as_the_document_states(at_root, tmp_path):
    """The committed runs' numbers (docs/SEARCH.md): the GA's from the reproduction, each strategy's own relived."""
    measured = study.TABLE.measure_search()
    rows = {(r["strategy"], r["condition"]): r for r in measured["rows"]}
    assert len(rows) == 9 and all(r["finished"] for r in rows.values())
    ga = rows["ga", "EE-LS"]
    assert (ga["seeds"], round(ga["final_best_mean"], 3), round(ga["final_best_sd"], 3)) == (10, 0.446, 0.039)
    assert (round(ga["fresh_mean"], 3), ga["colours_mean"], ga["plateau_generation"]) == (0.412, 1.51, 50)
    snes = rows["snes", "EE-LS"]
    assert (snes["seeds"], round(snes["final_best_mean"], 3), snes["probed"], snes["test_runs"]) == (5, 0.600, 50, 5)
    assert "colours_mean" not in rows["snes", "EE-ES"] and rows["sep_cma_es", "LE-LS"]["colours_mean"] == 2.36
    assert (round(measured["sle"]["steady_mean"], 3), measured["sle"]["test_runs"]) == (0.400, 10)
    assert sorted(measured["paths"]) == ["ga", "sep_cma_es", "snes"]  # each strategy's best EE-ES relived
    verdicts = {s: [c[n]["verdict"] for n in study.CLAIM_NUMBERS] for s, c in measured["claims"].items()}
    assert verdicts == {s: ["holds", "holds", "does not hold", "does not hold", "does not hold"]
                        for s in study.COMPARED}
    assert abs(measured["claims"]["snes"][3]["numbers"]["difference"] + 0.192) < 5e-4
    assert os.path.getsize(study.claims_figure(measured, str(tmp_path / "claims.png"))) > 10_000
    assert os.path.getsize(study.TABLE.figure(study.TABLE.measure(), str(tmp_path / "search.png"))) > 10_000


def test_run_path_relives_the_fittest_once_until_the_population_moves_on(tmp_path, monkeypatch):
    """run_path relives the fittest genome of final_population.npz's last generation once and keeps its path in
    path.json; a later generation is relived again; without a population there is nothing to relive."""
    import numpy as np

    from experiments.harness import relive

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


def test_a_running_evolution_is_drawn_but_not_measured_and_its_claims_wait(tmp_path):
    """Made-up runs for every row, SNES's EE-ES stopped at 40 of 100 generations: it is a row of the report without
    a final best or a test, SNES's claims that need it are n/a, the finished strategies' are judged."""
    table = relocated(study.TABLE, tmp_path)
    for row in table.rows:
        sizes, spec = table.scale_of(row), evolution_spec(row, table.scale_of(row))
        generations = 40 if row.name == "snes-EE-ES" else sizes["generations"]
        write_evolution(table.evolutions()[row.name], [[0.5 + 0.01 * s for s in range(len(spec.seeds))]] * generations,
                        dict(config=spec.config.to_dict(), seeds=list(spec.seeds), search=json.loads(spec.search)),
                        seeds=spec.seeds)
        if generations == sizes["generations"]:
            write_learning_test(table.tests()[row.name], [0.4, 0.5])
    measured = table.measure_search()
    rows = {(r["strategy"], r["condition"]): r for r in measured["rows"]}
    running, finished = rows["snes", "EE-ES"], rows["snes", "EE-LS"]
    assert (running["generations"], running["seeds"], running["finished"]) == (40, 5, False)
    assert "final_best_mean" not in running and "steady_mean" not in running
    assert finished["finished"] and finished["final_best_mean"] == pytest.approx(0.52)  # seeds 0.50 to 0.54
    assert finished["steady_mean"] == pytest.approx(0.45) and rows["ga", "EE-LS"]["seeds"] == 10
    claims = measured["claims"]
    assert [claims["snes"][n]["verdict"] for n in (1, 2, 4)] == ["n/a"] * 3  # each needs the running EE-ES
    assert claims["sep_cma_es"][1]["verdict"] != "n/a" and claims["snes"][3]["verdict"] == "does not hold"  # d = 0
    assert measured["sle"] is None and claims["ga"][6]["verdict"] == "n/a"  # SLE's test not made here
    assert table.report() == 0
    assert "| snes-EE-ES | EE-ES | skills | 5 | 40 of 100 | running | - | - |" in open(table.document).read()
