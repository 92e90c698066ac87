"""Task sets: the built-in ones pass their checks, the novel set is solvable only by composing, files load and fail."""

import json
import os

import numpy as np
import pytest
from helpers import evolve_args

from imrl_jax.analysis import controllers
from imrl_jax.commands import evolve, learning_test
from imrl_jax.world import tasks
from imrl_jax.config import Config, ConfigError, paper_tasks


def test_built_in_sets_pass_their_checks_and_round_trip_through_json(tmp_path):
    assert tasks.load("paper") == paper_tasks()
    novel = tasks.load("novel")
    assert len(novel) == 6 and not set(t.start for t in novel) & set(t.start for t in paper_tasks())
    # 5- and 6-edge zigzags (the six have 2 to 4), two per first colour turning the other way first
    routes = [tasks.zigzag_route(Config(), t) for t in novel]
    assert [len(colours) for colours, _ in routes] == [5, 6, 6, 5, 5, 6]
    assert [(colours[0], first) for colours, first in routes] == [(0, "L"), (0, "R"), (1, "L"), (1, "R"), (2, "L"),
                                                                  (2, "R")]
    assert Config(tasks=novel).steps_per_trip() == (83, 99, 99, 83, 83, 99)  # the straight line, as for the six
    path = tmp_path / "novel.json"
    path.write_text(tasks.to_json(novel, "novel"))
    assert tasks.load(str(path)) == novel


def test_the_novel_tasks_are_solved_by_composing_and_not_by_one_colour_follower():
    config = Config(tasks=tasks.load("novel"))
    composed = np.asarray(controllers.performance(config, 3000))
    assert composed.min() >= 0.8, composed  # measured: 0.92 to 0.94
    followers = np.asarray(controllers.follower_performance(config, 3000))
    assert followers.shape == (3, 6) and (followers.max(0) <= composed / 2).all(), followers  # measured: all 0


@pytest.mark.parametrize("text, message", [
    ("not json", "file: not JSON"),
    ('{"tasks": []}', "tasks: expected an object with a non-empty list"),
    ('{"tasks": [{"start": [200, 200], "heading_deg": 0}]}', "task 1: target: missing"),
    ('{"tasks": [{"start": [200], "heading_deg": 0, "target": [360, 269.282]}]}', "task 1: start: expected [x, y]"),
    ('{"tasks": [{"start": [200, 200], "heading_deg": "east", "target": [360, 269.282]}]}',
     "task 1: heading_deg: expected a number"),
    ('{"tasks": [{"start": [200, 200], "heading": 0, "target": [360, 269.282]}]}', "task 1: heading: unknown field"),
    ('{"tasks": [{"start": [210, 213], "heading_deg": 0, "target": [360, 269.282]}]}', "task 1: start: (210, 213) is "
                                                                                        "not on a line"),
    ('{"tasks": [{"start": [200, 200], "heading_deg": 30, "target": [360, 269.282]}]}',
     "task 1: heading_deg: 30 deg does not run along a line"),
    ('{"tasks": [{"start": [200, 200], "heading_deg": 0, "target": [500, 200]}]}', "task 1: target: (500, 200) is off"),
    ('{"tasks": [{"start": [200, 200], "heading_deg": 0, "target": [360, 269.282]}, '
     '{"start": [200, 200], "heading_deg": 0, "target": [380, 200]}]}', "task 2: target: no zigzag route"),
    # Files that gave tracebacks: not UTF-8, a number of more digits than int() takes, nested past the recursion
    # limit; and one too large to read (a 2 GB file took 4.4 GB of memory before the JSON error).
    (b"\xff\xfe{bad", "mine.json is not UTF-8 text (byte 0)"),
    ('{"tasks": [' + "1" * 5000 + "]}", "file: not JSON (Exceeds the limit (4300 digits) for integer string conversion"),
    ("[" * 100_000, "file: not JSON (nested too deeply)"),
    (b"1" * (2**20 + 1), "mine.json is larger than the limit of 1,048,576 bytes"),
])
def test_a_bad_task_set_file_exits_2_naming_the_task_and_field(tmp_path, capsys, text, message):
    path = tmp_path / "mine.json"
    path.write_bytes(text if isinstance(text, bytes) else text.encode())
    with pytest.raises(ConfigError) as error:
        tasks.load(str(path))
    assert str(error.value).startswith(f"--task-set: {path}") and message in str(error.value), str(error.value)
    out = tmp_path / "run"
    assert evolve.main([*evolve_args(seeds=1, generations=1), "--task-set", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: --task-set: ") and "\n" not in err and not out.exists()
    out = tmp_path / "test"
    assert learning_test.main(["--cond", "SLE", "--task-set", str(path), "--out", str(out)]) == 2
    assert message in capsys.readouterr().err and not out.exists()


def test_evolve_records_its_task_set_and_a_resume_on_another_is_refused(tmp_path, capsys):
    out = str(tmp_path / "run")
    args = evolve_args(seeds=1, population=4, parents=2, generations=1, task_steps=100, bins=1)
    assert evolve.main([*args, "--task-set", "novel", "--out", out]) == 0
    with open(os.path.join(out, "config.json")) as f:
        recorded = json.load(f)["config"]["tasks"]
    assert [tuple(t["start"]) for t in recorded] == [t.start for t in tasks.novel_tasks()]
    capsys.readouterr()
    assert evolve.main(["--resume", "--out", out, "--generations", "2", "--task-set", "paper"]) == 2
    assert capsys.readouterr().err.strip().endswith("tasks: 6 of the run's 6 tasks differ (--task-set)")
    assert evolve.main([*args, "--task-set", "nov", "--out", str(tmp_path / "other")]) == 2
    assert capsys.readouterr().err.strip() == ("error: --task-set: unknown task set 'nov' (choose from paper, novel, or "
                                               "give a .json file)")


def test_a_learning_test_on_another_task_set_tests_the_evolved_genomes_on_its_tasks(tiny_run, tmp_path, monkeypatch):
    import collections

    from imrl_jax.commands import learning_test

    seen = {}

    def run(config, genomes, out_dir, **options):
        seen.update(config=config, source=options["source"], genes=genomes.shape[-1])
        return collections.defaultdict(float, condition=config.condition)

    monkeypatch.setattr(learning_test, "run", run)
    argv = [tiny_run, "--best", "1", "--tests", "1", "--task-steps", "400", "--bins", "4", "--steady-steps", "200",
            "--chunks", "1", "--quiet", "--task-set", "novel", "--out", str(tmp_path / "t")]
    assert learning_test.main(argv) == 0
    evolved = learning_test.load_run(tiny_run, 1)[0]
    assert seen["config"].tasks == tasks.novel_tasks() and seen["genes"] == evolved.num_genes
    assert seen["config"] == evolved.replace(task_steps=400, num_bins=4, tasks=tasks.novel_tasks())
    assert seen["source"].endswith(", task set novel")
