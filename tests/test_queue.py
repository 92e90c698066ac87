"""The queue of studies: what is left of each, and one study after another."""

import subprocess

import pytest

from experiments import queue


def test_list_shows_every_study_and_what_is_left(capsys):
    assert queue.main(["--list"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert [line.split(":")[0].strip() for line in lines] == [
        "timescale", "novel_tasks", "claims_study screen", "reproduce paper", "claims_study experts", "search",
        "future_work", "in all"]
    left, count, hours = queue.remaining("novel_tasks", rate=1.0)
    stages, scale = queue.importlib.import_module("experiments.novel_tasks").all_stages()
    assert count == len(stages) and 0 <= left <= count
    assert hours * 3600 == pytest.approx(sum(queue.cost_left(s, scale) for s in stages))
    # a study with options counts the stages those options run: the reproduction's, with its faithful variant
    left, count, _ = queue.remaining("reproduce", argv=("--scale", "paper"))
    reproduce = queue.importlib.import_module("experiments.reproduce")
    stages, scale = reproduce.stages_for(["--scale", "paper"])
    assert count == len(stages) and "evolve faithful LE-LS" in [s.name for s in stages]
    assert left == sum(not reproduce.stage_done(s, scale) for s in stages) and stages[-1].kind == "report"


def test_studies_run_in_order_and_a_failure_stops_the_queue(monkeypatch, capsys):
    ran = []

    def fake_run(command, env):
        ran.append(" ".join(command[2:]))
        return subprocess.CompletedProcess(command, 3 if command[2] == "experiments.reproduce" else 0)

    monkeypatch.setattr(queue.subprocess, "run", fake_run)
    assert queue.main([]) == 3
    assert ran == ["experiments.timescale", "experiments.novel_tasks", "experiments.claims_study --only screen",
                   "experiments.reproduce --scale paper"]
    assert "study reproduce --scale paper stopped with exit code 3" in capsys.readouterr().err


def test_ctrl_c_stops_the_queue_with_one_line(monkeypatch, capsys):
    def interrupted(command, env):
        raise KeyboardInterrupt

    monkeypatch.setattr(queue.subprocess, "run", interrupted)
    assert queue.main([]) == 130
    err = capsys.readouterr().err.strip()
    assert err == "interrupted in study timescale: run the same command again to go on"
