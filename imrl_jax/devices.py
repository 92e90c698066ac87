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


def make_mesh():
    """A 1-D mesh over every device of every process."""
    from jax.sharding import Mesh

    return Mesh(np.asarray(jax.devices()), ("lanes",))


def population_sharding(mesh, num_seeds: int, population_size: int):
    """Shard the seeds axis if the devices divide it, else the population axis, else replicate."""
    from jax.sharding import NamedSharding, PartitionSpec

    n = mesh.devices.size
    if num_seeds % n == 0:
        spec = PartitionSpec("lanes")
    elif population_size % n == 0:
        spec = PartitionSpec(None, "lanes")
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
