"""Helpers shared by the tests: tiny configs and command lines, tree and run comparisons, evolve subprocesses.

The evolve subprocesses serve test_sharding.py (forced multi-device CPU) and
test_distributed.py (two jax.distributed processes). Each run is a fresh interpreter, so
the device count and jax.distributed can be chosen per run; they compare their outputs
with the same command on one device in one process (:func:`reference`, computed once per
pytest session).
"""

from __future__ import annotations

import atexit
import json
import os
import shutil
import socket
import subprocess
import sys
import tempfile
import time

import jax
import numpy as np

from imrl_jax.agent import reference as numpy_reference
from imrl_jax.config import Task, make_config

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
#: The committed results of every study.
RESULTS = os.path.join(ROOT, "experiments", "results")
#: Seconds any one run may take before every process of the test is killed.
TIMEOUT = 240

_DISTRIBUTED_ENV = ("JAX_COORDINATOR_ADDRESS", "JAX_NUM_PROCESSES", "JAX_PROCESS_ID")


def tiny_config(condition: str = "LE-LS", **overrides):
    """The paper's model with lifetimes of a few hundred steps."""
    sizes = dict(childhood_steps=400, task_steps=200, num_bins=2, population_size=4, num_parents=2)
    return make_config("paper", condition=condition, **{**sizes, **overrides})


def evolve_args(cond: str = "EE-LS", preset: str = "small", **options) -> list[str]:
    """Quiet ``imrl_jax.commands.evolve`` arguments; ``task_steps=200`` becomes ``--task-steps 200``."""
    args = ["--cond", cond, "--preset", preset]
    for name, value in options.items():
        args += [f"--{name.replace('_', '-')}", str(value)]
    return args + ["--quiet"]


def evolve_command(args) -> list[str]:
    """The command line of ``python -m imrl_jax.evolve`` with ``args``, in this interpreter."""
    return [sys.executable, "-m", "imrl_jax.evolve", *args]


#: A tiny evolve run (2 seeds, 1 generation) for the render and sweep tests (EE-LS: it
#: compiles in half the time of LE-LS, and they share everything these tests use).
TINY_RUN = evolve_args(seeds=2, population=4, parents=2, generations=1, task_steps=200, childhood_steps=200, bins=1)

#: Sharded runs (test_sharding, test_distributed). A 40 cm target makes reaches common at
#: this tiny scale, so fitness is not all 0. 2 seeds: 2 devices divide the seeds axis;
#: 1 seed of 4: they divide the population axis.
SHARDED_COMMON = ("--generations", "2", "--parents", "2", "--task-steps", "300", "--bins", "1",
                  "--set", "target_radius=40")
SHARDED_CASES = {
    "seeds": ("--seeds", "2", "--population", "4") + SHARDED_COMMON,
    "population": ("--seeds", "1", "--population", "4") + SHARDED_COMMON,
}

EXTENDED = numpy_reference.EXTENDED
SHORT_TASK = Task(**numpy_reference.SHORT_TASK_FIELDS)
hand_experts = numpy_reference.hand_experts


def random_genomes(config, n, seed=0):
    """``n`` genomes of ``config``'s condition, uniform in [-1, 1]."""
    return jax.random.uniform(jax.random.key(seed), (n, config.num_genes), minval=-1.0, maxval=1.0)


def assert_trees_close(actual, desired, rtol: float, atol: float, cast=None, name: str = "") -> None:
    """Leaf by leaf ``assert_allclose`` of two pytrees (PRNG keys skipped), each leaf named by its path."""
    assert jax.tree.structure(actual) == jax.tree.structure(desired), name
    leaves = zip(jax.tree_util.tree_leaves_with_path(actual), jax.tree.leaves(desired))
    for (path, x), y in leaves:
        if jax.dtypes.issubdtype(x.dtype, jax.dtypes.prng_key):
            continue
        np.testing.assert_allclose(np.asarray(x, cast), np.asarray(y, cast), rtol=rtol, atol=atol,
                                   err_msg=name + jax.tree_util.keystr(path))


def read_population(out_dir: str) -> dict:
    """Every array of a run's final_population.npz."""
    with np.load(os.path.join(out_dir, "final_population.npz")) as npz:
        return {name: npz[name] for name in npz.files}


def command(out_dir: str, args: tuple[str, ...]) -> list[str]:
    """A quiet small-preset EE-LS evolve command writing to ``out_dir``."""
    return evolve_command([*evolve_args(out=out_dir), *args])


def snapshot(out_dir: str) -> dict:
    """Every file under ``out_dir``: relative path -> bytes."""
    files = {}
    for root, _, names in os.walk(out_dir):
        for name in names:
            path = os.path.join(root, name)
            with open(path, "rb") as f:
                files[os.path.relpath(path, out_dir)] = f.read()
    return files


def interruptible_command(module: str, args) -> list[str]:
    """``python -m module args`` whose SIGINT is Ctrl-C even where the parent ignores SIGINT (as background jobs do)."""
    code = ("import runpy, signal; signal.signal(signal.SIGINT, signal.default_int_handler); "
            f"runpy.run_module({module!r}, run_name='__main__', alter_sys=True)")
    return [sys.executable, "-c", code, *args]


def write_lock(run_dir: str, pid: int, host: str | None = None, start: int = 0) -> str:
    """A lock file in ``run_dir`` naming ``pid`` on ``host`` (default: this one) as its writer; its path."""
    from imrl_jax.runs.rundir import LOCK

    os.makedirs(run_dir, exist_ok=True)
    path = os.path.join(run_dir, LOCK)
    with open(path, "w") as f:
        json.dump({"pid": pid, "host": host or socket.gethostname(), "start": start}, f)
    return path


def run_python(code: str, devices: int = 1, timeout: float = TIMEOUT) -> subprocess.CompletedProcess:
    """``python -c code`` in the repository root on ``devices`` forced CPU devices (tests/ on its path)."""
    env = environment(devices)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (os.path.join(ROOT, "tests"), env.get("PYTHONPATH")) if p)
    return subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True, text=True,
                          timeout=timeout)


def devices_seen(module: str, args) -> int:
    """The devices ``python -m module args`` has once its plan is made (``cli.execute`` replaced: nothing runs), in
    a fresh interpreter on CPU with no device count forced (the command asks for its own)."""
    code = (f"import sys, jax, {module} as command\n"
            "from imrl_jax.runs import cli\n"
            "def execute(plan):\n"
            "    print(len(jax.devices()))\n"
            "    return 0\n"
            "cli.execute = execute\n"
            f"sys.exit(command.main({list(args)!r}))\n")
    env = environment()
    env["XLA_FLAGS"] = " ".join(f for f in env["XLA_FLAGS"].split()
                                if not f.startswith("--xla_force_host_platform_device_count"))
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True, text=True,
                          timeout=TIMEOUT)
    assert done.returncode == 0 and done.stdout.strip(), done.stderr[-2000:]
    return int(done.stdout.split()[-1])


def environment(devices: int = 1) -> dict:
    """The environment of a run on ``devices`` forced CPU devices (nothing of ours inherited)."""
    env = {k: v for k, v in os.environ.items() if k not in _DISTRIBUTED_ENV}
    flags = [f for f in env.get("XLA_FLAGS", "").split() if not f.startswith("--xla_force_host_platform_device_count")]
    env["XLA_FLAGS"] = " ".join(flags + [f"--xla_force_host_platform_device_count={devices}"])
    env["JAX_PLATFORMS"] = "cpu"
    return env


class Job:
    """One subprocess, its output in a log file."""

    def __init__(self, name: str, cmd: list[str], env: dict, log_dir: str):
        self.name = name
        self.log = os.path.join(log_dir, name.replace(" ", "_").replace("/", "_") + ".log")
        with open(self.log, "wb") as log:
            self.proc = subprocess.Popen(cmd, cwd=ROOT, env=env, stdout=log, stderr=subprocess.STDOUT)

    def text(self, tail: int = 4000) -> str:
        with open(self.log, errors="replace") as f:
            return f.read()[-tail:]


def wait_all(jobs: list[Job], timeout: float = TIMEOUT) -> None:
    """Wait for every job; on a failure or past ``timeout`` kill the others and fail with their logs."""
    deadline = time.monotonic() + timeout
    try:
        while True:
            codes = [job.proc.poll() for job in jobs]
            failed = [job for job, code in zip(jobs, codes) if code not in (None, 0)]
            if failed:
                raise AssertionError("\n".join(f"{job.name} exited with {job.proc.returncode}:\n{job.text()}"
                                               for job in failed))
            if all(code == 0 for code in codes):
                return
            if time.monotonic() > deadline:
                raise AssertionError(f"timed out after {timeout} s:\n" + "\n".join(
                    f"{job.name}:\n{job.text()}" for job in jobs if job.proc.poll() is None))
            time.sleep(0.1)
    finally:
        for job in jobs:
            if job.proc.poll() is None:
                job.proc.kill()
            job.proc.wait()


def outputs(out_dir: str) -> dict:
    """history.csv (bytes), every array of final_population.npz, and config.json of a run."""
    with open(os.path.join(out_dir, "history.csv"), "rb") as f:
        result = {"history.csv": f.read()}
    result.update(read_population(out_dir))
    with open(os.path.join(out_dir, "config.json")) as f:
        result["config.json"] = json.load(f)
    return result


def assert_same_outputs(got: dict, want: dict) -> None:
    """Bitwise equality of the history and of the final populations and fitness."""
    assert got["history.csv"] == want["history.csv"]
    for name in ("seeds", "generation", "evaluated", "fitness", "next_population"):
        assert got[name].dtype == want[name].dtype and got[name].shape == want[name].shape, name
        assert got[name].tobytes() == want[name].tobytes(), f"{name} differs"


def free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


_scratch: list[str] = []
_references: dict[tuple[str, ...], dict] = {}


class Runs:
    """Evolution subprocesses run together; all are killed when the ``with`` block fails.

    ``with Runs() as runs: runs.need_reference(args); out = runs.start(...); runs.wait()``
    then ``reference(args)`` is the one-device, one-process run of ``args`` (run once
    per session, concurrently with the tested runs while it is not yet known).
    """

    def __init__(self):
        if not _scratch:
            _scratch.append(tempfile.mkdtemp(prefix="imrl_evolve_runs-"))
            atexit.register(shutil.rmtree, _scratch[0], ignore_errors=True)
        self.dir = tempfile.mkdtemp(dir=_scratch[0])
        self.jobs: list[Job] = []
        self._pending: dict[tuple[str, ...], str] = {}

    def start(self, name: str, args: tuple[str, ...], devices: int = 1, extra: tuple[str, ...] = (),
              out_dir: str | None = None) -> str:
        """Start one run (its output directory returned)."""
        out_dir = out_dir or os.path.join(self.dir, name.replace(" ", "_"))
        self.jobs.append(Job(name, command(out_dir, tuple(args) + tuple(extra)), environment(devices), self.dir))
        return out_dir

    def need_reference(self, args: tuple[str, ...]) -> None:
        if args not in _references and args not in self._pending:
            self._pending[args] = self.start(f"reference_{len(self._pending)}", args)

    def wait(self, timeout: float = TIMEOUT) -> None:
        wait_all(self.jobs, timeout)
        for args, out_dir in self._pending.items():
            _references[args] = outputs(out_dir)
        self._pending.clear()

    def __enter__(self) -> "Runs":
        return self

    def __exit__(self, *exc) -> None:
        for job in self.jobs:
            if job.proc.poll() is None:
                job.proc.kill()
            job.proc.wait()


def reference(args: tuple[str, ...]) -> dict:
    """The outputs of the one-device, one-process run of ``args`` (after Runs.wait)."""
    return _references[tuple(args)]


def tiny_baseline(agent: str = "ppo", **overrides):
    """A brax baseline of a few thousand steps with tiny networks and evaluations (imrl_jax.agent.brax_agents)."""
    from imrl_jax.agent.brax_agents import Baseline

    sizes = dict(steps=3000, seeds=1, tasks=(1,), num_evals=3, eval_lanes=4, eval_steps=300, hidden=(16,),
                 num_envs=8, unroll_length=10, batch_size=8, num_minibatches=4, updates_per_batch=2,
                 population=4, episode_length=100)
    return Baseline(agent=agent, **{**sizes, **overrides})


def reference_life(config, key, genome) -> dict:
    """The NumPy reference's whole life of ``genome`` with the draws ``lifetime.live(key, ...)`` makes (float64)."""
    from imrl_jax.agent import lifetime, reference

    return reference.live_with(config, genome, lifetime.life_draws(key, config, np.float64))


# ------------------------------------------------------------------------ made-up results, as the reports read them


def write_evolution(folder, best, config: dict | None = None, columns: dict | None = None, seeds=None) -> None:
    """An evolution as the reports read it: history.csv with ``best[generation][seed]`` (of ``seeds``, else 0, 1, ...)
    and ``columns`` (name: one value, or [generation][seed]), and config.json holding ``config`` (its whole JSON) if
    given."""
    os.makedirs(folder)  # a folder written twice is a mistake of the test
    columns = columns or {}
    cell = lambda v, g, s: v if np.ndim(v) == 0 else v[g][s]  # noqa: E731
    with open(os.path.join(folder, "history.csv"), "w") as f:
        f.write(",".join(["generation", "seed", "best", *columns]) + "\n")
        f.writelines(",".join(str(x) for x in [g, s if seeds is None else seeds[s], best[g][s],
                                                *(cell(v, g, s) for v in columns.values())]) + "\n"
                     for g in range(len(best)) for s in range(len(best[g])))
    if config is not None:
        with open(os.path.join(folder, "config.json"), "w") as f:
            json.dump(config, f)


def write_learning_test(folder, per_run, curve=(0.1, 0.3), bin_steps: int = 1000, **fields) -> None:
    """A finished learning test as the reports read it: steady.json (the steady state ``per_run``, its mean and sd
    over runs, ``fields``) and curve.csv (the mean curve ``curve``, a bin of ``bin_steps`` each)."""
    os.makedirs(folder)  # a folder written twice is a mistake of the test
    with open(os.path.join(folder, "steady.json"), "w") as f:
        json.dump(dict(dict(steady_per_run=list(per_run), steady_mean=float(np.mean(per_run)),
                            steady_sd=float(np.std(per_run)), num_runs=len(per_run)), **fields), f)
    with open(os.path.join(folder, "curve.csv"), "w") as f:
        f.write("bin,end_step,mean,sd_over_runs\n" + "".join(f"{b},{(b + 1) * bin_steps},{v},0.01\n"
                                                              for b, v in enumerate(curve)))


def relocated(table, tmp_path, document: str | None = None):
    """A study's table writing into ``tmp_path``: its results and folder there, and its document a copy (``document``:
    that text instead)."""
    import dataclasses

    copy = tmp_path / os.path.basename(table.document)
    copy.write_text(open(os.path.join(ROOT, table.document)).read() if document is None else document)
    results = tmp_path / "results"
    return dataclasses.replace(table, results=str(results), out=str(results / table.name), document=str(copy))


def stop_after_first(monkeypatch, module, name: str):
    """``module.name`` patched to run once, then raise KeyboardInterrupt (a kill between two runs of a test): the
    real function and the list its calls are counted in."""
    real, calls = getattr(module, name), []

    def stopped_after_one(*args, **kwargs):
        if calls:
            raise KeyboardInterrupt
        calls.append(1)
        return real(*args, **kwargs)

    monkeypatch.setattr(module, name, stopped_after_one)
    return real, calls
