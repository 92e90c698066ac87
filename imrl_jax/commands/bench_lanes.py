"""The benchmarks' lanes (one individual on one task each): their inputs, split over the devices, and a timed program."""

from __future__ import annotations

from typing import NamedTuple

import jax
import numpy as np


def shard(array, lanes: int):
    """Split the lane axis over the devices when they divide it."""
    from jax.sharding import Mesh, NamedSharding, PartitionSpec

    devices = jax.devices()
    if lanes % len(devices):
        return array
    return jax.device_put(array, NamedSharding(Mesh(np.asarray(devices), ("lanes",)), PartitionSpec("lanes")))


def lane_inputs(config, lanes: int):
    """Each lane's key and genome (uniform in [-1, 1]), the same in every run."""
    genome_size = max(config.num_genes, 1)
    genomes = jax.random.uniform(jax.random.key(1), (lanes, genome_size), minval=-1, maxval=1)[:, : config.num_genes]
    keys = jax.random.split(jax.random.key(0), lanes)
    return shard(keys, lanes), shard(genomes, lanes)


class Program(NamedTuple):
    """A timed program: call ``fn(*args)``; each call does ``lane_steps`` lane-steps."""

    fn: object
    args: tuple
    lane_steps: int
    config: object


def alternate(calls: dict, repeats: int) -> dict:
    """Seconds of ``repeats`` timed runs of each ``name: (fn, args)`` of ``calls`` (after compilation), the programs
    taking turns and their order reversed every other round, so that each sees the same machine."""
    import time

    order, times = list(calls), {name: [] for name in calls}
    for i in range(repeats):
        for name in (order if i % 2 == 0 else order[::-1]):
            fn, args = calls[name]
            start = time.perf_counter()
            jax.block_until_ready(fn(*args))
            times[name].append(time.perf_counter() - start)
    return times
