"""A study's own command line on the stage runner: parse, plan, then run its stages under the study's lock.

    python -m experiments.MODULE [NAME] [--report] [--jobs N] [--executor local|slurm|submitit-local] ...

The plan (:func:`plan_run`) reads and checks everything first and writes nothing: the options (each
bounded as it is parsed), the study's stages, its manifest (a damaged one is one line naming it and how
to repair it) and whether another runner holds the study. ``cli.execute`` then carries it out: it takes
the study's lock (``OUT/logs/.lock``, ``imrl_jax.runs.rundir.lock_run_dir``: one runner per study folder, and
that of a runner that died is taken over), reads the manifest again, and runs the stages, each started
so that it dies with its runner (``executor.dying_with_runner``): a second runner refuses while the first
runs, and a runner killed leaves no stage running.
"""

from __future__ import annotations

import argparse
import contextlib
import os
from typing import Callable, NamedTuple

from experiments.harness.executor import add_options, from_options
from experiments.harness.reproduce import MANIFEST, load_manifest, read_manifest, run_stages
from imrl_jax.runs import cli
from imrl_jax.runs.rundir import LOCK, RunDirError, holder_alive, lock_run_dir, read_lock

#: The folder of a study's runner within its own (its stages' logs and events): the runner's lock lies there, so
#: that it is never the lock of a stage writing into the study's folder itself.
RUNNER_FOLDER = "logs"


def lock_path(out: str) -> str:
    """The lock file of the runner of the study whose folder is ``out``."""
    return os.path.join(out, RUNNER_FOLDER, LOCK)


def check_free(name: str, out: str) -> None:
    """Raise RunDirError naming the live runner that holds the study (nothing is written)."""
    holder = read_lock(lock_path(out))
    if holder is not None and holder_alive(holder) is not False:
        raise RunDirError(f"study {name}: {out} is being run by pid {holder.pid} on {holder.host} (another runner; "
                          f"its lock {lock_path(out)}): wait for it to end or stop it")


@contextlib.contextmanager
def hold(name: str, out: str):
    """Hold the study's lock while the block runs (refused in one line while another runner holds it)."""
    check_free(name, out)
    folder = os.path.dirname(lock_path(out))
    os.makedirs(folder, exist_ok=True)
    with contextlib.ExitStack() as stack:
        try:
            stack.enter_context(lock_run_dir(folder))
        except RunDirError as error:  # taken between the check and the lock
            raise RunDirError(f"study {name}: another runner holds it ({str(error).removeprefix('--out: ')})") \
                from None
        yield


class StudyRun(NamedTuple):
    """A study's stages to run (or go on with), checked: nothing written yet."""

    name: str
    out: str
    stages: list
    scale: dict
    command_for: Callable
    options: argparse.Namespace  # the fan-out options (experiments.harness.executor.add_options)

    def execute(self) -> int:
        """Take the study's lock, read its manifest again, run what is not done."""
        with hold(self.name, self.out):
            manifest, path = load_manifest(self.out, study=self.name, sizes=self.scale)
            return run_stages(self.stages, self.scale, manifest, path, self.command_for,
                              **from_options(self.options, self.out))


class StudyReport(NamedTuple):
    """A study's report from what has finished, its manifest checked."""

    report: Callable[[], int]

    def execute(self) -> int:
        return self.report()


def plan_run(name: str, out: str, stages: list, scale: dict, command_for: Callable,
             options: argparse.Namespace) -> StudyRun:
    """A study's run, checked: its manifest readable and no other runner on it (raises a user error)."""
    read_manifest(os.path.join(out, MANIFEST))
    check_free(name, out)
    return StudyRun(name, out, list(stages), scale, command_for, options)


def parser(name: str) -> cli.Parser:
    """A study's own options: ``--report`` and the fan-out options."""
    p = cli.Parser(prog=f"python -m experiments run {name}")
    p.add_argument("--report", action="store_true", help="the table and figure of what has finished (runs nothing)")
    add_options(p)
    return p


@cli.exit_codes
def study_main(argv, name: str, out: str, all_stages: Callable[[], tuple[list, dict]], command_for: Callable,
               report: Callable[[], int] | None = None) -> int:
    """A study's command line: run (or go on with) its stages, or ``--report``; parse, plan, ``cli.execute``."""
    args = parser(name).parse_args(argv)
    if args.report:
        if report is None:
            raise cli.UsageError(f"--report: study {name} has no report of its own")
        read_manifest(os.path.join(out, MANIFEST))
        return cli.execute(StudyReport(report))
    stages, scale = all_stages()
    return cli.execute(plan_run(name, out, stages, scale, command_for, args))
