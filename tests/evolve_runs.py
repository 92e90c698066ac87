"""Helpers for the tests that run ``python -m imrl_jax.evolve`` in subprocesses.

Used by test_sharding.py (forced multi-device CPU) and test_distributed.py (two
jax.distributed processes). Each run is a fresh interpreter, so the device count and
jax.distributed can be chosen per run; they compare their outputs with the same command
on one device in one process (:func:`reference`, computed once per pytest session).
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

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
#: Seconds any one run may take before every process of the test is killed.
TIMEOUT = 240

_DISTRIBUTED_ENV = ("JAX_COORDINATOR_ADDRESS", "JAX_NUM_PROCESSES", "JAX_PROCESS_ID")


def command(out_dir: str, args: tuple[str, ...]) -> list[str]:
    return [sys.executable, "-m", "imrl_jax.evolve", "--cond", "EE-LS", "--preset", "small", "--quiet",
            "--out", out_dir, *args]


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
    with np.load(os.path.join(out_dir, "final_population.npz")) as npz:
        result.update({name: npz[name] for name in npz.files})
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


_scratch = tempfile.mkdtemp(prefix="imrl_evolve_runs-")
atexit.register(shutil.rmtree, _scratch, ignore_errors=True)
_references: dict[tuple[str, ...], dict] = {}


class Runs:
    """Evolution subprocesses run together; all are killed when the ``with`` block fails.

    ``with Runs() as runs: runs.need_reference(args); out = runs.start(...); runs.wait()``
    then ``reference(args)`` is the one-device, one-process run of ``args`` (run once
    per session, concurrently with the tested runs while it is not yet known).
    """

    def __init__(self):
        self.dir = tempfile.mkdtemp(dir=_scratch)
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
