"""Stages fanned out over processes or a cluster: what waits for what, and the executors (docs/STUDIES.md).

The stage runner (``reproduce.run_stages``) runs a study's stages one after another; given ``jobs``
above 1 or another executor it hands them to :func:`run_fanned`, which starts each stage as soon
as the stages it needs are done, up to ``jobs`` at once:

* an evolution needs nothing (but a measure planned before it);
* a learning test needs the evolutions of its condition planned before it;
* a measure needs every stage planned before it (a ``Stage.needs`` says otherwise).

The executors run a stage's command line (the same as the sequential runner's, so a stage that was
killed or preempted resumes from its checkpoint when it is submitted again, bitwise as ever):
``local`` as processes of this machine, ``slurm`` as SLURM jobs through submitit (its local executor
too, for a test on one machine). Multi-host runs of one evolution (``jax.distributed``) are the
evolve command's own (``--coordinator``), and stay as they are.
"""

from __future__ import annotations

import os
import re
import shutil
import signal
import subprocess
import sys
import time
from typing import Callable, Protocol

BARRIERS = ("measure",)
#: What a stage's command is started through on Linux: it asks the kernel to SIGKILL it when its parent (the runner)
#: ends, however that ends (prctl's PR_SET_PDEATHSIG, 1, kept across exec), then becomes the command. A launcher and
#: not a preexec_fn: a fork of a process with threads (JAX's) may deadlock before the child execs.
_LAUNCHER = ("import ctypes, os, signal, sys\n"
             "try:\n    ctypes.CDLL(None).prctl(1, signal.SIGKILL, 0, 0, 0)\n"
             "except (OSError, AttributeError):\n    pass\n"
             "if os.getppid() != int(sys.argv[1]):\n"
             "    sys.exit(137)  # the runner ended before: no signal would come\n"
             "os.execv(sys.argv[2], sys.argv[2:])\n")


def dying_with_runner(command: list[str]) -> list[str]:
    """``command`` started so that it is killed when this process (its runner) ends, even by SIGKILL (Linux; as it is
    elsewhere): a runner killed leaves no stage running unwatched, to race the next runner."""
    if not sys.platform.startswith("linux") or not command:
        return list(command)
    executable = command[0] if os.sep in command[0] else (shutil.which(command[0]) or command[0])
    return [sys.executable, "-c", _LAUNCHER, str(os.getpid()), executable, *command[1:]]


def needs(stages) -> dict[str, tuple[str, ...]]:
    """The stages each stage waits for, by name (``Stage.needs`` where given, else the rules above)."""
    out: dict[str, tuple[str, ...]] = {}
    for i, stage in enumerate(stages):
        before = stages[:i]
        if getattr(stage, "needs", None) is not None:
            out[stage.name] = tuple(stage.needs)
        elif stage.kind in BARRIERS:
            out[stage.name] = tuple(s.name for s in before)
        else:
            barriers = [s.name for s in before if s.kind in BARRIERS]
            evolutions = ([s.name for s in before if s.kind == "evolve" and s.condition == stage.condition]
                          if stage.kind == "test" else [])
            out[stage.name] = tuple(barriers + evolutions)
    return out


class Job(Protocol):
    """A submitted stage: poll it (None while it runs, else its exit code), or stop it."""

    def poll(self) -> int | None: ...

    def stop(self) -> None: ...


class LocalJob:
    """A stage as a process of this machine, its output in a log file."""

    def __init__(self, command: list[str], env: dict | None, log_path: str):
        os.makedirs(os.path.dirname(log_path), exist_ok=True)
        self.log = open(log_path, "a")
        self.process = subprocess.Popen(dying_with_runner(command), env=env, stdout=self.log,
                                        stderr=subprocess.STDOUT)
        self.id = str(self.process.pid)

    def poll(self) -> int | None:
        code = self.process.poll()
        if code is not None:
            self.log.close()
        return code

    def stop(self) -> None:
        """Interrupt it as Ctrl-C would (an evolution keeps its last checkpoint), then wait for it."""
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGINT)
            try:
                self.process.wait(timeout=60)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        self.log.close()


class Local:
    """Processes of this machine (``--executor local``)."""

    name = "local"

    def submit(self, command: list[str], env: dict | None, log_path: str) -> LocalJob:
        return LocalJob(command, env, log_path)


def job_environment(env: dict | None) -> dict:
    """A job's environment: ``env`` (or this one) without the events file of a runner that would not read it
    (a job's progress lines go to its log)."""
    from imrl_jax.runs.events import ENV, READER

    return {k: v for k, v in (os.environ if env is None else env).items() if k not in (ENV, READER)}


def run_command(command: list[str], env: dict | None, log_path: str) -> int:
    """A stage's command in a cluster job: its output appended to ``log_path`` as it comes; its exit code."""
    os.makedirs(os.path.dirname(log_path), exist_ok=True)
    with open(log_path, "a") as log:
        return subprocess.call(command, env=env, stdout=log, stderr=subprocess.STDOUT)


class SubmititJob:
    """A stage as a submitit job (running :func:`run_command`)."""

    def __init__(self, job):
        self.job, self.id = job, str(job.job_id)

    def poll(self) -> int | None:
        if not self.job.done():
            return None
        try:
            return int(self.job.result())
        except Exception:  # noqa: BLE001 - the job itself failed (cancelled, preempted, timed out): no exit code
            return 1

    def stop(self) -> None:
        self.job.cancel(check=False)


class Submitit:
    """SLURM jobs through submitit (``--executor slurm``), or submitit's local executor (``cluster="local"``)."""

    def __init__(self, folder: str, cluster: str | None = None, **parameters):
        try:
            import submitit
        except ImportError:
            raise ImportError('the slurm executor needs submitit: pip install -e ".[slurm]"') from None
        self.submitit, self.name = submitit, cluster or "slurm"
        self.executor = submitit.AutoExecutor(folder=folder, cluster=cluster)
        if parameters:
            self.executor.update_parameters(**parameters)

    def submit(self, command: list[str], env: dict | None, log_path: str) -> SubmititJob:
        return SubmititJob(self.executor.submit(run_command, command, env, log_path))


def make_executor(name: str, folder: str, **parameters):
    """An executor by name: ``local`` (this machine), ``slurm`` (submitit; parameters as submitit's
    ``update_parameters``: ``slurm_partition``, ``gpus_per_node``, ``timeout_min``...) or ``submitit-local``."""
    if name == "local":
        return Local()
    if name in ("slurm", "submitit-local"):
        return Submitit(folder, cluster="local" if name == "submitit-local" else None, **parameters)
    raise ValueError(f"--executor: unknown executor {name!r} (choose from local, slurm, submitit-local)")


def run_fanned(stages, scale: dict, manifest_path: str, command_for, jobs: int, executor, stage_done, record,
               prepare=None, finish=None, poll_s: float = 0.5, log=print) -> int:
    """Run every unfinished stage as soon as what it needs is done, up to ``jobs`` at once, on ``executor``.

    ``record(stage, command, seconds)`` writes a finished stage into the manifest; ``prepare(stage)`` runs
    before a stage is submitted and ``finish(stage)`` after it ends (an evolution's checkpoint published).
    A failed stage stops what needs it (the others go on). Returns 0 when every stage is done, the first failed
    stage's exit code, or 130 on Ctrl-C (running stages are stopped: an evolution keeps its last checkpoint and
    resumes from it the next time).
    """
    waits = needs(stages)
    by_name = {s.name: s for s in stages}
    unknown = [(s, n) for s in stages for n in waits[s.name] if n not in by_name]
    if unknown:
        log(f"error: stage {unknown[0][0].name} needs {unknown[0][1]!r}, which is not a stage of this study")
        return 2
    # A measure is done or due by what ran before it: it is judged when it could start, as the sequential runner
    # judges it.
    done = {s.name for s in stages if s.kind not in BARRIERS and stage_done(s, scale)}
    for s in stages:
        if s.name in done:
            log(f"== {s.name}: done ({s.out_dir})")
    pending = [s for s in stages if s.name not in done]
    running: dict[str, tuple[object, float, list[str]]] = {}
    logs = os.path.join(os.path.dirname(manifest_path), "logs")
    failed: dict[str, int] = {}  # failed stages (their exit code) and those that need one (0)
    try:
        while pending or running:
            for name, (job, started, command) in list(running.items()):
                code = job.poll()
                if code is None:
                    continue
                del running[name]
                stage = by_name[name]
                if finish:
                    finish(stage)
                if code:
                    path = os.path.join(logs, log_name(name) + ".log")
                    log(f"error: stage {name} failed with exit code {code} (log: {path})")
                    failed[name] = code
                    continue
                done.add(name)
                record(stage, command, time.perf_counter() - started)
                log(f"== {name}: done in {time.perf_counter() - started:.0f} s "
                    f"({len(done)}/{len(stages)} stages done, {len(running)} running)")
            for stage in list(pending):  # what needs a failed stage will not run this time
                if any(n in failed for n in waits[stage.name]):
                    pending.remove(stage)
                    failed[stage.name] = 0
                    log(f"== {stage.name}: not started (it needs a failed stage)")
            for stage in [s for s in pending if all(n in done for n in waits[s.name])]:
                if stage.kind in BARRIERS and stage_done(stage, scale):
                    pending.remove(stage)
                    done.add(stage.name)
                    log(f"== {stage.name}: done ({stage.out_dir})")
                    continue
                if len(running) >= jobs:
                    break
                pending.remove(stage)
                if prepare:
                    prepare(stage)
                command, env = command_for(stage)
                job = executor.submit(command, job_environment(env),
                                      os.path.join(logs, log_name(stage.name) + ".log"))
                running[stage.name] = (job, time.perf_counter(), command)
                log(f"== {stage.name}: started on {executor.name} (job {job.id}): "
                    f"{' '.join(command[1:] if command[0] == sys.executable else command)}")
            if pending and not running:
                blocked = pending[0]
                log(f"error: stage {blocked.name} waits for {', '.join(waits[blocked.name])}, which cannot run")
                return 1
            if running:
                time.sleep(poll_s)
    except KeyboardInterrupt:
        for job, *_ in running.values():
            job.stop()
        log("\ninterrupted: run the same command again to go on from here")
        return 130
    except BaseException:  # the runner itself broke: its jobs do not run on unwatched
        for job, *_ in running.values():
            job.stop()
        raise
    return next((code for code in failed.values() if code), 0)


def log_name(name: str) -> str:
    """A stage's name as a file name (what a file name cannot hold replaced): its log is NAME.log."""
    return "".join(c if c.isalnum() or c in "-_." else "_" for c in name)


EXECUTORS = ("local", "slurm", "submitit-local")
#: The most stages at once (local processes or SLURM jobs), GPUs of a job and minutes of a job's time limit (30 days).
MAX_JOBS = 1000
MAX_GPUS_PER_JOB = 64
MAX_TIMEOUT_MIN = 30 * 24 * 60
#: A SLURM partition's name (a list of them: comma-separated), as sbatch takes it.
PARTITION = re.compile(r"[A-Za-z0-9_.][A-Za-z0-9_.-]{0,63}(,[A-Za-z0-9_.][A-Za-z0-9_.-]{0,63}){0,15}")


def _bounded(least: int, most: int, what: str) -> Callable[[str], int]:
    """An option's type: a whole number from ``least`` to ``most`` (argparse names the option in its error)."""
    def parse(text: str) -> int:
        import argparse

        try:
            value = int(text)
        except ValueError:  # 1.5, 1e8, nan, a number of more digits than int() takes
            value = None
        if value is None or not least <= value <= most:
            raise argparse.ArgumentTypeError(f"must be a whole number of {what} from {least} to {most:,}, "
                                             f"got {text[:80]!r}")
        return value

    return parse


_jobs = _bounded(1, MAX_JOBS, "stages at once")


def _partition(text: str) -> str:
    import argparse

    if not PARTITION.fullmatch(text):
        raise argparse.ArgumentTypeError(f"not a SLURM partition name (letters, digits, '_.-', at most 64, "
                                         f"comma-separated), got {text[:80]!r}")
    return text


def _executor(name: str) -> str:
    import argparse

    if name not in EXECUTORS:
        raise argparse.ArgumentTypeError(f"unknown executor {name[:80]!r} (choose from {', '.join(EXECUTORS)})")
    if name != "local":
        try:
            import submitit  # noqa: F401
        except ImportError:
            raise argparse.ArgumentTypeError(f'{name} needs submitit: pip install -e ".[slurm]"') from None
    return name


def add_options(parser) -> None:
    """The fan-out options of a study's command line, each bounded as it is parsed (nothing is written first)."""
    parser.add_argument("--jobs", type=_jobs, default=1,
                        help=f"stages run at once, 1 to {MAX_JOBS:,} (default 1: one after another)")
    parser.add_argument("--executor", type=_executor, default="local",
                        help=f"where stages run: {', '.join(EXECUTORS)} (slurm and submitit-local: submitit)")
    parser.add_argument("--slurm-partition", type=_partition, help="the SLURM partition of each job (--executor slurm)")
    parser.add_argument("--gpus-per-job", type=_bounded(0, MAX_GPUS_PER_JOB, "GPUs"), default=0,
                        help="GPUs of each SLURM job (--executor slurm)")
    parser.add_argument("--timeout-min", type=_bounded(1, MAX_TIMEOUT_MIN, "minutes"), default=24 * 60,
                        help="each SLURM job's time limit in minutes")


def from_options(args, out: str) -> dict:
    """``run_stages``'s fan-out arguments (``jobs``, ``executor``) from the parsed options; {} for the sequential
    runner."""
    if args.executor == "local" and args.jobs == 1:
        return {}
    parameters = {}
    if args.executor == "slurm":
        parameters = dict(timeout_min=args.timeout_min, gpus_per_node=args.gpus_per_job, tasks_per_node=1)
        if args.slurm_partition:
            parameters["slurm_partition"] = args.slurm_partition
    return dict(jobs=args.jobs, executor=make_executor(args.executor, os.path.join(out, "jobs"), **parameters))


def options_argv(args) -> list[str]:
    """The fan-out options given, as a command line (for a study's own command)."""
    argv = []
    for name, default in (("jobs", 1), ("executor", "local"), ("slurm_partition", None), ("gpus_per_job", 0),
                          ("timeout_min", 24 * 60)):
        value = getattr(args, name)
        if value != default:
            argv += [f"--{name.replace('_', '-')}", str(value)]
    return argv
