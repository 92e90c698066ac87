"""The benchmark command: its input checks, and the world section measured at a tiny size."""

import json

import pytest

from imrl_jax.commands import bench


@pytest.mark.parametrize("argv, field", [
    (["--lanes", "1,x"], "--lanes"),
    (["--lanes", "0"], "--lanes"),
    (["--lifetime-lanes", ""], "--lifetime-lanes"),
    (["--lifetime-lanes", "300,-6"], "--lifetime-lanes"),
    (["--steps", "0"], "--steps"),
    (["--lifetime-task-steps", "15"], "--lifetime-task-steps"),
    (["--kernel", "xla,triton"], "--kernel"),
    (["--cpu-devices", "100000"], "--cpu-devices: 100,000 is above the limit"),
    (["--sweep-points", "-1"], "--sweep-points: must be in 0..1000"),
])
def test_bad_input_exits_2_naming_the_field(argv, field, capsys):
    assert bench.main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"error: {field}") and "\n" not in err


def test_json_path_that_is_a_directory_is_refused(tmp_path, capsys):
    assert bench.main(["--json", str(tmp_path)]) == 2
    assert "--json" in capsys.readouterr().err


def test_json_path_under_a_file_is_refused_before_measuring(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("kept")
    assert bench.main(["--json", str(blocker / "out.json")]) == 2
    assert "--json" in capsys.readouterr().err
    assert blocker.read_text() == "kept"


def test_help_shows_defaults(capsys):
    with pytest.raises(SystemExit):
        bench.main(["--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "(default: 1,50,300,3000)" in text and "(default: 1000)" in text and "(default: None)" not in text


@pytest.mark.slow
def test_the_sweep_benchmark_times_both_programs_on_the_same_generation():
    result = bench.sweep_benchmark(2, num_seeds=1, task_steps=20, pairs=1, log=lambda text: None)
    assert result["points"] == 2 and result["single_generation_s"] > 0 and result["sweep_generation_s"] > 0
    assert result["ratio"] == pytest.approx(result["sweep_generation_s"] / (2 * result["single_generation_s"]))


@pytest.mark.parametrize("argv, field", [
    (["--world", "nowhere"], "--world: unknown world 'nowhere'"),
    (["--world-set", "arm_length=5"], "--world-set arm_length=5: give the world too"),
    (["--only-world"], "--only-world"),
    (["--world", "xland", "--sweep-points", "2"], "--world"),
])
def test_a_world_section_it_cannot_measure_is_refused(argv, field, capsys):
    assert bench.main(argv) == 2
    assert capsys.readouterr().err.startswith(f"error: {field}")


def test_the_world_section_times_the_agent_against_the_world_stepped_alone(tmp_path, monkeypatch):
    """``--world xland --only-world``: the JSON's world section holds positive rates and their quotient; the world
    alone really steps the world (random actions move the agents; every step observes)."""
    pytest.importorskip("xminigrid")  # the worlds extra (not in the minimum environment)
    import jax
    import jax.numpy as jnp
    import numpy as np
    from imrl_jax.commands import bench_worlds
    from imrl_jax.world import worlds

    monkeypatch.setattr(bench_worlds, "WORLD_PHASES", bench_worlds.WORLD_PHASES[:1])  # childhood: two compilations
    timed = []  # (program, its compiled executable)
    compile_once = bench_worlds._compiled

    def recorded(program):
        compiled = compile_once(program)
        timed.append((program, compiled[0]))
        return compiled

    monkeypatch.setattr(bench_worlds, "_compiled", recorded)
    out = tmp_path / "bench.json"
    argv = ["--world", "xland", "--world-set", "arm_length=3", "--only-world", "--lanes", "2", "--steps", "16",
            "--repeats", "1", "--json", str(out)]
    assert bench.main(argv) == 0
    section = json.loads(out.read_text())["world"]
    assert (section["name"], section["settings"], section["inputs"], section["actions"]) == (
        "xland", {"arm_length": 3}, 55, 5)
    (row,) = section["rows"]
    assert row["phase"] == "LE-LS childhood" and row["lanes"] == 2 and row["steps"] == 16
    assert row["agent_lane_steps_per_s"] > 0 and row["world_lane_steps_per_s"] > 0
    assert row["ratio"] == pytest.approx(row["world_lane_steps_per_s"] / row["agent_lane_steps_per_s"])

    _, (world, compiled) = timed  # the world alone's program, run again
    state, seen, _ = compiled(*world.args)
    start = bench_worlds._phase_setup(world.config, False)[3]
    starts = [start(jax.random.split(key, 3)[0]) for key in world.args[0]]
    assert any(np.any(np.asarray(state.position[i]) != np.asarray(s.position)) for i, s in enumerate(starts))
    # Its scan is the plain loop: each step observed (summed) and stepped with its random action, lane by lane.
    _, env, task, _ = bench_worlds._phase_setup(world.config, False)
    for i, key in enumerate(world.args[0]):
        k_start, k_action, k_spawn = jax.random.split(key, 3)
        chosen = jax.random.randint(k_action, (16,), 0, 5, jnp.int32)
        spawn = jax.random.uniform(k_spawn, (16, worlds.world_of(world.config).num_spawn_draws))
        lane, total = starts[i], np.zeros(55, np.float32)
        for t in range(16):
            total += np.asarray(env.observe(lane), np.float32)
            lane, _ = env.transition(lane, chosen[t], task, spawn[t])
        np.testing.assert_array_equal(np.asarray(seen[i]), total)
        np.testing.assert_array_equal(np.asarray(state.position[i]), np.asarray(lane.position))
