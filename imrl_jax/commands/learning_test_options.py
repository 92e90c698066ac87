"""The learning_test command's options: the parser, their checks, and the genomes they ask to test.

A condition that is not evolved (SLE) is tested from scratch (``--cond``; its genomes are all zero);
an evolved one from a run directory: the ``--best`` fittest of each seed's last evaluated generation
(or those a report kept, ``--best-genomes``), under the run's config with ``--set`` applied.
"""

from __future__ import annotations

import argparse
import os
from typing import NamedTuple

import numpy as np

from imrl_jax.runs import cli
from imrl_jax.runs.cli import HelpFormatter, UsageError
from imrl_jax.conditions import CONDITIONS as TABLE
from imrl_jax.config import CONDITIONS, PRESETS, Config, ConfigError, make_config
from imrl_jax.runs.rundir import best_genomes, load_kept_best, load_run, unfinished
from imrl_jax.analysis.steady_state import steady_bins

#: Conditions that are not evolved: tested from scratch (``--cond``), without a run directory (the table's at import;
#: :func:`from_scratch` also has the rows registered since).
def from_scratch() -> tuple[str, ...]:
    """The conditions of the table as it is now that are not evolved (tested from scratch)."""
    return tuple(name for name, condition in TABLE.items() if not condition.evolved)


def parser() -> argparse.ArgumentParser:
    p = cli.Parser(prog="python -m imrl_jax.learning_test",
                   description="The paper's learning tests (section 3, Fig. 3b and 3c): the best individuals of an "
                               "evolution, or SLE from scratch, learn each task anew.",
                   formatter_class=HelpFormatter)
    p.add_argument("run_dir", nargs="?",
                   help=f"an evolution's run directory (omit with --cond {' or '.join(from_scratch())})")
    p.add_argument("--cond", metavar="{" + ",".join(CONDITIONS) + "}",
                   help=f"{', '.join(from_scratch())}: test learning from scratch (no run directory); "
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
    cli.add_world(p, "the world it learns in (a run's genomes: one of the same sizes)")
    p.add_argument("--allow-unfinished", action="store_true",
                   help="test a run whose evolution has not reached its last generation (killed, or still running): "
                        "its last evaluated generation, with a warning (steady.json records which)")
    p.add_argument("--allow-mixed-generations", action="store_true",
                   help="test a sweep whose points are at different generations (one extended alone) each at its own "
                        "last generation (sweep_tests.json records which); without it such a sweep is refused")
    p.add_argument("--best", type=int, default=10, help="best individuals of each run's last generation")
    p.add_argument("--tests", type=int, default=10, help="tests per individual")
    p.add_argument("--task-steps", type=int,
                   help=f"cycles per task (default: {TEST_SCALE} x the run's, or --preset's, task_steps, as the "
                        f"paper's test is 10 x its evolution's tasks: 1,000,000 for the paper's)")
    p.add_argument("--bins", type=int, help="bins of the learning curve (default: the run's, or --preset's, "
                                            "num_bins: 100 for the paper's)")
    p.add_argument("--steady-steps", type=int,
                   help="final cycles averaged for the steady state (default: the test's last tenth, in whole bins: "
                        "100,000 for the paper's)")
    p.add_argument("--chunks", type=int, help="pieces the test runs in (progress lines; default: the most of 10 or "
                                              "fewer that divide the bins: 10 for the paper's)")
    p.add_argument("--seed", type=int, default=0, help="seed of the tests' keys (0 to 2^32 - 1)")
    p.add_argument("--out", required=True,
                   help="output directory: new, empty, or an unfinished test of the same command to go on with")
    p.add_argument("--quiet", action="store_true", help="no progress lines (for logs)")
    p.add_argument("--log", help="also write the progress for TensorBoard: --log tensorboard (under OUT/tensorboard; "
                   "needs tensorboardX)")
    p.add_argument("--cpu-devices", type=int, default=0, help="CPU devices (0: one per core)")
    return p


#: The config fields that options of the command line set (``--set`` may not set them): field -> option.
OPTION_FIELDS = {"condition": "--cond", "task_steps": "--task-steps", "num_bins": "--bins"}


#: The paper's test tasks are this many times its evolution's (1,000,000 cycles against 100,000).
TEST_SCALE = 10
#: The steady state is this share of the test's last cycles (the paper's last 100,000 of 1,000,000).
STEADY_SHARE = 10
#: The most chunks a test runs in by default (progress lines).
DEFAULT_CHUNKS = 10


class Lengths(NamedTuple):
    """A test's lengths: cycles per task, bins, steady-state cycles and chunks."""

    task_steps: int
    bins: int
    steady_steps: int
    chunks: int


def check_sizes(args) -> None:
    """Refuse absurd sizes before anything is allocated (raises UsageError naming the option and its limit)."""
    for flag, value, limit in (("--best", args.best, cli.MAX_SEEDS), ("--tests", args.tests, cli.MAX_SEEDS),
                               ("--runs", args.runs, cli.MAX_SEEDS), ("--task-steps", args.task_steps, cli.MAX_STEPS),
                               ("--bins", args.bins, cli.MAX_BINS), ("--steady-steps", args.steady_steps, cli.MAX_STEPS),
                               ("--chunks", args.chunks, cli.MAX_BINS)):
        cli.check_at_least(flag, value)
        cli.check_at_most(flag, value, limit)
    cli.check_key("--seed", args.seed)
    cli.check_at_most("--best x --tests", args.best * args.tests, cli.MAX_LANES)


def test_lengths(args, base: Config) -> Lengths:
    """The lengths a test of ``base`` (a run's config, or the preset's) runs at: the options given, the others
    following ``base`` as the paper's test follows its evolution (10 x the tasks, their bins, the last tenth)."""
    task_steps = args.task_steps if args.task_steps is not None else TEST_SCALE * base.task_steps
    if args.task_steps is None and task_steps > cli.MAX_STEPS:
        raise UsageError(f"--task-steps: the default, {TEST_SCALE} x the run's {base.task_steps:,}, is above the limit "
                         f"of {cli.MAX_STEPS:,}; give --task-steps")
    bins = args.bins if args.bins is not None else base.num_bins
    steady = args.steady_steps
    if steady is None:
        steady = task_steps // bins * max(1, round(bins / STEADY_SHARE))
    chunks = args.chunks
    if chunks is None:
        chunks = max(c for c in range(1, DEFAULT_CHUNKS + 1) if bins % c == 0)
    return Lengths(task_steps, bins, steady, chunks)


def check_condition(args) -> None:
    """Refuse a ``--cond`` that is not a row of the condition table as it is now (after ``--register``)."""
    if args.cond is not None and args.cond not in TABLE:  # the table as it is now
        raise UsageError(f"--cond: unknown condition {args.cond!r} (choose from {', '.join(TABLE)}, or add a row "
                         f"with --register MODULE:ATTRIBUTE; only {', '.join(from_scratch())} are tested without "
                         f"a run directory)")


def tested_config(args, base: Config, source: str) -> tuple[Config, str]:
    """The config of a test of ``base`` at the command line's lengths (:func:`test_lengths`) and tasks, and the
    source's words with them."""
    lengths = test_lengths(args, base)
    try:  # evolved genomes may be tested on other tasks (they encode none)
        config = cli.apply_task_set(
            lambda **tasks: base.replace(task_steps=lengths.task_steps, num_bins=lengths.bins, **tasks), args)
    except ConfigError as error:
        if error.field in ("task_steps", "num_bins"):  # the options' values, named by the options
            raise ConfigError(f"--task-steps, --bins: {error}", error.field) from None
        raise
    if args.task_set is not None:
        source += f", task set {args.task_set}"
    moved = cli.apply_world(config, args)  # another world, or other settings of its own (tasks: task_set=...)
    if moved.num_genes != base.num_genes:  # a test from scratch has none; evolved genomes must fit
        raise UsageError(f"--world: genomes of {base.num_genes} genes evolved in world {base.world} cannot live in "
                         f"world {moved.world} ({moved.num_genes} genes)")
    if (moved.world, moved.world_settings) != (config.world, config.world_settings):
        source += f", world {moved.world}" + "".join(f", {k}={v}" for k, v in moved.world_settings)
    config = moved
    if config.num_bins % lengths.chunks:
        raise UsageError(f"--chunks: {lengths.bins} bins cannot be split into {lengths.chunks} chunks")
    try:
        steady_bins(config, lengths.steady_steps)
    except ConfigError as error:
        raise UsageError(f"--steady-steps: {error}") from None
    return config, source


def scratch_genomes(args, sets: dict) -> tuple[Config, np.ndarray, str, None, list[str]]:
    """A test from scratch (``--cond``, not evolved): its config (``--preset`` with ``--set``), its all-zero genomes
    (runs, best, genes), the source's words, no generation, no warnings."""
    if args.run_dir:
        raise UsageError(f"run_dir: {args.cond} is tested from scratch; give either a run directory or "
                         f"--cond {args.cond}")
    if args.best_genomes:
        raise UsageError("--best-genomes: only with a run directory")
    base = make_config(args.preset, **{**sets, "condition": args.cond})
    genomes = np.zeros((args.runs, args.best, base.num_genes), np.float32)
    source = f"{args.cond} from scratch, preset {args.preset}" + "".join(f", {s}" for s in args.set or [])
    return base, genomes, source, None, []


def evolved_genomes(args, run_dir: str, sets: dict) -> tuple[Config, np.ndarray, str, dict | None, list[str]]:
    """A run directory's config (with ``--set``), its best genomes, the source's words, its generation, warnings."""
    warnings, evolved = [], None
    if args.best_genomes:
        base, _, genomes = load_kept_best(run_dir, args.best_genomes, args.best)
    else:
        found = load_run(run_dir)
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
