"""The seeds x population axis sharded over several devices changes nothing.

``python -m imrl_jax.evolve`` on 2 forced CPU devices (XLA_FLAGS
--xla_force_host_platform_device_count=2) must write the same history.csv and
final_population.npz, bit for bit, as on one device, whichever axis it shards.
"""

import numpy as np
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


def unoptimised(env: dict) -> dict:
    """``env`` with XLA's backend optimisations off (JAX_DISABLE_MOST_OPTIMIZATIONS): these scripts compile many
    programs that each run in moments, and compare only programs compiled alike (one device, two; the shardings and
    the all-gathers are chosen by the partitioner before the backend), so the optimiser's time is spared."""
    return {**env, "JAX_DISABLE_MOST_OPTIMIZATIONS": "1"}


#: Two generations on 2 forced devices: do the next populations keep the input's sharding?
KEEPS_SHARDING = """
import jax, numpy as np
from imrl_jax.config import make_config
from imrl_jax.evolution.devices import make_mesh, population_sharding, replicated, to_global
from imrl_jax.evolution.search import evolution_keys
from imrl_jax.runs.run_state import initial_state
from imrl_jax.evolution.ga import make_generation
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

    done = subprocess.run([sys.executable, "-c", KEEPS_SHARDING], cwd=ROOT, env=unoptimised(environment(devices=2)),
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.split("\n")[:4] == ["2 0 True 2", "2 1 True 2", "1 0 True 2", "1 1 True 2"], done.stdout


#: Two generations with the Pallas kernel (interpreted off a GPU) on one device and on 2 forced devices.
KERNEL_LANES = """
import importlib.util, json, re, jax, numpy as np
from imrl_jax.config import make_config
from imrl_jax.evolution.devices import make_mesh, population_sharding, replicated, to_global
from imrl_jax.evolution.search import evolution_keys
from imrl_jax.runs.run_state import initial_state
from imrl_jax.evolution.ga import make_generation
from imrl_jax.commands.evolve_sweep import batched_values, make_points, make_sweep_step
from imrl_jax.agent import kernel as K
# A 40 cm target: reaches (and so resets) in 100 steps; one bin: the fewest kernel calls.
config = make_config("small", condition="EE-LS", task_steps=100, num_bins=1, population_size=4, num_parents=2,
                     target_radius=40, step_kernel="pallas")
def run(mesh, seeds, how="ga"):
    sharding = population_sharding(mesh, seeds, config.population_size)
    state = initial_state(config, list(range(seeds)), sharding, strategy if how == "snes" else None, mesh)
    keys = to_global(evolution_keys(state.key_data), replicated(mesh))
    args, populations = [keys, config.learning_params()], state.populations
    if how == "ga":  # step(keys, params, populations, index) -> (populations, stats)
        make = lambda: make_generation(config, sharding)
    elif how == "sweep":  # 2 points of 1 seed: B = 2 entries, each with its mutation size
        make, args = lambda: make_sweep_step(config, sharding), [keys, *sweep_values]
    else:  # search.make_generation with evosax's SNES: populations and strategies' states carried
        make = lambda: search.make_generation(strategy, lambda k, p, g: live(k, config, p, g), 1, sharding,
                                              kernel=True)
        populations = (populations, state.search)
    step, outputs, fitness = make(), [], []
    def call(step, populations, g):
        if how == "snes":
            return step(*args, *populations, strategy.default_params(), g)
        return step(*args, populations, g)
    lowered = call(lambda *a: (step.lower(*a), None), populations, 0)[0]
    compiled = lowered.compile().as_text()
    for g in range(2):
        out = call(step, populations, g)
        populations = out[:2] if how == "snes" else out[0]
        outputs += [np.asarray(x).tolist() for x in jax.tree.leaves(out)]
        fitness += np.asarray(out[-1].fitness).ravel().tolist()
    text = lowered.as_text()
    # The Triton kernel a GPU would run (lowered for CUDA here): its grid is each device's lanes.
    K._interpret = lambda: False
    first = (state.populations, state.search) if how == "snes" else state.populations
    cuda = call(lambda *a: (make().trace(*a), None), first, 0)[0]
    cuda = cuda.lower(lowering_platforms=("cuda",))
    K._interpret = interpret
    grids = re.findall(r"grid_x = (\\d+) : i32, grid_y = (\\d+) : i32, grid_z = (\\d+)", cuda.as_text())
    return dict(outputs=outputs, fitness=fitness, shard_map="sdy.manual_computation" in text or "SPMDFullToShardShape" in text,
                gathered=re.findall(r"= \\w+\\[([\\d,]*)\\]\\S* all-gather\\(", compiled),
                kernel_lanes=[int(x) * int(y) * int(z) for x, y, z in grids])
interpret = K._interpret
cases = {str(seeds): [run(make_mesh(1), seeds), run(make_mesh(), seeds)] for seeds in (2, 1)}
points = make_points(config, [0], [dict(mutation_scale=1.0), dict(mutation_scale=0.5)])
sweep_values = list(batched_values(points, 1))
cases["sweep"] = [run(make_mesh(1), 2, "sweep"), run(make_mesh(), 2, "sweep")]
if importlib.util.find_spec("evosax"):  # the evosax extra installed: SNES, 1 seed of 4 (the population axis)
    from imrl_jax.evolution import search, strategies
    from imrl_jax.agent.lifetime import live
    strategy = strategies.make_strategy("snes", config)
    cases["snes"] = [run(make_mesh(1), 1, "snes"), run(make_mesh(), 1, "snes")]
print(json.dumps(cases))
"""


def test_kernel_lanes_shard_over_devices():
    """With step_kernel=pallas each of 2 devices lives its own lanes (a shard_map), with the values of one device;
    the kernel lowered for CUDA is called on each device with half the lanes.

    Under plain jit XLA cannot split the kernel's call: it gathered every lane's state (draws, weights:
    arrays of rank 4 and more) to both devices, each living every lane. Now 2 seeds (the seeds axis
    sharded) gather nothing, and 1 seed of 4 (the population axis) gathers only its fitness,
    performance and genomes (rank 3 at most) to select and reproduce.
    """
    import importlib.util
    import json
    import subprocess
    import sys

    from helpers import ROOT, environment

    done = subprocess.run([sys.executable, "-c", KERNEL_LANES], cwd=ROOT, env=unoptimised(environment(devices=2)),
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    cases = json.loads(done.stdout.strip().splitlines()[-1])
    assert ("snes" in cases) == bool(importlib.util.find_spec("evosax")), list(cases)
    for case, (one, two) in cases.items():
        assert two["outputs"] == one["outputs"], f"{case}: 2 devices differ from one"
        assert np.any(two["fitness"]), f"{case}: no reach, a weak check"
        assert not one["shard_map"] and two["shard_map"], case
        assert one["gathered"] == [] and all(shape.count(",") < 3 for shape in two["gathered"]), two["gathered"]
    assert cases["2"][1]["gathered"] == cases["sweep"][1]["gathered"] == [] and len(cases["1"][1]["gathered"]) == 3
    assert "snes" not in cases or len(cases["snes"][1]["gathered"]) == 3, cases["snes"][1]["gathered"]
    lanes = {"2": 2 * 4 * 6, "1": 4 * 6, "sweep": 2 * 4 * 6, "snes": 4 * 6}  # entries x 4 individuals x 6 tasks
    for case, (one, two) in cases.items():  # in one call on one device, half of them on each of two
        assert one["kernel_lanes"] == [lanes[case]] and two["kernel_lanes"] == [lanes[case] // 2], case
