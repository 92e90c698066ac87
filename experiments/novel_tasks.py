"""Tasks never met in evolution (docs/NOVEL_TASKS.md): the generalisation tests, as stages of the shared runner.

    python -m experiments list novel-tasks      # the stages, done or to run
    python -m experiments run novel-tasks       # run (or go on with) every stage, in order
    python -m experiments report novel-tasks    # the advantage table, figure and verdict of what has finished

Three groups, all at the paper's test length (1,000,000 cycles per task):

- **novel**: the best individuals of the finished paper-scale runs (LE-LS, EE-LS under ``skills``
  and ``paper``; EE-ES, shared) learn the ``novel`` task set. Their final populations were not
  kept, so the tests take the 10 best of each seed from ``best_genomes.npz`` (here 5 best x 4
  tests of each of the 10 seeds), against SLE from scratch on the same set (5 runs x 5 x 4).
- **held out**: LE-LS, EE-LS and EE-ES under ``skills`` evolved on tasks 1, 3, 4 and 6 of the
  paper's six (5 seeds x 100 generations, paper lengths), then tested on those and on the other
  two (2 and 5: one of each pair the evolution saw, whose partner turns the other way).
- **baselines**: brax's PPO and ES from scratch on the novel set, 1,000,000 cycles per task, 5 seeds.

``--report`` (:func:`report`) measures learning's advantage (a condition's steady state minus
EE-ES's) on the tasks of evolution and on tasks never met in it, judges the paper's sentence
(``claims.claim_unseen``), draws the figures and writes the table into docs/NOVEL_TASKS.md, from
whatever stages have finished.

The stages run through the reproduction's resumable stage runner
(:func:`experiments.reproduce.run_stages`): run the same command again after an interruption.
"""

from __future__ import annotations

import argparse
import os
import sys
from typing import NamedTuple


from experiments.study import REPRODUCTION, SCREEN
from experiments.reproduce import (Stage, evolution_cost, evolve_command, load_manifest, run_stages,
                                   owner, test_command, test_cost)
from experiments.executor import add_options, from_options
from experiments.study import RESULTS, SCALES, Study
from imrl_jax import conditions
from imrl_jax.config import paper_tasks
from imrl_jax.tasks import to_json

OUT = os.path.join(RESULTS, "novel_tasks")
BEST_GENOMES = os.path.join(REPRODUCTION, "best_genomes.npz")
#: brax's baselines on the paper's six (docs/BASELINES.md), beside the same on the novel set.
BASELINES = os.path.join(RESULTS, "baselines")
#: The finished runs tested on the novel set: (variant, condition).
FINISHED = (("skills", "LE-LS"), ("skills", "EE-LS"), ("paper", "LE-LS"), ("paper", "EE-LS"), ("paper", "EE-ES"))
#: The paper's tasks (1-based) the held-out evolutions see, and those they never meet.
SEEN, UNSEEN = (1, 3, 4, 6), (2, 5)
#: The held-out task sets, by the key of their file in :func:`task_files`.
HELD_OUT = {"seen": SEEN, "unseen": UNSEEN}
#: The task set of the novel stages (the package's own).
NOVEL = "novel"
#: The conditions evolved on the seen tasks and tested on both sets (EE-ES: the gap's reference, learning nothing).
HELD_OUT_CONDITIONS = ("LE-LS", "EE-LS", "EE-ES")
#: Seeds of brax's PPO and ES on the novel set (as docs/BASELINES.md's 1,000,000-cycle budget).
BASELINE_SEEDS = 5
#: The learning conditions whose advantage over EE-ES the table shows.
LEARNING = ("LE-LS", "EE-LS", "SLE")
#: Those the verdict judges: evolved ones. SLE evolves nothing, so every set is new to it; its rows
#: show how much harder a set is to learn from scratch, not what evolution left unprepared.
JUDGED = ("LE-LS", "EE-LS")


class Variant(NamedTuple):
    """What a stage's variant runs: a preset on a task set."""

    preset: str
    tasks: str  # NOVEL, or a key of HELD_OUT (the held-out evolutions evolve on "seen")


def held_out_variant(which: str) -> str:
    """The stage variant of the held-out stages on the task set ``which`` (a key of HELD_OUT)."""
    return f"held_out_{which}"


#: Every stage variant of the study: the novel set under each finished run's preset, the held-out sets under skills.
#: The presets whose runs meet the novel tasks (their paper-scale reproduction runs exist).
PRESETS = ("skills", "paper")
VARIANTS = {**{preset: Variant(preset, NOVEL) for preset in PRESETS},
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
                    os.path.join(out, "novel", variant, condition), test_cost(FINISHED_TEST, condition),
                    runs=FINISHED_TEST["seeds"])
              for variant, condition in FINISHED]
    stages += [Stage(f"novel {variant} SLE", "test", variant, "SLE", os.path.join(out, "novel", variant, "SLE"),
                     test_cost(SCREEN, "SLE")) for variant in PRESETS]
    # brax's PPO and ES from scratch on the novel set, at the learning test's length (docs/BASELINES.md's budgets)
    stages += [Stage(f"novel baseline {agent}", "baseline", NOVEL, agent.upper(), os.path.join(out, "novel", "baselines",
                                                                                              f"{agent}_1M"),
                     float(BASELINE_SEEDS * 6 * FINISHED_TEST["test_steps"])) for agent in ("ppo", "es")]
    for condition in HELD_OUT_CONDITIONS:
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
    if stage.kind == "baseline":
        return [sys.executable, "-m", "imrl_jax.baselines", "--agent", stage.condition.lower(), "--steps",
                str(FINISHED_TEST["test_steps"]), "--seeds", str(BASELINE_SEEDS), "--evals", "11", "--task-set", NOVEL,
                "--out", stage.out_dir], None
    variant = VARIANTS[stage.variant]
    if variant.tasks != NOVEL:  # held out: evolved on the seen tasks, tested on the seen or the unseen ones
        task_set = ["--task-set", task_files(out)[variant.tasks]]
        if stage.kind == "evolve":
            return evolve_command(SCREEN, variant.preset, stage.condition, stage.out_dir) + task_set, None
        evolved = os.path.join(out, "held_out", stage.condition, "evolve")
        return test_command(SCREEN, variant.preset, stage.condition, evolved, stage.out_dir) + task_set, None
    if not conditions.get(stage.condition).evolved:
        return test_command(SCREEN, variant.preset, "SLE", "", stage.out_dir) + ["--task-set", NOVEL], None
    run_dir = os.path.join(REPRODUCTION, variant.preset, "evolve", stage.condition)
    return test_command(FINISHED_TEST, variant.preset, stage.condition, run_dir, stage.out_dir) + [
        "--best-genomes", BEST_GENOMES, "--task-set", NOVEL], None


#: Where the report's table goes in docs/NOVEL_TASKS.md.
TABLE_START = "<!-- advantage table: python -m experiments.novel_tasks --report -->"
TABLE_END = "<!-- end of advantage table -->"


def _per_run(test: dict | None, tasks=None) -> list[float] | None:
    """A finished learning test's steady state per run (None if unfinished); ``tasks``: its mean per task instead."""
    if test is None:
        return None
    if tasks is None:
        return list(test["steady"]["steady_per_run"])
    per_task = test["steady"]["steady_per_task"]
    return [sum(per_task[t - 1] for t in tasks) / len(tasks)]


def measure(out: str = OUT, reproduction: str = REPRODUCTION) -> dict:
    """Learning's advantage over EE-ES per comparison and set of tasks, and the verdicts, from the finished tests."""
    from experiments.claims import advantage, claim_unseen, final_best
    from experiments.loading import read_evolution, read_json, read_test

    seen_tests = {(v, c): read_test(os.path.join(reproduction, owner(v, c), "test", c))
                  for v in PRESETS for c in (*LEARNING, "EE-ES")}
    novel_tests = {(v, c): read_test(os.path.join(out, "novel", owner(v, c), c))
                   for v in PRESETS for c in (*LEARNING, "EE-ES")}
    held = {(c, which): read_test(os.path.join(out, "held_out", c, f"test_{which}"))
            for c in HELD_OUT_CONDITIONS for which in HELD_OUT}
    rows, seen, unseen = [], {}, {}
    for variant in PRESETS:
        for condition in LEARNING:
            name = f"{variant} {condition}"
            for kind, tests, target in (("paper's six (seen)", seen_tests, seen), ("novel (unseen)", novel_tests, unseen)):
                mine, reference = _per_run(tests[variant, condition]), _per_run(tests[variant, "EE-ES"])
                if mine and reference:
                    target[name] = dict(advantage(mine, reference), tasks=kind, runs=len(mine))
                    rows.append(dict(name=name, **target[name]))
    held_seen, held_unseen = {}, {}
    for condition in JUDGED:
        name = f"held out {condition}"
        for which, target in (("seen", held_seen), ("unseen", held_unseen)):
            mine, reference = _per_run(held[condition, which]), _per_run(held["EE-ES", which])
            if mine and reference:
                target[name] = dict(advantage(mine, reference), tasks=f"tasks {HELD_OUT[which]} ({which})",
                                    runs=len(mine))
                rows.append(dict(name=name, **target[name]))
    judged = {name for name in seen if is_judged(name)}
    verdicts = {"novel set": claim_unseen({n: seen[n] for n in judged}, {n: a for n, a in unseen.items() if n in judged}),
                "held-out tasks": claim_unseen(held_seen, held_unseen)}
    curves = {key: test for key, test in novel_tests.items() if test is not None}
    held_curves = {key: test for key, test in held.items() if test is not None}
    evolutions = {c: e for c in HELD_OUT_CONDITIONS
                  if (e := read_evolution(os.path.join(out, "held_out", c, "evolve"))) is not None}
    scratch = []  # brax's agents from scratch: nothing of them was evolved, so they learn each set alike
    for tasks, folder in (("paper's six", BASELINES), ("novel", os.path.join(out, "novel", "baselines"))):
        for agent in ("ppo", "es"):
            summary = read_json(os.path.join(folder, f"{agent}_1M", "summary.json"))
            if summary is not None:
                scratch.append(dict(agent=agent.upper(), tasks=tasks, seeds=len(summary["seeds"]),
                                    performance=summary["performance_mean"],
                                    sd=summary["performance_sd_over_seeds"]))
    finals = {c: final_best(e["best"]) for c, e in evolutions.items()}  # the report's own rule, per seed
    evolved = [dict(condition=c, seeds=e["best"].shape[1], generations=e["best"].shape[0],
                    final_best=float(finals[c].mean()), sd=float(finals[c].std())) for c, e in evolutions.items()]
    return dict(rows=rows, verdicts=verdicts, curves=curves, scratch=scratch, held_curves=held_curves,
                evolutions=evolutions, evolved=evolved)


#: The held-out individuals probed at junctions per seed (the report's claim-7 probe), and the key of their childhoods.
PROBED, PROBE_KEY = 10, 0
COLOUR_NAMES = ("red", "green", "blue")


def colour_summary(followed: list[list[int]]) -> dict:
    """Per individual the colour each expert follows (-1 none): how many follow 0-3 distinct colours, and the share
    of individuals with an expert following each colour."""
    distinct = [set(f) - {-1} for f in followed]
    counts = [sum(len(d) == k for d in distinct) for k in range(4)]
    shares = {name: sum(c in d for d in distinct) / max(len(followed), 1) for c, name in enumerate(COLOUR_NAMES)}
    return dict(individuals=len(followed), counts=counts, shares=shares)


def probe_held_out(out: str = OUT) -> dict:
    """The junction probe of each finished held-out evolution's best individuals (kept in ``probe.json``)."""
    from experiments.loading import read_json
    from experiments.relive import last_generation, run_probe

    probes = {}
    for condition in JUDGED:
        folder = os.path.join(out, "held_out", condition, "evolve")
        saved, best = read_json(os.path.join(folder, "config.json")), last_generation(folder)
        if saved is None or best is None or int(best["generations"]) < saved["config"]["num_generations"]:
            continue
        probes[condition] = colour_summary(run_probe(folder, saved["config"], PROBED, PROBE_KEY)["followed"])
    return probes


def table(measured: dict) -> str:
    """The report's markdown: learning's advantage per comparison and set of tasks, then the verdicts."""
    from experiments.claims import UNSEEN_RULE

    lines = ["| comparison | tasks | runs | steady state | EE-ES | advantage | se |", "|---|---|---|---|---|---|---|"]
    lines += [f"| {r['name']} | {r['tasks']} | {r['runs']} | {r['steady']:.3f} | {r['ee_es']:.3f} | "
              f"{r['advantage']:+.3f} | {r['standard_error']:.3f} |" for r in measured["rows"]]
    if not measured["rows"]:
        lines.append("| (no stage has finished yet) | | | | | | |")
    if measured["scratch"]:
        lines += ["", "brax's agents from scratch, 1,000,000 cycles per task (docs/BASELINES.md's measure):", "",
                  "| agent | tasks | seeds | performance | sd over seeds |", "|---|---|---|---|---|"]
        lines += [f"| {r['agent']} | {r['tasks']} | {r['seeds']} | {r['performance']:.3f} | {r['sd']:.3f} |"
                  for r in measured["scratch"]]
    if measured["evolved"]:
        generations = SCALES["paper"]["generations"]
        lines += ["", f"The held-out evolutions on tasks {SEEN} (best fitness: the best of each generation's noisy "
                  f"lives, the mean of the last 5 generations per seed, then over seeds):", "",
                  "| condition | seeds x generations | final best fitness (recorded) |", "|---|---|---|"]
        lines += [f"| {r['condition']} | {r['seeds']} x {r['generations']}"
                  f"{'' if r['generations'] >= generations else f' of {generations}, running'} | "
                  f"{r['final_best']:.3f} +- {r['sd']:.3f} |" for r in measured["evolved"]]
    if measured.get("probes"):
        lines += ["", f"The colours the held-out individuals' experts follow (the junction probe of claim 7, the "
                  f"{PROBED} best of each seed; LE-LS after a fresh childhood):", "",
                  "| condition | individuals | following 0 / 1 / 2 / 3 colours | with an expert following red / green / "
                  "blue |", "|---|---|---|---|"]
        lines += [f"| held out {c} | {p['individuals']} | {' / '.join(map(str, p['counts']))} | "
                  + " / ".join(f"{p['shares'][n]:.0%}" for n in COLOUR_NAMES) + " |" for c, p in measured["probes"].items()]
    lines += ["", f"Rule: {UNSEEN_RULE} SLE's rows are shown, not judged: it evolves nothing, so every set is new "
              f"to it.", ""]
    lines += [f"- **{where}: {v['verdict']}.** {v['measured']}" for where, v in measured["verdicts"].items()]
    return "\n".join(lines)


def is_judged(name: str) -> bool:
    """Whether the verdict judges a comparison ("skills LE-LS", "held out EE-LS"): its condition is evolved."""
    return name.rsplit(" ", 1)[-1] in JUDGED


def bar_label(name: str) -> str:
    """A comparison's label under its bars: SLE's say that the verdict leaves them out."""
    return name if is_judged(name) else f"{name} (not judged)"


def figure(measured: dict, path: str) -> str | None:
    """Fig. 3b-style curves on the novel set (a panel per preset) beside learning's advantage per comparison."""
    from experiments.figures import _draw_curves
    from imrl_jax.plotting import new_figure, save, style_axis

    if not any(measured[part] for part in ("rows", "curves", "held_curves", "evolutions")):
        return None
    fig = new_figure(13.0, 7.4)
    grid = fig.subplots(2, 3, gridspec_kw=dict(width_ratios=[1.0, 1.0, 1.2]))
    axes = grid[0]
    for ax, variant in zip(axes, PRESETS):
        series = {c: (t["steps"], t["mean"], t["sd"], c) for (v, c), t in measured["curves"].items()
                  if v == variant or not conditions.get(c).learns}
        if series:
            _draw_curves(ax, series, f"novel set, {variant}: learning tests", "cycles of the task",
                         "performance per bin")
        else:  # an unfinished stage: say so rather than leave a blank panel
            style_axis(ax, f"novel set, {variant}: learning tests", "cycles of the task", "performance per bin")
            ax.text(0.5, 0.5, "not run yet", transform=ax.transAxes, ha="center", va="center", color="0.4")
    bars = axes[2]
    names, labelled = list(dict.fromkeys(r["name"] for r in measured["rows"])), set()
    for i, name in enumerate(names):
        for j, row in enumerate(r for r in measured["rows"] if r["name"] == name):  # seen, then unseen
            label = ("tasks of its evolution", "tasks never met in it")[j]
            bars.bar(i + (j - 0.5) * 0.38, row["advantage"], 0.38, yerr=row["standard_error"], capsize=2,
                     color=("0.35", "tab:orange")[j], label=None if label in labelled else label)
            labelled.add(label)
    bars.axhline(0.0, color="black", lw=0.6)
    bars.set_xticks(range(len(names)), [bar_label(name) for name in names], rotation=30, ha="right", fontsize=7)
    style_axis(bars, "learning's advantage over EE-ES", "", "steady state minus EE-ES's")
    if names:
        bars.legend(fontsize=7)
    _draw_held_out(grid[1], measured)
    fig.tight_layout()
    return save(fig, path)


def _draw_held_out(axes, measured: dict) -> None:
    """The held-out row: learning tests on the seen and the unseen tasks, and the evolutions' best fitness."""
    from experiments.figures import _draw_curves, _fitness_series
    from imrl_jax.plotting import style_axis

    for ax, which in zip(axes, HELD_OUT):
        title = f"held out, tasks {', '.join(map(str, HELD_OUT[which]))} ({which}): learning tests"
        series = {c: (t["steps"], t["mean"], t["sd"], c) for (c, w), t in measured["held_curves"].items() if w == which}
        if series:
            _draw_curves(ax, series, title, "cycles of the task", "performance per bin")
        else:
            style_axis(ax, title, "cycles of the task", "performance per bin")
            ax.text(0.5, 0.5, "not run yet", transform=ax.transAxes, ha="center", va="center", color="0.4")
    title = f"held out: evolved on tasks {', '.join(map(str, SEEN))} (best of each generation's lives)"
    if measured["evolutions"]:
        _draw_curves(axes[2], _fitness_series({c: e["best"] for c, e in measured["evolutions"].items()}), title,
                     "generation", "best fitness", integer_x=True)
    else:
        style_axis(axes[2], title, "generation", "best fitness")
        axes[2].text(0.5, 0.5, "not run yet", transform=axes[2].transAxes, ha="center", va="center", color="0.4")


def report(out: str = OUT, document: str = os.path.join("docs", "NOVEL_TASKS.md")) -> int:
    """Measure, write advantage.json and the figure under ``out``, and the table into ``document``."""
    import json

    from experiments.study import write_table

    measured = measure(out)
    measured["probes"] = probe_held_out(out)
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, "advantage.json"), "w") as f:
        json.dump(dict(rows=measured["rows"], verdicts=measured["verdicts"], scratch=measured["scratch"],
                       evolved=measured["evolved"], probes=measured["probes"]), f, indent=2)
    drawn = figure(measured, os.path.join(out, "advantage.png"))
    write_table(document, table(measured), TABLE_START, TABLE_END)
    print(f"{len(measured['rows'])} comparisons measured; wrote {os.path.join(out, 'advantage.json')}"
          f"{', ' + drawn if drawn else ''} and the table of {document}")
    return 0


def all_stages(out: str = OUT) -> tuple[list[Stage], dict]:
    """Every stage of the study, and their scale."""
    return plan(out), SCREEN


def main(argv=None) -> int:
    """The command line: list the stages, or write the held-out task sets and run (or go on with) every stage."""
    p = argparse.ArgumentParser(prog="python -m experiments.novel_tasks", description=__doc__.split("\n\n")[0])
    p.add_argument("--out", default=OUT, help=f"results directory (default: {OUT})")
    p.add_argument("--list", action="store_true", help="print the stages and their commands, run nothing")
    p.add_argument("--report", action="store_true", help="measure the finished stages, draw the figure and write "
                   "docs/NOVEL_TASKS.md's table (runs nothing)")
    add_options(p)
    args = p.parse_args(argv)
    if args.report:
        return report(args.out)
    stages = plan(args.out)
    if args.list:
        for stage in stages:
            print(f"{stage.name}: {' '.join(stage_command(stage, args.out)[0][1:])}")
        return 0
    task_files(args.out, write=True)
    manifest, manifest_path = load_manifest(args.out, study="novel_tasks", sizes=SCREEN)
    return run_stages(stages, SCREEN, manifest, manifest_path, lambda stage: stage_command(stage, args.out),
                      **from_options(args, args.out))


#: The studies of this module (python -m experiments finds them).
STUDIES = (Study("novel-tasks", "novel_tasks", "docs/NOVEL_TASKS.md", 2),)


if __name__ == "__main__":
    sys.exit(main())
