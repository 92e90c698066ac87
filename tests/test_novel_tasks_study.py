"""The novel-tasks study's plan: the finished runs and SLE on the novel set, and evolutions on held-out tasks."""

import json

from experiments import novel_tasks as study
from imrl_jax import tasks
from imrl_jax.config import paper_tasks


def test_plan_and_commands(tmp_path):
    out = str(tmp_path / "novel")
    stages = study.plan(out)
    assert len(stages) == 5 + 2 + 2 * 3
    first = study.stage_command(stages[0], out)[0]
    assert first[first.index("--best-genomes") + 1] == study.BEST_GENOMES and first[-2:] == ["--task-set", "novel"]
    assert first[first.index("-m") + 2].endswith("paper/skills/evolve/LE-LS")  # the finished run's config
    sle = study.stage_command(stages[5], out)[0]
    assert sle[sle.index("--cond") + 1] == "SLE" and sle[-2:] == ["--task-set", "novel"]
    files = study.task_files(out, write=True)
    evolve = study.stage_command(stages[7], out)[0]
    assert evolve[evolve.index("--task-set") + 1] == files["seen"] and "--strategy" not in evolve
    unseen = study.stage_command(stages[9], out)[0]
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
        "held out: EE-LS tested on the unseen tasks": tests * 2 * 1_000_000}
