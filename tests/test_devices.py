"""One CPU device per core is asked for only before JAX starts, and never over the user's flag; the memory estimate."""

import os

import jax
import pytest

from imrl_jax.evolution.devices import HOST_DEVICE_FLAG, use_host_cores


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

    code = "from imrl_jax.evolution.devices import use_host_cores; n = use_host_cores(2); import jax; print(n, len(jax.devices()))"
    env = {k: v for k, v in os.environ.items() if k != "XLA_FLAGS"}
    out = subprocess.run([sys.executable, "-c", code], env={**env, "JAX_PLATFORMS": "cpu"}, capture_output=True,
                         text=True, timeout=120)
    assert out.stdout.split() == ["2", "2"], out.stderr


def test_the_host_estimate_holds_the_record_every_generation_adds(monkeypatch):
    """The history (and history.csv's text) grows with generations x seeds: it was left out, and a million
    generations of a thousand seeds passed the estimate, then failed at 36 GB."""
    from imrl_jax.evolution import devices
    from imrl_jax.runs.cli import UsageError
    from imrl_jax.config import make_config
    from imrl_jax.runs.run_state import history_bytes

    config = make_config("small", condition="LE-LS")
    row = history_bytes(config, 1) // config.num_generations
    assert history_bytes(config.replace(num_generations=1000), 30) == 1000 * 30 * row
    assert row >= 4 * (3 + config.num_tasks + 2 * 0)  # at least the float32 history itself
    monkeypatch.setattr(devices, "available_memory", lambda: 2**32)
    monkeypatch.setattr(devices, "accelerator_memory", lambda: None)
    devices.check_memory(config, 10, "a run", host_bytes=2**30)
    with pytest.raises(UsageError, match=r"needs about 4\.\d GiB \(4\.0 GiB of per-generation records, 10 lives at once "
                                         r".*use fewer generations or seeds$"):
        devices.check_memory(config, 10, "a run", host_bytes=2**32)
