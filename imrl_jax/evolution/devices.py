"""Devices: one CPU device per core, the seeds x population mesh, global and host arrays.

XLA's CPU runtime runs a lifetime's many small per-step kernels fastest when each core
is a device of its own with its share of the lanes (one thread each, no hand-offs), so
the command-line programs ask for one host device per core before JAX starts.
"""

from __future__ import annotations

import os

import jax
import numpy as np

HOST_DEVICE_FLAG = "--xla_force_host_platform_device_count"
#: The mesh's one axis: the lanes (seeds x population) divided over the devices.
AXIS = "lanes"


def use_host_cores(count: int | None = None) -> int | None:
    """Ask XLA for ``count`` CPU devices (default: one per core) before the backend starts.

    Does nothing, and returns None, when XLA_FLAGS already sets the count or a backend is
    already running; otherwise returns the count asked for. Results do not depend on it.
    """
    flags = os.environ.get("XLA_FLAGS", "")
    if HOST_DEVICE_FLAG in flags:
        return None
    from jax._src import xla_bridge  # no public test for "backend started" that does not start it

    if xla_bridge.backends_are_initialized():
        return None
    count = count or os.cpu_count() or 1
    os.environ["XLA_FLAGS"] = f"{flags} {HOST_DEVICE_FLAG}={count}".strip()
    return count


def make_mesh(count: int | None = None):
    """A 1-D mesh over every device of every process (or the first ``count``: one GPU against all, timed)."""
    from jax.sharding import Mesh

    return Mesh(np.asarray(jax.devices()[:count]), (AXIS,))


def population_sharding(mesh, num_seeds: int, population_size: int):
    """Shard the seeds axis if the devices divide it, else the population axis, else replicate."""
    from jax.sharding import NamedSharding, PartitionSpec

    n = mesh.devices.size
    if num_seeds % n == 0:
        spec = PartitionSpec(AXIS)
    elif population_size % n == 0:
        spec = PartitionSpec(None, AXIS)
    else:
        spec = PartitionSpec()
    return NamedSharding(mesh, spec)


def replicated(mesh):
    """The sharding of a value every device holds in full."""
    from jax.sharding import NamedSharding, PartitionSpec

    return NamedSharding(mesh, PartitionSpec())


def to_global(array, sharding) -> jax.Array:
    """A global array from a host value every process holds in full (typed PRNG keys too).

    Under jax.distributed, jit wants global arrays: a host-local (uncommitted, one-device)
    array is not one, so even the replicated inputs (the seeds' keys) go through here.
    """
    if isinstance(array, jax.Array) and jax.dtypes.issubdtype(array.dtype, jax.dtypes.prng_key):
        impl = jax.random.key_impl(array)
        return jax.random.wrap_key_data(to_global(np.asarray(jax.random.key_data(array)), sharding), impl=impl)
    array = np.asarray(array)
    return jax.make_array_from_callback(array.shape, sharding, lambda index: array[index])


def sharded_axis(sharding) -> str:
    """Which axis of the (seeds, population, ...) arrays ``sharding`` splits: seeds, population or none."""
    spec = tuple(sharding.spec) + (None, None)
    if sharding.mesh.devices.size == 1:
        return "none"
    return "seeds" if spec[0] else "population" if spec[1] else "none"


def to_host(array) -> np.ndarray:
    """The full value of a (possibly multi-process) array on this host."""
    if getattr(array, "is_fully_addressable", True):
        return np.asarray(array)
    from jax.experimental import multihost_utils

    return np.asarray(multihost_utils.process_allgather(array, tiled=True))


# ----------------------------------------------------------------------------- memory

#: What any computation takes besides its lanes: the runtime and the compiled program (measured: 0.5 GB on a CPU).
BASE_BYTES = 2**29
#: Compiling a life grows with its experts (measured on a CPU: about 2.5 MB an expert; a thousand took 3 GB at once).
EXPERT_BYTES = 2**22
#: Each CPU device holds its own runtime (measured: 100,000 devices took 19 GB, about 0.2 MB each).
DEVICE_BYTES = 2**20
#: XLA's temporaries and double buffers on top of a lane's carried state (a safety factor: the estimate is a bound).
SAFETY = 4


def lane_bytes(config) -> int:
    """Bytes one lane (one life) holds as it runs: its weights, traces, a block of draws, its curves and kept agents."""
    inputs, experts = config.num_inputs + 1, config.num_experts
    weights = inputs * (5 * experts + 1)  # reinforcer, actor (2), evaluator, selector actor; the selector critic
    traces = inputs * (experts + 4)
    draws = config.draw_block * 6  # u, z (2), spawn (3)
    curves = (config.num_tasks + 1) * config.num_bins * (experts + 3)  # reaches, timeouts, respawns, selections
    kept = config.num_tasks * weights  # each task's final weights (LifetimeResult.adult_agents)
    return 4 * SAFETY * (2 * weights + traces + draws + curves + kept + 6 * config.num_genes)


def memory_needed(config, lanes: int, devices: int, host_bytes: int = 0) -> int:
    """A conservative estimate of the bytes ``lanes`` lives of ``config`` at once on ``devices`` devices take."""
    return (BASE_BYTES + EXPERT_BYTES * config.num_experts + DEVICE_BYTES * devices + lanes * lane_bytes(config)
            + host_bytes)


def available_memory() -> int | None:
    """Bytes of memory a new computation may take: MemAvailable (Linux), else the physical memory; None if unknown."""
    try:
        with open("/proc/meminfo", "rb") as f:
            for line in f.read(1 << 16).decode("ascii", "replace").splitlines():
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, AttributeError):
        return None


def accelerator_memory() -> int | None:
    """Bytes of memory of the first device when it is an accelerator that says (None on a CPU or if it does not)."""
    device = jax.devices()[0]
    if device.platform == "cpu":
        return None
    try:
        return int((device.memory_stats() or {}).get("bytes_limit", 0)) or None
    except Exception:  # noqa: BLE001 - a backend without memory statistics
        return None


#: Host bytes (of the records a run keeps) from which a refusal names them.
RECORD_SHOWN = 2**26


def check_memory(config, lanes: int, what: str, host_bytes: int = 0) -> None:
    """Raise UsageError in one line, with the estimate and the memory there is, if ``lanes`` lives (and ``host_bytes``
    of the host's own: the records every generation adds) cannot fit."""
    from imrl_jax.config import UsageError

    devices = jax.device_count()
    accelerator = accelerator_memory()
    if accelerator is not None:  # the lanes live on the devices, each holding its share
        needed, have = lanes * lane_bytes(config) // devices, accelerator
        where = f"each {jax.devices()[0].platform} device"
        if needed <= have:
            needed, have, where = BASE_BYTES + host_bytes, available_memory(), "this machine"
    else:
        needed, have, where = memory_needed(config, lanes, devices, host_bytes), available_memory(), "this machine"
    if have is not None and needed > have:
        # The record of every generation, when it weighs: it grows with generations and seeds, not lanes.
        record = f"{host_bytes / 2**30:.1f} GiB of per-generation records, " if host_bytes >= RECORD_SHOWN else ""
        fewer = "fewer generations or seeds" if host_bytes >= needed // 2 else \
            "fewer seeds, a smaller population, fewer bins or experts"
        raise UsageError(f"memory: {what} needs about {needed / 2**30:.1f} GiB ({record}{lanes:,} lives at once of "
                         f"{lane_bytes(config) / 2**20:.2f} MiB each, {config.num_experts} experts, {devices} devices; "
                         f"an estimate) but {where} has {have / 2**30:.1f} GiB available; use {fewer}")


def init_distributed(coordinator: str | None, num_processes: int | None, process_id: int | None) -> None:
    """Start jax.distributed when a coordinator is given by flag or environment.

    Must run before anything starts a JAX backend (``jax.devices()``, any computation).
    On CPU the processes' collectives (the sharded generation, ``process_allgather``,
    barriers) go over gloo/TCP. Raises UsageError on bad flags or a failed start.
    """
    from imrl_jax.config import UsageError

    coordinator = coordinator or os.environ.get("JAX_COORDINATOR_ADDRESS")
    if not coordinator:
        return
    num = num_processes if num_processes is not None else os.environ.get("JAX_NUM_PROCESSES")
    pid = process_id if process_id is not None else os.environ.get("JAX_PROCESS_ID")
    if num is None or pid is None:
        raise UsageError("--coordinator needs --num-processes and --process-id (or JAX_NUM_PROCESSES, JAX_PROCESS_ID)")
    try:
        num, pid = int(num), int(pid)
    except ValueError:
        raise UsageError(f"--num-processes/--process-id: expected integers, got {num!r} and {pid!r}") from None
    if num < 1 or not 0 <= pid < num:
        raise UsageError(f"--process-id: must be in 0..{num - 1} (--num-processes {num}), got {pid}")
    from jax._src import xla_bridge  # no public test for "backend started" that does not start it

    if xla_bridge.backends_are_initialized():
        raise UsageError("--coordinator: a JAX backend is already running in this process; "
                         "jax.distributed must start first (call main() in a fresh process)")
    # Not jax.default_backend() here: it would start the backend before jax.distributed.
    # The flag only matters to the CPU backend (gloo is also JAX 0.10's default there).
    jax.config.update("jax_cpu_collectives_implementation", "gloo")
    try:
        jax.distributed.initialize(coordinator, num, pid)
    except (RuntimeError, ValueError) as error:
        reason = str(error).strip().splitlines()[0] if str(error).strip() else type(error).__name__
        raise UsageError(f"jax.distributed.initialize({coordinator!r}, {num}, {pid}) failed: {reason}") from None
