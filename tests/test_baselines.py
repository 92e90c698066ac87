"""Baselines from brax.training (imrl_jax.agent.brax_agents, imrl_jax.commands.baselines): the pipeline end to end at a tiny scale, the
measure and the command (the committed study: test_baselines_study.py)."""

import csv
import json
import os

import jax
import numpy as np
import pytest

pytest.importorskip("brax", reason="the brax extra: pip install -e '.[brax]'")

from helpers import ROOT, SHORT_TASK, tiny_baseline  # noqa: E402
from imrl_jax.commands import baselines
from imrl_jax.agent import brax_agents  # noqa: E402
from imrl_jax.agent.brax_env import TaskEnv, wrap_for_training  # noqa: E402
from imrl_jax.config import Config  # noqa: E402


def wrapped_reaches(env, policy, key, num_lanes: int, num_steps: int):
    """Reaches of ``policy`` on ``env`` under brax's training wrappers (auto-reset), per lane."""
    wrapped = wrap_for_training(env)

    def one(state, step_key):
        action, _ = policy(state.obs, step_key)
        state = wrapped.step(state, action)
        return state, state.reward

    state = wrapped.reset(jax.random.split(jax.random.PRNGKey(0), num_lanes))
    return jax.lax.scan(one, state, jax.random.split(key, num_steps))[1].sum(0)


def test_ppo_trains_end_to_end_and_its_reaches_replay_on_the_project_step():
    """A few thousand steps of brax's PPO: finite losses, evaluations on schedule, and the trained policy's
    reaches through the brax environment equal its replay by the project's own step."""
    config = Config(tasks=(SHORT_TASK,))  # a target 40 cm ahead: reaches come early
    b = tiny_baseline()
    run = brax_agents.train_ppo(b, config, 1, seed=0)
    assert len(run.steps) == b.num_evals and run.steps[0] == 0 and run.steps[-1] >= b.steps
    assert run.losses and all(np.isfinite(v) for v in run.losses.values()), run.losses
    assert {"policy_loss", "v_loss"} <= set(run.losses)
    env = TaskEnv(1, config)
    key = jax.random.key(5)
    total = 0
    for deterministic in (True, False):
        policy = run.make_policy(run.params, deterministic=deterministic)
        replayed = jax.jit(lambda k: brax_agents.rollout(k, env, policy, 4, 400))(key)
        through_brax = jax.jit(lambda k: wrapped_reaches(env, policy, k, 4, 400))(key)
        assert replayed.shape == (4,)
        np.testing.assert_array_equal(np.asarray(through_brax), np.asarray(replayed))
        total += int(replayed.sum())
    assert total > 0  # reaches happened, so the counts compared are not all zero
    # The evaluation is that replay, as a performance: reaches / theoretical maximum.
    acting, _ = brax_agents.make_evaluate(b, env, run.make_policy)(key, run.params)
    policy = run.make_policy(run.params, deterministic=False)
    reaches = brax_agents.rollout(key, env, policy, b.eval_lanes, b.eval_steps).sum()
    assert float(acting) == pytest.approx(float(reaches) * config.steps_per_trip()[0] / (b.eval_lanes * b.eval_steps))


def test_performance_is_reaches_over_the_theoretical_maximum():
    config = Config()  # task 3: 30 steps per trip; 3,000 steps allow 100 trips
    assert brax_agents.performance(config, 3, 50, 3000) == pytest.approx(0.5)
    assert brax_agents.performance(config, 2, [65, 0], 6500).tolist() == [0.65, 0.0]


@pytest.mark.slow
def test_es_run_writes_its_outputs(tmp_path):
    """The command with ES at a tiny scale: files, the summary, and a refusal to overwrite."""
    out = str(tmp_path / "es")
    args = ["--agent", "es", "--steps", "800", "--seeds", "2", "--tasks", "3", "--evals", "2", "--eval-steps", "200",
            "--hidden", "8", "--set", "population=2", "--set", "episode_length=100", "--out", out, "--quiet"]
    assert baselines.main(args) == 0
    with open(os.path.join(out, "runs.csv")) as f:
        rows = list(csv.DictReader(f))
    assert [(r["task"], r["seed"]) for r in rows] == [("3", "0"), ("3", "1")]
    with open(os.path.join(out, "curves.csv")) as f:
        curves = list(csv.DictReader(f))
    for r in rows:  # each curve ends with the measure of runs.csv, at the cycles trained (whole generations)
        last = [c for c in curves if c["seed"] == r["seed"]][-1]
        assert (last["step"], last["performance"]) == (r["steps"], r["performance"]) and r["steps"] == "800"
    with open(os.path.join(out, "summary.json")) as f:
        summary = json.load(f)
    assert summary["agent"] == "es" and summary["steps"] == 800 and summary["seeds"] == [0, 1]
    np.testing.assert_allclose(summary["performance_mean"], np.mean([float(r["performance"]) for r in rows]))
    assert os.path.getsize(os.path.join(out, "learning_curve.png")) > 10_000
    assert baselines.main(args) == 2  # an earlier run is replaced only with --overwrite
    assert baselines.main([*args, "--overwrite"]) == 0


@pytest.mark.parametrize("args, field", [
    (["--agent", "sac"], "agent"),
    (["--tasks", "3,7"], "tasks"),
    (["--tasks", "three"], "--tasks"),
    (["--steps", "many"], "--steps: invalid int value"),
    (["--task-set", "nov"], "--task-set: unknown task set"),
    (["--steps", "0"], "steps"),
    (["--evals", "1"], "num_evals"),
    (["--set", "entropy=0.1"], "entropy_cost"),
    (["--set", "num_envs=5"], "num_envs"),
])
def test_bad_input_exits_2_with_one_line(tmp_path, capsys, args, field):
    out = tmp_path / "out"
    assert baselines.main([*args, "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: ") and "\n" not in err and field in err, err
    assert not out.exists()


def test_an_out_holding_a_run_or_anything_else_is_refused_before_training(tmp_path, capsys):
    own, user = tmp_path / "es", tmp_path / "mine"
    own.mkdir(), user.mkdir()
    (own / "summary.json").write_text("{}")
    (user / "history.csv").write_text("kept")
    assert baselines.main(["--agent", "es", "--out", str(own), "--quiet"]) == 2
    assert capsys.readouterr().err.strip() == f"error: --out: {own} already holds a baseline run (pass --overwrite to replace it)"
    assert baselines.main(["--agent", "es", "--out", str(user), "--overwrite", "--quiet"]) == 2
    assert "holds no baseline run (it holds history.csv)" in capsys.readouterr().err
    assert (own / "summary.json").read_text() == "{}" and os.listdir(user) == ["history.csv"]


def test_steps_trained_is_what_the_committed_runs_trained():
    for name in ("ppo_1M", "ppo_5M", "es_1M", "es_5M"):
        folder = os.path.join(ROOT, "experiments", "results", "baselines", name)
        with open(os.path.join(folder, "summary.json")) as f:
            settings = json.load(f)["settings"]
        b = brax_agents.Baseline(**{**settings, "tasks": tuple(settings["tasks"]), "hidden": tuple(settings["hidden"])})
        with open(os.path.join(folder, "runs.csv")) as f:
            assert {int(r["steps"]) for r in csv.DictReader(f)} == {brax_agents.steps_trained(b)}, name
    assert brax_agents.steps_trained(brax_agents.Baseline(agent="es", steps=20_000)) == 32_000  # one generation


def test_the_learning_curve_shows_its_last_point_past_the_budget_asked():
    b = brax_agents.Baseline(agent="ppo", steps=20_000, tasks=(3,), seeds=1, num_evals=2)  # 2 updates: 20,480
    curves = [dict(task=3, seed=0, step=s, performance=p) for s, p in ((0, 0.0), (20_480, 0.5))]
    ax = baselines.plot_learning_curve(b, curves).axes[0]
    assert ax.get_xlim() == (0, 20_480) and ax.get_lines()[0].get_xdata()[-1] == 20_480


def test_run_refuses_a_task_the_task_set_lacks(tmp_path):
    from imrl_jax.config import ConfigError

    with pytest.raises(ConfigError, match=r"^tasks: task 2 is not in the task set \(tasks 1 to 1\)$"):
        baselines.run(tiny_baseline(tasks=(2,)), str(tmp_path / "out"), config=Config(tasks=Config().tasks[:1]))
    assert not (tmp_path / "out").exists()


def test_the_tasks_default_to_every_task_of_the_task_set(tmp_path, monkeypatch):
    from imrl_jax.world import tasks

    two = tmp_path / "two.json"
    two.write_text(tasks.to_json(Config().tasks[2:4], "two"))
    seen = {}

    def run(b, out_dir, config, **options):
        seen.update(b=b, config=config)
        return dict(agent=b.agent, steps=b.steps, performance_mean=0.0, performance_sd_over_seeds=0.0)

    monkeypatch.setattr(baselines, "run", run)
    assert baselines.main(["--agent", "es", "--task-set", str(two), "--out", str(tmp_path / "out"), "--quiet"]) == 0
    assert seen["b"].tasks == (1, 2) and seen["config"].tasks == Config().tasks[2:4]
