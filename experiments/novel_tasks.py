"""Tasks never met in evolution (docs/NOVEL_TASKS.md): the generalisation tests, as stages of the shared runner.

    python -m experiments.novel_tasks --list      # the stages and their commands, nothing run
    python -m experiments.novel_tasks             # run (or go on with) every stage, in order

Three groups, all at the paper's test length (1,000,000 cycles per task):

- **novel**: the best individuals of the finished paper-scale runs (LE-LS, EE-LS under ``skills``
  and ``paper``; EE-ES, shared) learn the ``novel`` task set. Their final populations were not
  kept, so the tests take the 10 best of each seed from ``best_genomes.npz`` (here 5 best x 4
  tests of each of the 10 seeds), against SLE from scratch on the same set (5 runs x 5 x 4).
- **held out**: LE-LS and EE-LS under ``skills`` evolved on tasks 1, 3, 4 and 6 of the paper's
  six (5 seeds x 100 generations, paper lengths), then tested on those and on the other two
  (2 and 5: one of each pair the evolution saw, whose partner turns the other way).

The stages run through the reproduction's resumable stage runner
(:func:`experiments.reproduce.run_stages`): run the same command again after an interruption.
"""

from __future__ import annotations

import argparse
import os
import sys
from typing import NamedTuple

from experiments.claims_study import REPRODUCTION, SCREEN
from experiments.reproduce import (SCALES, Stage, evolution_cost, evolve_command, load_manifest, run_stages,
                                   test_command, test_cost)
from imrl_jax.config import paper_tasks
from imrl_jax.tasks import to_json

OUT = os.path.join("experiments", "results", "novel_tasks")
BEST_GENOMES = os.path.join(REPRODUCTION, "best_genomes.npz")
#: The finished runs tested on the novel set: (variant, condition).
FINISHED = (("skills", "LE-LS"), ("skills", "EE-LS"), ("paper", "LE-LS"), ("paper", "EE-LS"), ("paper", "EE-ES"))
#: The paper's tasks (1-based) the held-out evolutions see, and those they never meet.
SEEN, UNSEEN = (1, 3, 4, 6), (2, 5)
#: The held-out task sets, by the key of their file in :func:`task_files`.
HELD_OUT = {"seen": SEEN, "unseen": UNSEEN}
#: The task set of the novel stages (the package's own).
NOVEL = "novel"


class Variant(NamedTuple):
    """What a stage's variant runs: a preset on a task set."""

    preset: str
    tasks: str  # NOVEL, or a key of HELD_OUT (the held-out evolutions evolve on "seen")


def held_out_variant(which: str) -> str:
    """The stage variant of the held-out stages on the task set ``which`` (a key of HELD_OUT)."""
    return f"held_out_{which}"


#: Every stage variant of the study: the novel set under each finished run's preset, the held-out sets under skills.
VARIANTS = {**{preset: Variant(preset, NOVEL) for preset in ("skills", "paper")},
            **{held_out_variant(which): Variant("skills", which) for which in HELD_OUT}}
#: Tests of the finished runs: all 10 seeds, 5 of the 10 best kept, 4 tests each; of SLE, 5 runs x 5 x 4.
FINISHED_TEST = dict(SCALES["paper"], seeds=10, best=5, tests=4)


def task_files(out: str = OUT, write: bool = False) -> dict[str, str]:
    """The held-out task sets' JSON files under ``out`` ({"seen": path, "unseen": path}), written if ``write``."""
    files = {}
    for name, numbers in HELD_OUT.items():
        path = os.path.join(out, f"tasks_{name}.json")
        if write and not os.path.exists(path):
            os.makedirs(out, exist_ok=True)
            with open(path, "w") as f:
                f.write(to_json([paper_tasks()[n - 1] for n in numbers], f"paper tasks {numbers}") + "\n")
        files[name] = path
    return files


def plan(out: str = OUT) -> list[Stage]:
    """Every stage, in order: the finished runs and SLE on the novel set, then the held-out evolutions and tests."""
    stages = [Stage(f"novel {variant} {condition}", "test", variant, condition,
                    os.path.join(out, "novel", variant, condition), test_cost(FINISHED_TEST, condition))
              for variant, condition in FINISHED]
    stages += [Stage(f"novel {variant} SLE", "test", variant, "SLE", os.path.join(out, "novel", variant, "SLE"),
                     test_cost(SCREEN, "SLE")) for variant in ("skills", "paper")]
    for condition in ("LE-LS", "EE-LS"):
        folder = os.path.join(out, "held_out", condition)
        # a life is the childhood (if any) then each task of the set once: the childhood is not per task
        stages.append(Stage(f"held out: evolve {condition} on tasks {SEEN}", "evolve", held_out_variant("seen"),
                            condition, os.path.join(folder, "evolve"),
                            evolution_cost(SCREEN, condition, num_tasks=len(SEEN))))
        for which, numbers in HELD_OUT.items():
            stages.append(Stage(f"held out: {condition} tested on the {which} tasks", "test", held_out_variant(which),
                                condition, os.path.join(folder, f"test_{which}"),
                                test_cost(SCREEN, condition, num_tasks=len(numbers))))
    return stages


def stage_command(stage: Stage, out: str = OUT) -> tuple[list[str], None]:
    """A stage's command line: evolve or learning_test with the stage's task set."""
    variant = VARIANTS[stage.variant]
    if variant.tasks != NOVEL:  # held out: evolved on the seen tasks, tested on the seen or the unseen ones
        task_set = ["--task-set", task_files(out)[variant.tasks]]
        if stage.kind == "evolve":
            return evolve_command(SCREEN, variant.preset, stage.condition, stage.out_dir) + task_set, None
        evolved = os.path.join(out, "held_out", stage.condition, "evolve")
        return test_command(SCREEN, variant.preset, stage.condition, evolved, stage.out_dir) + task_set, None
    if stage.condition == "SLE":
        return test_command(SCREEN, variant.preset, "SLE", "", stage.out_dir) + ["--task-set", NOVEL], None
    run_dir = os.path.join(REPRODUCTION, variant.preset, "evolve", stage.condition)
    return test_command(FINISHED_TEST, variant.preset, stage.condition, run_dir, stage.out_dir) + [
        "--best-genomes", BEST_GENOMES, "--task-set", NOVEL], None


def main(argv=None) -> int:
    """The command line: list the stages, or write the held-out task sets and run (or go on with) every stage."""
    p = argparse.ArgumentParser(prog="python -m experiments.novel_tasks", description=__doc__.split("\n\n")[0])
    p.add_argument("--out", default=OUT, help=f"results directory (default: {OUT})")
    p.add_argument("--list", action="store_true", help="print the stages and their commands, run nothing")
    args = p.parse_args(argv)
    stages = plan(args.out)
    if args.list:
        for stage in stages:
            print(f"{stage.name}: {' '.join(stage_command(stage, args.out)[0][1:])}")
        return 0
    task_files(args.out, write=True)
    manifest, manifest_path = load_manifest(args.out, study="novel_tasks", sizes=SCREEN)
    return run_stages(stages, SCREEN, manifest, manifest_path, lambda stage: stage_command(stage, args.out))


if __name__ == "__main__":
    sys.exit(main())
