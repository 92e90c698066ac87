"""The arena as brax environments (imrl_jax.agent.brax_env): the project's own step, bitwise; jit, vmap, wrappers, the shim."""

import subprocess
import sys

import jax
import jax.numpy as jnp
import numpy as np
import pytest

brax = pytest.importorskip("brax", reason="the brax extra: pip install -e '.[brax]'")

import brax.envs  # noqa: E402

from helpers import ROOT  # noqa: E402
from imrl_jax.agent import brax_env  # noqa: E402
from imrl_jax.config import Config  # noqa: E402
from imrl_jax.analysis.controllers import perceptron_followers  # noqa: E402
from imrl_jax.agent.learning import take_row  # noqa: E402
from imrl_jax.agent.lifetime import random_pose, step, task_spec, task_start  # noqa: E402
from imrl_jax.agent.networks import reinforce, with_bias, zero_agent  # noqa: E402
from imrl_jax.world.retina import observe  # noqa: E402
from imrl_jax.conditions import ADULT_EVOLVED_SELECTOR  # noqa: E402

STEPS = 2000


def project_steps(config, task: int, key):
    """STEPS adult steps of lifetime.step (EE-ES, perceptron followers chosen at random): what the env must give.

    Returns the view x_t before each step, the actor outputs executed, and the pose, reach
    and timeout after it.
    """
    agent = zero_agent(config)._replace(actor=perceptron_followers(config))
    spec = task_spec(config, task - 1)

    def one(state, _):
        new, record = step(key, config, ADULT_EVOLVED_SELECTOR, config.learning_params(), spec, STEPS, state)
        return new, (take_row(new.xbs, state.t % 2)[:-1], new.prev.action, record.world.pose, record.reached,
                     record.timeout)

    return jax.lax.scan(one, task_start(config, agent, task - 1), None, length=STEPS)[1]


def env_steps(env, outputs):
    """The env driven by the same actor outputs: the view before each step, and the pose, reward, done after it."""

    def one(state, a):
        new = env.drive(state, a)
        return new, (state.obs, new.pipeline_state.pose, new.reward, new.done, new.info["truncation"])

    return jax.lax.scan(one, env.reset(jax.random.PRNGKey(0)), outputs)[1]


def test_the_env_is_the_project_step_bitwise(task=3):
    """Same actor outputs, float32: the same views, poses, rewards, resets and timeouts as lifetime.step."""
    config = Config(condition="EE-ES")
    env = brax.envs.get_environment(f"imrl-task{task}")
    views, outputs, pose, reached, timeout = jax.jit(project_steps, static_argnums=(0, 1))(config, task,
                                                                                            jax.random.key(task))
    assert int(reached.sum()) >= 1 and int(timeout.sum()) >= 3  # the window holds reaches and timeouts
    obs, env_pose, reward, done, truncation = jax.jit(env_steps, static_argnums=0)(env, outputs)
    for got, want in ((obs, views), (env_pose.pos, pose.pos), (env_pose.heading, pose.heading),
                      (reward, reached), (done, reached | timeout), (truncation, timeout)):
        np.testing.assert_array_equal(np.asarray(got), np.asarray(want, np.asarray(got).dtype))


def test_actions_map_to_the_actor_outputs():
    """u in [-1, 1] is a = (u + 1) / 2, clipped; step(u) is drive(a)."""
    u = jnp.asarray([-1.0, 0.0, 1.0, -3.0, 3.0, 0.5], jnp.float32)
    np.testing.assert_array_equal(brax_env.robot_action(u), [0.0, 0.5, 1.0, 0.0, 1.0, 0.75])
    env = brax_env.TaskEnv(3)
    state = env.reset(jax.random.PRNGKey(0))
    action = jnp.asarray([0.3, -0.2])
    by_step = jax.jit(env.step)(state, action)
    by_drive = jax.jit(env.drive)(state, brax_env.robot_action(action))
    for got, want in zip(jax.tree.leaves(by_step), jax.tree.leaves(by_drive)):
        np.testing.assert_array_equal(got, want)


def test_registered_names_options_jit_and_vmap():
    env = brax.envs.get_environment("imrl-task5", task_id=True)
    assert isinstance(env, brax_env.TaskEnv) and env.task == 5
    assert (env.observation_size, env.action_size) == (42, 2)
    state = env.reset(jax.random.PRNGKey(0))
    np.testing.assert_array_equal(state.obs[36:], [0, 0, 0, 0, 1, 0])  # task 5, one-hot
    # A batch of 4 robots, jitted and vmapped, is each robot stepped alone.
    keys = jax.random.split(jax.random.PRNGKey(1), 4)
    actions = jax.random.uniform(jax.random.PRNGKey(2), (4, 2), minval=-1.0, maxval=1.0)
    batch = jax.jit(jax.vmap(env.step))(jax.vmap(env.reset)(keys), actions)
    for i in range(4):
        alone = env.step(env.reset(keys[i]), actions[i])
        np.testing.assert_array_equal(batch.pipeline_state.pose.pos[i], alone.pipeline_state.pose.pos)
        np.testing.assert_array_equal(batch.obs[i], alone.obs)
    assert batch.obs.shape == (4, 42) and batch.obs.dtype == jnp.float32
    with pytest.raises(ValueError, match="task: must be 1 to 6"):
        brax_env.TaskEnv(7)


def test_training_wrapper_keeps_timeouts_as_truncations():
    """Under wrap_for_training, timeouts are truncations, reaches terminals, and both restart at the start pose."""
    config = Config()
    env = brax_env.TaskEnv(3, config)
    wrapped = brax_env.wrap_for_training(env)
    straight = jnp.asarray([[0.0, 1.0], [0.0, 0.0]])  # lane 0 drives straight at full speed, lane 1 stands still

    def one(state, _):
        state = wrapped.step(state, straight)
        return state, (state.done, state.info["truncation"], state.reward, state.pipeline_state.pose.pos)

    _, (done, truncation, reward, pos) = jax.lax.scan(one, wrapped.reset(jax.random.split(jax.random.PRNGKey(0), 2)),
                                                      None, length=450)
    done, truncation, reward = np.asarray(done), np.asarray(truncation), np.asarray(reward)
    # Standing still times out at steps 200 and 400, truncated; nothing is reached.
    assert list(np.flatnonzero(done[:, 1])) == [199, 399] and (truncation[:, 1] == done[:, 1]).all()
    assert reward[:, 1].sum() == 0
    # Driving straight (task 3: its target is not straight ahead) also times out.
    assert list(np.flatnonzero(truncation[:, 0])) == [199, 399]
    np.testing.assert_array_equal(pos[199, 1], np.asarray(task_spec(config, 2).start.pos))
    with pytest.raises(ValueError, match="action_repeat"):
        brax_env.wrap_for_training(env, action_repeat=2)


def test_reaches_are_terminal_and_restart_at_the_start():
    """A robot started at the target's doorstep reaches it: reward 1, done, no truncation, back at the start."""
    config = Config()
    env = brax_env.TaskEnv(3, config)
    spec = task_spec(config, 2)
    state = env.reset(jax.random.PRNGKey(0))
    near = brax_env.Robot(brax_env.Pose(spec.target - jnp.asarray([0.0, 12.0]), jnp.float32(np.pi / 2)),
                          jnp.int32(5))
    new = env.step(state.replace(pipeline_state=near), jnp.asarray([0.0, 1.0]))  # 2 cm towards it
    assert (float(new.reward), float(new.done), float(new.info["truncation"])) == (1.0, 1.0, 0.0)
    np.testing.assert_array_equal(new.pipeline_state.pose.pos, spec.start.pos)
    assert int(new.pipeline_state.trial_step) == 0
    going_on = brax_env.TaskEnv(3, config, trial_episodes=False).step(state.replace(pipeline_state=near),
                                                                      jnp.asarray([0.0, 1.0]))
    assert (float(going_on.reward), float(going_on.done)) == (1.0, 0.0)  # the episode goes on from the start


def test_childhood_env():
    """A random start pose as childhood's, the reinforcer's reward of the new view, walls that clamp, no end."""
    config = Config()
    w = np.linspace(-1.0, 1.0, config.num_inputs + 1).astype(np.float32)
    env = brax.envs.get_environment("imrl-childhood", reinforcer=w)
    key = jax.random.PRNGKey(7)
    state = env.reset(key)
    want = random_pose(jax.random.wrap_key_data(key), config)
    np.testing.assert_array_equal(state.pipeline_state.pose.pos, want.pos)
    run = jax.jit(lambda s: jax.lax.scan(lambda s, _: (env.step(s, jnp.asarray([0.0, 1.0])),) * 2, s, None,
                                         length=300)[1])
    states = run(state)
    np.testing.assert_allclose(states.reward, jax.vmap(lambda x: reinforce(jnp.asarray(w), with_bias(x)))(states.obs),
                               rtol=1e-6)
    np.testing.assert_array_equal(states.obs[-1], observe(config, jax.tree.map(lambda x: x[-1],
                                                                               states.pipeline_state.pose)))
    pos = np.asarray(states.pipeline_state.pose.pos)
    assert pos.min() >= 15.0 and pos.max() <= 385.0
    assert (np.isclose(pos[-1], 15.0) | np.isclose(pos[-1], 385.0)).any()  # driven onto a wall, sliding along it
    assert float(states.done.max()) == 0.0
    with pytest.raises(ValueError, match="childhood_walls"):
        brax_env.ChildhoodEnv(Config(childhood_walls="respawn"))
    with pytest.raises(ValueError, match="reinforcer"):
        brax_env.ChildhoodEnv(reinforcer=np.zeros(3))


def test_device_put_replicated_shim(monkeypatch):
    """The shim stacks a pytree once per device; it is put on jax only where jax lacks it."""
    tree = {"a": jnp.arange(3.0), "b": (jnp.int32(4),)}
    out = brax_env.device_put_replicated(tree, jax.local_devices())
    n = len(jax.local_devices())
    assert out["a"].shape == (n, 3) and out["b"][0].shape == (n,)
    np.testing.assert_array_equal(out["a"][0], [0.0, 1.0, 2.0])
    assert out["a"].sharding.device_set == set(jax.local_devices())
    monkeypatch.delattr(jax, "device_put_replicated", raising=False)
    assert brax_env.install_jax_compat() is True and jax.device_put_replicated is brax_env.device_put_replicated
    assert brax_env.install_jax_compat() is False  # already there: left alone


def test_the_core_package_does_not_import_brax():
    code = ("import sys, imrl_jax, imrl_jax.agent.lifetime, imrl_jax.commands.evolve, imrl_jax.commands.learning_test, imrl_jax.commands.baselines, "
            "imrl_jax.agent.brax_agents; "
            "print(sorted(m for m in ('brax', 'flax', 'mujoco') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "[]"


def test_without_brax_the_import_and_the_command_say_how_to_install_it(tmp_path):
    """With brax unimportable: a clear ImportError, and the command exits 2 with one line."""
    code = ("import sys; sys.modules['brax'] = None\n"
            "try:\n    import imrl_jax.agent.brax_env\nexcept ImportError as error:\n    print(error)\n"
            "from imrl_jax.commands import baselines\n"
            f"sys.exit(baselines.main(['--steps', '10', '--out', {str(tmp_path / 'out')!r}]))")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert out.returncode == 2, out.stderr
    assert out.stdout.strip() == "imrl_jax.agent.brax_env needs brax: pip install -e '.[brax]' (docs/BASELINES.md)"
    assert out.stderr.strip() == "error: " + out.stdout.strip()
    assert not (tmp_path / "out").exists()


def test_importing_the_environments_and_agents_prints_nothing():
    code = ("import imrl_jax.agent.brax_env, brax.training.agents.ppo.train, brax.training.agents.es.train")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert done.stdout == ""  # mujoco prints "Failed to import warp" without its GPU extra
