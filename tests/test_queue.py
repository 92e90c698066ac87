"""The queue of studies: what is left of each, and one study after another."""

import subprocess

import pytest

from experiments import queue


def test_list_shows_every_study_and_what_is_left(capsys):
    assert queue.main(["--list"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert [line.split(":")[0].strip() for line in lines] == [m for m, _ in queue.STUDIES] + ["in all"]
    left, count, hours = queue.remaining("novel_tasks", rate=1.0)
    stages, scale = queue.importlib.import_module("experiments.novel_tasks").all_stages()
    assert count == len(stages) and 0 <= left <= count
    assert hours * 3600 == pytest.approx(sum(s.cost for s in stages if not queue.stage_done(s, scale)))


def test_studies_run_in_order_and_a_failure_stops_the_queue(monkeypatch, capsys):
    ran = []

    def fake_run(command, env):
        ran.append(command[-1])
        return subprocess.CompletedProcess(command, 3 if command[-1] == "experiments.novel_tasks" else 0)

    monkeypatch.setattr(queue.subprocess, "run", fake_run)
    assert queue.main([]) == 3
    assert ran == ["experiments.timescale", "experiments.novel_tasks"]
    assert "study novel_tasks stopped with exit code 3" in capsys.readouterr().err


def test_ctrl_c_stops_the_queue_with_one_line(monkeypatch, capsys):
    def interrupted(command, env):
        raise KeyboardInterrupt

    monkeypatch.setattr(queue.subprocess, "run", interrupted)
    assert queue.main([]) == 130
    err = capsys.readouterr().err.strip()
    assert err == "interrupted in study timescale: run the same command again to go on"
