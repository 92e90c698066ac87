"""The novel-tasks study as a table: its committed runs found, its stages' commands, and its report's measure."""

import json
import os

import helpers
from helpers import write_evolution, write_learning_test

from experiments import novel_tasks as study
from experiments.harness.reproduce import stage_done
from imrl_jax.world import tasks
from imrl_jax.config import paper_tasks


def test_the_plan_finds_every_committed_run_and_test():
    stages, scale = study.TABLE.all_stages()
    assert len(stages) == 12 + 2 + 3 + 5 + 2 + 6  # paper runs and tests, SLE on novel, held out, novel tests, brax
    assert [s.name for s in stages if not stage_done(s, scale)] == []
    evolutions, tests = study.TABLE.evolutions(), study.TABLE.tests()
    assert evolutions["skills LE-LS"] == os.path.join(study.REPRODUCTION, "skills", "evolve", "LE-LS")
    assert evolutions["held out EE-LS"] == os.path.join(study.OUT, "held_out", "EE-LS", "evolve")
    assert tests["paper SLE"] == os.path.join(study.REPRODUCTION, "paper", "test", "SLE")  # by its test key
    assert tests["skills SLE on novel"] == os.path.join(study.OUT, "novel", "skills", "SLE")


def command(name: str) -> list[str]:
    """The command line of the stage ``name``."""
    stages, _ = study.TABLE.all_stages()
    return study.TABLE.stage_command(next(s for s in stages if s.name == name))[0]


def option(line: list[str], name: str) -> str:
    return line[line.index(name) + 1]


def test_stage_commands_take_their_task_sets():
    novel = command("test skills LE-LS on novel")
    assert novel[3] == os.path.join(study.REPRODUCTION, "skills", "evolve", "LE-LS")  # the finished run
    assert option(novel, "--best-genomes") == os.path.join(study.REPRODUCTION, "best_genomes.npz")
    assert (option(novel, "--task-set"), option(novel, "--best"), option(novel, "--tests")) == ("novel", "5", "4")
    assert option(novel, "--out") == os.path.join(study.OUT, "novel", "skills", "LE-LS")
    sle = command("learning test skills SLE on novel")
    assert option(sle, "--cond") == "SLE" and option(sle, "--task-set") == "novel" and option(sle, "--runs") == "5"
    ppo = command("baseline ppo on novel")
    assert [option(ppo, o) for o in ("--agent", "--steps", "--seeds", "--task-set")] == ["ppo", "1000000", "5", "novel"]
    evolve = command("evolve held out LE-LS")
    assert option(evolve, "--task-set") == study.TASK_FILES["seen"] and "--strategy" not in evolve
    unseen = command("test held out EE-ES on the unseen tasks")
    assert option(unseen, "--task-set") == study.TASK_FILES["unseen"]
    assert unseen[3] == os.path.join(study.OUT, "held_out", "EE-ES", "evolve")
    for which, numbers in study.HELD_OUT.items():  # the committed sets hold the paper's tasks they name
        assert tasks.load(study.TASK_FILES[which]) == tuple(paper_tasks()[n - 1] for n in numbers)


def test_the_tests_on_other_task_sets_cost_the_tasks_they_run_and_one_childhood():
    costs = {s.name: s.cost for s in study.TABLE.all_stages()[0] if s.kind == "test" and " on " in s.name}
    tests, finished = 5 * 5 * 4, 10 * 5 * 4  # runs x best x tests
    assert costs["test held out LE-LS on the seen tasks"] == tests * (150_000 + 4 * 1_000_000)
    assert costs["test held out LE-LS on the unseen tasks"] == tests * (150_000 + 2 * 1_000_000)
    assert costs["test held out EE-LS on the unseen tasks"] == tests * 2 * 1_000_000
    assert costs["test skills LE-LS on novel"] == finished * (150_000 + 6 * 1_000_000)
    assert costs["test EE-ES on novel"] == finished * 6 * 1_000_000


def relocated(tmp_path):
    """The study's table writing into ``tmp_path``, its document a stub with the table's markers."""
    return helpers.relocated(study.TABLE, tmp_path, "intro\n<!-- advantage table: python -m experiments report "
                             "novel-tasks -->\nold\n<!-- end of advantage table -->\nend\n")


def fake_test(table, name, per_run, curve=(0.1, 0.3)):
    """A finished learning test of the row or measure ``name``."""
    folder = {**table.tests(), **{m.name: table.measure_folder(m) for m in table.measures}}[name]
    write_learning_test(folder, per_run, curve, steady_sd=0.0, steady_per_task=[0.5] * 6, pairs_both_ways=0.5)


def test_report_measures_the_advantage_and_judges_it(tmp_path):
    """Hand-made tests: LE-LS's advantage grows on unseen tasks, EE-LS's does not; the table and figures are written."""
    table = relocated(tmp_path)
    for preset in ("skills", "paper"):
        fake_test(table, f"{preset} LE-LS", [0.6, 0.62, 0.58])
        fake_test(table, f"{preset} EE-LS", [0.5, 0.52, 0.48])
    fake_test(table, "EE-ES", [0.4, 0.4, 0.4])  # shared by both presets
    fake_test(table, "skills LE-LS on novel", [0.5, 0.52, 0.48])
    fake_test(table, "skills EE-LS on novel", [0.15, 0.17, 0.13])
    fake_test(table, "EE-ES on novel", [0.05, 0.05, 0.05])
    measured = table.advantages()
    rows = {(r["name"], r["tasks"]): r for r in measured["rows"]}
    assert len(rows) == 6  # skills and paper on the six; skills only on the novel set (paper's not run)
    seen, unseen = rows["skills LE-LS", "paper's six (seen)"], rows["skills LE-LS", "novel (unseen)"]
    assert abs(seen["advantage"] - 0.2) < 1e-12 and abs(unseen["advantage"] - 0.45) < 1e-12
    assert abs(seen["standard_error"] - 0.02 / 3 ** 0.5) < 1e-12  # sd 0.02 over 3 runs; EE-ES's sd 0
    verdict = measured["verdicts"]["novel set"]
    assert verdict["verdict"] == "partly"  # LE-LS: +0.45 against +0.20, stronger; EE-LS: +0.10 against +0.10
    assert verdict["numbers"]["compared"]["skills LE-LS"]["stronger"]
    assert not verdict["numbers"]["compared"]["skills EE-LS"]["stronger"]
    assert measured["verdicts"]["held-out tasks"]["verdict"] == "n/a" and measured["evolved"] == []
    assert table.report() == 0
    text = open(table.document).read()
    assert "| skills LE-LS | novel (unseen) | 3 | 0.500 | 0.050 | +0.450 | 0.012 |" in text
    assert "**novel set: partly.**" in text and text.endswith("<!-- end of advantage table -->\nend\n")
    saved = json.load(open(os.path.join(table.out, "advantage.json")))
    assert saved["rows"] == measured["rows"] and saved["verdicts"]["novel set"]["verdict"] == "partly"
    for figure in ("novel.png", "held_out.png"):
        assert os.path.getsize(os.path.join(table.out, figure)) > 10_000


def write_history(folder, generations, best):
    """An evolution's history.csv of 2 seeds: ``best(generation, seed)`` in each of its ``generations``."""
    write_evolution(folder, [[best(g, s) for s in range(2)] for g in range(generations)], columns=dict(mean=0.1))


def test_report_judges_held_out_tasks_and_leaves_sle_unjudged(tmp_path):
    """SLE's rows are shown but not judged; held-out tests and the evolutions (one finished, one running) enter the
    table and figures."""
    table = relocated(tmp_path)
    fake_test(table, "skills SLE", [0.5, 0.5, 0.5])
    fake_test(table, "EE-ES", [0.4, 0.4, 0.4])
    fake_test(table, "skills SLE on novel", [0.9, 0.9, 0.9])  # far stronger unseen: would be "holds"
    fake_test(table, "EE-ES on novel", [0.05, 0.05, 0.05])
    for condition, seen, unseen in (("LE-LS", 0.6, 0.55), ("EE-LS", 0.5, 0.2), ("EE-ES", 0.3, 0.1)):
        fake_test(table, f"held out {condition} on the seen tasks", [seen - 0.01, seen + 0.01])
        fake_test(table, f"held out {condition} on the unseen tasks", [unseen - 0.01, unseen + 0.01])
    evolutions = table.evolutions()
    write_history(evolutions["held out LE-LS"], 7, lambda g, s: 0.1 * g + 0.01 * s)  # running
    write_history(evolutions["held out EE-LS"], 100, lambda g, s: 0.5 + 0.02 * s)
    measured = table.advantages()
    assert measured["verdicts"]["novel set"]["verdict"] == "n/a"  # only SLE compared: not judged
    held = measured["verdicts"]["held-out tasks"]
    # LE-LS: +0.45 unseen vs +0.30 seen (se 0.01): stronger; EE-LS: +0.10 vs +0.20: not
    assert held["verdict"] == "partly" and held["numbers"]["compared"]["held out LE-LS"]["stronger"]
    assert abs(held["numbers"]["compared"]["held out LE-LS"]["difference"] - 0.15) < 1e-9
    [evolved] = measured["evolved"]  # the finished one: the last 5 generations per seed, then over seeds
    assert evolved["condition"] == "EE-LS" and evolved["generations"] == 100 and evolved["seeds"] == 2
    assert abs(evolved["final_best"] - 0.51) < 1e-9 and abs(evolved["sd"] - 0.01) < 1e-9
    assert table.report() == 0
    text = open(table.document).read()
    assert "| held out LE-LS | LE-LS | skills | 2 | 7 of 100 | running |" in text
    assert "| held out EE-LS | EE-LS | skills | 2 | 100 of 100 | 0.510 +- 0.010 |" in text
    assert "| skills SLE | novel (unseen) | 3 | 0.900 | 0.050 | +0.850 | 0.000 |" in text
    assert "**held-out tasks: partly.**" in text
    assert os.path.getsize(os.path.join(table.out, "held_out.png")) > 10_000


def test_only_evolved_conditions_that_learn_are_judged():
    assert [row.name for row in study.FINISHED + study.HELD if study.judged(row)] == [
        "skills LE-LS", "skills EE-LS", "paper LE-LS", "paper EE-LS", "held out LE-LS", "held out EE-LS"]


def test_colour_summary_counts_individuals_and_colours():
    followed = [[1, 1, 1], [-1, 1, 0], [0, 1, 2], [-1, -1, -1]]  # green; green and red; all three; none
    summary = study.colour_summary(followed)
    assert summary["individuals"] == 4 and summary["counts"] == [1, 1, 1, 1]
    assert summary["shares"] == {"red": 0.5, "green": 0.75, "blue": 0.25}
    measured = dict(rows=[], scratch=[], verdicts={}, probes={"LE-LS": summary})
    assert "| held out LE-LS | 4 | 1 / 1 / 1 / 1 | 50% / 75% / 25% |" in study.advantage_table(measured, "")
