"""The seeds x population axis sharded over several devices changes nothing.

``python -m imrl_jax.evolve`` on 2 forced CPU devices (XLA_FLAGS
--xla_force_host_platform_device_count=2) must write the same history.csv and
final_population.npz, bit for bit, as on one device, whichever axis it shards.
"""

import pytest

from helpers import SHARDED_CASES as CASES
from helpers import Runs, assert_same_outputs, outputs, reference


# Sharding the population axis is slow; the seeds axis (what paper-scale runs shard) runs by default.
@pytest.mark.parametrize("axis", [a if a == "seeds" else pytest.param(a, marks=pytest.mark.slow) for a in sorted(CASES)])
def test_two_devices_match_one(axis):
    args = CASES[axis]
    with Runs() as runs:
        runs.need_reference(args)
        out = runs.start("2 devices", args, devices=2)
        runs.wait()
    got, want = outputs(out), reference(args)
    assert want["config.json"]["devices"] == 1 and want["config.json"]["sharded_axis"] == "none"
    assert got["config.json"]["devices"] == 2 and got["config.json"]["processes"] == 1
    assert got["config.json"]["sharded_axis"] == axis
    assert_same_outputs(got, want)
    assert got["fitness"].any(), "the check is weak if every individual has fitness 0"


#: Two generations on 2 forced devices: do the next populations keep the input's sharding?
KEEPS_SHARDING = """
import jax, numpy as np
from imrl_jax.config import make_config
from imrl_jax.devices import make_mesh, population_sharding, replicated, to_global
from imrl_jax.run_state import evolution_keys, initial_state
from imrl_jax.ga import make_generation
config = make_config("small", condition="EE-ES", task_steps=20, num_bins=1, population_size=4, num_parents=2)
mesh = make_mesh()
for seeds in (2, 1):  # the seeds axis sharded, then the population axis
    sharding = population_sharding(mesh, seeds, config.population_size)
    state = initial_state(config, list(range(seeds)), sharding)
    keys = to_global(evolution_keys(state.key_data), replicated(mesh))
    populations = state.populations
    generation = make_generation(config, sharding)
    for g in range(2):
        populations, _ = generation(keys, config.learning_params(), populations, g)
        print(seeds, g, populations.sharding.is_equivalent_to(sharding, 3), len(jax.devices()))
"""


def test_next_populations_keep_their_sharding():
    """Without the constraint XLA returns them replicated and later generations run unsharded."""
    import subprocess
    import sys

    from helpers import ROOT, environment

    done = subprocess.run([sys.executable, "-c", KEEPS_SHARDING], cwd=ROOT, env=environment(devices=2),
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.split("\n")[:4] == ["2 0 True 2", "2 1 True 2", "1 0 True 2", "1 1 True 2"], done.stdout
