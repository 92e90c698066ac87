"""The stage runner (progress and ETA, published checkpoints) and the reproduction's tables; end to end at the tiny
scale (slow)."""

import io
import json
import os
import shutil
import signal
import subprocess
import sys
import time

import pytest
from helpers import ROOT, evolve_args, outputs, write_lock

from experiments.harness import reproduce
from experiments.reproduction import TABLES, ReproductionTable, variant_rows
from experiments.harness.study import SCALES
from imrl_jax.commands import evolve


def tiny_table(results, variants=("paper", "extension")) -> ReproductionTable:
    """The reproduction at the tiny scale, its runs under ``results``."""
    rows = sum((variant_rows(v, 0 if v == "faithful" else None) for v in variants), ())
    return ReproductionTable("tiny", os.path.join(str(results), "REPRODUCTION_TINY.md"), 0, rows=rows,
                             scale=SCALES["tiny"], out=str(results), results=str(results), scale_name="tiny")


@pytest.mark.slow
def test_pipeline_runs_and_resumes(tmp_path, capsys):
    table = tiny_table(tmp_path / "results")
    assert table.main([]) == 0
    with open(os.path.join(table.out, "manifest.json")) as f:
        stages = json.load(f)["stages"]
    assert len(stages) == 3 + 5  # 3 evolutions (two of them sweeps of two runs) and 5 learning tests
    tests = table.tests()
    for row, tested in tests.items():
        assert os.path.exists(os.path.join(tested, "steady.json")), row
    assert tests["extension EE-ES"] == tests["paper EE-ES"] and tests["extension LE-LS"] != tests["paper LE-LS"]
    # A learning test not made yet (its folder gone) is run again; everything else is skipped.
    shutil.rmtree(tests["extension SLE"])
    capsys.readouterr()
    assert table.main([]) == 0
    out = capsys.readouterr().out
    assert out.count(": done (") == 3 + 4 and "] learning test extension SLE\n" in out and "imrl_jax.evolve" not in out


def test_partial_runs_counts_the_runs_an_interrupted_test_kept(tmp_path):
    assert reproduce.partial_runs(str(tmp_path / "none")) == 0
    (tmp_path / "partial").mkdir()
    for name in ("spec.json", "run_000.npz", "run_001.npz"):
        (tmp_path / "partial" / name).write_bytes(b"")
    assert reproduce.partial_runs(str(tmp_path)) == 2


def test_plan_costs_and_eta(tmp_path):
    stages, scale = tiny_table(tmp_path).all_stages()
    # each evolution then its test; paper's and extension's runs differ only in dynamic values: one program each
    # (a sweep); EE-ES's once, under the first variant; SLE tested from scratch
    assert [s.name for s in stages] == [
        "evolve paper LE-LS+extension LE-LS (one sweep)", "learning test paper LE-LS+extension LE-LS (one sweep)",
        "evolve paper EE-LS+extension EE-LS (one sweep)", "learning test paper EE-LS+extension EE-LS (one sweep)",
        "evolve paper EE-ES", "learning test paper EE-ES", "learning test paper SLE", "learning test extension SLE"]
    assert stages[5].needs == ("evolve paper EE-ES",) and stages[6].needs == ()
    # 2 seeds x 6 individuals x 2 generations x (400 childhood + 6 x 400 task steps), twice (the sweep's points)
    assert stages[0].cost == 2 * 2 * 6 * 2 * (400 + 6 * 400) and stages[4].cost == 2 * 6 * 2 * 6 * 400
    # 2 runs x 2 best x 1 test x 6 x 800 cycles
    assert stages[-1].cost == 2 * 2 * 1 * 6 * 800
    # under skills, paper and faithful: faithful's EE-LS is skills' run, EE-ES one run for all
    stages = tiny_table(tmp_path / "other", ("skills", "paper", "faithful")).all_stages()[0]
    assert sum(s.kind == "evolve" and "EE-ES" in s.name for s in stages) == 1
    assert sum(s.kind == "evolve" and "EE-LS" in s.name for s in stages) == 1  # skills' (= faithful's) and paper's
    # 100 lane-steps/s; the first stage half done at its own rate of 50: 1/2 x 1000/50 + 3000/100
    few = [s._replace(cost=c) for s, c in zip(stages, (1000.0, 1000.0, 2000.0))]
    assert reproduce.eta_seconds(few, 100.0, 0.5, 50.0) == pytest.approx(10 + 30)
    assert reproduce.eta_seconds(few, 100.0) == pytest.approx(40)
    assert reproduce.measured_rate({"stages": {"a": dict(cost=300, seconds=2), "b": dict(cost=100, seconds=2),
                                               "old": dict(seconds=9)}}) == 100


def test_the_reproduction_finds_every_committed_run():
    """Both scales' rows find their committed runs by key: nothing is left to run, no run is recomputed."""
    for table in TABLES.values():
        stages, scale = table.all_stages()
        assert [s.name for s in stages if not reproduce.stage_done(s, scale)] == [], table.name
        assert all(s.out_dir.startswith(table.out + os.sep) for s in stages), table.name
    paper, cpu = TABLES["paper"], TABLES["cpu"]
    assert paper.variants == ["skills", "paper", "faithful"] and cpu.variants == ["paper", "extension"]
    assert len(paper.all_stages()[0]) == 15 and len(cpu.all_stages()[0]) == 12
    evolutions = paper.evolutions()
    # EE-ES learns nothing: one run for every variant, paper's; faithful's EE-LS lives skills' lives
    assert {evolutions[f"{v} EE-ES"] for v in paper.variants} == {os.path.join(paper.out, "paper", "evolve", "EE-ES")}
    assert evolutions["faithful EE-LS"] == os.path.join(paper.out, "skills", "evolve", "EE-LS")
    assert paper.data()["owners"]["faithful", "EE-LS"] == "skills"


def test_the_reproductions_commands():
    """faithful evolves its own preset and tests SLE's noise over the whole test; skills' SLE anneals over one task."""
    paper = TABLES["paper"]
    stages = {s.name: s for s in paper.all_stages()[0]}
    evolve = paper.stage_command(stages["evolve faithful LE-LS"])[0]
    assert evolve[evolve.index("--preset") + 1] == "faithful" and "--set" not in evolve
    assert evolve[evolve.index("--seeds") + 1] == "10" and evolve[evolve.index("--generations") + 1] == "100"
    sle = paper.stage_command(stages["learning test faithful SLE"])[0]
    assert sle[sle.index("--set") + 1] == "sle_noise_steps=0" and sle.count("--set") == 1
    skills_sle = paper.stage_command(stages["learning test skills SLE"])[0]
    assert "sle_noise_steps=100000" in skills_sle and skills_sle[skills_sle.index("--preset") + 1] == "skills"
    test = paper.stage_command(stages["learning test faithful LE-LS"])[0]
    assert test[test.index("imrl_jax.learning_test") + 1] == stages["evolve faithful LE-LS"].out_dir
    # the cpu scale's SLE tests were made with SLE's noise over the whole test: so they are found
    cpu = TABLES["cpu"]
    assert [r.sets for r in cpu.rows if not r.evolved] == [("sle_noise_steps=0",)] * 2 and cpu.whole_test == ()
    assert paper.whole_test == ("faithful",)
    # the preset is the screen's row: the same lives as paper + the adult selector's values of skills
    from imrl_jax.config import make_config

    screened = make_config("paper", trace_lambda=0.98, eta_selector_actor=0.3, eta_selector_critic=0.001)
    assert make_config("faithful") == screened and make_config("faithful") != make_config("paper")


def test_stage_progress_is_shown_with_the_whole_pipelines(tmp_path, capfd):
    scale = SCALES["tiny"]
    stages = [reproduce.Stage("learning test paper SLE", "test", "paper", "SLE", str(tmp_path / "a"), 4000.0),
              reproduce.Stage("learning test paper EE-ES", "test", "paper", "EE-ES", str(tmp_path / "b"), 8000.0)]
    manifest = dict(sizes=scale, stages={"earlier": dict(cost=1000, seconds=10)})  # 100 lane-steps/s
    stream = io.StringIO()
    overall = reproduce.Overall(stages, manifest, stream=stream)
    # The stage reports through Progress; a line of its own that looks like progress is not taken for it.
    child = ("import sys, time\nfrom imrl_jax.runs.progress import Progress\np = Progress(4, unit='chunk')\n"
             "print('not progress (3/4)', file=sys.stderr)\n"
             "for i in range(1, 5):\n    p.update(i, 0.5, 0.25, 1e6, scores='performance')\n    time.sleep(0.2)\n"
             "p.note('a note')")
    manifest_path = str(tmp_path / "manifest.json")
    reproduce.run_stage(stages[0], 0, [sys.executable, "-c", child], overall, manifest_path)
    lines = stream.getvalue().splitlines()
    assert len(lines) == 4 and lines[0].startswith("chunk 1 (1/4) | performance | 0:00:00 elapsed, first chunk ")
    assert " || stage 1/2 | all stages: " in lines[0] and "(measured)" in lines[0]
    assert lines[3].startswith("chunk 4 (4/4) | performance | ") and "| 1.00 M lane-steps/s || stage 1/2" in lines[3]
    out, err = capfd.readouterr()
    assert "== [1/2] learning test paper SLE" in out
    assert "not progress (3/4)" in err and "a note" in err and "chunk 1" not in err  # its progress is the runner's
    events = [json.loads(line) for line in (tmp_path / "logs" / "learning_test_paper_SLE.events").read_text().splitlines()]
    assert [(e["kind"], e.get("done")) for e in events] == [("progress", 1), ("progress", 2), ("progress", 3),
                                                            ("progress", 4), ("note", None)]
    assert events[0]["lane_steps_per_s"] is None and events[1]["lane_steps_per_s"] == 1e6  # the first compiles
    with open(manifest_path) as f:
        recorded = json.load(f)["stages"]["learning test paper SLE"]
    assert recorded["cost"] == 4000 and recorded["seconds"] >= 0
    # before any stage has run: the whole of both stages at the earlier 100 lane-steps/s
    before = reproduce.Overall(stages, dict(sizes=scale, stages={"earlier": dict(cost=1000, seconds=10)}))
    assert before.status(0).endswith("ETA 0:02:00 (measured)")
    assert reproduce.Overall(stages, dict(sizes=scale, stages={})).status(1).endswith("(estimated)")
    # nothing timed yet, but the running stage has a rate: the rest at that rate (8000 / 100 s)
    assert reproduce.Overall(stages, dict(sizes=scale, stages={})).status(1, 0.0, 100.0).endswith(
        "ETA 0:01:20 (at this stage's rate)")


def test_a_fresh_clone_continues_from_the_published_checkpoint(tmp_path):
    """An unfinished evolution's newest checkpoint, published and put back, resumes bitwise."""
    args = evolve_args(seeds=1, population=4, parents=2, task_steps=200, bins=1)
    whole, cut = str(tmp_path / "whole"), str(tmp_path / "cut")
    assert evolve.main([*args, "--generations", "3", "--out", whole]) == 0
    assert evolve.main([*args, "--generations", "2", "--out", cut]) == 0
    assert reproduce.publish_checkpoint(cut) == 2
    assert os.listdir(os.path.join(cut, reproduce.PUBLISHED)) == ["2"]
    for name in ("checkpoints", "final_population.npz"):  # what git does not keep
        shutil.rmtree(os.path.join(cut, name)) if name == "checkpoints" else os.remove(os.path.join(cut, name))
    assert reproduce.restore_published(cut) == 2
    assert reproduce.restore_published(cut) is None  # checkpoints/ is there now
    assert reproduce.generations_done(cut) == 2
    assert evolve.main([*args, "--generations", "3", "--out", cut, "--resume"]) == 0
    got, want = outputs(cut), outputs(whole)
    assert got["history.csv"] == want["history.csv"]
    for name in ("evaluated", "fitness", "next_population"):
        assert got[name].tobytes() == want[name].tobytes(), name


def test_a_stage_is_done_when_its_last_file_exists(tmp_path):
    """Each kind of stage is done by the file its command writes last."""
    from experiments.harness import reproduce

    scale = dict(generations=3)
    for kind, last in (("test", "steady.json"), ("measure", "result.json"), ("baseline", "summary.json")):
        stage = reproduce.Stage("s", kind, "", "", str(tmp_path / kind), 1.0)
        assert not reproduce.stage_done(stage, scale)
        (tmp_path / kind).mkdir()
        (tmp_path / kind / last).write_text("{}")
        assert reproduce.stage_done(stage, scale), kind
    evolve = reproduce.Stage("e", "evolve", "", "", str(tmp_path / "evolve"), 1.0)
    (tmp_path / "evolve").mkdir()
    (tmp_path / "evolve" / "history.csv").write_text("generation,seed,best\n0,0,0.1\n1,0,0.2\n")
    assert not reproduce.stage_done(evolve, scale)  # 2 of 3 generations
    evolve = evolve._replace(cost=300.0)
    assert reproduce.cost_left(evolve, scale) == pytest.approx(100.0)  # one generation of three left
    assert reproduce.cost_left(stage, scale) == 0.0  # the finished baseline
    (tmp_path / "evolve" / "history.csv").write_text("generation,seed,best\n0,0,0.1\n1,0,0.2\n2,0,0.3\n")
    assert reproduce.stage_done(evolve, scale) and reproduce.cost_left(evolve, scale) == 0.0


def test_a_resumed_test_stage_counts_its_own_runs(tmp_path, capsys):
    """9 of a 10-run stage's runs kept: 10 % of its cost is left, whatever the scale's seeds (5 here)."""
    out = tmp_path / "test"
    (out / "partial").mkdir(parents=True)
    for i in range(9):
        (out / "partial" / f"run_{i:03d}.npz").write_bytes(b"")
    stage = reproduce.Stage("a test of 10 runs", "test", "paper", "EE-ES", str(out), 1000.0, runs=10)
    scale = dict(SCALES["tiny"], seeds=5)
    manifest, path = {"stages": {}, "sizes": scale}, str(tmp_path / "manifest.json")
    code = reproduce.run_stages([stage], scale, manifest, path,
                                lambda s: ([sys.executable, "-c", "pass"], None))
    assert code == 0
    with open(path) as f:
        assert json.load(f)["stages"]["a test of 10 runs"]["cost"] == 100
    # a cost recorded wrongly before (negative) is no measurement
    assert reproduce.measured_rate({"stages": {"a": dict(cost=300, seconds=3), "bad": dict(cost=-900, seconds=1)}}) == 100


def test_a_stage_another_command_is_writing_is_waited_for(tmp_path, monkeypatch, capsys):
    """Two studies' commands sharing a run: the second waits while the first's process holds the folder's lock, then
    skips the stage it finished; a holder that died without finishing leaves the stage to run."""
    import subprocess

    monkeypatch.setattr(reproduce, "LOCK_POLL_SECONDS", 0.05)
    out = tmp_path / "measure"
    out.mkdir()
    stage = reproduce.Stage("measure shared", "measure", "", "", str(out), 1.0)
    manifest, path = {"stages": {}, "sizes": {}}, str(tmp_path / "manifest.json")
    ran = []

    def command_for(s):
        ran.append(s.name)
        return [sys.executable, "-c", "pass"], None

    other = subprocess.Popen([sys.executable, "-c", "import os, time; time.sleep(1.0); "
                              f"open({str(out / 'result.json')!r}, 'w').write('{{}}'); os.remove({str(out / '.lock')!r})"])
    write_lock(str(out), other.pid)
    assert reproduce.run_stages([stage], {}, manifest, path, command_for) == 0
    other.wait()
    printed = capsys.readouterr().out
    assert ran == [] and f"is being written by pid {other.pid} (another command): waiting" in printed
    assert "measure shared: done by another command" in printed
    os.remove(out / "result.json")
    write_lock(str(out), other.pid)  # its process has ended: the lock is stale and the stage runs
    assert reproduce.run_stages([stage], {}, manifest, path, command_for) == 0 and ran == ["measure shared"]


#: A made-up study on the runner (experiments.harness.runner.study_main): ``python TINY OUT PAUSE [runner options]``, three
#: measures, each a small python script that writes its pid, sleeps PAUSE seconds and writes its result.json.
TINY_STUDY = f"""
import os, sys
sys.path[:0] = [{ROOT!r}]
from experiments.harness.reproduce import Stage
from experiments.harness.runner import study_main
out, pause = sys.argv[1], sys.argv[2]
stages = [Stage(f"measure {{i}}", "measure", "", "", os.path.join(out, f"m{{i}}"), 1.0, needs=()) for i in range(3)]
STAGE = ("import os, sys, time\\nos.makedirs(sys.argv[1], exist_ok=True)\\n"
         # the pid written whole, then renamed: a test reading it as soon as it appears reads all of it
         "p = os.path.join(sys.argv[1], 'pid')\\nopen(p + '.tmp', 'w').write(str(os.getpid()))\\n"
         "os.replace(p + '.tmp', p)\\ntime.sleep(float(sys.argv[2]))\\n"
         "open(os.path.join(sys.argv[1], 'r.tmp'), 'w').write('{{}}')\\n"
         "os.replace(os.path.join(sys.argv[1], 'r.tmp'), os.path.join(sys.argv[1], 'result.json'))\\n")
command_for = lambda stage: ([sys.executable, "-c", STAGE, stage.out_dir, pause], None)
sys.exit(study_main(sys.argv[3:], "tiny", out, lambda: (stages, {{}}), command_for))
"""


def _tiny(tmp_path, out, pause, *options, **popen) -> subprocess.Popen:
    script = tmp_path / "tiny_study.py"
    script.write_text(TINY_STUDY)
    return subprocess.Popen([sys.executable, str(script), str(out), str(pause), *options], text=True,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, **popen)


def _wait_for(path, seconds: float = 60.0) -> None:
    deadline = time.time() + seconds
    while not os.path.exists(path):
        assert time.time() < deadline, f"{path} never appeared"
        time.sleep(0.02)


def _gone(pid: int) -> bool:
    from imrl_jax.runs.rundir import _proc_stat

    stat = _proc_stat(pid)
    return stat is None or stat.state == "Z"  # ended (a zombie until whoever adopted it reaps it)


def _states(out) -> dict:
    """Each stage the manifest records, and whether it records it done."""
    return {name: reproduce.recorded_done(entry)
            for name, entry in reproduce.read_manifest(str(out / "manifest.json"))["stages"].items()}


def test_a_second_runner_of_a_study_refuses_while_the_first_runs(tmp_path):
    """Two runners of one study at once: the second refuses in one line, exit 2; no manifest entry is lost."""
    out = tmp_path / "tiny"
    first = _tiny(tmp_path, out, 0.8)
    _wait_for(out / "m0" / "pid")
    second = _tiny(tmp_path, out, 0.0)
    err = second.communicate(timeout=60)[1]
    assert second.returncode == 2, err
    assert err.splitlines() == [f"error: study tiny: {out} is being run by pid {first.pid} on "
                                f"{__import__('socket').gethostname()} (another runner; its lock "
                                f"{out / 'logs' / '.lock'}): wait for it to end or stop it"]
    assert first.wait(timeout=60) == 0
    assert _states(out) == {"measure 0": True, "measure 1": True, "measure 2": True}
    assert not (out / "logs" / ".lock").exists()  # released


@pytest.mark.parametrize("options", [(), ("--jobs", "2")])
def test_a_killed_runner_leaves_no_stage_running(tmp_path, options):
    """A runner SIGKILLed: its stage (started through the launcher that ties it to the runner) is gone within
    seconds, and the next runner takes over its lock and finishes the study."""
    out = tmp_path / "tiny"
    runner = _tiny(tmp_path, out, 60, *options)
    _wait_for(out / "m0" / "pid")
    stage = int((out / "m0" / "pid").read_text())
    os.kill(runner.pid, signal.SIGKILL)  # the runner alone, not its process group
    runner.wait()
    deadline = time.time() + 5
    while not _gone(stage) and time.time() < deadline:
        time.sleep(0.05)
    assert _gone(stage), f"the stage {stage} outlived its runner"
    again = _tiny(tmp_path, out, 0.0, *options)
    err = again.communicate(timeout=60)[1]
    assert again.returncode == 0, err
    assert "took over the stale lock" in err and set(_states(out).values()) == {True}


def test_a_runner_killed_at_a_random_point_resumes_to_an_uninterrupted_runs_manifest(tmp_path):
    """Killed at a random moment (the seed in the message), run again: the manifest records the same stages, each
    done, as a run never killed; killed, it is always readable (written atomically)."""
    import random

    seed = random.randrange(2**32)
    whole, cut = tmp_path / "whole", tmp_path / "cut"
    start = time.perf_counter()
    assert _tiny(tmp_path, whole, 0.2).wait(timeout=60) == 0
    moment = random.Random(seed).uniform(0.0, time.perf_counter() - start)  # anywhere in an uninterrupted run
    runner = _tiny(tmp_path, cut, 0.2)
    time.sleep(moment)
    os.kill(runner.pid, signal.SIGKILL)
    runner.wait()
    if (cut / "manifest.json").exists():
        reproduce.read_manifest(str(cut / "manifest.json"))  # whole: the old or the new file, never half
    again = _tiny(tmp_path, cut, 0.2)
    err = again.communicate(timeout=60)[1]
    assert again.returncode == 0, f"seed {seed}, killed at {moment:.2f} s: {err}"
    assert _states(cut) == _states(whole) == {f"measure {i}": True for i in range(3)}, f"seed {seed}"


def test_a_stage_that_ended_while_no_runner_watched_is_recorded_done(tmp_path):
    """The runner killed between a stage's end and its record: the next one records it done (its time unknown)."""
    out = tmp_path / "m"
    out.mkdir()
    (out / "result.json").write_text("{}")
    stage = reproduce.Stage("measure m", "measure", "", "", str(out), 1.0)
    path = str(tmp_path / "manifest.json")
    manifest = dict(sizes={}, stages={})
    reproduce.record_start(manifest, path, stage, [sys.executable, "-m", "x"])
    assert _states(tmp_path) == {"measure m": False}
    assert reproduce.run_stages([stage], {}, manifest, path, None) == 0
    entry = reproduce.read_manifest(path)["stages"]["measure m"]
    assert entry["done"] is True and entry["command"] == "python -m x" and "seconds" not in entry


def test_a_manifest_entry_is_written_into_the_manifest_on_disk(tmp_path, monkeypatch):
    """An entry is read-modify-written: what another sitting recorded meanwhile is kept; a write cut before its
    rename leaves the old manifest whole."""
    path = str(tmp_path / "manifest.json")
    stage = reproduce.Stage("b", "measure", "", "", str(tmp_path), 1.0)
    mine = dict(sizes={}, stages={})
    reproduce.write_entry(dict(sizes={}, stages={}), path, "a", dict(command="python a", done=True))
    reproduce.record_stage(mine, path, stage, [sys.executable, "b"], 2.0)
    assert _states(tmp_path) == {"a": True, "b": True} and mine["stages"].keys() == {"a", "b"}
    before = (tmp_path / "manifest.json").read_bytes()

    def cut(*args):
        raise KeyboardInterrupt  # killed between the write and the rename

    monkeypatch.setattr(os, "replace", cut)
    with pytest.raises(KeyboardInterrupt):
        reproduce.write_entry(mine, path, "c", dict(command="python c", done=True))
    monkeypatch.undo()
    assert (tmp_path / "manifest.json").read_bytes() == before
