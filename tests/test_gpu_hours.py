"""``python -m experiments list``: each study's hours on this CPU and on a GPU, from docs/gpu's measured speeds."""

import json
import math
import os

import pytest

from experiments import __main__ as experiments_main
from experiments.harness import gpu_hours
from experiments.harness.reproduce import Stage
from helpers import RESULTS

SPEED = gpu_hours.GpuSpeed("GPU X", {"pallas": [(500, 1e9, 6.0), (5000, 2e9, 7.0)], "xla": [(500, 4e7, 5.0)]}, "x")


def _stage(condition, kind="evolve", out_dir="nowhere", cost=3.6e12):
    return Stage(f"{kind} {condition}", kind, condition, condition, out_dir, cost)


def test_the_committed_check_gives_both_kernels_speeds():
    speed = gpu_hours.read_speed()
    assert speed.device == "NVIDIA H200" and speed.source == os.path.join("docs", "gpu", "gpu_check.json")
    assert {k: sorted(i for i, *_ in rows) for k, rows in speed.rows.items()} == {"pallas": [500, 5000],
                                                                                 "xla": [500, 5000]}
    assert all(rate > 0 and compile_s > 0 for rows in speed.rows.values() for _, rate, compile_s in rows)


@pytest.mark.parametrize("content", [None, b"{", b"[]", json.dumps({"dry": True, "steps": [{"step": "generation", "rows": [  # tiny sizes: no speed
                                         {"kernel": "xla", "individuals": 5, "lane_steps_per_s": 1e6}]}]}).encode(),
                                     json.dumps({"steps": [{"step": "generation", "rows": [
                                         {"kernel": "xla", "individuals": 5, "lane_steps_per_s": "nan"}]}]}).encode()])
def test_no_measured_speed_is_none(tmp_path, content):
    path = tmp_path / "gpu_check.json"
    if content is not None:
        path.write_bytes(content)
    assert gpu_hours.read_speed(str(path)) is None


#: The worlds study's LE-LS evolution, done: it recorded world xland, which the kernel does not implement.
XLAND_RUN = os.path.join(RESULTS, "runs", "f900b270720a2ed6", "evolve")


@pytest.mark.parametrize("condition, kernel", [("LE-LS", "pallas"), ("EE-ES", "pallas"), ("EV-LS", "pallas"),
                                               ("LE-LS-2R", "pallas"), ("", "xla")])
def test_a_stage_runs_the_kernel_auto_would_choose_for_its_condition(condition, kernel):
    assert gpu_hours.stage_kernel(_stage(condition)) == kernel


def test_a_done_stage_runs_the_kernel_auto_would_choose_for_its_recorded_model():
    """The worlds study's LE-LS evolution recorded world xland: the kernel lacks it, so the XLA step; the time-scale
    study's recorded selector_period=10, which the kernel lives."""
    assert gpu_hours.stage_kernel(_stage("LE-LS", out_dir=XLAND_RUN)) == "xla"
    done = os.path.join(RESULTS, "timescale", "skills+period-10", "LE-LS", "evolve")
    assert gpu_hours.stage_kernel(_stage("LE-LS", out_dir=done)) == "pallas"
    assert gpu_hours.stage_kernel(_stage("LE-LS", out_dir=os.path.join(RESULTS, "paper", "paper", "evolve",
                                                                       "LE-LS"))) == "pallas"


def test_a_stage_takes_its_lane_steps_at_the_nearest_measured_speed_and_one_compilation():
    scale = {"seeds": 10, "population": 50}  # 500 individuals
    assert gpu_hours.stage_seconds(_stage("LE-LS"), scale, SPEED) == pytest.approx(3.6e12 / 1e9 + 6.0)
    assert gpu_hours.stage_seconds(_stage("LE-LS"), {"seeds": 200}, SPEED) == pytest.approx(3.6e12 / 2e9 + 7.0)
    xland = _stage("LE-LS", out_dir=XLAND_RUN)
    assert gpu_hours.stage_seconds(xland, scale, SPEED) == pytest.approx(3.6e12 / 4e7 + 5.0)
    assert gpu_hours.stage_seconds(xland._replace(cost=0.0), scale, SPEED) == 0.0
    hours = gpu_hours.study_hours([_stage("LE-LS"), xland], scale, SPEED)
    assert hours == pytest.approx((3.6e12 / 1e9 + 6.0 + 3.6e12 / 4e7 + 5.0) / 3600)
    assert gpu_hours.study_hours([_stage("LE-LS")], scale, None) is None


def test_a_model_the_models_step_timed_runs_at_its_ratio_to_le_ls(tmp_path):
    """EV-LS measured at half LE-LS's speed on the kernel takes twice the lane-steps' time; the time-scale study's
    period-option run at its option's ratio; an unmeasured model and the XLA step's stages as before."""
    data = {"machine": {"device": "GPU Z"}, "steps": [
        {"step": "generation", "rows": [{"kernel": "pallas", "individuals": 500, "lane_steps_per_s": 1e9,
                                         "compile_s": 6.0},
                                        {"kernel": "xla", "individuals": 500, "lane_steps_per_s": 4e7,
                                         "compile_s": 5.0}]},
        {"step": "models", "rows": [
            {"condition": "LE-LS", "options": "", "status": "ok", "over_le_ls": 1.0},
            {"condition": "EV-LS", "options": "", "status": "ok", "over_le_ls": 0.5},
            {"condition": "LE-LS", "options": "period", "status": "ok", "over_le_ls": 0.8},
            {"condition": "EE-ES", "options": "", "status": "skipped (budget)"},
            {"condition": "LE-LS-2R", "options": "", "status": "ok", "over_le_ls": "nan"}]}]}
    path = tmp_path / "gpu_check.json"
    path.write_text(json.dumps(data))
    speed = gpu_hours.read_speed(str(path))
    assert speed.models == {("LE-LS", ""): 1.0, ("EV-LS", ""): 0.5, ("LE-LS", "period"): 0.8}
    scale = {"seeds": 10, "population": 50}
    assert gpu_hours.stage_seconds(_stage("EV-LS"), scale, speed) == pytest.approx(3.6e12 / 0.5e9 + 6.0)
    assert gpu_hours.stage_seconds(_stage("EE-ES"), scale, speed) == pytest.approx(3.6e12 / 1e9 + 6.0)
    period = os.path.join(RESULTS, "timescale", "skills+period-10", "LE-LS", "evolve")
    assert gpu_hours.stage_seconds(_stage("LE-LS", out_dir=period), scale, speed) == pytest.approx(
        3.6e12 / 0.8e9 + 6.0)
    assert gpu_hours.stage_seconds(_stage("LE-LS", out_dir=XLAND_RUN), scale, speed) == pytest.approx(
        3.6e12 / 4e7 + 5.0)


def test_a_world_is_priced_at_the_agents_benchmarked_speed_there_against_the_arena(tmp_path):
    """bench --world's rows of both worlds at the most lanes both measured: the geometric mean of the agent's rates
    there over the arena's (a world with settings of its own, another backend, or fewer lanes left aside)."""
    from imrl_jax.runs.progress import world_factor

    def bench(name, world, rows, backend="cpu", settings=None):
        (tmp_path / name).write_text(json.dumps({"backend": backend, "world": {
            "name": world, "settings": settings or {},
            "rows": [{"phase": p, "lanes": n, "agent_lane_steps_per_s": r} for p, n, r in rows]}}))

    bench("world-arena.json", "arena", [("child", 50, 1e6), ("child", 300, 2e6), ("adult", 300, 4e6)])
    bench("world-xland.json", "xland", [("child", 50, 9e5), ("child", 300, 5e5), ("adult", 300, 4e6 / 16)])
    bench("world-xland-big.json", "xland", [("child", 1000, 1e9)], settings={"arm_length": 20})
    bench("world-xland-gpu.json", "xland", [("child", 300, 1e9)], backend="gpu")
    assert world_factor("xland", folder=str(tmp_path)) == pytest.approx((0.25 * (1 / 16)) ** 0.5)  # 1/8
    assert world_factor("arena", folder=str(tmp_path)) == 1.0
    assert world_factor("corridor", folder=str(tmp_path)) is None
    assert world_factor("xland", folder=str(tmp_path / "none")) is None


def test_a_study_in_another_world_is_priced_there(monkeypatch):
    """The worlds study's stages live in XLand: on this CPU at the committed benchmarks' share of the arena's rate,
    and, were they not done, on a GPU with the XLA step (the kernel lives the arena only)."""
    from experiments import worlds
    from imrl_jax.runs.progress import world_factor

    stages, scale = worlds.TABLE.all_stages()
    assert {s.world for s in stages} == {"xland"}
    factor = world_factor("xland")
    assert 0.1 < factor < 0.5  # the agent 4 to 5 times slower there on 2 cores (docs/bench/world-*-cpu-2core.json)
    assert experiments_main.stage_rate(stages[0]) == pytest.approx(experiments_main.RATE * factor)
    assert experiments_main.stage_rate(stages[0]._replace(world="arena")) == experiments_main.RATE
    undone = stages[0]._replace(out_dir="nowhere")
    assert gpu_hours.stage_kernel(undone) == "xla" and gpu_hours.stage_kernel(undone._replace(world="arena")) == "pallas"
    assert gpu_hours.stage_config(undone._replace(condition="EE-LS-T")) is None  # a condition XLand refuses


def test_list_shows_each_study_on_this_cpu_and_on_a_gpu(capsys, monkeypatch):
    assert experiments_main.main(["list"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert all("h on this CPU, " in line and line.endswith(" h on a GPU") for line in lines[:-1])
    cpu = [float(line.split("whole: ")[1].split(" h")[0]) for line in lines[:-1]]
    assert abs(float(lines[-1].split("whole: ")[1].split(" h on this CPU, ")[0]) - math.fsum(cpu)) < 1
    assert "h on one NVIDIA H200 (docs/gpu/gpu_check.json" in lines[-1]
    monkeypatch.setattr(gpu_hours, "GPU_CHECK", "no-such-file.json")
    assert experiments_main.main(["list"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert "on a GPU" not in lines[0] and "no GPU measured" in lines[-1]


def _study_check(tmp_path, key, status="ok"):
    """A made-up gpu_check.json: a generation step and a study step that timed one program and two test sizes."""
    data = {"machine": {"device": "GPU Y"}, "steps": [
        {"step": "generation", "rows": [{"kernel": "pallas", "individuals": 500, "lane_steps_per_s": 1e9,
                                         "compile_s": 6.0}]},
        {"step": "study", "rows": [
            {"part": "evolution", "program": key, "lane_steps_per_s": 2e9, "compile_s": 9.0, "status": status},
            {"part": "evolution", "program": "0" * 12, "status": "skipped (budget)"},
            {"part": "test", "condition": "LE-LS", "lanes": 600, "lane_steps_per_s": 1e8, "compile_s": 3.0,
             "status": "ok"},
            {"part": "test", "condition": "LE-LS", "lanes": 6000, "lane_steps_per_s": 5e8, "compile_s": 4.0,
             "status": "ok"}]}]}
    path = tmp_path / "gpu_check.json"
    path.write_text(json.dumps(data))
    return gpu_hours.read_speed(str(path))


def test_a_stage_whose_program_the_study_step_timed_takes_that_speed(tmp_path):
    """The claims map's skills-bias0 LE-LS run (done: its recorded model) at its program's measured speed; a run of
    another program at the generation step's; a learning test at its condition's phase speed, nearest lanes."""
    from experiments.harness.study import SCREEN
    from imrl_jax.commands.gpu_study import program_key
    from imrl_jax.runs.rundir import read_config

    done = os.path.join(RESULTS, "claims", "skills-bias0", "evolve", "LE-LS")
    speed = _study_check(tmp_path, program_key(read_config(done)[0]))
    assert speed.programs == {program_key(read_config(done)[0]): (2e9, 9.0)}  # the skipped program has no speed
    assert speed.tests == {"LE-LS": [(600, 1e8, 3.0), (6000, 5e8, 4.0)]}
    scale = dict(SCREEN, population=50)
    assert gpu_hours.stage_seconds(_stage("LE-LS", out_dir=done), scale, speed) == pytest.approx(3.6e12 / 2e9 + 9.0)
    other = os.path.join(RESULTS, "claims", "skills-bias1", "evolve", "LE-LS")
    assert gpu_hours.stage_seconds(_stage("LE-LS", out_dir=other), scale, speed) == pytest.approx(3.6e12 / 1e9 + 6.0)
    # a screen test: 5 runs x 5 best x 4 tests = 100 individuals of 150,000 + 6 x 1,000,000 steps, 600 lanes
    test = _stage("LE-LS", kind="test", cost=100 * 6_150_000.0)
    assert gpu_hours.stage_seconds(test, scale, speed) == pytest.approx(6.15e8 / 1e8 + 3.0)
    paper_test = _stage("LE-LS", kind="test", cost=1000 * 6_150_000.0)  # 6,000 lanes
    assert gpu_hours.stage_seconds(paper_test, scale, speed) == pytest.approx(6.15e9 / 5e8 + 4.0)
    failed = _study_check(tmp_path, program_key(read_config(done)[0]), status="failed")
    assert failed.programs == {} and gpu_hours.stage_seconds(_stage("LE-LS", out_dir=done), scale, failed) == \
        pytest.approx(3.6e12 / 1e9 + 6.0)
