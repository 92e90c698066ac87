"""Tasks never met in evolution (docs/NOVEL_TASKS.md): is learning's advantage stronger on them?

    python -m experiments list novel-tasks      # the stages, done or to run
    python -m experiments run novel-tasks       # run (or go on with) every stage, in order
    python -m experiments report novel-tasks    # the advantage table, a figure per question and the verdicts

The novel set: the finished paper-scale runs learn the ``novel`` tasks (5 of the 10 best of each seed kept in
``best_genomes.npz``), beside their tests on the paper's six, SLE and brax's PPO and ES from scratch. Held-out
tasks: LE-LS, EE-LS and EE-ES evolved under ``skills`` on the paper's tasks 1, 3, 4 and 6 (``tasks_seen.json``),
tested on those and on tasks 2 and 5 (``tasks_unseen.json``), whose partners turn the other way. Learning's
advantage is a steady state minus EE-ES's (which learns nothing); ``further_claims.claim_unseen`` judges it.
"""

import os
import sys
from typing import NamedTuple

import numpy as np

from experiments.harness.figures import finish
from experiments.harness.loading import write_json
from experiments.harness.reproduce import test_command, test_cost
from experiments.harness.study import REPRODUCTION, RESULTS, SCALES, SCREEN
from experiments.harness.table import Measure, Row, Table
from imrl_jax import conditions

#: The study's manifest, task sets, tests on other task sets and report (its runs lie wherever their keys find them).
OUT = os.path.join(RESULTS, "novel_tasks")
#: The novel-set tests of the finished runs: 5 of the 10 best of each of the 10 seeds, 4 tests each.
FINISHED_TEST = dict(SCALES["paper"], best=5, tests=4)
NOVEL = ("--task-set", "novel")
#: The paper's tasks (1-based) of each held-out set, by the name of its file ``tasks_NAME.json``.
HELD_OUT = {"seen": (1, 3, 4, 6), "unseen": (2, 5)}
TASK_FILES = {which: os.path.join(OUT, f"tasks_{which}.json") for which in HELD_OUT}  # committed
#: The held-out individuals probed at junctions per seed (claim 7's probe), and the key of their lives.
PROBED, PROBE_KEY = 10, 0
COLOUR_NAMES = ("red", "green", "blue")


def learning_test(name: str, row: Row, scale: dict, options: tuple[str, ...], out: str, num_tasks: int = 6) -> Measure:
    """A learning test of ``row``'s run with options of its own (another task set) into the table's ``out``."""
    runner = tuple(test_command(scale, "paper", "EE-ES", "RUN", "OUT")[4:-2])  # the runner's options, at ``scale``
    return Measure(name, row.name, runner + options, "imrl_jax.learning_test",
                   test_cost(scale, row.condition, num_tasks=num_tasks), out, kind="test")


class Question(NamedTuple):
    """Rows tested on the tasks of their evolution and on tasks never met in it: the two tests' names and labels."""

    name: str
    rows: tuple[Row, ...]
    tests: tuple[str, str]  # the names of a row's two tests ("{}": the row's own)
    labels: tuple[str, str]


#: The finished paper-scale runs and SLE at their sizes (their tests on the paper's six), EE-ES shared by both presets.
FINISHED = tuple(Row(f"{preset} {condition}", condition, preset, scale=SCALES["paper"])
                 for preset in ("skills", "paper") for condition in ("LE-LS", "EE-LS", "SLE")) + (
    Row("EE-ES", "EE-ES", "paper", scale=SCALES["paper"]),)
HELD = tuple(Row(f"held out {condition}", condition, "skills", options=("--task-set", TASK_FILES["seen"]), test=False)
             for condition in ("LE-LS", "EE-LS", "EE-ES"))
QUESTIONS = (Question("novel set", FINISHED, ("{}", "{} on novel"), ("paper's six (seen)", "novel (unseen)")),
             Question("held-out tasks", HELD, tuple(f"{{}} on the {which} tasks" for which in HELD_OUT),
                      tuple(f"tasks {tasks} ({which})" for which, tasks in HELD_OUT.items())))


def judged(row: Row) -> bool:
    """Whether the verdict judges a row: it is evolved and learns."""
    return row.evolved and conditions.get(row.condition).learns


def colour_summary(followed: list[list[int]]) -> dict:
    """Per individual the colour each expert follows (-1 none): how many follow 0-3 distinct colours, and the share
    of individuals with an expert following each colour."""
    distinct = [set(f) - {-1} for f in followed]
    counts = [sum(len(d) == k for d in distinct) for k in range(4)]
    shares = {name: sum(c in d for d in distinct) / max(len(followed), 1) for c, name in enumerate(COLOUR_NAMES)}
    return dict(individuals=len(followed), counts=counts, shares=shares)


def advantage_table(measured: dict, evolutions: str) -> str:
    """The report's markdown: learning's advantage per row and set of tasks, brax's agents, the held-out evolutions
    (``evolutions``: their table) and their probes, then the verdicts."""
    from imrl_jax.analysis.further_claims import UNSEEN_RULE
    from experiments.harness.markdown import table

    lines = [table(("comparison", "tasks", "runs", "steady state", "EE-ES", "advantage", "se"), [
        (r["name"], r["tasks"], r["runs"], f"{r['steady']:.3f}", f"{r['ee_es']:.3f}", f"{r['advantage']:+.3f}",
         f"{r['standard_error']:.3f}") for r in measured["rows"]])]
    if measured["scratch"]:
        lines += ["", "brax's agents from scratch, 1,000,000 cycles per task (docs/BASELINES.md's measure):", "",
                  table(("agent", "tasks", "seeds", "performance", "sd over seeds"), [
                      (r["agent"], r["tasks"], r["seeds"], f"{r['performance']:.3f}", f"{r['sd']:.3f}")
                      for r in measured["scratch"]])]
    lines += ["", f"The held-out evolutions on tasks {HELD_OUT['seen']} (final best fitness: the best of each "
              f"generation's noisy lives, the mean of the last 5 generations per seed, then over seeds):", "",
              evolutions]
    if measured["probes"]:
        lines += ["", f"The colours the held-out individuals' experts follow (the junction probe of claim 7, the "
                  f"{PROBED} best of each seed; LE-LS after a fresh childhood):", "",
                  table(("condition", "individuals", "following 0 / 1 / 2 / 3 colours",
                         "with an expert following red / green / blue"), [
                      (f"held out {c}", p["individuals"], " / ".join(map(str, p["counts"])),
                       " / ".join(f"{p['shares'][n]:.0%}" for n in COLOUR_NAMES))
                      for c, p in measured["probes"].items()])]
    lines += ["", f"Rule: {UNSEEN_RULE} SLE's rows are shown, not judged: it evolves nothing, so every set is new "
              f"to it.", ""]
    return "\n".join(lines + [f"- **{q}: {v['verdict']}.** {v['measured']}" for q, v in measured["verdicts"].items()])


def draw_tests(ax, measured: dict, rows, name: str, title: str) -> None:
    """The learning curves of the tests ``name`` ("{}": the row's own) of ``rows``, one per condition."""
    from experiments.harness.figures import _draw_curves

    _draw_curves(ax, {r.condition: (t["steps"], t["mean"], t["sd"], r.condition) for r in rows
                      if (t := measured["tests"].get(name.format(r.name))) is not None}, title,
                 "cycles of the task", "performance per bin")


def draw_bars(ax, groups: dict, labels, title: str, ylabel: str, colours=("0.35", "tab:orange")) -> None:
    """Bars of each group's values side by side, a (value, error) pair or None; a colour per place in the group."""
    from imrl_jax.analysis.plotting import style_axis

    width = 0.8 / len(labels)
    for j, (label, colour) in enumerate(zip(labels, colours)):
        values = np.array([v[j] or (np.nan, np.nan) for v in groups.values()], float).reshape(-1, 2)
        ax.bar(np.arange(len(groups)) + (j - (len(labels) - 1) / 2) * width, values[:, 0], width, yerr=values[:, 1],
               capsize=2, color=colour, label=label)
    ax.axhline(0.0, color="black", lw=0.6)
    ax.set_xticks(range(len(groups)), list(groups), rotation=20, ha="right", fontsize=7)
    style_axis(ax, title, "", ylabel)
    ax.legend(fontsize=7)


def draw_advantages(ax, measured: dict, question: Question) -> None:
    """Learning's advantage over EE-ES of each row of a question, on the tasks of its evolution and those never met."""
    draw_bars(ax, {f"{r.name}{'' if judged(r) else ' (not judged)'}": [
        (a["advantage"], a["standard_error"]) if (a := measured["advantages"].get((r.name, label))) else None
        for label in question.labels] for r in question.rows if (r.name, question.labels[1]) in measured["advantages"]},
        ("tasks of its evolution", "tasks never met in it"), f"{question.name}: advantage over EE-ES",
        "steady state minus EE-ES's")


def novel_figure(measured: dict, path: str) -> str:
    """The novel set: curves per preset, learning's advantage, and evolved skills beside learning from scratch."""
    from imrl_jax.analysis.plotting import new_figure

    (skills, paper), (advantages, scratch) = (fig := new_figure(11.0, 7.4)).subplots(2, 2)
    for ax, preset in ((skills, "skills"), (paper, "paper")):
        draw_tests(ax, measured, [r for r in FINISHED if r.preset == preset or not conditions.get(r.condition).learns],
                   QUESTIONS[0].tests[1], f"novel set, {preset}: learning tests")
    draw_advantages(advantages, measured, QUESTIONS[0])
    groups = {name: [(a["steady"], np.nan) if (a := measured["advantages"].get((name, label))) else None
                     for label in QUESTIONS[0].labels] for name in ("skills LE-LS", "skills SLE")}
    for r in measured["scratch"]:
        groups.setdefault(r["agent"], [None, None])[r["tasks"] == "novel"] = (r["performance"], np.nan)
    draw_bars(scratch, groups, ("the paper's six", "the novel set"), "evolved skills beside learning from scratch",
              "steady state (brax: final performance)")
    return finish(fig, path)


def held_out_figure(measured: dict, path: str) -> str:
    """The held-out tasks: learning tests on both sets, learning's advantage, the evolutions' best fitness and the
    colours the evolved experts follow."""
    from experiments.harness.figures import _draw_curves, _fitness_series
    from imrl_jax.analysis.plotting import FLOOR_COLOURS, new_figure

    grid = (fig := new_figure(13.0, 7.4)).add_gridspec(2, 6)
    for k, (which, name) in enumerate(zip(HELD_OUT, QUESTIONS[1].tests)):
        draw_tests(fig.add_subplot(grid[0, 2 * k:2 * k + 2]), measured, HELD, name,
                   f"held out, tasks {', '.join(map(str, HELD_OUT[which]))} ({which}): learning tests")
    draw_advantages(fig.add_subplot(grid[0, 4:]), measured, QUESTIONS[1])
    _draw_curves(fig.add_subplot(grid[1, :3]), _fitness_series({m["condition"]: m["best"] for m in
                                                                measured["evolutions"] if m["generations"]}),
                 f"evolved on tasks {', '.join(map(str, HELD_OUT['seen']))} (best of each generation's lives)",
                 "generation", "best fitness", integer_x=True)
    draw_bars(fig.add_subplot(grid[1, 3:]), {f"held out {c}": [(p["shares"][n], np.nan) for n in COLOUR_NAMES]
                                              for c, p in measured["probes"].items()},
              [f"an expert follows {n}" for n in COLOUR_NAMES], f"why: the colours its experts follow ({PROBED} best "
              f"of each seed)", "share of individuals", FLOOR_COLOURS)
    return finish(fig, path)


class NovelTasksTable(Table):
    """The study's table, whose report measures learning's advantage per question and draws a figure for each."""

    def advantages(self) -> dict:
        """Learning's advantage per row and set of tasks, the verdicts, brax's agents, the held-out evolutions (the
        table's measure of their rows) and their probes, and the tests drawn."""
        from imrl_jax.analysis.further_claims import advantage, claim_unseen
        from experiments.harness.loading import read_json, read_test
        from experiments.harness.relive import run_probe

        folders = {**self.tests(), **{m.name: self.measure_folder(m) for m in self.measures}}
        tests = {name: test for name, folder in folders.items() if (test := read_test(folder)) is not None}
        steady = {name: test["steady"]["steady_per_run"] for name, test in tests.items()}
        measured = dict(advantages=(found := {}), verdicts={}, tests=tests, probes={})
        for q in QUESTIONS:
            reference = next(r for r in q.rows if not conditions.get(r.condition).learns)
            for row, (name, label) in ((r, t) for r in q.rows if r is not reference for t in zip(q.tests, q.labels)):
                mine, theirs = steady.get(name.format(row.name)), steady.get(name.format(reference.name))
                if mine and theirs:
                    found[row.name, label] = dict(advantage(mine, theirs), tasks=label, runs=len(mine))
            measured["verdicts"][q.name] = claim_unseen(*({r.name: found[r.name, label] for r in q.rows if judged(r)
                                                           and (r.name, label) in found} for label in q.labels))
        measured["rows"] = [dict(name=name, **a) for (name, _), a in found.items()]
        brax = [("paper's six", a, os.path.join(self.results, "baselines", f"{a}_1M")) for a in ("ppo", "es")] + [
            ("novel", m.args[1], self.measure_folder(m)) for m in self.measures if m.kind == "baseline"]
        measured["scratch"] = [  # from scratch, so they learn each set alike
            dict(agent=agent.upper(), tasks=tasks, seeds=len(s["seeds"]), performance=s["performance_mean"],
                 sd=s["performance_sd_over_seeds"])
            for tasks, agent, folder in brax if (s := read_json(os.path.join(folder, "summary.json"))) is not None]
        measured["evolutions"] = [m for m in self.measure() if m["row"] in {r.name for r in HELD}]  # in HELD's order
        measured["evolved"] = [dict(condition=m["condition"], seeds=m["seeds"], generations=m["generations"],
                                    final_best=m["final_mean"], sd=m["final_sd"])
                               for m in measured["evolutions"] if "final_mean" in m]
        for row, m in zip(HELD, measured["evolutions"]):  # the best of finished runs, probed once (probe.json)
            if judged(row) and "final_mean" in m and (probe := run_probe(m["dir"], None, PROBED, PROBE_KEY)):
                measured["probes"][row.condition] = colour_summary(probe["followed"])
        return measured

    def report(self) -> int:
        """Measure; write advantage.json and a figure per question under ``out``, and the table into the document."""
        from experiments.harness.study import markers, write_table

        measured = self.advantages()
        os.makedirs(self.out, exist_ok=True)
        write_json(os.path.join(self.out, "advantage.json"),
                   {k: measured[k] for k in ("rows", "verdicts", "scratch", "evolved", "probes")}, indent=2)
        drawn = [novel_figure(measured, os.path.join(self.out, "novel.png")),
                 held_out_figure(measured, os.path.join(self.out, "held_out.png"))]
        write_table(self.document, advantage_table(measured, self.table(measured["evolutions"])),
                    *markers("advantage table", self.name))
        print(f"{len(measured['rows'])} comparisons measured; wrote {', '.join(drawn)} and the table of "
              f"{self.document}")
        return 0


TABLE = NovelTasksTable("novel-tasks", "docs/NOVEL_TASKS.md", 2, out=OUT, scale=SCREEN, rows=(
    *FINISHED, *(Row(f"{preset} SLE on novel", "SLE", preset, options=NOVEL) for preset in ("skills", "paper")), *HELD,
), measures=(
    *(learning_test(f"{r.name} on novel", r, FINISHED_TEST, ("--best-genomes", os.path.join(
        REPRODUCTION, "best_genomes.npz"), *NOVEL), os.path.join("novel", r.preset, r.condition))
      for r in FINISHED if r.evolved),
    *(Measure(f"{agent} on novel", "", ("--agent", agent, "--steps", str(FINISHED_TEST["test_steps"]), "--seeds", "5",
              "--evals", "11", *NOVEL), "imrl_jax.baselines", 5 * 6.0 * FINISHED_TEST["test_steps"],
              os.path.join("novel", "baselines", f"{agent}_1M"), kind="baseline") for agent in ("ppo", "es")),
    *(learning_test(f"{r.name} on the {which} tasks", r, SCREEN, ("--task-set", TASK_FILES[which]),
                    os.path.join("held_out", r.condition, f"test_{which}"), len(tasks))
      for r in HELD for which, tasks in HELD_OUT.items())))
all_stages, main = TABLE.all_stages, TABLE.main
#: The studies of this module (python -m experiments finds them).
STUDIES = (TABLE.study(__name__.rsplit(".", 1)[-1]),)


if __name__ == "__main__":
    sys.exit(main())
