"""``python -m imrl_jax.learning_test``: the paper's learning tests (section 3, Fig. 3b and 3c).

    python -m imrl_jax.learning_test runs/EE-LS --out runs/EE-LS-test        # evolved individuals
    python -m imrl_jax.learning_test --cond SLE --runs 10 --out runs/SLE-test  # SLE, from scratch

From an evolution's run directory, the ``--best`` best individuals of each seed's last
generation each live ``--tests`` fresh lives whose tasks last ``--task-steps`` cycles
(paper: 10 best x 10 tests x 6 tasks x 1,000,000 cycles). A test is an ordinary life of
the run's condition with longer tasks: LE-LS first lives a fresh childhood of the run's
length, EE-ES does not learn, EE-LS's selector learns each task from zero. SLE is not
evolved: its ``--runs`` x ``--best`` x ``--tests`` tests all start from scratch (the
"runs" only group them like the evolved conditions' seeds).

The tests of one run are lanes of one jitted program, and the runs go through it one after
the other (one compilation). The task phase runs in ``--chunks`` pieces with the state
carried between them (the same computation as one scan; memory does not grow with the test
length) so that progress can be shown. Each finished run is kept in ``--out/partial/``, so
that the same command after an interruption goes on from the first unfinished run (with
the same results as an uninterrupted test); ``partial/`` is removed once the test is done.
A run whose evolution is unfinished (killed before its last generation, or still running) is
refused unless ``--allow-unfinished``. ``--out`` must be new, empty or such an unfinished
test, and one process writes it at a time (``.lock``). Writes to ``--out``: ``curve.csv``
(performance per bin: mean over all tests and per run), ``steady.json`` (performance over
the last ``--steady-steps`` cycles: mean over runs, best run, per run, per task; the
generation of the run tested; the command and git commit), ``curves.npz`` (every test's
reaches per bin) and ``learning_curve.png``.
"""

from __future__ import annotations

import argparse
import functools
import hashlib
import io
import json
import os
import shutil
import sys
import time
import zipfile
from typing import Callable, NamedTuple, Sequence

import jax
import jax.numpy as jnp
import numpy as np

from jax.sharding import NamedSharding, PartitionSpec

from imrl_jax.checkpoint import git_commit
from imrl_jax.devices import check_memory, make_mesh, use_host_cores
from imrl_jax.conditions import CONDITIONS as TABLE
from imrl_jax.config import COMPUTE_FIELDS, CONDITIONS, PRESETS, Config, ConfigError, LearningParams, make_config
from imrl_jax import cli
from imrl_jax.cli import HelpFormatter, UsageError, exit_codes, parse_sets
from imrl_jax.lifetime import grow_up, lifetime_keys, run_phase, task_spec, task_start
from imrl_jax.state import State
from imrl_jax.events import check_log, log_for
from imrl_jax.progress import Progress
from imrl_jax.rundir import (LOCK, Run, RunDirError, RunWriteError, best_genomes, check_npz, check_unlocked,
                             check_writable, entries, holder_alive, is_output, load_run as read_run, lock_run_dir,
                             make_dir, not_empty, read_config, read_json, read_kept_best, read_lock, read_text,
                             recorded_points,
                             write_atomic, write_errno)


class TestState(NamedTuple):
    """Where one test stands between chunks: the six task phases' carries and keys."""

    states: State  # (tasks, ...); their step counter ``t`` is passed to :func:`advance` instead
    keys: jax.Array  # (tasks,): each task phase's key
    childhood_selections: jnp.ndarray  # (bins, K): zeros without childhood


class TestCurves(NamedTuple):
    """Per-bin counts of one chunk of every task of one test."""

    reaches: jnp.ndarray  # (tasks, bins)
    selections: jnp.ndarray  # (tasks, bins, K)


def begin(key: jax.Array, config: Config, params: LearningParams, genome: jnp.ndarray) -> TestState:
    """A test up to its first task step: LE-LS lives its childhood; every task starts as in :func:`live`."""
    keys = lifetime_keys(key, config.num_tasks)
    agent, childhood_selections = grow_up(keys, config, params, genome)
    states = jax.vmap(lambda index: task_start(config, agent, index))(jnp.arange(config.num_tasks))
    return TestState(states, keys.tasks, childhood_selections)


def advance(config: Config, params: LearningParams, test: TestState, num_chunks: int,
            t: jnp.ndarray) -> tuple[TestState, TestCurves]:
    """One of ``num_chunks`` equal pieces of every task of a test, starting at the task's step ``t``.

    ``t`` is passed, not read from the carried states, so that it is one value for every lane
    (not batched under vmap): the step draws its random numbers a block at a time only then.
    """
    phase = config.spec.adult
    dtype = test.states.agent.actor.dtype

    def one_task(key, index, state):
        # The carried t is batched (begin's output is per task and test); an unbatched one keeps the
        # step's block draws a real branch instead of a select that draws on every step (3x slower).
        state = state._replace(t=t)
        state, curves = run_phase(key, config, phase, params, task_spec(config, index, dtype), state,
                                  config.task_steps // num_chunks, phase_steps=config.adult_noise_steps,
                                  num_bins=config.num_bins // num_chunks)
        return state, TestCurves(curves.reaches, curves.selections)

    states, curves = jax.vmap(one_task)(test.keys, jnp.arange(config.num_tasks), test.states)
    return test._replace(states=states), curves


def make_learning_test(config: Config, num_chunks: int):
    """Jitted ``begin(keys, params, genomes)`` and ``advance(params, t, tests)`` over a batch of tests.

    Tests of configs that differ only in dynamic values (``sweeps.DYNAMIC_FIELDS``: they are ``params``) share
    one program, so the points of a sweep compile once.
    """
    from imrl_jax.sweeps import static_part

    return _make_learning_test(static_part(config), num_chunks)


@functools.lru_cache(maxsize=8)  # tests of the same program in one process (a notebook, a sweep) compile once
def _make_learning_test(config: Config, num_chunks: int):
    """:func:`make_learning_test` for a config whose dynamic values are the defaults."""
    if config.num_bins % num_chunks:
        raise ConfigError(f"num_bins: {config.num_bins} bins cannot be split into {num_chunks} chunks")
    begin_all = jax.jit(jax.vmap(lambda k, p, g: begin(k, config, p, g), (0, None, 0)))
    advance_all = jax.jit(jax.vmap(lambda p, t, tests: advance(config, p, tests, num_chunks, t), (None, None, 0)),
                          donate_argnums=2)
    return begin_all, advance_all


def run_tests(keys: jax.Array, config: Config, params: LearningParams, genomes, num_chunks: int = 1,
              progress: Progress | None = None, done_before: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Every test (one key and genome each) to the end: reaches (tests, tasks, bins), selections (tests, tasks, bins, K).

    ``done_before``: progress units finished before this batch. The programs are cached: batches
    of the same config compile once.
    """
    begin_all, advance_all = make_learning_test(config, num_chunks)
    # Split the tests over every device (one per CPU core in the CLI); pad to a multiple with copies of
    # the last test (lanes are independent: the copies change no other lane, and are dropped below).
    num_tests, num_devices = len(genomes), len(jax.devices())
    pad = -num_tests % num_devices
    genomes = np.concatenate([genomes, np.repeat(genomes[-1:], pad, 0)]) if pad else genomes
    keys = jnp.concatenate([keys, jnp.repeat(keys[-1:], pad, axis=0)]) if pad else keys  # typed keys: no .repeat
    sharding = NamedSharding(make_mesh(), PartitionSpec("lanes"))
    tests = begin_all(jax.device_put(keys, sharding), params, jax.device_put(np.asarray(genomes), sharding))
    reaches, selections = [], []
    best = np.asarray(config.theoretical_max())
    lane_steps = num_tests * config.num_tasks * config.task_steps / num_chunks  # per chunk
    for chunk in range(num_chunks):
        start = time.perf_counter()
        tests, curves = advance_all(params, jnp.int32(chunk * (config.task_steps // num_chunks)), tests)
        reaches.append(np.asarray(curves.reaches)[:num_tests])
        selections.append(np.asarray(curves.selections)[:num_tests])
        if progress is not None:
            recent = reaches[-1].sum(-1) / (best / num_chunks)  # (tests, tasks)
            progress.update(done_before + chunk + 1, 0.0, 0.0, lane_steps / (time.perf_counter() - start),
                            scores=f"performance in this chunk {recent.mean():.4f}")
    return np.concatenate(reaches, -1), np.concatenate(selections, -2)


# ----------------------------------------------------------------------------- statistics

PAIR_LEVEL = 0.2  # a task counts as solved in a test at this steady-state performance
#: Conditions that are not evolved: tested from scratch (``--cond``), without a run directory (the table's at import;
#: :func:`from_scratch` also has the rows registered since).
FROM_SCRATCH = tuple(name for name, condition in TABLE.items() if not condition.evolved)


def from_scratch() -> tuple[str, ...]:
    """The conditions of the table as it is now that are not evolved (tested from scratch)."""
    return tuple(name for name, condition in TABLE.items() if not condition.evolved)


def performance_curve(config: Config, reaches: np.ndarray) -> np.ndarray:
    """Reaches per bin (..., tasks, bins) as task performance per bin (the paper's normalised reward)."""
    per_bin = np.asarray(config.theoretical_max()) / config.num_bins
    return np.asarray(reaches, float) / per_bin[:, None]


def steady_bins(config: Config, steady_steps: int) -> int:
    """Number of final bins that make up the last ``steady_steps`` cycles."""
    bin_steps = config.task_steps // config.num_bins
    if steady_steps % bin_steps or not 0 < steady_steps <= config.task_steps:
        raise ConfigError(f"steady_steps: {steady_steps} is not a whole number of bins of {bin_steps} steps "
                          f"within a task of {config.task_steps}")
    return steady_steps // bin_steps


def summarise(config: Config, reaches: np.ndarray, steady_steps: int) -> dict:
    """Fig. 3c numbers from reaches (runs, best, tests, tasks, bins): steady state per run, mean, best run."""
    curve = performance_curve(config, reaches)
    steady = curve[..., -steady_bins(config, steady_steps):].mean(-1)  # (runs, best, tests, tasks)
    per_run = steady.mean((1, 2, 3))
    return dict(
        steady_mean=float(per_run.mean()), steady_sd=float(per_run.std()), best_run=int(per_run.argmax()),
        steady_best_run=float(per_run.max()), steady_per_run=[float(v) for v in per_run],
        steady_per_task=[float(v) for v in steady.mean((0, 1, 2))],
        whole_test_mean=float(curve.mean()),
        pairs_both_ways=pairs_both_ways(steady),
    )


def pairs_both_ways(performance, level: float = PAIR_LEVEL) -> float:
    """Share of (test, task pair) with both tasks of the pair at performance ``level`` or more.

    ``performance`` (..., tasks): each test's steady state per task. Tasks 2i and 2i+1 look
    the same up to their first junction and turn the other way there, so a fixed controller
    solves at most one of them: solving both takes choices learned for each task.
    """
    performance = np.asarray(performance, float)
    pairs = performance.reshape(performance.shape[:-1] + (-1, 2))
    return float((pairs >= level).all(-1).mean())


def curve_csv(config: Config, reaches: np.ndarray) -> str:
    """Performance per bin: the mean over all tests, its sd over runs, and each run's mean."""
    curve = performance_curve(config, reaches).mean((1, 2, 3))  # (runs, bins)
    bin_steps = config.task_steps // config.num_bins
    lines = ["bin,end_step,mean,sd_over_runs," + ",".join(f"run_{r}" for r in range(curve.shape[0]))]
    for b in range(curve.shape[1]):
        lines.append(f"{b},{(b + 1) * bin_steps},{curve[:, b].mean():.5f},{curve[:, b].std():.5f},"
                     + ",".join(f"{v:.5f}" for v in curve[:, b]))
    return "\n".join(lines) + "\n"


# ----------------------------------------------------------------------------- command line


def load_run(run_dir: str, num_best: int) -> tuple[Config, list[int], np.ndarray]:
    """A run's config, its seeds and the ``num_best`` best genomes (seeds, best, genes) of its last generation."""
    found = read_run(run_dir)
    return found.config, found.seeds, best_genomes(found, num_best)


def unfinished(run_dir: str, run: Run) -> str:
    """Why ``run`` is not a finished evolution ("" if it is): generations left, or a live writer."""
    holder = read_lock(os.path.join(run_dir, LOCK))
    writing = holder is not None and holder_alive(holder) is not False
    if run.generation >= run.config.num_generations and not writing:
        return ""
    return (f"{run_dir} has {run.generation} of its {run.config.num_generations} generations evaluated"
            + (f" and is being written by pid {holder.pid} on {holder.host}" if writing else ""))


def load_kept_best(run_dir: str, path: str, num_best: int) -> tuple[Config, list[int], np.ndarray]:
    """A run's config and the ``num_best`` best genomes of each seed kept in a report's ``best_genomes.npz``
    (for a run whose final population was not kept); its key is the run's ``VARIANT/evolve/CONDITION`` path."""
    config, _ = read_config(run_dir)
    variant = os.path.basename(os.path.dirname(os.path.dirname(os.path.abspath(run_dir))))
    genomes, seeds, _ = read_kept_best(path, variant, config.condition)
    if not 1 <= num_best <= genomes.shape[1]:
        raise RunDirError(f"--best: must be between 1 and the {genomes.shape[1]} kept in {path}")
    if genomes.shape[-1] != config.num_genes:
        raise RunDirError(f"--best-genomes: {variant}__{config.condition} has {genomes.shape[-1]} genes, the run's "
                          f"config {config.num_genes}")
    return config, seeds, genomes[:, :num_best]


def test_keys(seed: int, num_runs: int, num_best: int, num_tests: int) -> jax.Array:
    """One key per (run, individual, test), all from ``seed``."""
    return jax.random.split(jax.random.key(seed), num_runs * num_best * num_tests)


#: The folder of ``--out`` that keeps each finished run of an unfinished test.
PARTIAL = "partial"


def fingerprint(config: Config, genomes: np.ndarray, num_tests: int, seed: int) -> str:
    """What a test's results depend on, hashed: a resumed test continues only a test of the same.

    Only the config fields away from their defaults count, so that a field added to ``Config``
    later (its default keeping the old behaviour) does not stop an older test from resuming; the
    compute choices (step kernel, unroll) do not count.
    """
    default = Config().to_dict()
    changed = {name: value for name, value in config.to_dict().items()
               if value != default.get(name) and name not in COMPUTE_FIELDS}  # how, not what: a test resumes
    digest = hashlib.sha256(json.dumps(dict(config=changed, num_tests=num_tests, seed=seed),
                                       sort_keys=True, default=str).encode())
    digest.update(np.ascontiguousarray(genomes, np.float32).tobytes())
    return digest.hexdigest()[:16]


def finished_runs(partial: str, stamp: str, num_runs: int, warn: Callable[[str], None] = print,
                  limit: int | None = None) -> dict:
    """The runs kept in ``partial`` by an interrupted test of the same fingerprint: {run: (reaches, selections)}
    (``limit``: the bytes a run's arrays take at most; a larger file is tested again)."""
    if not os.path.isdir(partial):
        return {}
    spec_path = os.path.join(partial, "spec.json")
    found = None
    if os.path.exists(spec_path):
        try:
            found = json.loads(read_text(spec_path, ""))["fingerprint"]
        except (RunDirError, ValueError, KeyError, TypeError, RecursionError) as error:
            raise UsageError(f"--out: {spec_path} cannot be read ({type(error).__name__}), so the runs kept beside it "
                             f"cannot be checked; remove {partial} to start the test over") from None
    if found != stamp:
        raise UsageError(f"--out: {partial} holds an unfinished learning test of other settings or individuals; "
                         f"remove it or choose another directory")
    done = {}
    for r in range(num_runs):
        path = os.path.join(partial, f"run_{r:03d}.npz")
        if os.path.exists(path):
            try:
                if limit is not None:
                    check_npz(path, "", limit)
                with np.load(path) as data:
                    done[r] = (data["reaches"], data["selections"])
            except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile) as error:  # RunDirError: a ValueError
                warn(f"warning: {path} cannot be read ({type(error).__name__}); run {r} is tested again")
    return done


#: The files a learning test writes into ``--out`` (its last, steady.json, marks it finished).
OUTPUTS = ("curves.npz", "curve.csv", "learning_curve.png", "steady.json")


def check_out_dir(out_dir: str) -> None:
    """Refuse an ``--out`` that is neither new, nor empty, nor an unfinished learning test (raises a user error)."""
    if os.path.exists(os.path.join(out_dir, "steady.json")):
        raise UsageError(f"--out: {out_dir} already holds a learning test; choose another directory")
    found = entries(out_dir)
    if not found:
        return
    partial = os.path.join(out_dir, PARTIAL)
    unfinished = os.path.isdir(partial) and (os.path.exists(os.path.join(partial, "spec.json"))
                                             or not os.listdir(partial))
    # An interrupted test may also have written some outputs (and a temporary file) before steady.json.
    others = [name for name in found if name != PARTIAL and not is_output(name, OUTPUTS)]
    if not unfinished or others:
        raise not_empty(out_dir, "unfinished learning test", others or found)


def run(config: Config, genomes: np.ndarray, out_dir: str, *, num_tests: int, steady_steps: int, num_chunks: int,
        seed: int = 0, quiet: bool = False, source: str = "", command: str = "", warnings: Sequence[str] = (),
        notes: Sequence[str] = (), evolved: dict | None = None, log: str | None = None) -> dict:
    """Run the tests of ``genomes`` (runs, best, genes) run by run, resuming from ``partial/``; write the outputs.

    ``out_dir`` is locked for the whole test (:func:`imrl_jax.rundir.lock_run_dir`). ``warnings`` are
    printed once the checks pass, ``notes`` too unless ``quiet``. ``evolved``: which generation of how many the
    genomes come from (recorded in steady.json).
    """
    steady_bins(config, steady_steps)
    num_runs, num_best = genomes.shape[:2]
    kept = num_runs * num_best * num_tests * config.num_tasks * config.num_bins * (config.num_experts + 1) * 4 * 3
    check_memory(config, num_best * num_tests * config.num_tasks,  # a run's tests at once; every run's curves kept
                 f"testing {num_best} x {num_tests} test(s) of {config.num_tasks} tasks a run", host_bytes=kept)
    try:
        check_log(log)
    except ValueError as error:
        raise UsageError(str(error)) from None
    check_writable(out_dir)
    check_unlocked(out_dir)
    check_out_dir(out_dir)  # before the directory is made or locked: nothing is written into another's
    make_dir(out_dir)
    with lock_run_dir(out_dir):
        check_out_dir(out_dir)  # again, locked: another test may have written there in between
        for line in [*warnings, *([] if quiet else notes)]:
            print(line, file=sys.stderr, flush=True)
        try:
            return _run_locked(config, genomes, out_dir, num_tests=num_tests, steady_steps=steady_steps,
                               num_chunks=num_chunks, seed=seed, quiet=quiet, source=source, command=command,
                               evolved=evolved, log=log)
        except OSError as error:
            if write_errno(error) is None:
                raise
            raise RunWriteError(f"cannot write {error.filename or out_dir} ({error.strerror}); free space or fix "
                                f"permissions, then run the same command again (the finished runs are kept in "
                                f"{os.path.join(out_dir, PARTIAL)})") from None


def _run_locked(config: Config, genomes: np.ndarray, out_dir: str, *, num_tests: int, steady_steps: int,
                num_chunks: int, seed: int, quiet: bool, source: str, command: str,
                evolved: dict | None = None, log: str | None = None) -> dict:
    """:func:`run` once the directory is checked and locked."""
    num_runs, num_best = genomes.shape[:2]
    keys = test_keys(seed, num_runs, num_best, num_tests).reshape(num_runs, num_best * num_tests)
    partial, stamp = os.path.join(out_dir, PARTIAL), fingerprint(config, genomes, num_tests, seed)
    per_run = num_best * num_tests * config.num_tasks * config.num_bins * (config.num_experts + 1) * 4 + 2**16
    done = finished_runs(partial, stamp, num_runs, warn=lambda text: print(text, file=sys.stderr), limit=per_run)
    resumed = sorted(done)
    progress = Progress(num_runs * num_chunks, done=len(done) * num_chunks, quiet=quiet, unit="chunk",
                        group=("run", num_chunks), log=log_for(log, out_dir))
    progress.note(f"{config.condition} learning test: {num_runs} run(s) x {num_best} best x {num_tests} test(s) x "
                     f"{config.num_tasks} tasks = {num_runs * num_best * num_tests * config.num_tasks} lanes of "
                     f"{config.task_steps} cycles"
                     + (f" after a {config.childhood_steps}-step childhood" if config.spec.has_childhood else "")
                     + ", run by run" + (f"; {len(done)} run(s) done before, kept in {partial}" if done else ""))
    start = time.perf_counter()
    params = config.learning_params()
    os.makedirs(partial, exist_ok=True)
    write_atomic(os.path.join(partial, "spec.json"), json.dumps(dict(fingerprint=stamp, command=command)).encode())
    for r in range(num_runs):
        if r in done:
            continue
        lanes = np.repeat(genomes[r], num_tests, axis=0).astype(np.float32)
        done[r] = run_tests(keys[r], config, params, lanes, num_chunks, progress, done_before=r * num_chunks)
        buffer = io.BytesIO()
        np.savez_compressed(buffer, reaches=done[r][0].astype(np.int32), selections=done[r][1].astype(np.int32))
        write_atomic(os.path.join(partial, f"run_{r:03d}.npz"), buffer.getvalue())
    seconds = time.perf_counter() - start
    shape = (num_runs, num_best, num_tests)
    reaches = np.stack([done[r][0] for r in range(num_runs)]).reshape(shape + done[0][0].shape[1:])
    selections = np.stack([done[r][1] for r in range(num_runs)]).reshape(shape + done[0][1].shape[1:])
    summary = dict(condition=config.condition, source=source, num_runs=num_runs, num_best=num_best,
                   num_tests=num_tests, task_steps=config.task_steps, childhood_steps=config.childhood_steps,
                   num_bins=config.num_bins, steady_steps=steady_steps, seed=seed,
                   **(evolved or dict(generation=None, generations_done=None, num_generations=None)),
                   **summarise(config, reaches, steady_steps),
                   seconds=round(seconds, 1), resumed_runs=resumed, backend=jax.default_backend(), command=command,
                   git_commit=git_commit(), config=config.to_dict())
    buffer = io.BytesIO()
    np.savez_compressed(buffer, reaches=reaches.astype(np.int32), selections=selections.astype(np.int32))
    write_atomic(os.path.join(out_dir, "curves.npz"), buffer.getvalue())
    write_atomic(os.path.join(out_dir, "curve.csv"), curve_csv(config, reaches).encode())
    _write_plot(config, reaches, os.path.join(out_dir, "learning_curve.png"))
    write_atomic(os.path.join(out_dir, "steady.json"), json.dumps(summary, indent=2).encode())  # marks completion
    shutil.rmtree(partial)  # curves.npz now holds every run
    return summary


#: What the test of a sweep writes beside its points' tests once all are done.
SWEEP_TESTS = "sweep_tests.json"

PAPER_TEST = dict(task_steps=1_000_000, shape=(10, 10, 10))  # the paper's tests: 1,000,000 cycles, 10 x 10 x 10


def scale_label(config: Config, shape: tuple[int, ...]) -> str:
    """", reduced scale (...)" when a test is shorter or smaller than the paper's, else ""."""
    short = bool(config.task_steps < PAPER_TEST["task_steps"])
    small = bool(np.prod(shape) < np.prod(PAPER_TEST["shape"]))
    parts = [f"{config.task_steps:,} cycles"] * short + [f"{int(np.prod(shape)):,} tests"] * small
    return f", reduced scale ({', '.join(parts)})" if parts else ""


def _write_plot(config: Config, reaches: np.ndarray, path: str) -> None:
    from imrl_jax.plotting import new_figure, save, style_axis

    curve = performance_curve(config, reaches)
    bin_steps = config.task_steps // config.num_bins
    x = (np.arange(config.num_bins) + 0.5) * bin_steps
    fig = new_figure(6.0, 3.6)
    fig.set_layout_engine("constrained")
    ax = fig.subplots()
    per_run = curve.mean((1, 2, 3))
    ax.fill_between(x, per_run.min(0), per_run.max(0), color="0.85", label="range of the runs' means")
    ax.plot(x, curve.mean((0, 1, 2, 3)), color="k", lw=2, label="mean of all tests")
    ax.set_ylim(0, 1)
    ax.set_xlim(0, config.task_steps)
    runs, best, tests = reaches.shape[:3]
    style_axis(ax, f"{config.condition} learning test: {runs} run(s) x {best} best x {tests} test(s), "
                   f"{config.num_tasks} tasks each{scale_label(config, reaches.shape[:3])}",
               "cycles of the task (bin centres)",
               "performance per bin (1: straight line)")
    ax.legend(fontsize=7)
    save(fig, path)


def parser() -> argparse.ArgumentParser:
    p = cli.Parser(prog="python -m imrl_jax.learning_test",
                   description="The paper's learning tests (section 3, Fig. 3b and 3c): the best individuals of an "
                               "evolution, or SLE from scratch, learn each task anew.",
                   formatter_class=HelpFormatter)
    p.add_argument("run_dir", nargs="?",
                   help=f"an evolution's run directory (omit with --cond {' or '.join(FROM_SCRATCH)})")
    p.add_argument("--cond", metavar="{" + ",".join(CONDITIONS) + "}",
                   help=f"{', '.join(FROM_SCRATCH)}: test learning from scratch (no run directory); "
                        "another condition: check that run_dir is a run of it")
    cli.add_register(p)
    p.add_argument("--runs", type=int, default=10, help="from scratch: groups of tests, like an evolution's seeds")
    p.add_argument("--preset", default="paper", choices=sorted(PRESETS),
                   help="from scratch: the learning rules' preset")
    p.add_argument("--set", action="append", metavar="FIELD=VALUE",
                   help="set a Config field other than those the options set (from scratch: of --preset; with a run "
                        "directory: of its evolution's config, the genome unchanged) (repeatable)")
    p.add_argument("--best-genomes", metavar="FILE",
                   help="take the best genomes from a report's best_genomes.npz (the 10 best of each seed), for a run "
                        "whose final_population.npz was not kept; the run directory gives the config")
    cli.add_task_set(p, "the tasks to learn (default: the run's, or paper)")
    p.add_argument("--allow-unfinished", action="store_true",
                   help="test a run whose evolution has not reached its last generation (killed, or still running): "
                        "its last evaluated generation, with a warning (steady.json records which)")
    p.add_argument("--best", type=int, default=10, help="best individuals of each run's last generation")
    p.add_argument("--tests", type=int, default=10, help="tests per individual")
    p.add_argument("--task-steps", type=int, default=1_000_000, help="cycles per task")
    p.add_argument("--bins", type=int, default=100, help="bins of the learning curve")
    p.add_argument("--steady-steps", type=int, default=100_000, help="final cycles averaged for the steady state")
    p.add_argument("--chunks", type=int, default=10, help="pieces the test runs in (progress lines)")
    p.add_argument("--seed", type=int, default=0, help="seed of the tests' keys")
    p.add_argument("--out", required=True,
                   help="output directory: new, empty, or an unfinished test of the same command to go on with")
    p.add_argument("--quiet", action="store_true", help="no progress lines (for logs)")
    p.add_argument("--log", help="also write the progress for TensorBoard: --log tensorboard (under OUT/tensorboard; "
                   "needs tensorboardX)")
    p.add_argument("--cpu-devices", type=int, default=0, help="CPU devices (0: one per core)")
    return p


#: The config fields that options of the command line set (``--set`` may not set them): field -> option.
OPTION_FIELDS = {"condition": "--cond", "task_steps": "--task-steps", "num_bins": "--bins"}


def check_sizes(args) -> None:
    """Refuse absurd sizes before anything is allocated (raises UsageError naming the option and its limit)."""
    for name in ("best", "tests", "task_steps", "bins", "chunks", "runs"):
        if getattr(args, name) < 1:
            raise UsageError(f"--{name.replace('_', '-')}: must be at least 1")
    for flag, value, limit in (("--task-steps", args.task_steps, cli.MAX_STEPS), ("--runs", args.runs, cli.MAX_SEEDS),
                               ("--best", args.best, cli.MAX_SEEDS), ("--tests", args.tests, cli.MAX_SEEDS),
                               ("--bins", args.bins, cli.MAX_BINS)):
        cli.check_at_most(flag, value, limit)
    cli.check_at_most("--best x --tests", args.best * args.tests, cli.MAX_LANES)


@exit_codes
def main(argv: Sequence[str] | None = None) -> int:
    command = "python -m imrl_jax.learning_test " + " ".join(sys.argv[1:] if argv is None else argv)
    args = parser().parse_args(argv)
    check_sizes(args)
    cli.register(args.register)
    if args.cond is not None and args.cond not in TABLE:  # the table as it is now
        raise UsageError(f"--cond: unknown condition {args.cond!r} (choose from {', '.join(TABLE)}, or add a row "
                         f"with --register MODULE:ATTRIBUTE; only {', '.join(from_scratch())} are tested without "
                         f"a run directory)")
    cli.check_cpu_devices(args.cpu_devices)
    cli.check_out(args.out)
    use_host_cores(args.cpu_devices or None)  # before anything starts JAX (the task set's checks)
    cli.refuse_option_fields(args.set, OPTION_FIELDS)
    sets = parse_sets(args.set)
    warnings, evolved = [], None
    if args.cond in from_scratch():
        if args.run_dir:
            raise UsageError(f"run_dir: {args.cond} is tested from scratch; give either a run directory or "
                             f"--cond {args.cond}")
        if args.best_genomes:
            raise UsageError("--best-genomes: only with a run directory")
        base = make_config(args.preset, **{**sets, "condition": args.cond})
        genomes = np.zeros((args.runs, args.best, base.num_genes), np.float32)
        source = f"{args.cond} from scratch, preset {args.preset}" + "".join(f", {s}" for s in args.set or [])
        summaries = [(args.out, _test(args, base, genomes, source, evolved, warnings, sets, command, args.out))]
    else:
        if not args.run_dir:
            raise UsageError(f"run_dir: give an evolution's run directory, or --cond "
                             f"{' or '.join(from_scratch())} to test learning from scratch")
        points = sweep_points(args.run_dir)
        if points is not None and args.best_genomes:
            raise UsageError(f"--best-genomes: {args.run_dir} is a sweep: its points' populations are kept")
        summaries = []
        for run_dir, out_dir in ([(args.run_dir, args.out)] if points is None else
                                 [(point, os.path.join(args.out, os.path.basename(point))) for point in points]):
            if points is not None and os.path.isfile(os.path.join(out_dir, "steady.json")):
                check_tested_before(args, run_dir, out_dir)
                summaries.append((out_dir, None))  # a point tested before: the sweep's test goes on after it
                continue
            base, genomes, source, evolved, warnings = _evolved(args, run_dir, sets)
            summaries.append((out_dir, _test(args, base, genomes, source, evolved, warnings, sets, command,
                                             out_dir)))
        if points is not None:
            sweep_summary(args.run_dir, args.out)
    for out_dir, summary in summaries:
        if summary is None:
            print(f"{out_dir}: tested before (steady.json)")
            continue
        print(f"{summary['condition']}: steady state (last {args.steady_steps} cycles) {summary['steady_mean']:.4f} "
              f"mean over {summary['num_runs']} run(s), best run {summary['steady_best_run']:.4f}; whole test "
              f"{summary['whole_test_mean']:.4f}; outputs in {out_dir}")
    return 0


def sweep_points(run_dir: str) -> list[str] | None:
    """A sweep's point directories (``evolve --sweep``, in its order), or None if ``run_dir`` is not a sweep."""
    points = recorded_points(run_dir)
    return None if points is None else [os.path.join(run_dir, key) for key, _ in points]


def check_tested_before(args, run_dir: str, out_dir: str) -> None:
    """Refuse a point's earlier test (in a sweep's test) made with other settings or of another generation."""
    steady = read_json(os.path.join(out_dir, "steady.json"), "")
    asked = dict(num_best=args.best, num_tests=args.tests, task_steps=args.task_steps, steady_steps=args.steady_steps,
                 seed=args.seed, generations_done=read_run(run_dir).generation)
    differ = [f"{name} {steady.get(name)} (asked {value})" for name, value in asked.items() if steady.get(name) != value]
    if differ:
        raise UsageError(f"--out: {out_dir} holds a test of other settings: {', '.join(differ)}; choose another --out")


def sweep_summary(run_dir: str, out_dir: str) -> dict:
    """Each point's settings and steady state, once every point of the sweep in ``run_dir`` is tested in ``out_dir``
    (written to ``out_dir/sweep_tests.json``: a sweep's test is done when it is there)."""
    points = {}
    for key, settings in recorded_points(run_dir):
        steady = read_json(os.path.join(out_dir, key, "steady.json"), "")
        points[key] = dict(settings=settings, steady_mean=steady["steady_mean"], steady_sd=steady["steady_sd"],
                           whole_test_mean=steady["whole_test_mean"])
    summary = dict(sweep=os.path.abspath(run_dir), points=points)
    write_atomic(os.path.join(out_dir, SWEEP_TESTS), json.dumps(summary, indent=2).encode())
    return summary


def _evolved(args, run_dir: str, sets: dict) -> tuple[Config, np.ndarray, str, dict | None, list[str]]:
    """An evolved run's config (with ``--set``), its best genomes, the source's words, its generation, warnings."""
    warnings, evolved = [], None
    if args.best_genomes:
        base, _, genomes = load_kept_best(run_dir, args.best_genomes, args.best)
    else:
        found = read_run(run_dir)
        base, genomes = found.config, best_genomes(found, args.best)
        evolved = dict(generation=found.generation - 1, generations_done=found.generation,
                       num_generations=found.config.num_generations)
        why = unfinished(run_dir, found)
        if why and not args.allow_unfinished:
            raise UsageError(f"run_dir: {why}: its evolution is unfinished (pass --allow-unfinished to test "
                             f"generation {found.generation - 1} anyway)")
        if why:
            warnings.append(f"warning: {why}: testing generation {found.generation - 1} (steady.json records it)")
    if args.cond is not None and args.cond != base.condition:
        raise UsageError(f"--cond: {run_dir} is a {base.condition} run, not {args.cond}")
    source = os.path.abspath(run_dir) + "".join(f", {s}" for s in args.set or [])
    if sets:  # the evolved genomes tested under other values (their evolution's config otherwise)
        tested = base.replace(**sets)
        if tested.num_genes != base.num_genes:
            raise UsageError(f"--set: {', '.join(sets)} changes the genome ({base.num_genes} genes evolved, "
                             f"{tested.num_genes} asked)")
        base = tested
    return base, genomes, source, evolved, warnings


def _test(args, base: Config, genomes: np.ndarray, source: str, evolved: dict | None, warnings: list[str],
          sets: dict, command: str, out_dir: str) -> dict:
    """The learning test of ``genomes`` under ``base`` at the command line's lengths, into ``out_dir``."""
    # Evolved genomes may be tested on other tasks (they encode none).
    config = cli.apply_task_set(
        lambda **tasks: base.replace(task_steps=args.task_steps, num_bins=args.bins, **tasks), args)
    if args.task_set is not None:
        source += f", task set {args.task_set}"
    if config.num_bins % args.chunks:
        raise UsageError(f"--chunks: {args.bins} bins cannot be split into {args.chunks} chunks")
    steady_bins(config, args.steady_steps)
    return run(config, genomes, out_dir, num_tests=args.tests, steady_steps=args.steady_steps,
               num_chunks=args.chunks, seed=args.seed, quiet=args.quiet, source=source, command=command,
               warnings=[*warnings, *cli.device_warnings(config, args.cpu_devices)],
               notes=cli.ignored_notes(config, sets), evolved=evolved, log=args.log)


if __name__ == "__main__":
    sys.exit(main())
