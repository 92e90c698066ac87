"""The resumable stage runner every study shares: stages, their commands, costs, progress and published checkpoints.

Every stage is a command of the package, printed before it runs, its progress line shown beside
the whole pipeline's (stage i of N, elapsed time, and an ETA from the stages' costs in lane-steps
at the rate measured so far, or an assumed one before any stage is timed). A finished stage is
skipped; an interrupted evolution resumes from its last checkpoint; an interrupted learning test
goes on from its first unfinished run (the runs it finished are kept in its ``partial/`` folder,
committed with the results). Run the same command again to go on after an interruption. The newest
checkpoint of every evolution, unfinished or finished, is copied into its run directory's
``resume_checkpoint/`` (``checkpoints/`` is not committed), so that a fresh clone with the results
committed goes on from there, or extends a finished run (``evolve --resume --generations 150``).
The studies (``python -m experiments list|run|report NAME``) plan their stages as tables over
shared runs (``experiments.harness.table``); the paper's Fig. 3 is ``experiments.reproduction``.
"""

from __future__ import annotations

import json
import math
import os
import shutil
import subprocess
import sys
import time
from typing import NamedTuple

from experiments.harness.study import MEASURED
from imrl_jax import conditions  # the condition table (no JAX)
from imrl_jax.runs.progress import clock
from imrl_jax.runs.rundir import RunDirError, read_json, saved_steps, sweep_points, write_atomic

#: The paper's conditions (rows of imrl_jax.conditions): those evolved, and those learning-tested.
EVOLVED = conditions.PAPER_EVOLVED
TESTED = conditions.PAPER


def _set_options(sets) -> list[str]:
    return [option for assignment in sets for option in ("--set", assignment)]


def evolve_command(scale: dict, variant: str, condition: str, out_dir: str, sets: tuple[str, ...] = (),
                   sweep: tuple[str, ...] = ()) -> list[str]:
    """The evolve command of a stage: ``variant`` is the preset, ``sets`` more FIELD=VALUE overrides, ``sweep``
    FIELD=V1,V2 values taken in step (``--sweep ... --zip``: a sweep's points in one program)."""
    command = [sys.executable, "-m", "imrl_jax.evolve", "--cond", condition, "--preset", variant, *_set_options(sets),
               "--seeds", str(scale["seeds"]), "--generations", str(scale["generations"]),
               "--childhood-steps", str(scale["childhood_steps"]), "--task-steps", str(scale["task_steps"]),
               "--bins", str(scale["bins"]), "--out", out_dir]
    if "population" in scale:
        command += ["--population", str(scale["population"]), "--parents", str(scale["parents"])]
    if sweep:
        command += [option for values in sweep for option in ("--sweep", values)] + ["--zip"]
    started = any(os.path.exists(os.path.join(out_dir, name)) for name in ("config.json", "sweep.json"))
    return command + (["--resume"] if started else [])


def test_command(scale: dict, variant: str, condition: str, run_dir: str, out_dir: str,
                 sets: tuple[str, ...] = (), sle_noise_steps: int | None = None) -> list[str]:
    """The learning-test command of a stage (SLE: ``variant`` is the preset, ``sets`` more overrides)."""
    command = [sys.executable, "-m", "imrl_jax.learning_test"]
    if not conditions.get(condition).evolved:
        # SLE's noise anneals over an adult task's length, not the whole test (claim 5 compares speeds);
        # sle_noise_steps=0 anneals it over the whole test instead.
        noise_steps = scale["task_steps"] if sle_noise_steps is None else sle_noise_steps
        command += ["--cond", condition, "--preset", variant, "--runs", str(scale["seeds"]), *_set_options(sets),
                    "--set", f"sle_noise_steps={noise_steps}"]
    else:  # the test runs with its evolution's config, step kernel included
        command += [run_dir]
    return command + ["--best", str(scale["best"]), "--tests", str(scale["tests"]),
                      "--task-steps", str(scale["test_steps"]), "--bins", str(scale["test_bins"]),
                      "--steady-steps", str(scale["steady_steps"]), "--chunks", str(min(10, scale["test_bins"])),
                      "--out", out_dir]


#: Lane-steps per second assumed before any stage of this results directory has been timed
#: (the cpu-scale evolutions ran at 1.1-1.3 million on 2 CPU cores).
DEFAULT_RATE = 1.2e6
#: Where an unfinished evolution's newest checkpoint is copied (committed: checkpoints/ is not).
PUBLISHED = "resume_checkpoint"
#: How often the runner reads a running stage's events.
POLL_SECONDS = 0.5
#: How often the runner looks again at a stage's folder that another command is writing.
LOCK_POLL_SECONDS = 10.0
#: A study's record of its stages (in its folder): each one's command, and once done its time and cost.
MANIFEST = "manifest.json"


class Stage(NamedTuple):
    """One stage of the pipeline: what it is, where it writes, what it costs (lane-steps, estimated)."""

    name: str
    kind: str  # evolve, test, measure (a command that writes MEASURED into out_dir when it is done), baseline
    variant: str
    condition: str
    out_dir: str
    cost: float
    runs: int = 0  # a test stage's runs when they are not the scale's seeds (0: the scale's)
    needs: tuple[str, ...] | None = None  # the stages it waits for when fanned out (None: experiments.harness.executor.needs)
    generations: int = 0  # an evolve stage's generations when they are not the scale's (0: the scale's)
    world: str = "arena"  # the world its lives are lived in (docs/WORLDS.md)


def life_steps(scale: dict, condition: str, task_steps: int, *, num_tasks: int = 6) -> int:
    """Steps of one life of ``condition`` at ``scale``: its childhood, if any, then ``num_tasks`` of ``task_steps``."""
    return (scale["childhood_steps"] if conditions.get(condition).has_childhood else 0) + num_tasks * task_steps


def evolution_cost(scale: dict, condition: str, *, num_tasks: int = 6) -> float:
    """Lane-steps of an evolution of ``condition`` at ``scale`` (every life of every generation and seed)."""
    return float(scale["seeds"] * scale.get("population", 50) * scale["generations"]
                 * life_steps(scale, condition, scale["task_steps"], num_tasks=num_tasks))


def test_cost(scale: dict, condition: str, *, num_tasks: int = 6) -> float:
    """Lane-steps of a learning test of ``condition`` at ``scale`` on ``num_tasks`` tasks."""
    return float(scale["seeds"] * scale["best"] * scale["tests"]
                 * life_steps(scale, condition, scale["test_steps"], num_tasks=num_tasks))


def generations_done(run_dir: str) -> int:
    """Generations an evolution has finished, from its history.csv (0 if none; a sweep: its least advanced point)."""
    points = sweep_points(run_dir)
    if points is not None:
        return min(generations_done(point) for point in points)
    path = os.path.join(run_dir, "history.csv")
    if not os.path.isfile(path):
        return 0
    with open(path) as f:
        rows = [line.split(",", 1)[0] for line in f.read().splitlines()[1:] if line]
    return max((int(g) for g in rows), default=-1) + 1


def partial_runs(test_dir: str) -> int:
    """Runs an interrupted learning test has finished (kept in its ``partial/`` folder)."""
    folder = os.path.join(test_dir, "partial")
    return sum(name.startswith("run_") for name in os.listdir(folder)) if os.path.isdir(folder) else 0


def stage_done(stage: Stage, scale: dict) -> bool:
    """A finished evolution (all generations in its history), learning test (its steady.json), measurement (its
    result.json) or baseline (its summary.json)."""
    if stage.kind == "evolve":
        return generations_done(stage.out_dir) >= (stage.generations or scale["generations"])
    if stage.kind == "test":  # a sweep's test (of every point) writes sweep_tests.json when all are done
        return any(os.path.exists(os.path.join(stage.out_dir, name)) for name in ("steady.json", "sweep_tests.json"))
    if stage.kind == "measure":
        return os.path.exists(os.path.join(stage.out_dir, MEASURED))
    if stage.kind == "baseline":  # python -m imrl_jax.baselines writes its summary last
        return os.path.exists(os.path.join(stage.out_dir, "summary.json"))
    return False


def wait_unlocked(stage: Stage, scale: dict, say=print) -> bool:
    """Wait while another process of this host writes the stage's folder (another study's command running the same
    run or test: its lock); whether the stage is done by then. A holder on another host is left to the stage's
    command, which refuses in one line."""
    from imrl_jax.runs.rundir import LOCK, holder_alive, read_lock

    told = False
    while (holder := read_lock(os.path.join(stage.out_dir, LOCK))) is not None and holder_alive(holder):
        if not told:
            say(f"== {stage.name}: {stage.out_dir} is being written by pid {holder.pid} (another command): waiting "
                f"for it to end", flush=True)
            told = True
        time.sleep(LOCK_POLL_SECONDS)
    return stage_done(stage, scale)


def fraction_done(stage: Stage, scale: dict) -> float:
    """How much of an unfinished stage its files already hold: an evolution's generations, a test's finished runs."""
    if stage.kind == "evolve":
        return min(1.0, generations_done(stage.out_dir) / (stage.generations or scale["generations"]))
    if stage.kind == "test":
        return min(1.0, partial_runs(stage.out_dir) / (stage.runs or scale["seeds"]))
    return 0.0


def cost_left(stage: Stage, scale: dict) -> float:
    """The lane-steps a stage has still to run: none when done, else the part its files do not hold yet."""
    return 0.0 if stage_done(stage, scale) else stage.cost * (1.0 - fraction_done(stage, scale))


def measured_rate(manifest: dict) -> float | None:
    """Lane-steps per second over the timed stages of the manifest (None when none is)."""
    # a cost of 0 or less is no measurement (a manifest written before resumed stages counted their runs right)
    timed = [s for s in manifest.get("stages", {}).values() if (s.get("cost") or 0) > 0 and s.get("seconds")]
    return sum(s["cost"] for s in timed) / sum(s["seconds"] for s in timed) if timed else None


def eta_seconds(remaining: list[Stage], rate: float, fraction: float = 0.0, stage_rate: float | None = None) -> float:
    """Seconds left: the running stage (``remaining[0]``, ``fraction`` done) and those after it."""
    if not remaining:
        return 0.0
    first = (1.0 - fraction) * remaining[0].cost / (stage_rate or rate)
    return first + sum(s.cost for s in remaining[1:]) / rate


def publish_checkpoint(run_dir: str, at_most: int | None = None) -> int | None:
    """Copy the newest checkpoint of ``run_dir`` (up to generation ``at_most``) into ``run_dir/resume_checkpoint``
    (which is committed); a sweep's of each point at the newest generation all of them have, so that a clone goes
    on with every point together."""
    points = sweep_points(run_dir)
    if points is not None:
        newest = [(saved_steps(os.path.join(point, "checkpoints")) or [None])[-1] for point in points]
        if None in newest:
            return None
        published = [publish_checkpoint(point, min(newest)) for point in points]
        return None if None in published else min(published)
    steps = [s for s in saved_steps(os.path.join(run_dir, "checkpoints")) if at_most is None or s <= at_most]
    published = os.path.join(run_dir, PUBLISHED)
    if not steps or saved_steps(published) == steps[-1:]:
        return steps[-1] if steps else None
    tmp = published + ".tmp"
    shutil.rmtree(tmp, ignore_errors=True)
    shutil.copytree(os.path.join(run_dir, "checkpoints", str(steps[-1])), os.path.join(tmp, str(steps[-1])))
    shutil.rmtree(published, ignore_errors=True)
    os.replace(tmp, published)
    return steps[-1]


def restore_published(run_dir: str) -> int | None:
    """In a fresh clone (no checkpoints/), put the published checkpoint back where ``evolve --resume`` reads it (a
    sweep: each point's; returning the least advanced restored)."""
    points = sweep_points(run_dir)
    if points is not None:
        restored = [r for r in (restore_published(point) for point in points) if r is not None]
        return min(restored) if restored else None
    checkpoints = os.path.join(run_dir, "checkpoints")
    steps = saved_steps(os.path.join(run_dir, PUBLISHED))
    if saved_steps(checkpoints) or not steps:
        return None
    shutil.copytree(os.path.join(run_dir, PUBLISHED, str(steps[-1])), os.path.join(checkpoints, str(steps[-1])))
    return steps[-1]


class Overall:
    """The whole pipeline's progress: stages done of the total, elapsed time, ETA."""

    def __init__(self, stages: list[Stage], manifest: dict, stream=None):
        self.stages, self.manifest = stages, manifest
        self.stream = stream or sys.stderr
        self.tty = hasattr(self.stream, "isatty") and self.stream.isatty()
        self.start = time.perf_counter()

    def rate(self) -> tuple[float, str]:
        measured = measured_rate(self.manifest)
        return (measured, "measured") if measured else (DEFAULT_RATE, "estimated")

    def status(self, index: int, fraction: float = 0.0, stage_rate: float | None = None) -> str:
        """'stage i/N, all: elapsed, ETA' for the stage at ``index`` (``fraction`` of it done)."""
        rate, how = self.rate()
        if how == "estimated" and stage_rate:  # nothing timed yet: the running stage's rate beats a guess
            rate, how = stage_rate, "at this stage's rate"
        remaining = [s for s in self.stages[index:] if not stage_done(s, self.manifest["sizes"])]
        if remaining and remaining[0] is not self.stages[index]:
            fraction = 0.0
        eta = eta_seconds(remaining, rate, fraction, stage_rate)
        return (f"stage {index + 1}/{len(self.stages)} | all stages: {clock(time.perf_counter() - self.start)} "
                f"elapsed, ETA {clock(eta)} ({how})")

    def line(self, text: str) -> None:
        self.stream.write(("\r\033[K" if self.tty else "") + text + ("" if self.tty else "\n"))
        self.stream.flush()

    def end_line(self) -> None:
        if self.tty:
            self.stream.write("\n")
            self.stream.flush()


def run_stage(stage: Stage, index: int, command: list[str], overall: Overall, manifest_path: str,
              done_before: float = 0.0, env: dict | None = None) -> None:
    """Run one stage, its progress (read from its events, imrl_jax.runs.events) shown after the whole pipeline's;
    record its command, time and cost. Its other output passes straight through."""
    from experiments.harness.executor import dying_with_runner, log_name
    from imrl_jax.runs.events import ENV, READER, Reader

    manifest = overall.manifest
    print(f"\n== [{index + 1}/{len(overall.stages)}] {stage.name}\n"
          f"$ {' '.join(command[1:] if command[0] == sys.executable else command)}\n"
          f"{overall.status(index, done_before)}", flush=True)
    events = os.path.join(os.path.dirname(manifest_path), "logs", log_name(stage.name) + ".events")
    if os.path.exists(events):
        os.remove(events)  # this attempt's events alone
    reader = Reader(events)
    record_start(manifest, manifest_path, stage, command)
    start = time.perf_counter()
    process = subprocess.Popen(dying_with_runner(command), env={**(env or os.environ), ENV: events, READER: "1"})
    first = None  # (fraction, time) at the first progress event: the stage's own rate is measured from there
    try:
        while True:
            code = process.poll()
            for event in reader.read():
                if event.get("kind") != "progress":
                    continue
                fraction = event["done"] / max(event["total"], 1)
                now = time.perf_counter()
                first = first or (fraction, now)
                stage_rate = ((fraction - first[0]) * stage.cost / (now - first[1])
                              if fraction > first[0] and now > first[1] else None)
                overall.line(f"{event['line']} || {overall.status(index, fraction, stage_rate)}")
                if stage.kind == "evolve":
                    publish_checkpoint(stage.out_dir)
            if code is not None:
                break
            time.sleep(POLL_SECONDS)
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
        overall.end_line()
        if stage.kind == "evolve":
            publish_checkpoint(stage.out_dir)
    if code:
        raise subprocess.CalledProcessError(code, command)
    record_stage(manifest, manifest_path, stage, command, time.perf_counter() - start, done_before)


def manifest_problem(manifest) -> str:
    """What makes a parsed manifest unusable ("" if nothing): its shape, and each stage's entry."""
    if not isinstance(manifest, dict):
        return "is not a JSON object"
    if not isinstance(manifest.get("stages"), dict):
        return "has no \"stages\" object"
    for name, entry in manifest["stages"].items():
        if not isinstance(entry, dict) or not isinstance(entry.get("command", ""), str):
            return f"records stage {name[:80]!r} as no object with a command"
        for key in ("seconds", "cost"):
            value = entry.get(key)
            if value is not None and (isinstance(value, bool) or not isinstance(value, (int, float))
                                      or not math.isfinite(value)):
                return f"records stage {name[:80]!r} with {key} {str(value)[:40]!r}, not a number"
        if not isinstance(entry.get("done", True), bool):
            return f"records stage {name[:80]!r} with done neither true nor false"
    return ""


def read_manifest(path: str) -> dict:
    """A study's manifest read and checked ({} where there is none yet); a damaged one is a RunDirError in one line
    naming it and its repair."""
    if not os.path.lexists(path):
        return {}
    repair = (f"remove {path} to start a new one (the stages' own folders say what is done; only the commands and "
              f"times it recorded are lost)")
    try:
        manifest = read_json(path, "manifest")
    except RunDirError as error:
        raise RunDirError(f"{error}; {repair}") from None
    problem = manifest_problem(manifest)
    if problem:
        raise RunDirError(f"manifest: {path} {problem}; {repair}")
    return manifest


def recorded_done(entry: dict) -> bool:
    """Whether a manifest entry records its stage as finished (an entry written before ``done`` was recorded is)."""
    return entry.get("done", True)


def write_entry(manifest: dict, manifest_path: str, name: str, entry: dict) -> None:
    """Record one stage's entry: read the manifest again, change that entry alone, write it atomically (the runner
    holds the study's lock, so no other runner's entry is lost; a kill leaves the old or the new file)."""
    stored = read_manifest(manifest_path)
    stages = {**manifest.get("stages", {}), **stored.get("stages", {})}
    stages[name] = entry
    manifest["stages"] = stages
    write_atomic(manifest_path, (json.dumps({**stored, **manifest}, indent=2) + "\n").encode())


def record_start(manifest: dict, manifest_path: str, stage: Stage, command: list[str]) -> None:
    """Record a stage as started: should the runner be killed before it records the end, the next one knows."""
    write_entry(manifest, manifest_path, stage.name, dict(command=" ".join(["python"] + command[1:]), done=False,
                                                          started=time.strftime("%Y-%m-%dT%H:%M:%S%z")))


def record_stage(manifest: dict, manifest_path: str, stage: Stage, command: list[str], seconds: float,
                 done_before: float = 0.0) -> None:
    """Write a finished stage into the manifest: its command, time and cost."""
    write_entry(manifest, manifest_path, stage.name, dict(
        command=" ".join(["python"] + command[1:]), seconds=round(seconds, 1),
        cost=round(stage.cost * (1.0 - done_before)), done=True))


def record_found_done(stages: list[Stage], scale: dict, manifest: dict, manifest_path: str) -> None:
    """Record as done each stage the manifest has as started that has finished since (its runner was killed between
    the stage's end and its record): the manifest then ends as an uninterrupted run's would, its time unknown."""
    for stage in stages:
        entry = manifest["stages"].get(stage.name)
        if entry is not None and not recorded_done(entry) and stage_done(stage, scale):
            write_entry(manifest, manifest_path, stage.name, dict(
                {k: v for k, v in entry.items() if k != "started"}, done=True,
                note="found finished after its runner stopped (its time unknown)"))


def run_stages(stages: list[Stage], scale: dict, manifest: dict, manifest_path: str, command_for, jobs: int = 1,
               executor=None) -> int:
    """The resumable stage runner every study shares: skip finished stages, resume the others, one after another
    (or, given ``jobs`` above 1 or an executor, each as soon as what it needs is done: ``experiments.harness.executor``).

    ``command_for(stage)`` gives a stage's command line and environment (None: this one's).
    Returns the exit code: 0 when every stage is done, a failed stage's code, or 130 on Ctrl-C.
    """
    record_found_done(stages, scale, manifest, manifest_path)
    if jobs > 1 or executor is not None:
        from experiments.harness.executor import Local, run_fanned

        done_before = {}  # the part of each stage its files held when it was submitted (its cost is the rest)

        def prepare(stage):
            if stage.kind == "evolve" and restore_published(stage.out_dir) is not None:
                print(f"== {stage.name}: continuing from its published checkpoint", flush=True)
            done_before[stage.name] = fraction_done(stage, scale)

        def record(stage, command, seconds):
            record_stage(manifest, manifest_path, stage, command, seconds, done_before.get(stage.name, 0.0))

        def finish(stage):
            if stage.kind == "evolve":
                publish_checkpoint(stage.out_dir)

        def started(stage):  # each stage recorded as started as it is submitted
            command, env = command_for(stage)
            record_start(manifest, manifest_path, stage, command)
            return command, env

        return run_fanned(stages, scale, manifest_path, started, jobs, executor or Local(), stage_done, record,
                          prepare, finish, log=lambda line: print(line, flush=True))
    overall = Overall(stages, manifest)
    try:
        for index, stage in enumerate(stages):
            if stage_done(stage, scale):
                print(f"== [{index + 1}/{len(stages)}] {stage.name}: done ({stage.out_dir})")
                if stage.kind == "evolve":  # its last checkpoint stays published: a clone can extend the run
                    publish_checkpoint(stage.out_dir)
                continue
            if wait_unlocked(stage, scale):
                print(f"== [{index + 1}/{len(stages)}] {stage.name}: done by another command ({stage.out_dir})")
                continue
            if stage.kind == "evolve":
                restored = restore_published(stage.out_dir)
                if restored is not None:
                    print(f"== {stage.name}: continuing from the published checkpoint of generation {restored - 1} "
                          f"({os.path.join(stage.out_dir, PUBLISHED)})")
            command, env = command_for(stage)
            run_stage(stage, index, command, overall, manifest_path, fraction_done(stage, scale), env)
    except subprocess.CalledProcessError as error:
        print(f"error: stage failed with exit code {error.returncode}: {' '.join(error.cmd[1:])}", file=sys.stderr)
        return error.returncode or 1
    except KeyboardInterrupt:
        print("\ninterrupted: run the same command again to go on from here", file=sys.stderr)
        return 130
    print(f"\nall stages done in {time.perf_counter() - overall.start:.0f} s; results in {os.path.dirname(manifest_path)}")
    return 0


def load_manifest(out: str, **fields) -> tuple[dict, str]:
    """A results directory's manifest (its stages kept from earlier sittings; a damaged one refused: RunDirError) and
    its path; the directory made if need be (the runner's execution calls it, under the study's lock)."""
    os.makedirs(out, exist_ok=True)
    manifest_path = os.path.join(out, MANIFEST)
    manifest = dict(fields, stages=dict(read_manifest(manifest_path).get("stages", {})))
    from imrl_jax.runs.checkpoint import git_commit

    manifest["git_commit"] = git_commit()
    return manifest, manifest_path
