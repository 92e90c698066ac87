"""The novel-tasks study's plan: the finished runs and SLE on the novel set, and evolutions on held-out tasks."""

import json

from experiments import novel_tasks as study
from imrl_jax import tasks
from imrl_jax.config import paper_tasks


def test_plan_and_commands(tmp_path):
    out = str(tmp_path / "novel")
    stages = study.plan(out)
    assert len(stages) == 5 + 2 + 2 + 3 * 3  # finished runs, SLE, brax's two, held out (3 conditions x 3)
    first = study.stage_command(stages[0], out)[0]
    assert first[first.index("--best-genomes") + 1] == study.BEST_GENOMES and first[-2:] == ["--task-set", "novel"]
    assert first[first.index("-m") + 2].endswith("paper/skills/evolve/LE-LS")  # the finished run's config
    sle = study.stage_command(stages[5], out)[0]
    assert sle[sle.index("--cond") + 1] == "SLE" and sle[-2:] == ["--task-set", "novel"]
    files = study.task_files(out, write=True)
    ppo = study.stage_command(stages[7], out)[0]
    assert ppo[ppo.index("--agent") + 1] == "ppo" and ppo[ppo.index("--task-set") + 1] == "novel"
    assert ppo[ppo.index("--steps") + 1] == "1000000" and stages[8].kind == "baseline"
    evolve = study.stage_command(stages[9], out)[0]
    assert evolve[evolve.index("--task-set") + 1] == files["seen"] and "--strategy" not in evolve
    unseen = study.stage_command(stages[11], out)[0]
    assert unseen[unseen.index("--task-set") + 1] == files["unseen"]
    assert tasks.load(files["seen"]) == tuple(paper_tasks()[n - 1] for n in study.SEEN)
    with open(files["unseen"]) as f:
        assert len(json.load(f)["tasks"]) == 2


def test_held_out_stages_cost_the_tasks_they_run_and_one_childhood():
    costs = {s.name: s.cost for s in study.plan() if s.name.startswith("held out")}
    generations, tests = 5 * 50 * 100, 5 * 5 * 4  # seeds x population x generations; runs x best x tests
    assert costs == {  # LE-LS: one 150,000-step childhood a life, then 100,000 (evolution) or 1,000,000 per task
        "held out: evolve LE-LS on tasks (1, 3, 4, 6)": generations * (150_000 + 4 * 100_000),
        "held out: LE-LS tested on the seen tasks": tests * (150_000 + 4 * 1_000_000),
        "held out: LE-LS tested on the unseen tasks": tests * (150_000 + 2 * 1_000_000),
        "held out: evolve EE-LS on tasks (1, 3, 4, 6)": generations * 4 * 100_000,
        "held out: EE-LS tested on the seen tasks": tests * 4 * 1_000_000,
        "held out: EE-LS tested on the unseen tasks": tests * 2 * 1_000_000,
        "held out: evolve EE-ES on tasks (1, 3, 4, 6)": generations * 4 * 100_000,
        "held out: EE-ES tested on the seen tasks": tests * 4 * 1_000_000,
        "held out: EE-ES tested on the unseen tasks": tests * 2 * 1_000_000}


def _fake_test(folder, per_run, per_task=(0.5,) * 6, curve=(0.1, 0.3)):
    """A finished learning test as the report reads it: steady.json and curve.csv."""
    folder.mkdir(parents=True)
    (folder / "steady.json").write_text(json.dumps(dict(steady_per_run=list(per_run), steady_per_task=list(per_task),
                                                        pairs_both_ways=0.5)))
    rows = "".join(f"{b},{(b + 1) * 1000},{v},0.01\n" for b, v in enumerate(curve))
    (folder / "curve.csv").write_text("bin,end_step,mean,sd_over_runs\n" + rows)


def test_report_measures_the_advantage_and_judges_it(tmp_path):
    """Hand-made tests: LE-LS's advantage grows on unseen tasks, EE-LS's does not; the table and figure are written."""
    reproduction, out = tmp_path / "paper", tmp_path / "novel_tasks"
    for variant in ("skills", "paper"):
        _fake_test(reproduction / variant / "test" / "LE-LS", [0.6, 0.62, 0.58])
        _fake_test(reproduction / variant / "test" / "EE-LS", [0.5, 0.52, 0.48])
    _fake_test(reproduction / "paper" / "test" / "EE-ES", [0.4, 0.4, 0.4])  # shared by both variants
    _fake_test(out / "novel" / "skills" / "LE-LS", [0.5, 0.52, 0.48])
    _fake_test(out / "novel" / "skills" / "EE-LS", [0.15, 0.17, 0.13])
    _fake_test(out / "novel" / "paper" / "EE-ES", [0.05, 0.05, 0.05])
    measured = study.measure(str(out), str(reproduction))
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
    document = tmp_path / "NOVEL_TASKS.md"
    document.write_text(f"intro\n{study.TABLE_START}\nold\n{study.TABLE_END}\nend\n")
    assert study.figure(measured, str(tmp_path / "advantage.png"))
    text = study.table(measured)
    assert "| skills LE-LS | novel (unseen) | 3 | 0.500 | 0.050 | +0.450 | 0.012 |" in text
    assert "**novel set: partly.**" in text


def test_report_judges_held_out_tasks_and_leaves_sle_unjudged(tmp_path):
    """SLE's rows are shown but not judged; held-out tests and a running evolution enter the table and figure."""
    reproduction, out = tmp_path / "paper", tmp_path / "novel_tasks"
    _fake_test(reproduction / "skills" / "test" / "SLE", [0.5, 0.5, 0.5])
    _fake_test(reproduction / "paper" / "test" / "EE-ES", [0.4, 0.4, 0.4])
    _fake_test(out / "novel" / "skills" / "SLE", [0.9, 0.9, 0.9])  # far stronger unseen: would be "holds"
    _fake_test(out / "novel" / "paper" / "EE-ES", [0.05, 0.05, 0.05])
    for condition, seen, unseen in (("LE-LS", 0.6, 0.55), ("EE-LS", 0.5, 0.2), ("EE-ES", 0.3, 0.1)):
        _fake_test(out / "held_out" / condition / "test_seen", [seen - 0.01, seen + 0.01])
        _fake_test(out / "held_out" / condition / "test_unseen", [unseen - 0.01, unseen + 0.01])
    evolve = out / "held_out" / "LE-LS" / "evolve"
    evolve.mkdir(parents=True)
    rows = "".join(f"{g},{s},{0.1 * g + 0.01 * s},0.1\n" for g in range(7) for s in range(2))
    (evolve / "history.csv").write_text("generation,seed,best,mean\n" + rows)
    measured = study.measure(str(out), str(reproduction))
    assert measured["verdicts"]["novel set"]["verdict"] == "n/a"  # only SLE compared: not judged
    held = measured["verdicts"]["held-out tasks"]
    # LE-LS: +0.45 unseen vs +0.30 seen (se 0.01): stronger; EE-LS: +0.10 vs +0.20: not
    assert held["verdict"] == "partly" and held["numbers"]["compared"]["held out LE-LS"]["stronger"]
    assert abs(held["numbers"]["compared"]["held out LE-LS"]["difference"] - 0.15) < 1e-9
    [evolved] = measured["evolved"]  # the last 5 generations (2-6), per seed, then over seeds
    assert evolved["condition"] == "LE-LS" and evolved["generations"] == 7 and evolved["seeds"] == 2
    assert abs(evolved["final_best"] - 0.405) < 1e-9 and abs(evolved["sd"] - 0.005) < 1e-9
    text = study.table(measured)
    assert "| LE-LS | 2 x 7 of 100, running | 0.405 +- 0.005 |" in text
    assert study.figure(measured, str(tmp_path / "advantage.png"))
    assert [study.bar_label(n) for n in ("held out LE-LS", "held out EE-LS", "skills SLE", "paper EE-LS")] == [
        "held out LE-LS", "held out EE-LS", "skills SLE (not judged)", "paper EE-LS"]


def test_colour_summary_counts_individuals_and_colours():
    followed = [[1, 1, 1], [-1, 1, 0], [0, 1, 2], [-1, -1, -1]]  # green; green and red; all three; none
    summary = study.colour_summary(followed)
    assert summary["individuals"] == 4 and summary["counts"] == [1, 1, 1, 1]
    assert summary["shares"] == {"red": 0.5, "green": 0.75, "blue": 0.25}
    measured = dict(rows=[], scratch=[], evolved=[], verdicts={}, probes={"LE-LS": summary})
    assert "| held out LE-LS | 4 | 1 / 1 / 1 / 1 | 50% / 75% / 25% |" in study.table(measured)
