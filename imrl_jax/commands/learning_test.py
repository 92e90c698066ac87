"""``python -m imrl_jax.learning_test``: the paper's learning tests (section 3, Fig. 3b and 3c).

    python -m imrl_jax.learning_test runs/EE-LS --out runs/EE-LS-test        # evolved individuals
    python -m imrl_jax.learning_test --cond SLE --runs 10 --out runs/SLE-test  # SLE, from scratch

From an evolution's run directory, the ``--best`` best individuals of each seed's last
generation each live ``--tests`` fresh lives whose tasks last ``--task-steps`` cycles
(paper: 10 best x 10 tests x 6 tasks x 1,000,000 cycles). The lengths not given follow the
run's (or, from scratch, ``--preset``'s) as the paper's test follows its evolution: tasks 10 x
its ``task_steps``, its ``num_bins`` bins, the steady state over the last tenth (the paper's
1,000,000 / 100 / 100,000; a ``small`` run's 50,000 / 10 / 5,000). A test is an ordinary life of
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
refused unless ``--allow-unfinished``. The command is built as every command is (``imrl_jax/runs/cli.py``):
:func:`plan` reads and checks everything (sizes, runs, every point of a sweep, ``--out``, memory,
``--log``) and writes nothing; :func:`cli.execute` then locks and writes. ``--out`` must be new, empty or such an unfinished
test, and one process writes it at a time (``.lock``). Writes to ``--out``: ``curve.csv``
(performance per bin: mean over all tests and per run), ``steady.json`` (performance over
the last ``--steady-steps`` cycles: mean over runs, best run, per run, per task; the
generation of the run tested; the command and git commit), ``curves.npz`` (every test's
reaches per bin) and ``learning_curve.png``.
"""

from __future__ import annotations

import functools
import os
import sys
import time
from typing import NamedTuple, Sequence

import jax
import jax.numpy as jnp
import numpy as np

from jax.sharding import NamedSharding, PartitionSpec

from imrl_jax.runs.checkpoint import git_commit
from imrl_jax.evolution.devices import check_memory, make_mesh, memory_needed, use_host_cores
from imrl_jax.config import Config, ConfigError, LearningParams
from imrl_jax.runs import cli, runspec
from imrl_jax.agent import kernel_choice
from imrl_jax.runs.cli import UsageError, exit_codes, parse_sets
from imrl_jax.agent.lifetime import grow_up, lifetime_keys, run_phase, task_start
from imrl_jax.world.worlds import task_maxima, world_of
from imrl_jax.agent.state import State
from imrl_jax.runs.events import check_log, log_for
from imrl_jax.commands.learning_test_options import (OPTION_FIELDS, check_condition, check_sizes, evolved_genomes, from_scratch,
                                            parser, scratch_genomes, test_lengths, tested_config)
from imrl_jax.runs.learning_test_state import (PARTIAL, check_out_before, fingerprint, finished_runs, keep_run,
                                          locked_out_dir, start_partial, write_errors, write_outputs)
from imrl_jax.commands.learning_test_sweep import (check_generations, check_keys, check_out_root, check_record,
                                          check_tested_before, sweep_summary)
from imrl_jax.runs.progress import Progress, cost_line
from imrl_jax.runs.rundir import best_genomes, load_run as read_run, lock_run_dir, make_dir, recorded_points
from imrl_jax.analysis.steady_state import performance_curve, steady_bins, summarise
from imrl_jax.evolution.sweeps import static_part


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
        state, curves = run_phase(key, config, phase, params, world_of(config).task(config, index, dtype), state,
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
    best = task_maxima(config)
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


# ----------------------------------------------------------------------------- command line


def load_run(run_dir: str, num_best: int) -> tuple[Config, list[int], np.ndarray]:
    """A run's config, its seeds and the ``num_best`` best genomes (seeds, best, genes) of its last generation."""
    found = read_run(run_dir)
    return found.config, found.seeds, best_genomes(found, num_best)


def test_keys(seed: int, num_runs: int, num_best: int, num_tests: int) -> jax.Array:
    """One key per (run, individual, test), all from ``seed``."""
    return jax.random.split(jax.random.key(seed), num_runs * num_best * num_tests)


class PointTest(NamedTuple):
    """One test, checked: what it tests, under which config, into which ``--out``, at which sizes."""

    config: Config
    genomes: np.ndarray  # (runs, best, genes)
    out_dir: str
    num_tests: int
    steady_steps: int
    num_chunks: int
    seed: int = 0
    quiet: bool = False
    source: str = ""
    command: str = ""
    warnings: Sequence[str] = ()
    notes: Sequence[str] = ()
    evolved: dict | None = None
    log: str | None = None

    def lanes(self) -> int:
        """The lanes of the whole test: runs x best x tests x tasks."""
        return int(np.prod(self.genomes.shape[:2])) * self.num_tests * self.config.num_tasks

    def check(self) -> None:
        """Every check of the test before it writes: lengths, chunks, memory, ``--log``, ``--out`` (a user error)."""
        config = self.config
        steady_bins(config, self.steady_steps)
        if config.num_bins % self.num_chunks:
            raise UsageError(f"--chunks: {config.num_bins} bins cannot be split into {self.num_chunks} chunks")
        num_runs, num_best = self.genomes.shape[:2]
        if self.genomes.shape[-1] != config.num_genes:
            raise UsageError(f"genomes: {self.genomes.shape[-1]} genes, the config's {config.num_genes}")
        check_memory(config, num_best * self.num_tests * config.num_tasks,  # a run's tests at once; all runs' curves
                     f"testing {num_best} x {self.num_tests} test(s) of {config.num_tasks} tasks a run",
                     host_bytes=curves_bytes(config, num_runs * num_best * self.num_tests))
        try:
            check_log(self.log, self.out_dir)  # OUT/tensorboard too
        except ValueError as error:
            raise UsageError(str(error)) from None
        check_out_before(self.out_dir)

    def test(self) -> dict:
        """Lock ``--out``, check it again, run the tests run by run (resuming from ``partial/``), write; the summary."""
        with locked_out_dir(self.out_dir), write_errors(self.out_dir):  # a full disk: one line, the finished runs kept
            for line in [*self.warnings, *([] if self.quiet else self.notes)]:
                print(line, file=sys.stderr, flush=True)
            return _test_runs(self.config, self.genomes, self.out_dir, self.num_tests, self.steady_steps,
                              self.num_chunks, self.seed, self.quiet, self.source, self.command, self.evolved, self.log)


def run(config: Config, genomes: np.ndarray, out_dir: str, *, num_tests: int, steady_steps: int, num_chunks: int,
        seed: int = 0, quiet: bool = False, source: str = "", command: str = "", warnings: Sequence[str] = (),
        notes: Sequence[str] = (), evolved: dict | None = None, log: str | None = None) -> dict:
    """Run the tests of ``genomes`` (runs, best, genes) run by run, resuming from ``partial/``; write the outputs.

    ``out_dir`` is locked for the whole test (:func:`imrl_jax.runs.rundir.lock_run_dir`). ``warnings`` are
    printed once the checks pass, ``notes`` too unless ``quiet``. ``evolved``: which generation of how many the
    genomes come from (recorded in steady.json).
    """
    test = PointTest(config, genomes, out_dir, num_tests, steady_steps, num_chunks, seed, quiet, source, command,
                     tuple(warnings), tuple(notes), evolved, log)
    test.check()
    return test.test()


def curves_bytes(config: Config, num_tests: int) -> int:
    """The host memory every test's curves take, kept until the outputs are written (with their copies)."""
    return num_tests * config.num_tasks * config.num_bins * (config.num_experts + 1) * 12


#: The test programs this process has compiled (config's static part, chunks, lanes): "compiling" is said once each.
_COMPILED: set = set()


def _test_runs(config: Config, genomes: np.ndarray, out_dir: str, num_tests: int, steady_steps: int, num_chunks: int,
               seed: int, quiet: bool, source: str, command: str, evolved: dict | None, log: str | None) -> dict:
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
    if len(done) < num_runs:  # what the runs left will cost, before the compilation they wait for
        progress.note(cost_line(f"testing {num_runs - len(done)} run(s)", num_best * num_tests,
                                num_best * num_tests * config.lifetime_steps, num_runs - len(done),
                                jax.default_backend(), memory_needed(config, num_best * num_tests * config.num_tasks,
                                jax.device_count(), curves_bytes(config, num_runs * num_best * num_tests)), unit="run",
                                world=config.world))
    start = time.perf_counter()
    params = config.learning_params()
    sizes = dict(num_runs=num_runs, num_best=num_best, num_tests=num_tests, steady_steps=steady_steps, seed=seed)
    start_partial(partial, stamp, command, None if config.spec.evolved else runspec.test_key(config, sizes))
    for r in range(num_runs):
        if r in done:
            continue
        lanes = np.repeat(genomes[r], num_tests, axis=0).astype(np.float32)
        program = (static_part(config), num_chunks, lanes.shape)
        if program not in _COMPILED:  # the first run of a program in this process compiles it (a minute or more)
            progress.note(f"compiling the test's program ({num_best * num_tests} x {config.num_tasks} lanes of "
                          f"{config.task_steps // num_chunks} cycles a chunk) ...")
            _COMPILED.add(program)
        done[r] = run_tests(keys[r], config, params, lanes, num_chunks, progress, done_before=r * num_chunks)
        keep_run(partial, r, *done[r])
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
    write_outputs(out_dir, config, reaches, selections, performance_curve(config, reaches), summary)
    return summary


class CommandPlan(NamedTuple):
    """What the command will do, every check done: the tests to run (one, or a sweep's points not tested before),
    the sweep's points tested before, and (a sweep) what its sweep_tests.json records."""

    tests: list[PointTest]
    tested_before: list[str]  # a sweep's points' --out tested before (checked against the settings asked)
    sweep: SweepRecord | None = None

    def execute(self) -> int:
        """Run the tests (a sweep's under its ``--out``'s lock, its record written last); print each one's line."""
        if self.sweep is None:
            return _report([(test.out_dir, run(**test._asdict())) for test in self.tests], self.tests[0].steady_steps)
        sweep = self.sweep
        if not sweep.quiet:
            at = "each at its own last generation" if sweep.generation is None else f"at generation {sweep.generation}"
            print(f"learning test of the {len(sweep.keys)} point(s) of {sweep.run_dir} {at}: {len(self.tests)} to test "
                  f"one after the other into {sweep.out}, {len(self.tested_before)} tested before", file=sys.stderr,
                  flush=True)
        make_dir(sweep.out)
        with lock_run_dir(sweep.out):
            check_out_root(sweep.out, sweep.keys)  # again, locked: another process may have written there since
            check_record(sweep.out, sweep.keys)
            done = {test.out_dir: run(**test._asdict()) for test in self.tests}  # each checked again, locked
            with write_errors(sweep.out):
                sweep_summary(sweep.run_dir, sweep.out, sweep.recorded, sweep.generation, sweep.sizes)
        return _report([(out_dir, done.get(out_dir)) for out_dir in sweep.out_dirs()], sweep.sizes["steady_steps"])


class SweepRecord(NamedTuple):
    """A sweep's test: its run directory, ``--out``, points (key and settings), common generation and sizes."""

    run_dir: str
    out: str
    recorded: list[tuple[str, dict]]
    generation: int | None
    sizes: dict
    quiet: bool = False

    @property
    def keys(self) -> list[str]:
        return [key for key, _ in self.recorded]

    def out_dirs(self) -> list[str]:
        return [os.path.join(self.out, key) for key in self.keys]


def _report(summaries: list[tuple[str, dict | None]], steady_steps: int) -> int:
    """Print each test's line (None: a point tested before); exit code 0."""
    for out_dir, summary in summaries:
        if summary is None:
            print(f"{out_dir}: tested before (steady.json)")
            continue
        print(f"{summary['condition']}: steady state (last {steady_steps} cycles) {summary['steady_mean']:.4f} "
              f"mean over {summary['num_runs']} run(s), best run {summary['steady_best_run']:.4f}; whole test "
              f"{summary['whole_test_mean']:.4f}; outputs in {out_dir}")
    return 0


@exit_codes
def main(argv: Sequence[str] | None = None) -> int:
    command = "python -m imrl_jax.learning_test " + " ".join(sys.argv[1:] if argv is None else argv)
    args = parser().parse_args(argv)
    return cli.execute(plan(args, command))


def plan(args, command: str) -> CommandPlan:
    """Everything the command line asks, checked (a user error at the first thing wrong); nothing written."""
    check_sizes(args)
    cli.register(args.register)
    check_condition(args)
    cli.check_cpu_devices(args.cpu_devices)
    cli.check_out(args.out)
    use_host_cores(args.cpu_devices or None)  # before anything starts JAX (the task set's checks)
    cli.refuse_option_fields(args.set, OPTION_FIELDS)
    sets = parse_sets(args.set)
    if args.cond in from_scratch():
        return CommandPlan([_point_test(args, *scratch_genomes(args, sets), sets, command, args.out)], [])
    if not args.run_dir:
        raise UsageError(f"run_dir: give an evolution's run directory, or --cond "
                         f"{' or '.join(from_scratch())} to test learning from scratch")
    recorded = recorded_points(args.run_dir)
    if recorded is None:
        return CommandPlan([_point_test(args, *evolved_genomes(args, args.run_dir, sets), sets, command, args.out)], [])
    return _plan_sweep(args, recorded, sets, command)


def _plan_sweep(args, recorded: list[tuple[str, dict]], sets: dict, command: str) -> CommandPlan:
    """The test of every point of the sweep in ``args.run_dir``: each checked, the sweep's ``--out`` too."""
    if args.best_genomes:
        raise UsageError(f"--best-genomes: {args.run_dir} is a sweep: its points' populations are kept")
    keys = check_keys(args.run_dir, recorded)
    check_out_root(args.out, keys)
    check_record(args.out, keys)
    found = {key: evolved_genomes(args, os.path.join(args.run_dir, key), sets) for key in keys}
    generation = check_generations(args, args.run_dir, {key: point[3] for key, point in found.items()})
    mixed = [] if generation is not None else [
        f"warning: the points of {args.run_dir} are tested each at its own last generation "
        f"(--allow-mixed-generations; sweep_tests.json records which)"]
    tests, before, sizes = [], [], None
    for key, (base, genomes, source, evolved, warnings) in found.items():
        out_dir = os.path.join(args.out, key)
        test = _point_test(args, base, genomes, source, evolved, [*mixed, *warnings], sets, command, out_dir,
                           check=False)
        mixed = []  # said once
        sizes = dict(num_best=args.best, num_tests=test.num_tests, task_steps=test.config.task_steps,
                     num_bins=test.config.num_bins, steady_steps=test.steady_steps, seed=test.seed)
        if os.path.isfile(os.path.join(out_dir, "steady.json")):
            check_tested_before(args, out_dir, test.config, evolved, sizes)
            before.append(out_dir)
            continue
        test.check()
        tests.append(test)
    return CommandPlan(tests, before, SweepRecord(args.run_dir, args.out, recorded, generation, sizes, args.quiet))


def _point_test(args, base: Config, genomes: np.ndarray, source: str, evolved: dict | None, warnings: list[str],
                sets: dict, command: str, out_dir: str, check: bool = True) -> PointTest:
    """The learning test of ``genomes`` under ``base`` at the command line's lengths, into ``out_dir``, checked."""
    config, source = tested_config(args, base, source)
    # A test is computed anew: its kernel chosen for this machine (the evolution's was for its own), unless --set.
    config, kernel_note = kernel_choice.resolve(config if "step_kernel" in sets else config.replace(step_kernel="auto"))
    lengths = test_lengths(args, base)
    test = PointTest(config, genomes, out_dir, args.tests, lengths.steady_steps, lengths.chunks, args.seed, args.quiet,
                     source, command, (*warnings, *cli.device_warnings(config, args.cpu_devices)),
                     (*cli.ignored_notes(config, sets), *filter(None, [kernel_note])), evolved, args.log)
    if check:
        test.check()
    return test


if __name__ == "__main__":
    sys.exit(main())
