"""The evolve command's options: the parser, their checks, and the config, seeds and strategy they ask for.

Resuming (``--resume --out RUN``), whatever the command line leaves out is the run's own
(its config.json and search); an option that differs from them is refused by the run's checks.
"""

from __future__ import annotations

import argparse

from imrl_jax.runs import cli
from imrl_jax import conditions
from imrl_jax.runs.cli import HelpFormatter, UsageError, parse_sets
from imrl_jax.config import EVOLVED_CONDITIONS, PRESETS, WORLD_FIELDS, Config, make_config
from imrl_jax.evolution.strategies import GA_NAME, make_strategy, parse_settings


#: The config fields that options of the command line set (``--set`` may not set them): field -> option
#: (:func:`build_config` reads each option's value into its field).
OPTION_FIELDS = {"condition": "--cond", "num_generations": "--generations", "population_size": "--population",
                 "num_parents": "--parents", "num_elites": "--elites", "childhood_steps": "--childhood-steps",
                 "task_steps": "--task-steps", "num_bins": "--bins"}


def check_sizes(args) -> None:
    """Refuse absurd sizes before anything is allocated (raises UsageError naming the option and its limit)."""
    for flag, value, limit in (("--generations", args.generations, cli.MAX_GENERATIONS),
                               ("--seeds", args.seeds, cli.MAX_SEEDS),
                               ("--population", args.population, cli.MAX_POPULATION),
                               ("--childhood-steps", args.childhood_steps, cli.MAX_STEPS),
                               ("--task-steps", args.task_steps, cli.MAX_STEPS),
                               ("--bins", args.bins, cli.MAX_BINS)):
        cli.check_at_most(flag, value, limit)
    if args.seeds is not None and args.seeds < 1:
        raise UsageError("--seeds: must be at least 1")
    if args.first_seed is not None and args.first_seed < 0:
        raise UsageError(f"--first-seed: must be 0 or more (got {args.first_seed})")
    if args.first_seed is not None and args.first_seed + (args.seeds or 1) > cli.MAX_KEY + 1:
        raise UsageError(f"--first-seed: the seeds must stay below 2^32 (got {args.first_seed:,} and on)")
    if args.seeds is not None and args.population is not None:
        cli.check_at_most("--seeds x --population", args.seeds * args.population, cli.MAX_LANES)
    for flag, value in (("--checkpoint-every", args.checkpoint_every), ("--keep", args.keep)):
        cli.check_at_most(flag, value, cli.MAX_GENERATIONS)
    cli.check_at_least("--num-processes", args.num_processes)  # None (not given) passes both
    cli.check_at_most("--num-processes", args.num_processes, cli.MAX_SEEDS)
    cli.check_at_least("--process-id", args.process_id, 0)
    cli.check_at_most("--process-id", args.process_id, cli.MAX_SEEDS)


def check_condition(args) -> None:
    """Refuse a ``--cond`` that is not a row of the condition table as it is now (after ``--register``), or none."""
    if args.cond is not None and args.cond not in conditions.CONDITIONS:  # the table as it is now
        evolved = [name for name, row in conditions.CONDITIONS.items() if row.evolved]
        raise UsageError(f"--cond: unknown condition {args.cond!r} (choose from {', '.join(evolved)}, or add a row "
                         f"with --register MODULE:ATTRIBUTE)")
    if args.resume and not (args.out or args.cond):
        raise UsageError("--resume: give the run to continue with --out RUN")
    if args.cond is None and not args.resume:
        raise UsageError("--cond: required (or --resume --out RUN to continue a run with its own config)")


def build_config(args, saved: tuple[Config, list[int]] | None = None) -> tuple[Config, list[int]]:
    """The config and seeds the command line asks for (raises UsageError naming the field).

    ``saved``: the config and seeds of the run being resumed, used for whatever the command line
    leaves out (a preset given explicitly is used instead, but not its number of generations:
    only ``--generations`` extends a run).
    """
    cli.refuse_option_fields(args.set, OPTION_FIELDS)
    given = {field: getattr(args, _dest(flag)) for field, flag in OPTION_FIELDS.items()}
    overrides = {field: value for field, value in given.items() if value is not None}
    overrides.update(parse_sets(args.set))
    if saved is None:
        make = lambda **tasks: make_config(args.preset or "paper", **overrides, **tasks)  # noqa: E731
        first, count = args.first_seed or 0, args.seeds or 1
        seeds = list(range(first, first + count))
    else:
        saved_config, seeds = saved
        if args.preset is None:
            make = lambda **tasks: saved_config.replace(**overrides, **tasks)  # noqa: E731
        else:  # the preset's values, on the run's condition and length (only --cond, --generations change those)
            kept = {"condition": saved_config.condition, "num_generations": saved_config.num_generations,
                    "step_kernel": saved_config.step_kernel,  # a compute choice, not the preset's: the run's own
                    **{field: getattr(saved_config, field) for field in WORLD_FIELDS}}  # and its world
            make = lambda **tasks: make_config(args.preset, **{**kept, **overrides, **tasks})  # noqa: E731
        if args.first_seed is not None or args.seeds is not None:
            first = seeds[0] if args.first_seed is None else args.first_seed
            count = len(seeds) if args.seeds is None else args.seeds
            seeds = list(range(first, first + count))
    # The tasks are checked against the geometry of this config (its preset and --set), made with them; then the
    # config moves into --world (which brings its own tasks).
    return cli.apply_world(cli.apply_task_set(make, args), args), seeds


def _dest(flag: str) -> str:
    """The attribute of the parsed arguments that an option sets (argparse's name for it)."""
    return flag.lstrip("-").replace("-", "_")


def build_strategy(args, config: Config, saved: dict | None = None):
    """The search strategy the command line asks for; resuming, the run's own (``saved``) for what it leaves out."""
    name = args.strategy or (saved["strategy"] if saved else GA_NAME)
    if args.strategy_set is not None:
        settings = parse_settings(args.strategy_set)
    else:
        settings = saved["settings"] if saved and args.strategy in (None, saved["strategy"]) else {}
    return make_strategy(name, config, settings)


def parser() -> argparse.ArgumentParser:
    """The evolve command line's parser."""
    p = cli.Parser(
        prog="python -m imrl_jax.evolve",
        description="Evolve one of the paper's conditions for several seeds at once "
                    "(Schembri, Mirolli & Baldassarre 2007). With --resume --out RUN the run's own config "
                    "and seeds are used; an option that differs from them is refused (but a grown "
                    "--generations extends the run).",
        formatter_class=HelpFormatter)
    p.add_argument("--cond", metavar="{" + ",".join(EVOLVED_CONDITIONS) + "}",
                   help="condition to evolve (SLE is not evolved), or a row added by --register; required unless "
                        "--resume")
    cli.add_register(p)
    p.add_argument("--seeds", type=int,
                   help=f"number of independent evolutions (default: 1, or the run's; at most {cli.MAX_SEEDS:,})")
    p.add_argument("--first-seed", type=int, help="seed of the first evolution; the others follow (default: 0)")
    p.add_argument("--preset", choices=sorted(PRESETS),
                   help="paper (the default): the paper's rules at full scale; skills: full scale with the childhood "
                        "study's choice (docs/CHILDHOOD.md); extension: full scale with the learning extensions; "
                        "small: reduced lengths for quick CPU checks")
    p.add_argument("--generations", type=int, help="generations (default: the preset's; paper 100, small 10; "
                                                    f"at most {cli.MAX_GENERATIONS:,})")
    p.add_argument("--population", type=int, help="population size (default: the preset's; paper 50, small 20)")
    p.add_argument("--parents", type=int, help="best individuals that reproduce (default: the preset's; paper 10, small 4)")
    p.add_argument("--elites", type=int, help="parents copied unmutated (default: the preset's; paper 0)")
    p.add_argument("--childhood-steps", type=int, help="LE-LS childhood length (default: the preset's; paper 150000, "
                                                        "small 15000)")
    p.add_argument("--task-steps", type=int, help="steps per adulthood task (default: the preset's; paper 100000, "
                                                   f"small 5000; at most {cli.MAX_STEPS:,})")
    p.add_argument("--bins", type=int, help="bins of the per-task reward curves (default: the preset's; paper 100, small 10)")
    p.add_argument("--set", action="append", metavar="FIELD=VALUE",
                   help="set any other scalar Config field, e.g. --set trace_lambda=0.9 (repeatable)")
    cli.add_task_set(p, "the tasks of adulthood (default: paper, or the run's)")
    cli.add_world(p)
    p.add_argument("--strategy", metavar="NAME",
                   help="the search: ga (the paper's genetic algorithm, the default) or an evolution strategy of "
                        "evosax (the evosax extra): sep_cma_es, cma_es, snes, xnes, open_es, pgpe; docs/SEARCH.md")
    p.add_argument("--strategy-set", action="append", metavar="FIELD=VALUE",
                   help="set a parameter of an evosax strategy, e.g. --strategy-set std_init=0.3 (repeatable)")
    p.add_argument("--sweep", action="append", metavar="FIELD=V1,V2",
                   help="evolve at every value of a dynamic field (learning rates, discount, trace, noise, "
                        "mutation; eta sets every rate) in one program, each point a run in OUT/KEY (repeatable: "
                        "the product of the values; docs/STUDIES.md \"Sweeps\")")
    p.add_argument("--zip", action="store_true", help="with several --sweep: their values taken in step, not "
                                                      "every combination")
    p.add_argument("--out", help="run directory: new, empty, or the run to resume (default: runs/COND, "
                                 "runs/COND-sweep for a sweep)")
    p.add_argument("--resume", action="store_true",
                   help="continue the run in --out from its latest checkpoint (a finished run is extended by a "
                        "larger --generations)")
    p.add_argument("--checkpoint-every", type=int, default=1, help="generations between checkpoints")
    p.add_argument("--keep", type=int, default=3, help="checkpoints kept (at least 1)")
    p.add_argument("--quiet", action="store_true", help="print only errors, warnings and the final summary (for logs)")
    p.add_argument("--log", help="also write the progress for TensorBoard: --log tensorboard (under OUT/tensorboard; "
                   "needs tensorboardX)")
    p.add_argument("--cpu-devices", type=int, default=0,
                   help="CPU devices to split the lanes over (0: one per core; ignored if XLA_FLAGS sets it)")
    p.add_argument("--coordinator", help="multi-host: coordinator address host:port (default: JAX_COORDINATOR_ADDRESS; none: one process)")
    p.add_argument("--num-processes", type=int, help="multi-host: number of processes (or JAX_NUM_PROCESSES)")
    p.add_argument("--process-id", type=int, help="multi-host: this process's id (or JAX_PROCESS_ID)")
    return p
