"""The claims study's tables: what each rule set runs, what it shares (and that sharing is sound), its report."""

import dataclasses
import os
import sys

import numpy as np
import pytest
from helpers import write_evolution, write_learning_test

from experiments import claims_study as study
from experiments.harness import study as S
from experiments.harness.reproduce import stage_done
from experiments.harness.study import SCALES, SCREEN
from experiments.harness.table import evolution_spec, scratch_test_key
from imrl_jax.analysis import claims


#: Where the map was measured: each rule set's run of each condition, by the owner whose folder holds it (a rule
#: set of the reproduction: ``paper/OWNER``; else ``claims/OWNER``).
MEASURED_ON = {
    "paper": ("paper/paper", "paper/paper", "paper/paper", "paper/paper"),
    "skills": ("paper/skills", "paper/skills", "paper/paper", "paper/skills"),
    "skills-clamp": ("claims/skills-clamp", "paper/skills", "paper/paper", "paper/skills"),
    "paper-selector": ("claims/paper-selector", "paper/skills", "paper/paper", "claims/skills-bias0"),
    "paper-selector-sle-test": ("claims/paper-selector", "paper/skills", "paper/paper", "claims/skills-bias0-sle-test"),
    "faithful": ("paper/faithful", "paper/skills", "paper/paper", "paper/faithful"),
    "skills-sle-test": ("paper/skills", "paper/skills", "paper/paper", "claims/skills-sle-test"),
    "skills-clamp-sle-test": ("claims/skills-clamp", "paper/skills", "paper/paper", "claims/skills-sle-test"),
    "extension-sle-test": ("claims/extension", "paper/skills", "paper/paper", "claims/skills-bias0-sle-test"),
    "skills-bias1": ("claims/skills-bias1", "paper/skills", "paper/paper", "claims/skills-bias1"),
}


def owner_of(folder: str) -> str:
    """``paper/OWNER`` or ``claims/OWNER`` of a run's or test's folder under the results."""
    return "/".join(os.path.relpath(folder, study.RESULTS).split(os.sep)[:2])


@pytest.mark.parametrize("name", MEASURED_ON)
def test_each_rule_set_finds_by_key_the_runs_the_map_was_measured_on(name):
    """The keys share a run between rule sets exactly where the map did (LE-LS, EE-LS, EE-ES, SLE)."""
    runs = study.rule_runs(study.BY_NAME[name])
    expected = dict(zip(("LE-LS", "EE-LS", "EE-ES", "SLE"), MEASURED_ON[name]))
    assert {c: owner_of(folder) for c, folder in runs.tests.items()} == expected
    assert {c: owner_of(folder) for c, folder in runs.evolutions.items()} == {c: expected[c] for c in runs.evolutions}
    assert runs.reproduction == {c: o.split("/")[1] for c, o in expected.items() if o.startswith("paper/") and c != "SLE"}


def test_the_sharing_would_catch_a_wrong_share():
    """skills' EE-LS cannot stand for paper's (the adult selector differs), nor skills' SLE for bias 0's: their
    keys differ."""
    skills, paper, bias0 = (study.rule_rows(study.BY_NAME[n]) for n in ("skills", "paper", "skills-bias0"))
    assert study.config_of(study.BY_NAME["paper"], "EE-LS").model_differences(
        study.config_of(study.BY_NAME["skills"], "EE-LS")) == ["trace_lambda", "eta_selector_actor", "eta_selector_critic"]
    assert evolution_spec(paper[1], SCALES["paper"]).key() != evolution_spec(skills[1], SCALES["paper"]).key()
    assert scratch_test_key(bias0[3], SCREEN) != scratch_test_key(skills[3], SCREEN)
    assert study.config_of(study.BY_NAME["skills-bias0"], "SLE").model_differences(
        study.config_of(study.BY_NAME["skills"], "SLE")) == ["initial_speed_bias"]


def test_the_screen_runs_only_what_no_other_run_provides():
    """Every committed run is found (nothing left to run), each run or test once; a new rule set's stages have the
    right overrides and sizes."""
    stages, scale = study.SCREEN_TABLE.all_stages()
    assert all(stage_done(s, scale) for s in stages) and len({s.out_dir for s in stages}) == len(stages)
    assert [s.name for s in stages][:3] == ["evolve skills-sle-test LE-LS", "learning test skills-sle-test LE-LS",
                                            "evolve skills-sle-test EE-LS"]
    new = dataclasses.replace(study.SCREEN_TABLE, rows=study.rule_rows(study.RuleSet(
        "mine", "skills", ("childhood_walls=clamp", "initial_speed_bias=3.0"), "", "skills", sle_noise_steps=0)))
    stages = {s.name: s for s in new.all_stages()[0]}
    evolve = new.stage_command(stages["evolve mine LE-LS"])[0]
    assert evolve[evolve.index("--preset") + 1] == "skills" and "childhood_walls=clamp" in evolve
    assert evolve[evolve.index("--seeds") + 1] == "5" and evolve[evolve.index("--task-steps") + 1] == "100000"
    sle = new.stage_command(stages["learning test mine SLE"])[0]
    assert "sle_noise_steps=0" in sle and sle[sle.index("--runs") + 1] == "5"
    test = new.stage_command(stages["learning test mine LE-LS"])[0]
    assert test[test.index("--best") + 1] == "5" and test[test.index("--tests") + 1] == "4"
    assert not stage_done(stages["evolve mine LE-LS"], SCREEN)
    assert stages["evolve mine EE-LS"].out_dir.endswith(os.path.join("paper", "skills", "evolve", "EE-LS"))


def test_the_faithful_row_is_the_reproductions_and_the_screens_closest_row_at_full_scale():
    """Its lives are paper-selector-sle-test's, at the paper's sizes."""
    faithful, screened = study.BY_NAME["faithful"], study.BY_NAME["paper-selector-sle-test"]
    for condition in ("LE-LS", "SLE"):
        assert study.config_of(faithful, condition).model_differences(study.config_of(screened, condition)) == []


def test_the_screen_and_claim_8_are_two_studies_of_one_module():
    """``run all`` runs the screen, then the reproduction, then claim 8; ``--report`` writes each one's report."""
    found = S.studies()
    assert found["claims-screen"].command() == [sys.executable, "-m", "experiments.claims_study", "screen"]
    assert found["claims-experts"].command(report=True)[-2:] == ["experts", "--report"]
    experts, _ = found["claims-experts"].stages()
    assert [s.name for s in experts][:2] == ["evolve skills LE-LS 4 experts", "learning test skills LE-LS 4 experts"]
    assert not any("experts" in s.name for s in found["claims-screen"].stages()[0])


def test_shared_runs_read_the_reproduction_reports_probes():
    summary = dict(colours_followed={"skills/EE-LS": [3, 2, 3]},
                   best_individuals={"paper/EE-ES": {"fitness": 0.4, "fresh_mean_per_seed": [0.3, 0.5]}})
    owners = study.rule_runs(study.BY_NAME["paper-selector"]).reproduction  # EE-LS skills', EE-ES paper's
    assert owners == {"EE-LS": "skills", "EE-ES": "paper"}  # its LE-LS is its own: not the reproduction's
    assert study.probed("/nonexistent", None, summary, owners["EE-LS"], "EE-LS") == ([3, 2, 3], None, None)
    colours, idle, fresh = study.probed("/nonexistent", None, summary, owners["EE-ES"], "EE-ES")
    assert colours is None and idle is None and fresh["mean"] == pytest.approx(0.4)
    assert fresh["sd_over_seeds"] == pytest.approx(np.std([0.3, 0.5], ddof=1))
    assert study.probed(None, None, summary, "paper", "LE-LS") == (None, None, None)  # the report has none


def test_claim_5_under_the_whole_test_reading_is_measured_not_na():
    steps = np.arange(1, 11) * 100_000
    fast, slow = np.full(10, 0.8), np.linspace(0.1, 0.9, 10)
    curves = {"LE-LS": (steps, fast), "EE-LS": (steps, fast), "SLE": (steps, slow)}
    steady = {"LE-LS": 0.8, "EE-LS": 0.8}
    assert claims.claim_learning_speed(curves, steady, 0)["verdict"] == claims.NOT_AVAILABLE
    whole = claims.claim_learning_speed(curves, steady, 0, whole_test=True)
    # 90 % of 0.8 is 0.72: LE-LS's first bin, SLE's 9th (0.1 + 8 x 0.1 = 0.9 >= 0.72 first at bin 8: 800,000).
    assert whole["numbers"]["cycles"]["LE-LS"] == dict(level=pytest.approx(0.72), cycles=100_000, sle_cycles=800_000)
    assert whole["verdict"] == claims.HOLDS and "the whole test of 1,000,000 cycles" in whole["measured"]


def test_the_table_goes_between_its_markers(tmp_path):
    path = tmp_path / "CLAIMS.md"
    path.write_text(f"# Title\n\n{study.TABLE_START}\nstale row\n{study.TABLE_END}\n\nafter\n")
    row = {k: dict(verdict="holds" if k < 4 else "n/a", measured=f"m{k}; more") for k in range(1, 8)}
    study.write_table(str(path), study.table_markdown({"paper": dict(claims=row)}, ["paper", "skills-bias0"]), study.TABLE_START,
                      study.TABLE_END)
    text = path.read_text()
    assert "stale row" not in text and text.endswith("after\n") and text.startswith("# Title")
    lines = text.split("\n")
    paper = next(line for line in lines if line.startswith("| `paper`"))
    assert paper.split(" | ")[1] == "10x100, 10x10x10" and "**holds**: m1 |" in paper and "n/a: m7 |" in paper
    assert any(line.startswith("| `skills-bias0` | not finished") for line in lines)


def test_claim_experts_on_hand_made_numbers():
    from imrl_jax.analysis.claims import DOES_NOT, HOLDS, NOT_AVAILABLE, PARTLY
    from imrl_jax.analysis.further_claims import claim_experts

    three, same, lower = [0.40, 0.44], [0.41, 0.45], [0.20, 0.22]
    claim = claim_experts({("LE-LS", 3): three, ("LE-LS", 4): same, ("LE-LS", 6): same})
    assert claim["verdict"] == HOLDS and len(claim["numbers"]["compared"]) == 2
    entry = claim["numbers"]["compared"]["LE-LS final 6 vs 3"]
    assert entry["ratio"] == pytest.approx(0.43 / 0.42) and entry["difference"] == pytest.approx(0.01)
    assert entry["standard_error"] == pytest.approx(np.sqrt(2 * 0.04 ** 2 / 2 / 2))
    assert claim_experts({("EE-LS", 3): three, ("EE-LS", 6): lower}, {("EE-LS", 3): three, ("EE-LS", 6): same}
                         )["verdict"] == PARTLY  # the steady state unchanged, the final best halved
    assert claim_experts({("EE-LS", 3): three, ("EE-LS", 4): lower})["verdict"] == DOES_NOT
    assert claim_experts({("EE-LS", 4): same})["verdict"] == NOT_AVAILABLE  # no 3-expert run to compare with


def test_claim_8_runs_are_shared_as_the_three_expert_runs_are():
    """Claim 8's stages evolve more experts and test their own runs; paper-selector evolves its own LE-LS with more
    experts, its EE-LS is skills' (found by key: the share is sound)."""
    stages, scale = study.EXPERTS_TABLE.all_stages()
    assert [s.name for s in stages[8:]] == [
        "evolve paper-selector LE-LS 4 experts", "learning test paper-selector LE-LS 4 experts",
        "evolve paper-selector LE-LS 6 experts", "learning test paper-selector LE-LS 6 experts"]
    assert all(stage_done(s, scale) for s in stages) and stages[2].cost == 5 * 50 * 100 * 6 * 100_000  # no childhood
    evolve = study.EXPERTS_TABLE.stage_command(stages[8])[0]
    assert evolve[evolve.index("--preset") + 1] == "paper" and "num_experts=4" in evolve and "trace_lambda=0.98" in evolve
    found = study.experts_runs(study.EXPERTS_TABLE)
    assert found["paper-selector", "EE-LS", 4] == found["skills", "EE-LS", 4][:2] + ("skills",)
    assert found["paper-selector", "LE-LS", 4][2] == "paper-selector" and found["paper-selector", "EE-LS", 3][2] == "skills"
    assert found["skills", "EE-LS", 6][1].endswith(os.path.join("claims", "skills", "experts6", "test", "EE-LS"))
    selector, skills = study.BY_NAME["paper-selector"], study.BY_NAME["skills"]
    for k in study.EXPERT_COUNTS:
        own, shared = study.config_of(selector, "EE-LS", k), study.config_of(skills, "EE-LS", k)
        assert own.num_experts == k and own.model_differences(shared) == []
        assert study.config_of(selector, "LE-LS", k).model_differences(study.config_of(skills, "LE-LS", k))


def test_fresh_table_shows_the_recorded_best_beside_the_fresh_lives():
    measured = {"skills-bias0": {"fresh": {"LE-LS": dict(recorded=0.412, fresh=0.371, fresh_sd_over_seeds=0.0123,
                                                         seeds=5)}}}
    text = study.fresh_table(measured, ["paper", "skills-bias0"])
    assert text.splitlines()[2] == "| `skills-bias0` | 0.412 / 0.371 (sd 0.012, 5 seeds) | - | - |"
    assert len(text.splitlines()) == 3  # rule sets not measured are left out


def test_speed_dial_reads_claim_3_fresh_lives_and_claim_6_levels_per_bias():
    def row(le_ls, steady):
        six = claims.claim_ordering({"EE-LS": np.full(5, 0.51), "SLE": np.full(5, 0.2), "LE-LS": np.full(5, steady),
                                     "EE-ES": np.full(5, 0.37)})
        return {"3": dict(numbers=dict(le_ls=le_ls, ee_ls=0.446)), "6": six,
                "fresh": {"LE-LS": dict(fresh=le_ls - 0.06, fresh_sd_over_seeds=0.02)}}

    points = study.speed_dial({"skills": row(0.79, 0.84), "skills-bias1": row(0.58, 0.60), "paper": row(0.2, 0.2)})
    assert [p.bias for p in points] == [1.0, 4.0]  # sorted by bias; rows off the dial are left out
    assert points[0].speed == pytest.approx(1 / (1 + np.exp(-1)))  # sigmoid(1) = 0.731
    assert (points[1].le_ls_recorded, points[1].le_ls_steady, points[1].ee_ls_steady) == pytest.approx((0.79, 0.84, 0.51))
    assert points[1].le_ls_fresh == pytest.approx(0.73)


def _hand_made_run(folder, best_per_generation, steady_per_run):
    """An evolution (history.csv, config.json) with ``best_per_generation`` (generations, seeds) and its test."""
    evolve, test = folder / "evolve", folder / "test"
    best = np.asarray(best_per_generation, float)
    write_evolution(evolve, best.tolist(), {"config": {"num_generations": best.shape[0]}})
    write_learning_test(test, steady_per_run, (0.5,), 10)
    return str(evolve), str(test)


def test_claim_8_alone_measures_hand_made_runs_and_says_so_far_while_one_is_missing(tmp_path):
    """Claim 8's report: each 3-expert run against its 4- and 6-expert runs, with the sizes and the levels."""
    runs = {}
    for condition, k, level in (("LE-LS", 3, 0.8), ("LE-LS", 4, 0.72), ("LE-LS", 6, 0.4), ("EE-LS", 3, 0.5),
                                ("EE-LS", 4, 0.45)):  # EE-LS with 6 experts has not run
        runs[condition, k] = _hand_made_run(tmp_path / f"{condition}{k}", [[0.1, 0.1]] * 5 + [[level - 0.01, level + 0.01]] * 5,
                                            [level, level, level + 0.02])
    found = {("skills", c, k): (*runs.get((c, k), ("/nonexistent", "/nonexistent")), "skills")
             for c in study.EXPERT_CONDITIONS for k in (3, *study.EXPERT_COUNTS)}
    claim = study.measure_experts(study.BY_NAME["skills"], found)
    assert claim["sizes"] == {"LE-LS 3": "2x10", "LE-LS 4": "2x10", "LE-LS 6": "2x10", "EE-LS 3": "2x10", "EE-LS 4": "2x10"}
    assert claim["missing"] == ["EE-LS final 6", "EE-LS steady 6"]
    # hand-made runs have no population to live or probe again
    assert [(r["condition"], r["num_experts"], r["fresh"], r["colours"]) for r in claim["runs"]] == [
        ("LE-LS", 3, None, None), ("LE-LS", 4, None, None), ("LE-LS", 6, None, None), ("EE-LS", 3, None, None),
        ("EE-LS", 4, None, None)]
    # final best: mean of the last 5 generations, per seed; 0.72 / 0.8 = 0.9 and 0.45 / 0.5 = 0.9 are unchanged, 0.5 not
    assert claim["numbers"]["compared"]["LE-LS final 4 vs 3"]["ratio"] == pytest.approx(0.9)
    assert claim["numbers"]["compared"]["LE-LS final 6 vs 3"]["ratio"] == pytest.approx(0.5)
    assert claim["verdict"] == claims.PARTLY
    level = next(p for p in claim["levels"] if (p["condition"], p["measure"], p["num_experts"]) == ("LE-LS", "final", 4))
    assert (level["mean"], level["sd"], level["count"]) == pytest.approx((0.72, 0.01 * np.sqrt(2), 2))
    row = study.experts_table({"skills": claim}).splitlines()[2]
    assert row.startswith("| `skills` | LE-LS 3: 2x10, ") and "| partly so far (not finished: EE-LS final 6, EE-LS steady 6): " in row
    done = dict(claim, missing=[])
    assert "| partly: EE-LS final 4/3 experts 0.450/0.500 = 0.90; LE-LS final 4/3 experts 0.720/0.800 = 0.90;" in study.experts_table({"skills": done})


def test_claim_8_alone_writes_its_table_json_and_figure_and_keeps_the_rest(tmp_path, monkeypatch, capsys):
    (tmp_path / "docs").mkdir()
    document = (f"keep\n{study.TABLE_START}\nthe map\n{study.TABLE_END}\n{study.EXPERTS_START}\nold\n{study.EXPERTS_END}\n"
                f"{study.EXPERTS_RUNS_START}\nold\n{study.EXPERTS_RUNS_END}\n")
    (tmp_path / "docs" / "CLAIMS.md").write_text(document)
    hand = dict(verdict=claims.HOLDS, measured="m", numbers={}, sizes={"LE-LS 4": "5x100"}, missing=[], runs=[],
                levels=[dict(rule="skills", condition="LE-LS", measure=m, num_experts=k, mean=0.8, sd=0.01, count=5)
                        for m in ("final", "steady") for k in (3, 4, 6)])
    monkeypatch.setattr(study, "measure_experts", lambda rule, found, summary, reproduction: dict(hand))
    table = dataclasses.replace(study.EXPERTS_TABLE, document=str(tmp_path / "docs" / "CLAIMS.md"),
                                out=str(tmp_path / "claims"), results=str(tmp_path / "results"))
    assert table.main(["--report"]) == 0
    assert capsys.readouterr().out.splitlines() == ["claim 8, skills: holds", "claim 8, paper-selector: holds"]
    text = (tmp_path / "docs" / "CLAIMS.md").read_text()
    assert text.startswith(f"keep\n{study.TABLE_START}\nthe map\n") and "| `paper-selector` | LE-LS 4: 5x100 | holds: m |" in text
    assert (tmp_path / "claims" / "claim8.json").exists() and (tmp_path / study.EXPERTS_FIGURE).stat().st_size > 10_000


def test_claim_8_runs_table_shows_each_run_once_with_its_probe():
    """A run two rule sets share (paper-selector's EE-LS is skills') is one row; what was not measured is '-'."""
    def level(rule, condition, measure, k, mean):
        return dict(rule=rule, condition=condition, measure=measure, num_experts=k, mean=mean, sd=0.01, count=5)

    def run(rule, condition, k, **probe):
        return dict(rule=rule, condition=condition, num_experts=k, size="5x100",
                    **{**dict(fresh=None, fresh_sd=None, colours=None, idle_experts=None), **probe})

    skills = dict(levels=[level("skills", "EE-LS", "final", 4, 0.344), level("skills", "EE-LS", "steady", 4, 0.378)],
                  runs=[run("skills", "EE-LS", 4, fresh=0.322, fresh_sd=0.038, colours=[0, 20, 29, 1],
                            idle_experts=1.6)])
    faithful = dict(levels=[level("paper-selector", "EE-LS", "final", 4, 0.344),
                            level("paper-selector", "LE-LS", "final", 4, 0.398)],
                    runs=[run("skills", "EE-LS", 4), run("paper-selector", "LE-LS", 4)])
    lines = study.experts_runs_table({"skills": skills, "paper-selector": faithful}).splitlines()
    assert lines[2:] == ["| skills EE-LS | 4 | 5x100 | 0.344 | 0.322 (0.038) | 0.378 (0.010) | 0/20/29/1 | 1.6 |",
                         "| paper-selector LE-LS | 4 | 5x100 | 0.398 | - | - | - | - |"]


def test_run_probe_keeps_its_probe_until_the_population_moves_on(tmp_path, monkeypatch):
    """run_probe probes each seed's best of final_population.npz once, keeps it in probe.json, probes again for
    another generation or key; without a population there is nothing to probe."""
    from experiments.harness import relive

    calls = []

    def fake_followed(config_dict, best, key):
        calls.append((best["genomes"][:, :, 0].tolist(), key))
        return [[0, -1, 2]] * best["genomes"].shape[0] * best["genomes"].shape[1]

    monkeypatch.setattr(relive, "followed_best", fake_followed)
    assert relive.run_probe(str(tmp_path), {"c": 1}) is None
    evaluated = np.arange(2 * 3 * 1, dtype=np.float32).reshape(2, 3, 1)  # 2 seeds, 3 lives, 1 gene

    def save(generation):
        np.savez(tmp_path / "final_population.npz", evaluated=evaluated, fitness=np.asarray([[0.1, 0.9, 0.5],
                 [0.3, 0.2, 0.4]]), generation=generation, seeds=np.asarray([0, 1]))

    save(3)
    first = relive.run_probe(str(tmp_path), {"c": 1}, num_best=2, key=0)
    assert calls == [([[1.0, 2.0], [5.0, 3.0]], 0)]  # each seed's two fittest, fittest first
    assert first["followed"] == [[0, -1, 2]] * 4 and first["generations"] == 3
    assert relive.run_probe(str(tmp_path), {"c": 1}, num_best=2, key=0) == first and len(calls) == 1
    relive.run_probe(str(tmp_path), {"c": 1}, num_best=2, key=1)  # another key: probed again
    save(4)
    relive.run_probe(str(tmp_path), {"c": 1}, num_best=2, key=1)  # another generation: probed again
    assert len(calls) == 3 and not (tmp_path / "probe.json.tmp").exists()


def test_a_rows_own_run_is_probed_once_for_claim_7_and_kept(tmp_path, monkeypatch):
    """measure_runs probes a row's own LE-LS (claim 7's 10 best per seed, key 0) through run_probe: kept in
    probe.json, so a second table probes nothing."""
    from experiments.harness import relive

    folder = tmp_path / "evolve" / "LE-LS"
    write_evolution(folder, [[0.4, 0.4]] * 2, {"config": {"num_generations": 2}})
    np.savez(folder / "final_population.npz", evaluated=np.zeros((2, 12, 3), np.float32),
             fitness=np.tile(np.linspace(0, 1, 12), (2, 1)), generation=2, seeds=np.asarray([0, 1]))
    calls = []

    def fake_followed(config_dict, best, key):
        calls.append((best["genomes"].shape, key))
        return [[0, 1, 2], [0, -1, 0]] * 10  # 20 individuals: 3 colours, then 1

    monkeypatch.setattr(relive, "followed_best", fake_followed)
    monkeypatch.setattr(relive, "fresh_fitness", lambda c, b, n, s: dict(mean=np.asarray([0.3, 0.35]),
                                                                         sd=np.asarray([0.01, 0.02])))
    runs = study.RowRuns({"LE-LS": str(folder)}, {}, {})
    first = study.measure_runs("row", runs, {})
    assert calls == [((2, 10, 3), 0)] and (folder / "probe.json").exists()
    assert first["fresh"]["LE-LS"] == pytest.approx(dict(recorded=0.4, fresh=0.325, fresh_sd_over_seeds=np.std(
        [0.3, 0.35], ddof=1), seeds=2))
    assert "LE-LS 0/10/0/10" in first["claims"][7]["measured"]  # 10 follow one colour, 10 all three
    study.measure_runs("row", runs, {})
    assert len(calls) == 1
