"""``python -m imrl_jax.evolve --sweep FIELD=V1,V2``: evolutions at several settings as one program.

    python -m imrl_jax.evolve --cond LE-LS --seeds 10 --sweep trace_lambda=0,0.9,0.98 \\
        --sweep eta_selector_actor=0.01,0.3 --out runs/lambda

A sweep evolves one condition at every point of a grid of **dynamic** values (the learning rules'
rates, discount, trace decay and noise, and the GA's mutation: ``sweeps.DYNAMIC_FIELDS``; MODEL.md
"Learning" and "Genetic algorithm") for the same seeds. Points x seeds are one batch axis of one
compiled generation, each entry with its own values, so the sweep costs one compilation, and on a
GPU about the time of one run until the device is full. A static field (one that changes shapes
or loop lengths) needs a program per value and is refused.

Each point is a run of its own: ``OUT/KEY`` (KEY its content key, :mod:`imrl_jax.runs.runspec`) holds
the files a single run writes (``config.json``, ``history.csv``, ``fitness.png``,
``final_population.npz``, ``checkpoints/``), so a study finds it by its key and
``evolve --resume --out OUT/KEY`` continues one point alone. ``OUT`` holds ``sweep.json`` (the base
config, the seeds and the points), ``sweep.csv`` (each point's settings, key and fitness) and
``sweep.png``. ``evolve --resume --out OUT`` continues the whole sweep (``--generations N`` extends
it); what a point equals is in docs/NUMERICS.md ("A point of a sweep"). A swept value is the float32 the program
computes with (:func:`imrl_jax.evolution.sweeps.swept_value`): ``-0`` is the point ``0``, in its key too.
"""

from __future__ import annotations

import contextlib
import csv
import io
import json
import math
import os
import sys
import time
from typing import NamedTuple, Sequence

import jax
import numpy as np

import imrl_jax
from imrl_jax.runs import cli
from imrl_jax.agent import kernel_choice
from imrl_jax.evolution import sweeps
from imrl_jax.runs.checkpoint import Checkpointer, RunState, _silence_failed_reads, git_commit
from imrl_jax.runs.cli import UsageError, device_warnings, ignored_notes, parse_sets
from imrl_jax.config import Config, ConfigError
from imrl_jax.evolution.devices import check_memory, make_mesh, memory_needed, population_sharding, replicated, to_global, to_host
from imrl_jax.runs.events import add_log, make_log
from imrl_jax.evolution.ga import GAParams, evolve_step
from imrl_jax.agent.networks import trait_names, traits
from imrl_jax.runs.progress import Progress, cost_line
from imrl_jax.runs.rundir import (RunDirError, check_unlocked, check_writable, entries, lock_run_dir, make_dir, not_empty,
                             read_json, recorded_points, saved_steps, write_atomic, write_errno)
from imrl_jax.runs.rundir import SWEEP_FILE, is_sweep  # noqa: F401 - the sweep's names for them
from imrl_jax.evolution.search import evolution_keys
from imrl_jax.runs.run_state import (RunInterrupted, check_run_dir, check_run_options, extend_config_json,
                                 history_bytes, initial_state, record, record_traits, write_failed, write_outputs)
from imrl_jax.runs.runspec import RunSpec
from imrl_jax.evolution.search import over_seeds
from imrl_jax.evolution.sweeps import MAX_POINTS, parse, swept_fields, swept_value  # noqa: F401 - the sweep's names
from imrl_jax.evolution.strategies import GA_NAME, GA_RECORD



class Point(NamedTuple):
    """One point of a sweep: the values it sets, its config and its run's key (its directory's name)."""

    settings: dict
    config: Config
    key: str


def make_points(config: Config, seeds: Sequence[int], settings: Sequence[dict]) -> list[Point]:
    """The points of a sweep from its base config (raises UsageError naming the field, or two points that are one run)."""
    points, seen = [], {}
    for values in settings:
        try:
            changed = sweeps.changed(config, **values)
        except ConfigError as error:
            raise UsageError(f"--sweep: {error}") from None
        key = RunSpec.make(changed, seeds, GA_RECORD).key()
        if key in seen:
            same = [f for f in values if f in changed.spec.ignored_fields()]
            why = f" ({', '.join(same)}: not read by {config.condition})" if same else ""
            raise UsageError(f"--sweep: {label(values)} and {label(seen[key])} are the same run{why}")
        seen[key] = values
        points.append(Point(dict(values), changed, key))
    return points


def label(values: dict) -> str:
    """A point's settings in words: ``trace_lambda=0.9, eta=0.3`` (float32's 9 digits: distinct values read apart)."""
    return ", ".join(f"{k}={v:.9g}" for k, v in values.items())


def sweep_record(config: Config, seeds: Sequence[int], points: Sequence[Point]) -> dict:
    """What sweep.json holds: the base config, the seeds and every point (settings and key)."""
    return {"config": config.to_dict(), "seeds": list(seeds),
            "points": [{"settings": p.settings, "key": p.key} for p in points]}


def read_sweep(out_dir: str) -> tuple[Config, list[int], list[dict]]:
    """The base config, seeds and points' settings a sweep directory records (raises RunDirError naming the file)."""
    path = os.path.join(out_dir, SWEEP_FILE)
    saved = read_json(path, "")
    try:
        found = (Config.from_dict(saved["config"]), [int(s) for s in saved["seeds"]],
                 [dict(p["settings"]) for p in saved["points"]])
    except (ConfigError, ValueError, KeyError, TypeError, AttributeError) as error:
        raise RunDirError(f"{path} is unreadable ({error})") from None
    if not found[2]:
        raise RunDirError(f"{path} records no points (a sweep of none); it is no sweep to resume")
    for settings in found[2]:
        for name, value in settings.items():
            if name not in sweeps.DYNAMIC_FIELDS or isinstance(value, bool) or not isinstance(value, (int, float)) \
                    or not math.isfinite(value):
                raise RunDirError(f"{path} is unreadable (a point sets {name!r} to {value!r}: not a swept field's "
                                  f"finite number)")
    return found


def check_sweep_dir(out_dir: str, config: Config, seeds: Sequence[int], points: Sequence[Point], resume: bool) -> None:
    """Refuse anything but a new or empty directory, or (resuming) this sweep (raises UsageError or RunDirError)."""
    if os.path.exists(out_dir) and not os.path.isdir(out_dir):
        raise UsageError(f"--out: {out_dir} is not a directory")
    exists = is_sweep(out_dir)
    if exists and not resume:
        raise UsageError(f"{out_dir} already holds a sweep ({SWEEP_FILE}); pass --resume to continue it or choose "
                         f"another --out")
    if resume and not exists:
        raise UsageError(f"--resume: {out_dir} holds no sweep to resume (no {SWEEP_FILE})")
    if not exists and entries(out_dir):
        raise not_empty(out_dir, "sweep", entries(out_dir), missing=SWEEP_FILE)
    if exists:
        saved_config, saved_seeds, saved_settings = read_sweep(out_dir)
        if saved_seeds != list(seeds):
            raise UsageError(f"--resume: seeds {list(seeds)} differ from the sweep's {saved_seeds}")
        if saved_settings != [p.settings for p in points]:
            raise UsageError(f"--sweep: the points differ from the sweep's in {out_dir} (resume it without --sweep)")
        differing = [name for name in saved_config.model_differences(config)
                     if not (name == "num_generations" and config.num_generations >= saved_config.num_generations)]
        if differing:
            raise UsageError(f"--resume: the config differs from the sweep's in {out_dir}: {', '.join(differing)} "
                             f"(a sweep goes on with its own; only --generations may grow)")
        saved_keys = [key for key, _ in recorded_points(out_dir)]
        if saved_keys != [p.key for p in points]:
            raise RunDirError(f"{os.path.join(out_dir, SWEEP_FILE)}: its points' keys are not those its config and "
                              f"settings give (made by another version?)")
    for p in points:
        point_dir = os.path.join(out_dir, p.key)
        check_run_dir(point_dir, p.config, seeds, resume and os.path.isfile(os.path.join(point_dir, "config.json")))


def make_sweep_step(config: Config, sharding):
    """The jitted generation ``step(keys, params, ga_params, populations, index)`` of every entry (leading axis B)."""
    return over_seeds(lambda k, p, ga, pop, i: evolve_step(k, config, p, pop, i, ga), (0, 0, 0, 0, None), sharding,
                      genomes=3, kernel=kernel_choice.chosen(config) == "pallas")


def batched_values(points: Sequence[Point], num_seeds: int):
    """Each entry's LearningParams and GAParams (B = points x seeds, points outer), as float32 arrays."""
    def stacked(values):
        return jax.tree.map(lambda *xs: np.repeat(np.asarray(xs, np.float32), num_seeds), *values)

    params = stacked([p.config.learning_params() for p in points])
    ga = stacked([GAParams(p.config.mutation_prob, p.config.mutation_scale) for p in points])
    return params, ga


def run(config: Config, out_dir: str, seeds: Sequence[int], settings: Sequence[dict], *, resume: bool = False,
        checkpoint_every: int = 1, keep: int = 3, quiet: bool = False, log: str | None = None,
        registered: Sequence[str] = ()) -> dict[str, RunState]:
    """Evolve ``config`` at every point of ``settings`` for every seed into ``out_dir``; return each point's final
    state by key (each point's directory is ``out_dir/KEY``). Checked first (:func:`plan`), then run."""
    return plan(config, out_dir, seeds, settings, resume=resume, checkpoint_every=checkpoint_every, keep=keep,
                quiet=quiet, log=log, registered=registered).run()


def plan(config: Config, out_dir: str, seeds: Sequence[int], settings: Sequence[dict], *, resume: bool = False,
         checkpoint_every: int = 1, keep: int = 3, quiet: bool = False, log: str | None = None,
         registered: Sequence[str] = (), lines: Sequence[str] = ()) -> "SweepPlan":
    """Every check of a sweep, nothing written: the plan :meth:`SweepPlan.run` carries out (raises a user error)."""
    config, kernel_note = kernel_choice.resolve(config)  # the points differ in dynamic values only: one program
    lines = (*lines, *([] if quiet or kernel_note is None else [kernel_note]))
    seeds = check_run_options(config, seeds, checkpoint_every, keep, log, out_dir)
    if keep < 2:
        raise UsageError("--keep: a sweep keeps at least 2 checkpoints a point (killed while saving, its points can be "
                         "a generation apart: each needs the one before to go on together)")
    if not settings:
        raise UsageError("--sweep: a sweep needs at least one point")
    if jax.process_count() > 1:
        raise UsageError("--sweep: a sweep runs in one process (its points are its batch); start it without "
                         "--coordinator")
    points = make_points(config, seeds, settings)
    check_writable(out_dir)
    check_unlocked(out_dir)
    for p in points:
        check_unlocked(os.path.join(out_dir, p.key))
    check_sweep_dir(out_dir, config, seeds, points, resume)
    common = resumable_from(out_dir, points) if resume else 0
    lanes = len(points) * len(seeds) * config.population_size * config.lives_per_fitness
    check_memory(config, lanes, f"a sweep of {len(points)} point(s) x {len(seeds)} seed(s) x "
                                f"{config.population_size} individuals",
                 host_bytes=len(points) * history_bytes(config, len(seeds)))
    return SweepPlan(config, out_dir, seeds, points, resume, checkpoint_every, keep, quiet, log, tuple(registered),
                     common, tuple(lines))


class SweepPlan(NamedTuple):
    """A checked sweep: its base config, seeds and points, and what the folders said (``common``: the generation
    a resume goes on from, as the checkpoints' folders tell); :meth:`execute` carries it out."""

    config: Config
    out_dir: str
    seeds: list[int]
    points: list[Point]
    resume: bool
    checkpoint_every: int
    keep: int
    quiet: bool
    log: str | None
    registered: tuple
    common: int
    lines: tuple  # warnings and notes, printed once it starts

    def execute(self) -> int:
        """Run the sweep and say where its points are; the exit code."""
        states = self.run()
        done = min(int(s.generation) for s in states.values())
        print(f"{self.config.condition}: sweep of {len(states)} point(s) x {len(self.seeds)} seed(s), generations "
              f"0-{done - 1} done; per point in {os.path.join(self.out_dir, 'sweep.csv')}, each point's run in "
              f"{self.out_dir}/KEY")
        return 0

    def run(self) -> dict[str, RunState]:
        """Lock, check again, restore every point (read only), then write the records and evolve."""
        config, out_dir, seeds, points = self.config, self.out_dir, self.seeds, self.points
        for line in self.lines:
            print(line, file=sys.stderr, flush=True)
        _silence_failed_reads()  # Ctrl-C in a save: orbax's threads end without their tracebacks
        mesh = make_mesh()
        sharding = population_sharding(mesh, len(points) * len(seeds), config.population_size)
        dirs = [os.path.join(out_dir, p.key) for p in points]
        with contextlib.ExitStack() as stack:
            try:
                make_dir(out_dir)
                stack.enter_context(lock_run_dir(out_dir))
                for existing in [d for d in dirs if os.path.isdir(d)]:  # a point may be resumed alone meanwhile
                    stack.enter_context(lock_run_dir(existing))
                check_sweep_dir(out_dir, config, seeds, points, self.resume)  # again, locked
                if self.resume and resumable_from(out_dir, points) != self.common:
                    raise RunDirError(f"--resume: {out_dir} changed while the sweep was being checked; run it again")
            except OSError as error:
                raise RunDirError(f"--out: cannot write {error.filename or out_dir} ({error.strerror})") from None
            events = stack.enter_context(contextlib.closing(make_log()))  # its --log sink added once restored
            progress = Progress(config.num_generations, quiet=self.quiet, first_index=0, log=events)
            one = population_sharding(mesh, len(seeds), config.population_size)
            states = [initial_state(p.config, seeds, one) for p in points]
            checkpointers, first, elapsed = None, 0, 0.0
            if self.common:  # read only, before anything is written: a refusal here leaves every file as it was
                checkpointers = [stack.enter_context(contextlib.closing(Checkpointer(os.path.join(d, "checkpoints"),
                                                                                     keep=self.keep))) for d in dirs]
                states, first, elapsed = restore(points, states, checkpointers, progress)
            try:
                self._write_records(stack)
            except OSError as error:
                raise RunDirError(f"--out: cannot write {error.filename or out_dir} ({error.strerror})") from None
            if checkpointers is None:
                checkpointers = [stack.enter_context(contextlib.closing(Checkpointer(os.path.join(d, "checkpoints"),
                                                                                     keep=self.keep))) for d in dirs]
            add_log(events, self.log, out_dir, first)
            if first:
                progress = Progress(config.num_generations, done=first, quiet=self.quiet, first_index=0, log=events,
                                    elapsed=elapsed)
                progress.note(f"resuming the sweep in {out_dir} after generation {first - 1} ({first} of "
                              f"{config.num_generations} done, {len(points)} points)")
            elif self.resume:
                progress.note(f"no checkpoint common to the sweep's {len(points)} points yet: starting from "
                              f"generation 0")
            return _evolve(config, out_dir, seeds, points, states, checkpointers, sharding, mesh, first=first,
                           progress=progress, checkpoint_every=self.checkpoint_every)

    def _write_records(self, stack: contextlib.ExitStack) -> None:
        """sweep.json first (a grown num_generations), then each point's config.json (new, or extended), each point
        locked (those that were not: new folders) as it is made."""
        config, out_dir, seeds = self.config, self.out_dir, self.seeds
        info = {**sweep_record(config, seeds, self.points), "version": imrl_jax.__version__,
                "git_commit": git_commit(), "created": time.strftime("%Y-%m-%dT%H:%M:%S%z")}
        if self.resume:
            info = {**read_json(os.path.join(out_dir, SWEEP_FILE), ""), "config": config.to_dict()}
        write_atomic(os.path.join(out_dir, SWEEP_FILE), json.dumps(info, indent=2).encode())
        for p in self.points:
            point_dir = os.path.join(out_dir, p.key)
            if not os.path.isdir(point_dir):
                make_dir(point_dir)
                stack.enter_context(lock_run_dir(point_dir))
            if not os.path.isfile(os.path.join(point_dir, "config.json")):
                write_atomic(os.path.join(point_dir, "config.json"),
                             json.dumps(point_record(p, seeds, self.registered), indent=2).encode())
            elif self.resume:
                extend_config_json(point_dir, p.config)


def point_record(point: Point, seeds: Sequence[int], registered: Sequence[str] = ()) -> dict:
    """What a point's config.json holds: its config and seeds, the GA, where its sweep is and what it sets."""
    return {"config": point.config.to_dict(), "seeds": list(seeds), "search": GA_RECORD,
            "sweep": {"root": "..", "settings": point.settings},
            **({"register": list(registered)} if registered else {}), "version": imrl_jax.__version__,
            "git_commit": git_commit(), "created": time.strftime("%Y-%m-%dT%H:%M:%S%z")}


def no_checkpoint(point: Point, steps: list[int], common: int | None = None) -> UsageError:
    """Why a sweep cannot go on as one: a point has nothing to go on from where the others are."""
    return UsageError(f"--resume: point {point.key} ({label(point.settings)}) has no readable checkpoint"
                      + (f" at or before generation {common}" if common is not None else "")
                      + f" (its checkpoints: {', '.join(map(str, steps)) or 'none'}), so the sweep cannot go on as "
                        f"one; resume the points alone (evolve --resume --out {os.path.join('OUT', 'KEY')})")


def resumable_from(out_dir: str, points: Sequence[Point]) -> int:
    """The generation a resumed sweep goes on from, as its points' checkpoint folders tell (0: none has any), read
    before anything is written; refused if a point has none there (raises UsageError saying what to do).

    A sweep goes on from the newest generation every point holds: a point resumed alone past the others goes back
    there (its later generations are redone in the sweep, bitwise the same), which needs a checkpoint of it there.
    """
    steps = [saved_steps(os.path.join(out_dir, p.key, "checkpoints")) for p in points]
    if not any(steps):
        return 0
    if not all(steps):  # starting every point again would throw the others' generations away
        raise no_checkpoint(points[steps.index([])], [])
    common = min(s[-1] for s in steps)
    for p, saved in zip(points, steps):
        if saved[0] > common:
            raise UsageError(
                f"--resume: point {p.key} ({label(p.settings)}) was resumed alone to generation {saved[-1]}: it keeps "
                f"checkpoints of {', '.join(map(str, saved))} generations, none of {common} or fewer where the other "
                f"points are, and a sweep goes on from the generation every point holds; extend the others alone "
                f"first (evolve --resume --out {os.path.join(out_dir, 'KEY')} --generations {saved[-1]}), then resume "
                f"the sweep")
    return common


def restore(points: Sequence[Point], states: list[RunState], checkpointers: Sequence[Checkpointer],
            progress: Progress) -> tuple[list[RunState], int, float]:
    """Every point at the newest generation all of them have a readable checkpoint of (0: none), and the
    seconds the sweep had run; a point checkpointed further (resumed alone) starts again from there, said."""
    template = list(states)
    if not any(c.steps() for c in checkpointers):
        return template, 0, 0.0
    found = [c.restore_latest(s, warn=lambda text: progress.message(f"warning: {text}"))
             for c, s in zip(checkpointers, template)]
    common = None
    while True:
        missing = [i for i, f in enumerate(found) if f is None]
        if missing:  # some point has none to go on from: starting every point again would throw the others' away
            raise no_checkpoint(points[missing[0]], checkpointers[missing[0]].steps(), common)
        common = min(int(f[0].generation) for f in found)
        if all(int(f[0].generation) == common for f in found):
            break
        for i, f in enumerate(found):
            if int(f[0].generation) > common:
                progress.message(f"warning: point {points[i].key} ({label(points[i].settings)}) was checkpointed "
                                 f"after generation {int(f[0].generation) - 1}; the sweep goes on from generation "
                                 f"{common} for every point")
                found[i] = checkpointers[i].restore_latest(template[i], warn=progress.message, at_most=common)
    return [f[0] for f in found], common, min(float(f[1].get("elapsed_seconds", 0.0)) for f in found)


def _evolve(config: Config, out_dir: str, seeds: list[int], points: Sequence[Point], states: list[RunState],
            checkpointers: Sequence[Checkpointer], sharding, mesh, *, first: int, progress: Progress,
            checkpoint_every: int) -> dict[str, RunState]:
    """The generations of :func:`run` after its checks and restore, from generation ``first``."""
    num_seeds = len(seeds)
    progress.note(f"sweep of {len(points)} point(s) x {num_seeds} seed(s) of {config.condition} in one program: "
                  + "; ".join(f"{p.key} {label(p.settings)}" for p in points))
    step = make_sweep_step(config, sharding)
    key_data = np.concatenate([s.key_data for s in states])
    keys = to_global(evolution_keys(key_data), replicated(mesh))
    params, ga = batched_values(points, num_seeds)
    params, ga = (jax.tree.map(lambda x: to_global(x, replicated(mesh)), tree) for tree in (params, ga))
    populations = to_global(np.concatenate([to_host(s.populations) for s in states]), sharding)
    lives = len(points) * num_seeds * config.population_size * config.lives_per_fitness
    lane_steps = lives * config.lifetime_steps
    if first < config.num_generations:  # what it will cost, before the compilation it waits for
        progress.note(cost_line(f"evolving {len(points)} point(s) x {num_seeds} seed(s) x {config.population_size} "
                                f"individuals x {config.num_generations - first} generation(s)", lives, lane_steps,
                                config.num_generations - first, jax.default_backend(),
                                memory_needed(config, lives, jax.device_count(),
                                              len(points) * history_bytes(config, num_seeds)), world=config.world))
        progress.note("compiling the generation of every point (its first line comes once it is compiled and run) ...")
    names = trait_names(config)
    trait_values = jax.jit(jax.vmap(jax.vmap(lambda genome: traits(config, genome)))) if names else None
    done = first
    try:
        for g in range(first, config.num_generations):
            start = time.perf_counter()
            evaluated = populations
            populations, stats = step(keys, params, ga, evaluated, g)
            fitness, performance = to_host(stats.fitness), to_host(stats.performance)
            evaluated_host, next_host = to_host(evaluated), to_host(populations)
            values = to_host(trait_values(evaluated)) if names else None
            seconds = time.perf_counter() - start
            for i, (p, state) in enumerate(zip(points, states)):
                part = slice(i * num_seeds, (i + 1) * num_seeds)
                recorded = record_traits(state.traits, g, fitness[part], values[part]) if names else state.traits
                states[i] = RunState(np.asarray(g + 1, np.int32), next_host[part], evaluated_host[part],
                                     fitness[part], state.key_data,
                                     record(state.history, g, fitness[part], performance[part]), state.search,
                                     recorded)
            done = g + 1
            means = fitness.max(1).reshape(len(points), num_seeds).mean(1)
            best_point = int(np.argmax(means))
            progress.update(done, float(means.max()), float(fitness.mean()), lane_steps / seconds,
                            scores=f"best fitness, mean over seeds: best point {label(points[best_point].settings)} "
                                   f"{means[best_point]:.4f}, worst {means.min():.4f}")
            if done % checkpoint_every == 0 or done == config.num_generations:
                for p, state, checkpointer in zip(points, states, checkpointers):
                    meta = {"config": p.config.to_dict(), "seeds": seeds, "search": GA_RECORD,
                            "elapsed_seconds": round(progress.elapsed(), 3)}
                    try:
                        checkpointer.save(state, meta)
                        write_outputs(os.path.join(out_dir, p.key), p.config, seeds, state)
                    except Exception as error:  # noqa: BLE001 - orbax wraps the OS error in its own
                        if write_errno(error) is None:
                            raise
                        raise write_failed(error, os.path.join(out_dir, p.key), out_dir, done, done - 1) from None
                try:
                    write_summary(out_dir, config, points, states)
                except OSError as error:
                    if write_errno(error) is None:
                        raise
                    raise write_failed(error, out_dir, out_dir, done, done) from None
        if first == config.num_generations:
            progress.note(f"{out_dir} is finished ({first} of {first} generations): its outputs are rewritten; "
                          f"--generations N (more than {first}) extends it")
            for p, state in zip(points, states):
                write_outputs(os.path.join(out_dir, p.key), p.config, seeds, state)
            write_summary(out_dir, config, points, states)
    except KeyboardInterrupt:
        raise RunInterrupted(out_dir, done, min(c.steps()[-1] if c.steps() else 0 for c in checkpointers),
                             config.num_generations) from None
    return {p.key: s for p, s in zip(points, states)}


def summary_csv(points: Sequence[Point], states: Sequence[RunState], last: int = 5) -> str:
    """One row per point: its settings, key, generations done and the recorded best fitness of the last ``last``
    generations (the best of each generation's noisy lives, mean over those generations, then mean and std over seeds)."""
    fields = list(dict.fromkeys(f for p in points for f in p.settings))
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(fields + ["key", "generations", f"best_last{last}_mean", f"best_last{last}_std"])
    for p, state in zip(points, states):
        done = int(state.generation)
        per_seed = np.asarray(state.history.best[max(done - last, 0):done]).mean(0) if done else np.full(1, np.nan)
        writer.writerow([repr(float(p.settings.get(f, float("nan")))) for f in fields]  # round-trip exact
                        + [p.key, done, f"{per_seed.mean():.6f}", f"{per_seed.std():.6f}"])
    return out.getvalue()


def write_summary(out_dir: str, config: Config, points: Sequence[Point], states: Sequence[RunState]) -> None:
    """Rewrite sweep.csv and sweep.png (every point's best fitness per generation, mean and std over seeds)."""
    from imrl_jax.analysis.charts import plot_fitness
    from imrl_jax.analysis.plotting import save

    write_atomic(os.path.join(out_dir, "sweep.csv"), summary_csv(points, states).encode())
    done = int(states[0].generation)
    if done:
        curves = {label(p.settings): np.asarray(s.history.best[:done]).T for p, s in zip(points, states)}
        save(plot_fitness(curves, title=f"{config.condition}: best fitness per generation at each point, "
                                        f"mean and std over {states[0].key_data.shape[0]} seed(s)",
                          ylabel="best fitness of the population"),
             os.path.join(out_dir, "sweep.png"))


def plan_from_args(args, out_dir: str, registered: Sequence[str], build_config) -> SweepPlan:
    """The evolve command's plan for a sweep (``--sweep``, or ``--resume`` of a sweep's directory), every check
    done and nothing written; ``build_config``: the command's, from its parsed arguments."""
    if args.strategy not in (None, GA_NAME) or args.strategy_set:
        flag = "--strategy-set" if args.strategy in (None, GA_NAME) else "--strategy"
        raise UsageError(f"{flag}: a sweep evolves with the paper's GA (its mutation values may be swept)")
    saved = None
    if args.resume:
        if not is_sweep(out_dir):
            raise UsageError(f"--resume: {out_dir} holds no sweep to resume (no {SWEEP_FILE})")
        base, seeds, settings = read_sweep(out_dir)
        saved = (base, seeds)
    if args.sweep:
        settings = parse(args.sweep, args.zip)
    sets = parse_sets(args.set)
    swept = swept_fields(settings)
    for name, value in sets.items():  # the point's value would silently win
        if name in swept:
            raise UsageError(f"--set {name}={value}: {name} is swept (--sweep {swept[name]}=...); give its values "
                             f"there")
    config, seeds = build_config(args, saved)
    lines = device_warnings(config, args.cpu_devices) + ([] if args.quiet else ignored_notes(config, sets))
    return plan(config, out_dir, seeds, settings, resume=args.resume, checkpoint_every=args.checkpoint_every,
                keep=args.keep, quiet=args.quiet, log=args.log, registered=registered, lines=lines)


def main(args, out_dir: str, registered: Sequence[str], build_config) -> int:
    """The evolve command for a sweep: its plan (:func:`plan_from_args`) carried out."""
    return cli.execute(plan_from_args(args, out_dir, registered, build_config))


__all__ = ["Point", "parse", "make_points", "read_sweep", "is_sweep", "recorded_points", "run", "plan", "SweepPlan",
           "plan_from_args", "summary_csv", "main"]
