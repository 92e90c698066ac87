"""The report's claim rules on hand-made numbers (imrl_jax.analysis.claims); the report of a made-up reproduction's runs."""

import json
import math
import os

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from experiments.harness import reproduce
from experiments.report import run, share_probes, shared_once
from experiments.reproduction import ReproductionTable, variant_rows
from experiments.harness.table import evolution_spec
from imrl_jax.analysis import claims
from imrl_jax.analysis.claims import DOES_NOT, HOLDS, NOT_AVAILABLE, PARTLY
from imrl_jax import conditions


def test_measures():
    best = np.array([[0.1, 0.2], [0.5, 0.6], [0.8, 0.8], [0.9, 1.0]])  # (generations, seeds)
    np.testing.assert_allclose(claims.final_best(best, last=2), [0.85, 0.9])
    # final value of the mean curve (0.15, 0.55, 0.8, 0.95) over the last 2 = 0.875; 90 % = 0.7875
    assert claims.plateau_generation(best.mean(1), 0.9, last=2) == 2
    assert claims.plateau_generation(np.zeros(4)) is None
    assert claims.first_reach([10, 20, 30], [0.1, 0.5, 0.4], 0.45) == 20
    assert claims.first_reach([10, 20, 30], [0.1, 0.5, 0.4], 0.6) is None
    before = np.zeros(6)
    after = np.radians([10, 10, 10, -10, 0.5, 90])  # the last step is a reset, 0.5 deg is no turn
    assert claims.turn_consistency(before, after, [0, 0, 0, 0, 0, 1]) == pytest.approx(0.75)
    assert claims.turn_consistency(np.radians([359.0]), np.radians([3.0]), [0]) == 1.0  # across 0: a left turn
    assert claims.mean_speed([[0, 0], [0, 0]], [[3, 4], [9, 9]], [0, 1]) == 5.0


def test_specialisation_score():
    shares = np.array([[0.8, 0.1, 0.0, 0.1], [0.1, 0.6, 0.1, 0.2], [0.0, 0.1, 0.7, 0.2]])
    assert claims.specialisation_score(shares, [100, 100, 100]) == (3, ["red", "green", "blue"])
    assert claims.specialisation_score(shares[[0, 0, 2]], [100, 100, 100]) == (2, ["red", "red", "blue"])
    assert claims.specialisation_score(shares, [100, 100, 2])[1] == ["red", "green", None]  # too little control
    assert claims.specialisation_score(np.full((3, 4), np.nan), [0, 0, 0])[0] == 0


def test_claims_1_to_4():
    assert claims.claim_evolvability({"LE-LS": 5, "EE-LS": 30, "EE-ES": 10})["verdict"] == HOLDS
    assert claims.claim_evolvability({"LE-LS": 6, "EE-LS": 30, "EE-ES": 10})["verdict"] == PARTLY  # 2 x 6 > 10
    assert claims.claim_evolvability({"LE-LS": 12, "EE-LS": 30, "EE-ES": 10})["verdict"] == PARTLY
    assert claims.claim_evolvability({"LE-LS": 30, "EE-LS": 30, "EE-ES": 10})["verdict"] == DOES_NOT
    assert claims.claim_evolvability({"LE-LS": None, "EE-LS": 30, "EE-ES": 10})["verdict"] == NOT_AVAILABLE

    assert claims.claim_reliability({"LE-LS": 0.025, "EE-LS": 0.1, "EE-ES": 0.05})["verdict"] == HOLDS
    assert claims.claim_reliability({"LE-LS": 0.04, "EE-LS": 0.1, "EE-ES": 0.05})["verdict"] == PARTLY  # half of one
    assert claims.claim_reliability({"LE-LS": 0.07, "EE-LS": 0.1, "EE-ES": 0.08})["verdict"] == PARTLY  # smaller
    assert claims.claim_reliability({"LE-LS": 0.07, "EE-LS": 0.1, "EE-ES": 0.05})["verdict"] == DOES_NOT
    assert claims.claim_reliability({"LE-LS": 0.2, "EE-LS": 0.1, "EE-ES": 0.05})["verdict"] == DOES_NOT

    # d = 0.2; sd (ddof 1) 0.1 each over 4 seeds: se = sqrt(2 * 0.01 / 4) = 0.0707; 2 se = 0.141
    le = np.array([0.5 - 0.1 * math.sqrt(3) / 2 * s for s in (1, -1, 1, -1)])  # mean 0.5, sd (ddof 1) 0.1
    ee = le + 0.2
    claim = claims.claim_ee_ls_higher(ee, le)
    assert claim["verdict"] == HOLDS
    assert claim["numbers"]["standard_error"] == pytest.approx(math.sqrt(2 * 0.01 / 4))
    assert claims.claim_ee_ls_higher(le + 0.1, le)["verdict"] == PARTLY
    assert claims.claim_ee_ls_higher(le - 0.01, le)["verdict"] == DOES_NOT

    one_circle = [0.95, 0.55, 0.5, 0.6, None, 0.55]  # a circle in task 1 only: its mean, 0.63, is below 0.75
    assert claims.claim_ee_es_about(0.45, 0.5, one_circle)["verdict"] == HOLDS  # ratio 0.9
    assert claims.claim_ee_es_about(0.45, 0.5, one_circle)["numbers"]["circular_tasks"] == 1
    assert claims.claim_ee_es_about(0.3, 0.5, one_circle)["verdict"] == PARTLY  # ratio 0.6
    assert claims.claim_ee_es_about(0.45, 0.5, [0.6] * 6)["verdict"] == PARTLY
    assert claims.claim_ee_es_about(0.3, 0.5, [0.6] * 6)["verdict"] == DOES_NOT
    assert claims.claim_ee_es_about(0.3, 0.5, [None] * 6)["verdict"] == DOES_NOT  # no turns: the ratio alone
    assert claims.claim_ee_es_about(0.45, 0.5, None)["verdict"] == PARTLY  # the path was not measured
    assert claims.claim_ee_es_about(None, None, None)["verdict"] == NOT_AVAILABLE


def test_claim_5_learning_speed():
    steps = np.arange(1, 11) * 1000
    fast = np.array([0.2, 0.5, 0.6, 0.6, 0.6, 0.6, 0.6, 0.6, 0.6, 0.6])  # reaches 0.54 at 3000
    slow = np.linspace(0.05, 0.7, 10)  # reaches 0.54 at 8000 (0.555...)
    steady = {"LE-LS": 0.6, "EE-LS": 0.6, "SLE": 0.7}
    speed = lambda curves, steady=steady: claims.claim_learning_speed(curves, steady, 1000)  # noqa: E731
    claim = speed({"LE-LS": (steps, fast), "EE-LS": (steps, fast), "SLE": (steps, slow)})
    assert claim["verdict"] == HOLDS
    assert claim["numbers"]["ratio"]["LE-LS"] == pytest.approx(8000 / 3000)
    # SLE never reaches 0.54: reported as such (no ratio), and not as a pass
    never = speed({"LE-LS": (steps, fast), "EE-LS": (steps, fast), "SLE": (steps, slow * 0.5)})
    assert never["verdict"] == PARTLY and never["numbers"]["sle_never"] == {"LE-LS": True, "EE-LS": True}
    assert never["numbers"]["ratio"] == {"LE-LS": None, "EE-LS": None}
    assert "SLE never reached it in 10,000 (x > 3.3)" in never["measured"]
    same = speed({"LE-LS": (steps, fast), "EE-LS": (steps, slow), "SLE": (steps, slow)},
                 {"LE-LS": 0.6, "EE-LS": 0.7, "SLE": 0.7})
    assert same["verdict"] == PARTLY  # x2.7 for LE-LS, x1 for EE-LS
    assert speed({"LE-LS": (steps, slow), "EE-LS": (steps, slow), "SLE": (steps, fast)},
                 {"LE-LS": 0.6, "EE-LS": 0.6, "SLE": 0.6})["verdict"] == DOES_NOT
    assert speed({"LE-LS": (steps, fast)})["verdict"] == NOT_AVAILABLE
    # SLE's noise annealed over the whole test: when SLE gets good depends on the test's length
    whole = claims.claim_learning_speed({"LE-LS": (steps, fast), "EE-LS": (steps, fast), "SLE": (steps, slow)},
                                        steady, 0)
    assert whole["verdict"] == NOT_AVAILABLE and "whole test" in whole["measured"]


def _runs(mean, sd=0.01):
    """Four runs with the given mean and sd (ddof 1): se of a difference of two = sqrt(2 sd^2 / 4) = 0.71 sd."""
    return [mean + sd * math.sqrt(3) / 2 * s for s in (1, -1, 1, -1)]


def test_claim_6_ordering():
    assert claims.pair_order(_runs(0.52), _runs(0.5)) == "in order"  # 0.02 > 2 x 0.0071
    assert claims.pair_order(_runs(0.51), _runs(0.5)) == "tied"  # 0.01 < 2 x 0.0071
    assert claims.pair_order(_runs(0.5), _runs(0.52)) == "reversed"
    claim = claims.claim_ordering({"EE-LS": _runs(0.8), "SLE": _runs(0.7), "LE-LS": _runs(0.5), "EE-ES": _runs(0.3)})
    assert claim["verdict"] == HOLDS and claim["numbers"]["pairs_held"] == 6
    claim = claims.claim_ordering({"EE-LS": _runs(0.6), "SLE": _runs(0.7), "LE-LS": _runs(0.5), "EE-ES": _runs(0.3)})
    assert claim["verdict"] == PARTLY and claim["numbers"]["outcome"]["EE-LS > SLE"] == "reversed"
    assert claim["numbers"]["pairs_held"] == 5
    # EE-LS above SLE by less than 2 se: tied, not ordered
    claim = claims.claim_ordering({"EE-LS": _runs(0.71, 0.05), "SLE": _runs(0.7, 0.05), "LE-LS": _runs(0.5),
                                   "EE-ES": _runs(0.3)})
    assert claim["numbers"]["outcome"]["EE-LS > SLE"] == "tied" and claim["numbers"]["pairs_held"] == 5
    assert "tied: EE-LS > SLE" in claim["measured"]
    # LE-LS > EE-ES > SLE > EE-LS
    claim = claims.claim_ordering({"EE-LS": _runs(0.1), "SLE": _runs(0.2), "LE-LS": _runs(0.5), "EE-ES": _runs(0.3)})
    assert claim["verdict"] == DOES_NOT and claim["numbers"]["pairs_held"] == 1
    assert claims.claim_ordering({"EE-LS": _runs(0.1), "SLE": _runs(0.2)})["verdict"] == NOT_AVAILABLE


def test_claim_7_specialisation():
    three, one, two = [3, 3, 3, 2], [1, 1, 0, 1], [2, 2, 3, 1]  # colours followed by 4 probed individuals
    composes = {"LE-LS": 0.5, "EE-LS": 0.1}
    claim = claims.claim_specialisation({"LE-LS": three, "EE-LS": three}, composes)
    assert claim["verdict"] == HOLDS and claim["numbers"]["specialised"] == {"LE-LS": 0.75, "EE-LS": 0.75}
    assert claim["numbers"]["counts"]["LE-LS"] == [0, 0, 1, 3]
    assert claims.claim_specialisation({"LE-LS": three, "EE-LS": three}, {})["verdict"] == PARTLY  # no composition
    assert claims.claim_specialisation({"LE-LS": three, "EE-LS": one}, composes)["verdict"] == PARTLY
    assert claims.claim_specialisation({"LE-LS": three}, composes)["verdict"] == PARTLY  # EE-LS not probed
    assert claims.claim_specialisation({"LE-LS": one, "EE-LS": two}, {})["verdict"] == PARTLY  # EE-LS: mean 2
    assert claims.claim_specialisation({"LE-LS": one, "EE-LS": two[:-1] + [0]}, {})["verdict"] == DOES_NOT  # 1.75
    assert claims.claim_specialisation({"LE-LS": one, "EE-LS": one}, {"EE-LS": 0.5})["verdict"] == PARTLY
    assert claims.claim_specialisation({"LE-LS": one, "EE-LS": one}, {"EE-LS": 0.1})["verdict"] == DOES_NOT
    assert claims.claim_specialisation({}, composes)["verdict"] == NOT_AVAILABLE


#: The made-up runs' sizes: 3 seeds x 8 generations, learning tests of 2 runs x 2 best x 1 test.
SIZES = dict(seeds=3, generations=8, childhood_steps=30_000, task_steps=20_000, bins=20, best=2, tests=1,
             test_steps=1000, test_bins=10, steady_steps=200)


def _write_results(root, doc, generations=8, variants=("paper", "extension"), scale="cpu"):
    """A reproduction table over made-up runs in the committed layout (``VARIANT/evolve/CONDITION``; a run two
    variants share, once), found there by their keys; its document ``doc`` (no population: no behaviour)."""
    rows = sum((variant_rows(v, 0 if v == "faithful" else None) for v in variants), ())
    table = ReproductionTable(f"made-up-{scale}", str(doc), 0, rows=rows, scale=SIZES, out=str(root),
                              results=str(root), scale_name=scale, whole_test=("faithful",))
    plateau = {"LE-LS": 1, "EE-LS": 6, "EE-ES": 3}
    final = {"LE-LS": 0.5, "EE-LS": 0.7, "EE-ES": 0.45}
    written = set()  # in the committed layout a shared run lies in paper's folder, else in skills'
    for row in sorted((r for r in rows if r.evolved), key=lambda r: {"paper": 0, "skills": 1}.get(r.preset, 2)):
        # faithful differs from skills in childhood alone: its runs without one lie in skills' folder
        folder = "skills" if row.preset == "faithful" and not conditions.get(row.condition).has_childhood else row.preset
        run_dir, spec = os.path.join(str(root), folder, "evolve", row.condition), evolution_spec(row, SIZES)
        if spec.key() in written:  # a run two variants share
            continue
        written.add(spec.key())
        os.makedirs(run_dir)
        lines = ["generation,seed,best,mean,std," + ",".join(f"best_task{i}" for i in range(1, 7))]
        for g in range(generations):
            for s in spec.seeds:
                best = final[row.condition] * min(1.0, (g + 1) / (plateau[row.condition] + 1))
                best += (0.01 if row.condition == "LE-LS" else 0.05) * (s - 1)
                lines.append(f"{g},{s},{best:.6f},{best / 2:.6f},0.1," + ",".join(["0.5"] * 6))
        with open(os.path.join(run_dir, "history.csv"), "w") as f:
            f.write("\n".join(lines) + "\n")
        with open(os.path.join(run_dir, "config.json"), "w") as f:
            json.dump({"seeds": list(spec.seeds), "git_commit": "abc", "config": spec.config.to_dict()}, f)
    steady = {"EE-LS": 0.8, "SLE": 0.7, "LE-LS": 0.5, "EE-ES": 0.3}
    rise = {"EE-LS": 2, "LE-LS": 2, "SLE": 8, "EE-ES": 0}
    for row, out in zip(rows, table.tests().values()):
        if os.path.isdir(out):
            continue
        os.makedirs(out)
        level = steady[row.condition]
        curve = [level * min(1.0, (b + 1) / (rise[row.condition] + 1)) for b in range(10)]
        lines = ["bin,end_step,mean,sd_over_runs,run_0,run_1"]
        lines += [f"{b},{(b + 1) * 100},{v:.5f},0.01,{v:.5f},{v:.5f}" for b, v in enumerate(curve)]
        with open(os.path.join(out, "curve.csv"), "w") as f:
            f.write("\n".join(lines) + "\n")
        with open(os.path.join(out, "steady.json"), "w") as f:  # SLE's config: its noise horizon alone
            json.dump(dict(steady_mean=level, steady_sd=0.02, steady_best_run=level + 0.02, best_run=1,
                           steady_per_run=[level - 0.02, level + 0.02], steady_per_task=[level] * 6,
                           whole_test_mean=float(np.mean(curve)), num_runs=2, num_best=2, num_tests=1,
                           task_steps=1000, steady_steps=200, num_bins=10, git_commit="abc",
                           config=dict(sle_noise_steps=100 if row.preset != "faithful" else 0)), f)
    with open(os.path.join(root, "manifest.json"), "w") as f:
        json.dump(dict(stages={"evolve paper LE-LS": {"command": "python -m imrl_jax.evolve ...", "seconds": 1.0}},
                       git_commit="abc"), f)
    return table


def _report(table, baselines=None):
    """The report of a table without reliving anyone; its figures folder."""
    run(table, behaviour=False, baselines_dir=str(baselines or os.path.join(os.path.dirname(table.document), "none")))
    return os.path.join(os.path.dirname(table.document), os.path.splitext(os.path.basename(table.document))[0].lower())


def test_report_of_a_fabricated_results_directory(tmp_path):
    results, doc = tmp_path / "results", tmp_path / "docs" / "REPRODUCTION.md"
    table = _write_results(results, doc)
    assert table.data()["missing"] == [] and len(table.all_stages()[0]) == 5 + 7  # every made-up run found by key
    (results / "discussion.md").write_text("Hand-written words.\n")
    figures = tmp_path / "docs" / "reproduction"
    assert _report(table) == str(figures)
    for name in ("fig1_arena.png", "fig3a_paper.png", "fig3a_extension.png", "fig3b_paper.png", "fig3c.png",
                 "fig3_paper.png", "fig3_extension.png",
                 "summary.json", "claims.json", "specialisation.csv"):
        assert (figures / name).is_file(), name
    claims = json.loads((figures / "claims.json").read_text())
    assert claims["scale"] == "cpu"
    verdicts = {n: c["variants"]["paper"]["verdict"] for n, c in claims["claims"].items()}
    # plateau generations LE-LS 1, EE-LS 5, EE-ES 3; sd over seeds 0.008 vs 0.04; EE-LS 0.58 vs LE-LS 0.5 with
    # se 0.03; EE-ES / LE-LS = 0.45 / 0.5 = 0.9 (no path measured); SLE reaches 0.9 x 0.5 at 600 cycles (LE-LS:
    # 300) and never 0.9 x 0.8 (partly); each pair's difference >= 0.1 against 2 se = 0.057; no probes
    assert verdicts == {"1": HOLDS, "2": HOLDS, "3": HOLDS, "4": PARTLY, "5": PARTLY, "6": HOLDS, "7": NOT_AVAILABLE}
    summary = json.loads((figures / "summary.json").read_text())
    assert summary["evolution"]["paper"]["LE-LS"]["final_best_mean"] == pytest.approx(0.5)
    text = doc.read_text()
    assert "cpu scale" in text and "](reproduction/fig3a_paper.png)" in text and "](reproduction/fig3_paper.png)" in text
    assert "## Discussion\n\nHand-written words." in text
    assert "- Command: `python -m experiments run made-up-cpu`\n" in text  # not a committed study: no make target
    assert "EE-ES learns nothing, so its one evolution serves every variant." in text
    assert "brax" not in text and not (figures / "baselines.png").exists()  # no baselines: no section


def test_the_faithful_variant_has_claim_5_measured_over_the_whole_test(tmp_path):
    """Its SLE explores the whole test by definition: claim 5 is measured at the test's length, not n/a."""
    results, doc = tmp_path / "results", tmp_path / "docs" / "REPRODUCTION.md"
    table = _write_results(results, doc, variants=("paper", "faithful"))
    figures = tmp_path / "docs" / "reproduction"
    _report(table)
    claim5 = json.loads((figures / "claims.json").read_text())["claims"]["5"]["variants"]
    # paper's SLE anneals over 100 cycles: measured; faithful's over the whole test: measured too, at its length
    assert claim5["paper"]["verdict"] == PARTLY and claim5["faithful"]["verdict"] == PARTLY
    assert "the whole test of 1,000 cycles, the paper's length" in claim5["faithful"]["measured"]
    # faithful's EE-LS lives skills' lives: its key finds the run in skills' folder
    assert table.evolutions()["faithful EE-LS"] == str(results / "skills" / "evolve" / "EE-LS")
    assert table.data()["owners"]["faithful", "EE-LS"] == "skills"
    assert "`faithful`: the learning rules as written but for the extension's selector" in doc.read_text()
    assert "faithful's EE-LS is the skills run (the same rules for it)" in doc.read_text()


def test_a_variant_that_shares_a_run_shares_its_probes():
    """faithful's EE-LS is skills': claim 7 reads skills' EE-LS probes for it; its own LE-LS keeps its own."""
    probes = {("skills", "EE-LS"): [3, 2], ("skills", "LE-LS"): [1], ("faithful", "LE-LS"): [2, 2]}
    owners = {(v, c): v for v in ("skills", "paper", "faithful") for c in ("LE-LS", "EE-LS")}
    shared = share_probes(probes, dict(owners={**owners, ("faithful", "EE-LS"): "skills"}))
    assert shared[("faithful", "EE-LS")] == [3, 2] and shared[("faithful", "LE-LS")] == [2, 2]
    assert ("paper", "EE-LS") not in shared and probes.keys() <= shared.keys() and len(shared) == 4


def test_paper_and_cpu_reports_each_name_the_other_and_an_unfinished_run_says_so(tmp_path):
    """Each scale's report has its own file; the other scale's verdicts are a labelled section; missing stages are named."""
    from experiments.document import figures_of, report_name
    from experiments.reproduction import TABLES

    assert [report_name(s) for s in ("paper", "cpu")] == ["REPRODUCTION.md", "REPRODUCTION_CPU.md"]
    assert [t.document for t in TABLES.values()] == ["docs/REPRODUCTION.md", "docs/REPRODUCTION_CPU.md"]
    assert figures_of("docs/REPRODUCTION_CPU.md") == os.path.join("docs", "reproduction_cpu")
    docs = tmp_path / "docs"
    cpu = _write_results(tmp_path / "cpu", docs / "REPRODUCTION_CPU.md")
    paper = _write_results(tmp_path / "paper", docs / "REPRODUCTION.md", scale="paper")
    os.remove(os.path.join(paper.tests()["extension SLE"], "steady.json"))
    history = tmp_path / "paper" / "paper" / "evolve" / "EE-ES" / "history.csv"  # EE-ES stopped after 5 of 8
    history.write_text("".join(history.read_text().splitlines(keepends=True)[:1 + 5 * 3]))
    _report(cpu)
    assert "Unfinished run" not in (docs / "REPRODUCTION_CPU.md").read_text()
    assert "(REPRODUCTION.md)" not in (docs / "REPRODUCTION_CPU.md").read_text()  # no paper-scale report yet
    _report(paper)
    text = (docs / "REPRODUCTION.md").read_text()
    assert "**Unfinished run: 2 stage(s) not done yet** (evolve paper EE-ES, learning test extension SLE)" in text
    assert "| paper | EE-ES | " in text and "| 5 of 8 |" in text  # drawn and tabled, labelled unfinished
    verdicts = json.loads((docs / "reproduction" / "claims.json").read_text())["claims"]
    for n in ("1", "2", "4"):  # judged on finished evolutions only: EE-ES's is not
        assert verdicts[n]["variants"]["paper"]["verdict"] == NOT_AVAILABLE, n
    assert verdicts["3"]["variants"]["paper"]["verdict"] == HOLDS  # LE-LS and EE-LS are finished
    section = text.split("## The same claims at the cpu scale")[1]
    assert "[REPRODUCTION_CPU.md](REPRODUCTION_CPU.md)" in section
    cpu_claims = json.loads((docs / "reproduction_cpu" / "claims.json").read_text())["claims"]
    first = cpu_claims["1"]["variants"]
    assert f"| 1 | {cpu_claims['1']['text']} | {first['paper']['verdict']} ({first['paper']['measured']}) |" in section
    assert text.startswith("# Reproduction of Schembri, Mirolli & Baldassarre (2007): Fig. 3 and the seven claims\n")
    # The reduced report, written again, links the paper-scale one and says it is reduced; it repeats no verdicts.
    _report(cpu)
    text = (docs / "REPRODUCTION_CPU.md").read_text()
    assert text.startswith("# Reproduction of Schembri, Mirolli & Baldassarre (2007): Fig. 3 and the seven claims, "
                           "at the cpu scale (reduced)\n")
    assert "reported in [REPRODUCTION.md](REPRODUCTION.md)" in text and "## The same claims at the" not in text


def _write_baselines(root):
    """A baselines directory as imrl_jax.commands.baselines writes it: PPO, 1M cycles, 2 seeds at 0.5 and 0.7 on every task."""
    from imrl_jax.commands.baselines import summarise
    from imrl_jax.agent.brax_agents import Baseline
    from imrl_jax.config import Config
    from imrl_jax.runs.rundir import csv_bytes

    b = Baseline(agent="ppo", steps=1_000_000, seeds=2)
    rows = [dict(agent="ppo", task=t, seed=s, steps=1_024_000, performance=0.5 + 0.2 * s,
                 performance_deterministic=0.4, seconds=1.0, steps_per_s=100_000) for t in b.tasks for s in (0, 1)]
    curves = [dict(agent="ppo", task=t, seed=s, step=step, performance=value * (0.5 + 0.2 * s),
                   performance_deterministic=0.4)
              for t in b.tasks for s in (0, 1) for step, value in ((0, 0.0), (1024, 0.25), (1_024_000, 1.0))]
    out = root / "ppo_1M"
    out.mkdir(parents=True)
    (out / "runs.csv").write_bytes(csv_bytes(rows))
    (out / "curves.csv").write_bytes(csv_bytes(curves))
    (out / "summary.json").write_text(json.dumps(summarise(b, Config(), rows, curves)))


def test_report_shows_the_baselines_beside_the_learning_tests(tmp_path):
    doc = tmp_path / "docs" / "REPRODUCTION.md"
    table = _write_results(tmp_path / "results", doc)
    _write_baselines(tmp_path / "baselines")
    (tmp_path / "baselines" / "unfinished").mkdir()  # no summary.json: left out
    figures = tmp_path / "docs" / "reproduction"
    _report(table, tmp_path / "baselines")
    assert (figures / "baselines.png").is_file()
    text = doc.read_text()
    assert "## Modern deep RL baselines (brax.training)" in text and "](reproduction/baselines.png)" in text
    # mean over seeds of each seed's mean over tasks: (0.5 + 0.7) / 2, sd 0.1; at the tests' 1,000 cycles,
    # interpolated between 0 (at 0 cycles) and 0.15 (at 1,024): 0.146; the mode's performance 0.4
    assert "| PPO, 1M cycles (2 seeds) | 0.600 +- 0.100 | 0.60, 0.60, 0.60, 0.60, 0.60, 0.60 | 0.146 | 0.400 |" in text
    assert "Training speed (median control cycles per second over runs, compilation and evaluation excluded): " \
           "PPO, 1M cycles: 100,000." in text
    assert "| EE-LS, paper rules: steady state (cpu scale) | 0.800 +- 0.020 |" in text
    assert "best steady state EE-LS under the paper rules, 0.800" in text


def test_probe_best_counts_the_colours_each_best_individual_follows(tiny):
    """Claim 7's probes: ideal colour followers follow 3 colours, a straight driver none; LE-LS grows up first."""
    from imrl_jax.analysis.relive import probe_best
    from imrl_jax.analysis.behaviour import colour_reinforcers
    from imrl_jax.analysis.controllers import perceptron_followers

    config = tiny("EE-LS")
    followers = np.asarray(perceptron_followers(config)).reshape(-1)
    best = dict(genomes=np.stack([followers, np.zeros_like(followers)])[None])  # (1 seed, 2 best, genes)
    assert probe_best(config.to_dict(), best) == [3, 0]
    le_ls = tiny("LE-LS", childhood_steps=400)
    genomes = np.stack([colour_reinforcers(le_ls), np.zeros(le_ls.num_genes, np.float32)])[:, None]  # (2, 1, genes)
    colours = probe_best(le_ls.to_dict(), dict(genomes=genomes))
    assert len(colours) == 2 and all(0 <= c <= 3 for c in colours)
    assert colours[1] == 0  # no reinforcement, no learning: zero actors drive straight on


def test_fresh_lives_of_each_seeds_best_genome(tiny):
    """fresh_fitness lives each seed's best genome with keys of its own seed: reproducible, other keys other lives."""
    from imrl_jax.analysis.relive import fresh_fitness
    from imrl_jax.analysis.controllers import perceptron_followers
    from imrl_jax.agent.lifetime import make_evaluate

    config = tiny("EE-LS", task_steps=300, num_bins=1, target_radius=30.0)  # reaches are common: lives differ
    followers = np.asarray(perceptron_followers(config)).reshape(-1)
    best = dict(genomes=np.stack([followers, np.zeros_like(followers)])[:, None])  # (2 seeds, 1 best, genes)
    fresh = fresh_fitness(config.to_dict(), best, num_lives=4, seed=5)
    assert fresh["fitness"].shape == (2, 4) and np.ptp(fresh["fitness"][0]) > 0  # lives of one genome differ
    np.testing.assert_allclose(fresh["mean"], fresh["fitness"].mean(1))
    np.testing.assert_allclose(fresh["sd"], fresh["fitness"].std(1, ddof=1))
    assert fresh["mean"][0] > fresh["mean"][1]  # followers beat a zero genome
    again = make_evaluate(config)(jax.random.key(5), config.learning_params(),
                                  jnp.asarray(np.repeat(best["genomes"][:, 0], 4, 0)))
    np.testing.assert_array_equal(np.asarray(again.fitness).reshape(2, 4), fresh["fitness"])
    assert not np.array_equal(fresh_fitness(config.to_dict(), best, num_lives=4, seed=6)["fitness"], fresh["fitness"])


def test_run_fresh_keeps_its_lives_until_the_population_moves_on(tmp_path, monkeypatch):
    """run_fresh lives each seed's best of final_population.npz once, keeps the result, and lives again when the
    population has another generation; without a population there is nothing to live."""
    from experiments.harness import relive

    calls = []

    def fake_fresh(config_dict, best, num_lives, seed):
        calls.append((best["genomes"][:, 0, 0].tolist(), num_lives, seed))
        fitness = np.asarray([[0.2, 0.4], [0.6, 0.6], [0.1, 0.3]])[:len(best["genomes"])]
        return dict(fitness=fitness, mean=fitness.mean(1), sd=fitness.std(1, ddof=1))

    monkeypatch.setattr(relive, "fresh_fitness", fake_fresh)
    assert relive.run_fresh(str(tmp_path)) is None  # no population yet
    evaluated = np.arange(3 * 4 * 2, dtype=np.float32).reshape(3, 4, 2)  # 3 seeds, 4 lives, 2 genes
    fitness = np.asarray([[0.1, 0.9, 0.2, 0.3], [0.5, 0.4, 0.8, 0.0], [0.7, 0.1, 0.1, 0.1]])

    def save(generation):
        np.savez(tmp_path / "final_population.npz", evaluated=evaluated, fitness=fitness, generation=generation,
                 seeds=np.asarray([4, 5, 6]))

    save(7)
    first = relive.run_fresh(str(tmp_path), {"unused": True}, num_lives=2, seed=9)
    assert calls == [([2.0, 12.0, 16.0], 2, 9)]  # each seed's fittest: lives 1, 2 and 0
    assert first["mean_per_seed"] == pytest.approx([0.3, 0.6, 0.2]) and first["mean"] == pytest.approx(1.1 / 3)
    assert first["sd_over_seeds"] == pytest.approx(np.std([0.3, 0.6, 0.2], ddof=1))
    assert (first["generations"], first["seeds"]) == (7, [4, 5, 6])
    assert relive.run_fresh(str(tmp_path), {"unused": True}, num_lives=2, seed=9) == first and len(calls) == 1
    relive.run_fresh(str(tmp_path), {"unused": True}, num_lives=2, seed=10)  # another key: lived again
    save(8)
    relive.run_fresh(str(tmp_path), {"unused": True}, num_lives=2, seed=10)  # another generation: lived again
    assert len(calls) == 3
    relive.run_fresh(str(tmp_path), {"other": True}, num_lives=2, seed=10)  # another config: lived again
    evaluated[0, 1, 0] += 1.0  # seed 4's fittest genome changed in place, same generation and seeds
    save(8)
    again = relive.run_fresh(str(tmp_path), {"other": True}, num_lives=2, seed=10)
    assert len(calls) == 5 and calls[-1][0] == [3.0, 12.0, 16.0]
    assert relive.run_fresh(str(tmp_path), {"other": True}, num_lives=2, seed=10) == again and len(calls) == 5
    assert not os.path.exists(tmp_path / "fresh.json.tmp")


def test_a_childhood_that_stays_put_is_marked_and_said(tiny):
    """fig_paths: a childhood path under 2 cm across is drawn as a mark, and its title says where the robot stays."""
    from experiments.harness.figures import fig_paths
    from imrl_jax.analysis.behaviour import Trajectory

    config = tiny("LE-LS")

    def path(pos):
        steps = len(pos)
        no = np.zeros(steps, bool)
        return Trajectory(pos, np.zeros(steps), pos, np.zeros(steps), np.zeros(steps, int), no, no, no)

    still = path(np.tile([[120.0, 80.0]], (50, 1)) + np.linspace(0, 1.0, 50)[:, None])  # 1 cm in x and y
    moving = path(np.stack([np.linspace(100, 300, 400), np.full(400, 200.0)], 1))
    life = dict(config=config, tasks=[moving] * config.num_tasks, performance=[0.5] * config.num_tasks,
                shares=np.full((config.num_experts, 4), 0.25), steps=[100] * config.num_experts)
    titles = {}
    for name, childhood in (("still", still), ("moving", moving)):
        fig = fig_paths(dict(life, childhood=childhood), name)
        titles[name] = fig.axes[0].get_title()
        assert fig._suptitle.get_text() == name  # the figure keeps its own title
    assert "the robot stays at (120, 80) cm" in titles["still"]
    assert "stays" not in titles["moving"] and titles["moving"].startswith("last 400 childhood steps")


def test_fig3_has_the_papers_three_panels():
    """(a) the three evolved conditions, (b) the three that learn (no EE-ES, as in the paper), (c) four bar pairs."""
    from experiments.harness.figures import fig3

    best = np.linspace(0.1, 0.5, 12).reshape(4, 3)  # (generations, seeds)
    evolutions = {c: best for c in reproduce.EVOLVED}
    curve = dict(steps=np.array([100, 200]), mean=np.array([0.1, 0.2]), sd=np.array([0.01, 0.01]))
    tests = {c: curve for c in reproduce.TESTED}
    steady = {("skills", c): dict(steady_mean=0.2 + 0.1 * i, steady_sd=0.01, steady_best_run=0.25 + 0.1 * i)
              for i, c in enumerate(reproduce.TESTED)}
    fig = fig3(evolutions, tests, steady, "skills", "title")
    a, b, c = fig.axes
    assert [line.get_label() for line in a.get_legend().get_lines()] == [f"{k} (3 seeds)" for k in reproduce.EVOLVED]
    assert [line.get_label() for line in b.get_legend().get_lines()] == ["LE-LS", "EE-LS", "SLE"]
    heights = [round(p.get_height(), 3) for p in c.patches]
    assert heights == [0.2, 0.3, 0.4, 0.5, 0.25, 0.35, 0.45, 0.55]  # means, then best runs, in TESTED order
    assert [t.get_text() for t in c.get_xticklabels()] == list(reproduce.TESTED)


def test_reproduction_fresh_reads_the_reports_lives():
    from experiments.harness import relive

    summary = {"best_individuals": {"skills/LE-LS": dict(fresh_mean_per_seed=[0.7, 0.8, 0.9], fresh_lives=7)}}
    fresh = relive.reproduction_fresh(summary, "skills", "LE-LS")
    assert fresh["num_lives"] == 7 and fresh["mean"] == pytest.approx(0.8) and fresh["sd_over_seeds"] == pytest.approx(0.1)
    assert relive.reproduction_fresh(summary, "paper", "LE-LS") is None


def test_runs_shared_by_variants_are_drawn_once():
    """faithful's EE-LS is skills' and EE-ES is every variant's: each appears once, labelled by its sharers."""
    variants = ("skills", "paper", "faithful")
    runs = {(v, c): f"{v}/{c}" for v in variants for c in ("LE-LS", "EE-LS", "EE-ES")}
    owners = {**{(v, c): v for v in variants for c in ("LE-LS", "EE-LS")}, ("faithful", "EE-LS"): "skills",
              **{(v, "EE-ES"): "paper" for v in variants}}
    assert shared_once(runs, dict(variants=variants, owners=owners)) == {
        ("skills", "LE-LS"): "skills/LE-LS", ("skills, faithful", "EE-LS"): "skills/EE-LS",
        ("every variant", "EE-ES"): "paper/EE-ES", ("paper", "LE-LS"): "paper/LE-LS",
        ("paper", "EE-LS"): "paper/EE-LS", ("faithful", "LE-LS"): "faithful/LE-LS"}

