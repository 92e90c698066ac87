"""One CPU device per core is asked for only before JAX starts, and never over the user's flag."""

import os

import jax

from imrl_jax.devices import HOST_DEVICE_FLAG, use_host_cores


def test_user_flag_is_left_alone(monkeypatch):
    monkeypatch.setenv("XLA_FLAGS", f"{HOST_DEVICE_FLAG}=3 --xla_cpu_enable_fast_math=false")
    assert use_host_cores() is None
    assert os.environ["XLA_FLAGS"] == f"{HOST_DEVICE_FLAG}=3 --xla_cpu_enable_fast_math=false"


def test_too_late_once_the_backend_runs(monkeypatch):
    monkeypatch.setenv("XLA_FLAGS", "--xla_cpu_enable_fast_math=false")
    jax.devices()  # the backend is up
    assert use_host_cores(2) is None
    assert os.environ["XLA_FLAGS"] == "--xla_cpu_enable_fast_math=false"


def test_fresh_process_gets_the_devices_asked_for():
    import subprocess
    import sys

    code = "from imrl_jax.devices import use_host_cores; n = use_host_cores(2); import jax; print(n, len(jax.devices()))"
    env = {k: v for k, v in os.environ.items() if k != "XLA_FLAGS"}
    out = subprocess.run([sys.executable, "-c", code], env={**env, "JAX_PLATFORMS": "cpu"}, capture_output=True,
                         text=True, timeout=120)
    assert out.stdout.split() == ["2", "2"], out.stderr
