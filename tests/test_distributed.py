"""Evolution under jax.distributed: two local CPU processes, one run.

Two ``python -m imrl_jax.evolve --coordinator 127.0.0.1:PORT --num-processes 2
--process-id 0/1`` processes (one CPU device each, collectives over gloo) share one
--out directory; the leader writes history.csv and final_population.npz, which must
equal, bit for bit, the same command in one process on one device. Both processes
save the orbax checkpoints together into the shared directory.
"""

import os

import pytest

from helpers import SHARDED_CASES as CASES
from helpers import Runs, assert_same_outputs, free_port, outputs, reference


@pytest.mark.parametrize("axis", ["seeds", pytest.param("population", marks=pytest.mark.slow)])
def test_two_processes_match_one(axis):
    args = CASES[axis]
    coordinator = f"127.0.0.1:{free_port()}"
    with Runs() as runs:
        runs.need_reference(args)
        out = os.path.join(runs.dir, "distributed")
        for pid in (0, 1):
            runs.start(f"process {pid}", args, devices=1, out_dir=out,
                       extra=("--coordinator", coordinator, "--num-processes", "2", "--process-id", str(pid)))
        runs.wait()
        follower_log = runs.jobs[-1].text()
    got, want = outputs(out), reference(args)
    info = got["config.json"]
    assert (info["processes"], info["devices"], info["sharded_axis"]) == (2, 2, axis)
    assert_same_outputs(got, want)
    assert "seed(s) done" in runs.jobs[-2].text() and "seed(s) done" not in follower_log  # the leader reports
    assert sorted(os.listdir(os.path.join(out, "checkpoints"))) == ["1", "2"]


def _args(*argv):
    from imrl_jax.commands.evolve import parser

    return parser().parse_args(["--cond", "EE-LS", *argv])


def test_init_distributed_rejects_bad_flags(monkeypatch):
    import jax

    from imrl_jax.runs.cli import UsageError
    from imrl_jax.evolution.devices import init_distributed as start

    def init_distributed(args):  # the evolve command's call
        return start(args.coordinator, args.num_processes, args.process_id)

    for name in ("JAX_COORDINATOR_ADDRESS", "JAX_NUM_PROCESSES", "JAX_PROCESS_ID"):
        monkeypatch.delenv(name, raising=False)
    assert init_distributed(_args()) is None  # no coordinator: single process, nothing started
    bad = {("--num-processes", "2"): "needs --num-processes and --process-id",
           ("--num-processes", "2", "--process-id", "2"): "must be in 0..1",
           ("--num-processes", "0", "--process-id", "0"): "must be in"}
    for flags, message in bad.items():
        with pytest.raises(UsageError, match=message):
            init_distributed(_args("--coordinator", "127.0.0.1:1", *flags))
    monkeypatch.setenv("JAX_NUM_PROCESSES", "two")
    with pytest.raises(UsageError, match="expected integers"):
        init_distributed(_args("--coordinator", "127.0.0.1:1", "--process-id", "0"))
    jax.devices()  # the backend is up: too late for jax.distributed, said as a usage error, not a crash
    with pytest.raises(UsageError, match="already running"):
        init_distributed(_args("--coordinator", "127.0.0.1:1", "--num-processes", "2", "--process-id", "0"))
