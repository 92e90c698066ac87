"""The seeds x population axis sharded over several devices changes nothing.

``python -m imrl_jax.evolve`` on 2 forced CPU devices (XLA_FLAGS
--xla_force_host_platform_device_count=2) must write the same history.csv and
final_population.npz, bit for bit, as on one device, whichever axis it shards.
"""

import pytest

from evolve_runs import Runs, assert_same_outputs, outputs, reference

#: A 40 cm target makes reaches common at this tiny scale, so fitness is not all 0.
COMMON = ("--generations", "2", "--parents", "2", "--task-steps", "300", "--bins", "1", "--set", "target_radius=40")
#: 2 seeds: the devices divide the seeds axis. 1 seed of 4: they divide the population axis.
CASES = {
    "seeds": ("--seeds", "2", "--population", "4") + COMMON,
    "population": ("--seeds", "1", "--population", "4") + COMMON,
}


@pytest.mark.parametrize("axis", sorted(CASES))
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
