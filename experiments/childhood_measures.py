"""The childhood study's measures' command line (``python -m experiments.childhood_study [RUN...] --out OUT STAGE``):
parse, plan (every value bounded, the runs read and checked, the memory estimated, --out checked), then execute.

It reads the study's stages and rules from a :class:`Study` the study's module gives it (``childhood_study.measures``):
the study imports this module, not the other way round."""

from __future__ import annotations

import itertools
import os
from typing import Callable, NamedTuple

import numpy as np

from experiments.harness.measures import check_counts, check_out_dir, checked_config, listed
from imrl_jax.runs import cli
from imrl_jax.runs.cli import HelpFormatter, Parser, UsageError, exit_codes
from imrl_jax.config import CHILDHOOD_SELECTOR_REWARDS, CHILDHOOD_WALLS


class Study(NamedTuple):
    """What the measures read of the childhood study: its stages (name -> (function, key, lives)), rules and reader."""

    description: str
    stages: dict
    rules: dict
    ceiling_rules: dict
    best_of_run: Callable


def measure_parser(study: Study) -> Parser:
    """A measure's command line: ``[RUN...] --out OUT STAGE [options]``."""
    STAGES, RULES = study.stages, study.rules
    p = Parser(prog="python -m experiments.childhood_study", description=study.description,
               formatter_class=HelpFormatter)
    p.add_argument("words", nargs="+", metavar="RUN|STAGE", help=f"the runs it reads, and one of {', '.join(STAGES)}")
    p.add_argument("--out", required=True, help="the measure's folder (its CSV is named after it)")
    p.add_argument("--lengths", default="30000,150000,600000", help="hand: childhood lengths (steps)")
    p.add_argument("--walls", default="clamp,respawn", help="hand: how walls act")
    p.add_argument("--rewards", default="surprise,progress", help="hand: the childhood selector's rewards")
    p.add_argument("--rules", default="paper,extension,uniform", help=f"hand: of {', '.join(RULES)}")
    p.add_argument("--respawn-steps", type=int, default=20, help="hand: steps on a wall before a respawn")
    p.add_argument("--speed-bias", type=float, default=0.0, help="hand: initial bias of the actors' speed unit")
    p.add_argument("--seeds", type=int, default=4, help="hand: seeds of each setting")
    p.add_argument("--task-steps", default="20000,100000", help="ceiling: steps per task")
    p.add_argument("--biases", default="0,2,4", help="speed: initial biases of the speed unit (0: the paper's)")
    p.add_argument("--preset", default="skills", help="speed, random: the preset")
    p.add_argument("--best", type=int, default=10, help="evolved, heritability: best genomes of each seed")
    p.add_argument("--individuals", type=int, default=30, help="random: genomes")
    p.add_argument("--lives", type=int, help="ceiling, heritability, speed: lives of each (default: " + ", ".join(
        f"{name} {lives}" for name, (_, _, lives) in STAGES.items() if lives) + ")")
    p.add_argument("--key", type=int, help="the random key (default: " + ", ".join(
        f"{name} {key}" for name, (_, key, _) in STAGES.items()) + ")")
    return p


#: The largest --key: the random stage draws from key, key + 1 and key + 2, each a 32-bit seed.
MAX_KEY = 2**32 - 3


def checked_runs(args, study: Study) -> list[tuple]:
    """Each run's best genomes and rows (:func:`best_of_run`), checked: readable, finite fitness (raises a user
    error naming the file)."""
    from imrl_jax.runs.rundir import RunDirError

    read = []
    for run in args.runs:
        if not os.path.isfile(os.path.join(run, "config.json")):
            raise UsageError(f"runs: not a run directory (no config.json): {run}")
        try:
            config, genomes, best = study.best_of_run(run, args.best)
        except (KeyError, TypeError, ValueError, IndexError) as error:  # RunDirError is a ValueError: its own line
            if isinstance(error, RunDirError):
                raise
            raise RunDirError(f"{run}: its best genomes are unreadable ({cli.one_line(error)})") from None
        if genomes.shape[-1] != config.num_genes or not np.isfinite(genomes).all() or \
                not np.isfinite([b["fitness"] for b in best]).all():
            raise RunDirError(f"{run}: its best genomes are not {config.num_genes} finite genes of a finite fitness "
                              f"(final_population.npz or best_genomes.npz damaged?)")
        read.append((config, len(genomes)))
    return read


def lanes_of(args, study: Study) -> list[tuple]:
    """(config, lives at once) of each program the stage runs, every config checked (raises a user error)."""
    if args.stage == "hand":
        for flag, field, text, known in (("--walls", "childhood_walls", args.walls, CHILDHOOD_WALLS),
                                         ("--rewards", "childhood_selector_reward", args.rewards,
                                          CHILDHOOD_SELECTOR_REWARDS)):
            if unknown := [v for v in text.split(",") if v not in known]:
                raise UsageError(f"{flag}: unknown {field} {unknown[0]!r} (choose from {', '.join(known)})")
        checked_config("--respawn-steps", "paper", wall_respawn_steps=args.respawn_steps)
        checked_config("--speed-bias", "paper", initial_speed_bias=args.speed_bias)
        return [(checked_config("--lengths", "paper", condition="LE-LS", childhood_steps=length, childhood_walls=wall,
                         childhood_selector_reward=reward, wall_respawn_steps=args.respawn_steps,
                         initial_speed_bias=args.speed_bias), len(args.rules.split(",")) * args.seeds)
                for length, wall, reward in itertools.product(listed("--lengths", args.lengths),
                                                              args.walls.split(","), args.rewards.split(","))]
    if args.stage == "ceiling":
        return [(checked_config("--task-steps", "paper", condition="EE-LS", task_steps=steps, num_bins=10, **rules),
                 args.lives * 6)
                for steps in listed("--task-steps", args.task_steps) for rules in study.ceiling_rules.values()]
    if args.stage in ("speed", "random"):
        config = checked_config("--preset", args.preset, condition="LE-LS")
        if args.stage == "random":
            return [(config, args.individuals)]
        biases = listed("--biases", args.biases, float)
        for bias in biases:
            checked_config("--biases", args.preset, condition="LE-LS", initial_speed_bias=bias)
        return [(config, len(biases) * args.lives)]
    return [(config, genomes * (args.lives if args.stage == "heritability" else 1))
            for config, genomes in checked_runs(args, study)]


def measure_plan(argv, study: Study) -> cli.Call:
    """Parse and check a measure: every value bounded, the runs it reads, its memory and --out (nothing written)."""
    from imrl_jax.evolution.devices import check_memory, use_host_cores

    STAGES, RULES = study.stages, study.rules
    args = measure_parser(study).parse_intermixed_args(argv)
    stages = [w for w in args.words if w in STAGES]
    if len(stages) != 1:
        raise UsageError(f"stage: name one of {', '.join(STAGES)} (got {' '.join(args.words)})")
    args.stage, args.runs = stages[0], [w for w in args.words if w not in STAGES]
    stage, key, lives = STAGES[args.stage]
    args.key = key if args.key is None else args.key
    args.lives = lives if args.lives is None else args.lives
    check_counts(args, dict(lives=cli.MAX_SEEDS, seeds=cli.MAX_SEEDS, best=cli.MAX_POPULATION,
                            individuals=cli.MAX_LANES, respawn_steps=cli.MAX_STEPS))
    cli.check_key("--key", args.key, MAX_KEY)
    unknown = [r for r in args.rules.split(",") if r not in RULES]
    if unknown:
        raise UsageError(f"--rules: unknown rules {unknown[0]!r} (choose from {', '.join(RULES)})")
    if bool(args.runs) != (args.stage in ("evolved", "heritability")):
        raise UsageError(f"runs: {args.stage} reads {'no run' if args.runs else 'run directories'}")
    programs = lanes_of(args, study)
    use_host_cores(1)  # before the memory estimate starts JAX's backend
    for config, lanes in programs:
        cli.check_at_most(f"lives at once of the {args.stage} measure", lanes, cli.MAX_LANES)
        check_memory(config, lanes, f"the {args.stage} measure")
    name = os.path.basename(os.path.normpath(args.out))
    check_out_dir(args.out, (f"{name}.csv", "result.json"), f"{args.stage} measure")
    return cli.Call(lambda: stage(args), stage=args.stage, args=args)


@exit_codes
def measure_main(argv, study: Study) -> int:
    """A measure's command line: ``[RUN...] --out OUT STAGE [options]``."""
    return cli.execute(measure_plan(argv, study))
