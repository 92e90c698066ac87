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
