"""Stages fanned out (experiments.harness.executor): what waits for what, local jobs and submitit's local executor give the
sequential runner's files, and a killed fan-out goes on where it stopped."""

import json
import os
import signal
import subprocess
import sys
import textwrap
import time

import pytest
from helpers import ROOT

from experiments.harness import executor as X
from experiments.harness.reproduce import Stage, load_manifest, run_stages

#: A resumable stand-in for the package's commands: an "evolution" appends one generation at a time to its
#: history.csv (going on from what it holds, as evolve --resume does), a "test" refuses to start before its
#: evolution is whole and writes steady.json.
FAKE = textwrap.dedent('''
    import json, os, sys, time
    kind, out = sys.argv[1], sys.argv[2]
    os.makedirs(out, exist_ok=True)
    if kind == "evolve":
        generations, pause = int(sys.argv[3]), float(sys.argv[4])
        path = os.path.join(out, "history.csv")
        done = len(open(path).read().splitlines()) - 1 if os.path.exists(path) else 0
        if not done:
            open(path, "w").write("generation,seed,best\\n")
        open(os.path.join(out, "started"), "a").write(f"{time.time()}\\n")
        for g in range(done, generations):
            time.sleep(pause)
            with open(path, "a") as f:
                f.write(f"{g},0,{g / 10:.1f}\\n")
        open(os.path.join(out, "ended"), "w").write(f"{time.time()}")
    elif kind == "test":
        evolved = sys.argv[3]
        if not os.path.exists(os.path.join(evolved, "ended")):
            sys.exit(3)  # its evolution is not finished: the runner started it too early
        open(os.path.join(out, "started"), "w").write(f"{time.time()}")
        rows = open(os.path.join(evolved, "history.csv")).read().splitlines()[1:]
        json.dump({"steady": {"steady_per_run": [float(rows[-1].split(",")[2])]}},
                  open(os.path.join(out, "steady.json"), "w"))
''')

GENERATIONS = 4
SCALE = {"generations": GENERATIONS, "seeds": 1}


def plan(out: str) -> list[Stage]:
    stages = []
    for condition in ("LE-LS", "EE-LS"):
        evolved = os.path.join(out, condition, "evolve")
        stages.append(Stage(f"evolve {condition}", "evolve", "v", condition, evolved, 1.0))
        stages.append(Stage(f"learning test {condition}", "test", "v", condition, os.path.join(out, condition, "test"),
                            1.0))
    return stages


def commands(script: str, pause: float):
    def command_for(stage):
        if stage.kind == "evolve":
            return [sys.executable, script, "evolve", stage.out_dir, str(GENERATIONS), str(pause)], None
        evolved = os.path.join(os.path.dirname(stage.out_dir), "evolve")
        return [sys.executable, script, "test", stage.out_dir, evolved], None

    return command_for


def run(out: str, script: str, pause: float = 0.3, **fan) -> int:
    manifest, path = load_manifest(out, sizes=SCALE)
    return run_stages(plan(out), SCALE, manifest, path, commands(script, pause), **fan)


def results(out: str) -> dict:
    """Every file the stages wrote but the timing marks and logs, by path."""
    found = {}
    for folder, _, files in os.walk(out):
        for name in files:
            if name in ("history.csv", "steady.json"):
                with open(os.path.join(folder, name)) as f:
                    found[os.path.relpath(os.path.join(folder, name), out)] = f.read()
    return found


@pytest.fixture
def script(tmp_path):
    path = tmp_path / "fake_command.py"
    path.write_text(FAKE)
    return str(path)


def test_what_waits_for_what():
    stages = [Stage("circles", "measure", "", "EE-ES", "c", 1.0), Stage("evolve a LE-LS", "evolve", "a", "LE-LS", "e1", 1),
              Stage("evolve a EE-LS", "evolve", "a", "EE-LS", "e2", 1), Stage("test b LE-LS", "test", "b", "LE-LS", "t", 1),
              Stage("test SLE", "test", "a", "SLE", "s", 1), Stage("baseline", "baseline", "", "PPO", "b", 1),
              Stage("probe", "measure", "", "", "r", 1),
              Stage("odd", "test", "a", "EE-LS", "o", 1, needs=("circles",))]
    assert X.needs(stages) == {
        "circles": (), "evolve a LE-LS": ("circles",), "evolve a EE-LS": ("circles",),
        # a test waits for the evolutions of its condition planned before it, whatever their variant
        "test b LE-LS": ("circles", "evolve a LE-LS"), "test SLE": ("circles",), "baseline": ("circles",),
        "probe": ("circles", "evolve a LE-LS", "evolve a EE-LS", "test b LE-LS", "test SLE", "baseline"),
        "odd": ("circles",)}


def test_two_local_jobs_end_with_the_sequential_runners_files(tmp_path, script, capsys):
    assert run(str(tmp_path / "sequential"), script) == 0
    assert run(str(tmp_path / "fanned"), script, jobs=2) == 0
    want = results(str(tmp_path / "sequential"))
    assert len(want) == 4 and results(str(tmp_path / "fanned")) == want
    fanned = tmp_path / "fanned"
    # Both evolutions ran at once; each test started after its own evolution ended.
    starts = {c: float((fanned / c / "evolve" / "started").read_text().split()[0]) for c in ("LE-LS", "EE-LS")}
    ends = {c: float((fanned / c / "evolve" / "ended").read_text()) for c in ("LE-LS", "EE-LS")}
    assert max(starts.values()) < min(ends.values())
    assert all(float((fanned / c / "test" / "started").read_text()) >= ends[c] for c in ends)
    manifest = json.loads((fanned / "manifest.json").read_text())["stages"]
    assert sorted(manifest) == sorted(s.name for s in plan(str(fanned)))
    assert all(entry["cost"] == 1 for entry in manifest.values())
    out = capsys.readouterr().out
    assert "== evolve LE-LS: started on local" in out and "(4/4 stages done, 0 running)" in out
    # Run again: everything is done, nothing starts.
    assert run(str(fanned), script, jobs=2) == 0
    assert "started on" not in capsys.readouterr().out


def test_submitit_local_executor_gives_the_same_files(tmp_path, script):
    pytest.importorskip("submitit")
    want = tmp_path / "sequential"
    assert run(str(want), script, pause=0.05) == 0
    fanned = str(tmp_path / "submitit")
    executor = X.make_executor("submitit-local", os.path.join(fanned, "jobs"))
    assert run(fanned, script, pause=0.05, jobs=2, executor=executor) == 0
    assert results(fanned) == results(str(want))


def test_a_failed_stage_stops_what_needs_it(tmp_path, script, capsys):
    def command_for(stage):
        if stage.name == "evolve EE-LS":
            return [sys.executable, "-c", "import sys; sys.exit(5)"], None
        return commands(script, 0.05)(stage)

    out = str(tmp_path / "r")
    manifest, path = load_manifest(out, sizes=SCALE)
    assert run_stages(plan(out), SCALE, manifest, path, command_for, jobs=2) == 5
    printed = capsys.readouterr().out
    assert "error: stage evolve EE-LS failed with exit code 5" in printed
    assert "== learning test EE-LS: not started (it needs a failed stage)" in printed
    assert os.path.exists(os.path.join(out, "LE-LS", "test", "steady.json"))  # the other branch went on
    assert not os.path.exists(os.path.join(out, "EE-LS", "test"))


def test_a_killed_fan_out_goes_on_where_it_stopped(tmp_path, script):
    """The runner and its jobs killed mid-evolution: run again, each evolution goes on from what it holds."""
    out = tmp_path / "r"
    code = (f"import sys; sys.path[:0] = [{os.path.join(ROOT, 'tests')!r}, {ROOT!r}]\n"
            f"import test_executor as t\nsys.exit(t.run({str(out)!r}, {script!r}, pause=0.5, jobs=2))\n")
    runner = subprocess.Popen([sys.executable, "-c", code], start_new_session=True, stdout=subprocess.DEVNULL)
    history = out / "LE-LS" / "evolve" / "history.csv"
    deadline = time.time() + 60
    while time.time() < deadline and not (history.exists() and len(history.read_text().splitlines()) >= 3):
        time.sleep(0.1)
    os.killpg(runner.pid, signal.SIGKILL)  # the runner and every job it started
    runner.wait()
    held = len(history.read_text().splitlines()) - 1
    assert 1 <= held < GENERATIONS and not (out / "LE-LS" / "test").exists()
    assert run(str(out), script, pause=0.05, jobs=2) == 0
    want = tmp_path / "whole"
    assert run(str(want), script, pause=0.05) == 0
    assert results(str(out)) == results(str(want))  # every generation once, in order
    assert len((out / "LE-LS" / "evolve" / "started").read_text().split()) == 2  # started, then resumed


def test_fan_out_options(tmp_path, capsys):
    import argparse

    p = argparse.ArgumentParser()
    X.add_options(p)
    for bad, message in ((["--jobs", "0"], "--jobs: must be a whole number of stages at once from 1 to 1,000, got '0'"),
                         (["--executor", "k8s"], "--executor: unknown executor 'k8s'")):
        with pytest.raises(SystemExit):
            p.parse_args(bad)
        assert message in capsys.readouterr().err
    assert X.from_options(p.parse_args([]), str(tmp_path)) == {}
    fan = X.from_options(p.parse_args(["--jobs", "3"]), str(tmp_path))
    assert fan["jobs"] == 3 and isinstance(fan["executor"], X.Local)
    assert X.options_argv(p.parse_args(["--jobs", "3", "--executor", "local"])) == ["--jobs", "3"]
    assert not os.listdir(tmp_path)


def test_a_submitit_job_gives_its_commands_exit_code_and_logs_as_it_runs(tmp_path):
    pytest.importorskip("submitit")
    executor = X.make_executor("submitit-local", str(tmp_path / "jobs"))
    log = tmp_path / "logs" / "stage.log"
    job = executor.submit([sys.executable, "-c", "print('half way', flush=True); import sys; sys.exit(5)"], None,
                          str(log))
    deadline = time.time() + 60
    while job.poll() is None and time.time() < deadline:
        time.sleep(0.2)
    assert job.poll() == 5 and log.read_text() == "half way\n"


def test_a_measure_is_judged_when_it_could_start(tmp_path):
    """A measure is judged done or due when it could start, after the stages before it ran, not when the fanned
    runner begins (here the stand-in done-ness undoes it once a stage before it runs)."""
    stages = [Stage("evolve a", "evolve", "v", "LE-LS", str(tmp_path / "a"), 1.0),
              Stage("probe", "measure", "", "", str(tmp_path), 1.0)]
    finished = {"probe"}  # the measure was done; the evolution was not
    ran = []

    def command_for(stage):
        ran.append(stage.name)
        return [sys.executable, "-c", "pass"], None

    def record(stage, command, seconds):
        finished.add(stage.name)
        if stage.name != "probe":
            finished.discard("probe")  # what it measured changed: it is due

    code = X.run_fanned(stages, {}, str(tmp_path / "manifest.json"), command_for, 2, X.Local(),
                        lambda s, scale: s.name in finished, record, poll_s=0.05, log=lambda line: None)
    assert code == 0 and ran == ["evolve a", "probe"]
    ran.clear()
    assert X.run_fanned(stages, {}, str(tmp_path / "manifest.json"), command_for, 2, X.Local(),
                        lambda s, scale: s.name in finished, record, poll_s=0.05, log=lambda line: None) == 0
    assert ran == []  # both done now


def test_a_need_that_is_no_stage_is_refused(tmp_path):
    stages = [Stage("test", "test", "v", "LE-LS", str(tmp_path), 1.0, needs=("evolve typo",))]
    lines = []
    assert X.run_fanned(stages, {}, str(tmp_path / "m.json"), None, 1, X.Local(), lambda s, scale: False, None,
                        log=lines.append) == 2
    assert lines == ["error: stage test needs 'evolve typo', which is not a stage of this study"]
