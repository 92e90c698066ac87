"""A selector on its own time-scale (docs/TIMESCALE.md): the composition ceiling per option, then evolutions.

    python -m experiments.timescale --list      # the stages and their commands, nothing run
    python -m experiments.timescale             # run (or go on with) every stage, in order
    python -m experiments.timescale --measures-only  # the three measurements only (minutes)
    python -m experiments.timescale ceiling|rates|confirm --out DIR [--lives N]   # one of them by hand
    python -m experiments.timescale --report    # the evolutions' tables, claims and figure (runs nothing)

Stage 1 (``ceiling``) measures what composing ideal colour followers is worth when the
selector chooses options (:data:`OPTIONS`, ``Config.selector_period`` and
``selector_termination``) rather than every step: EE-LS individuals whose experts are
``controllers.perceptron_followers``, the selector learning as in adulthood, at the paper's task
length (6 x 100,000 steps), under the paper's one-step adult rules, under ``skills``' adult rules
and with a selector that does not learn (:data:`RULES`). Stage 2 (``rates``) sweeps the
selector's trace decay and rates for some options (:data:`RATE_GRID`: ``skills``' values were
chosen for a selector that learns every step); stage 3 (``confirm``) lives each option's best point
again in 8 fresh lives. Then (:func:`evolution_groups`) LE-LS and EE-LS under ``skills`` with the
option that scores highest there, at its best rates (5 seeds x 100 generations, paper
lengths) with learning tests of their best (5 x 4 tests of 1,000,000 cycles per task); and, if
an option lets the paper's own rules compose (a ceiling of at least :data:`COMPOSES`), LE-LS,
EE-LS and EE-ES under ``paper`` with it, for the claims. The stages run through the
reproduction's resumable stage runner (:func:`experiments.reproduce.run_stages`): run the same
command again after an interruption.
"""

from __future__ import annotations

import argparse
import csv
import itertools
import json
import os
import sys
import time

import numpy as np

from experiments.study import REPRODUCTION, SCREEN
from experiments.reproduce import (MEASURED, Stage, evolution_cost, evolve_command, load_manifest, run_stages,
                                   test_command, test_cost)
from experiments.executor import add_options, from_options
from experiments.study import RESULTS, Study
from imrl_jax.config import ADULT_SELECTOR

OUT = os.path.join(RESULTS, "timescale")
#: The selector's options: name -> Config fields. "per-step" is the paper's selector.
OPTIONS = {
    "per-step": dict(selector_period=1),
    "period-5": dict(selector_period=5),
    "period-10": dict(selector_period=10),
    "period-20": dict(selector_period=20),
    "period-40": dict(selector_period=40),
    "colour-20": dict(selector_period=20, selector_termination="colour"),
    "colour-60": dict(selector_period=60, selector_termination="colour"),
}
#: Adult learning rules of the ceiling: the paper's one-step rules, and skills' adult selector (traces, rates).
RULES = {
    "paper": {},
    "skills": dict(ADULT_SELECTOR),
    # The selector does not learn: what choosing at random (s = 0.5 for every expert) is worth, per option.
    "random": dict(eta_selector_actor=0.0, eta_selector_critic=0.0),
}
RULE_LABELS = {"paper": "paper's one-step selector rules", "skills": "skills' adult selector (traces, rates)",
               "random": "selector does not learn (random choices)"}
#: A ceiling at least this high means composition pays under those rules: above what one colour follower
#: gets on the paper's tasks (it can solve at most one task of each pair) and half the hand-written composition.
COMPOSES = 0.5
#: The ceiling's size: lives per (option, rules), and its task length (the paper's).
LIVES, TASK_STEPS = 8, 100_000
#: Stage 2: the selector's rates and trace decay swept for these options (skills' values were chosen for a
#: per-step selector, which learns once a step; an option's selector learns once an option).
RATE_OPTIONS = ("per-step", "period-5", "period-10", "colour-20", "colour-60")
RATE_GRID = dict(trace_lambda=(0.0, 0.9, 0.98), eta_selector_actor=(0.01, 0.1, 0.3, 1.0, 3.0, 10.0),
                 eta_selector_critic=(0.001, 0.01, 0.1))
RATE_LIVES = 3


def result_path(out: str, folder: str) -> str:
    """Where the measure stage of ``folder`` ("ceiling", "rates", "confirm") writes its result."""
    return os.path.join(out, folder, MEASURED)


def _read_measure(out: str, folder: str) -> list[dict] | None:
    """The rows a measure stage wrote into ``out/folder`` (None before it has run)."""
    path = result_path(out, folder)
    if not os.path.exists(path):
        return None
    with open(path) as f:
        return json.load(f)["rows"]


def read_ceiling(out: str = OUT) -> list[dict] | None:
    """The ceiling's rows (None before it has run)."""
    return _read_measure(out, "ceiling")


def read_rates(out: str = OUT) -> list[dict] | None:
    """The rate sweep's rows (None before it has run)."""
    return _read_measure(out, "rates")


def read_confirmed(out: str = OUT) -> list[dict] | None:
    """The confirmation's rows (None before it has run)."""
    return _read_measure(out, "confirm")


def best_rates(rows: list[dict], option: str, trace_lambda: float | None = None) -> dict:
    """The swept row of ``option`` with the highest mean fitness (at ``trace_lambda`` only, if given)."""
    mine = [r for r in rows if r["option"] == option and (trace_lambda is None or r["trace_lambda"] == trace_lambda)]
    return max(mine, key=lambda r: r["fitness"])


def best_option(rows: list[dict], rules: str) -> tuple[str, float]:
    """The option other than per-step with the highest mean ceiling under ``rules``, and that ceiling."""
    candidates = [r for r in rows if r["rules"] == rules and r["option"] != "per-step"]
    best = max(candidates, key=lambda r: r["fitness"])
    return best["option"], best["fitness"]


def option_sets(option: str) -> tuple[str, ...]:
    """The ``--set`` assignments of an option."""
    return tuple(f"{field}={value}" for field, value in OPTIONS[option].items())


def evolution_groups(out: str = OUT) -> dict[str, tuple[tuple[str, ...], tuple[str, ...]]]:
    """The evolutions the measures call for: {"PRESET+OPTION": (--set assignments, conditions)} (none before they ran).

    Under ``skills``: LE-LS and EE-LS with the option (other than per-step) whose best point of the rate
    sweep scores highest in the confirmation's fresh lives, at that point's rates. Under ``paper``: LE-LS, EE-LS and EE-ES with the option of the
    highest ceiling under the paper's own rules, if that ceiling reaches :data:`COMPOSES`.
    """
    ceiling, confirmed = read_ceiling(out), read_confirmed(out)
    if ceiling is None or confirmed is None:
        return {}
    best = max((r for r in confirmed if r["option"] != "per-step"), key=lambda r: r["fitness"])
    tuned = tuple(f"{field}={best[field]}" for field in RATE_GRID)
    groups = {f"skills+{best['option']}": (option_sets(best["option"]) + tuned, ("LE-LS", "EE-LS"))}
    option, value = best_option(ceiling, "paper")
    if value >= COMPOSES:
        groups[f"paper+{option}"] = (option_sets(option), ("LE-LS", "EE-LS", "EE-ES"))
    return groups


def mismatched_runs(out: str = OUT) -> list[str]:
    """Evolutions already under ``out`` whose config differs from what the measures call for now (one line each).

    A run's folder names its option, not its rates: if the sweep or its confirmation ran again and
    chose other rates, the old run must not pass for the new one.
    """
    from experiments.loading import read_json
    from imrl_jax.cli import parse_sets

    lines = []
    for variant, (sets, names) in evolution_groups(out).items():
        for condition in names:
            folder = os.path.join(out, variant, condition, "evolve")
            saved = (read_json(os.path.join(folder, "config.json")) or {}).get("config")
            if saved is None:
                continue
            for field, value in parse_sets(list(sets)).items():
                if saved.get(field) != value:
                    lines.append(f"{folder}: evolved with {field}={saved.get(field)}, but the measures now call for "
                                 f"{field}={value}; move the run away to evolve it again")
    return lines


def plan(out: str = OUT, scale: dict = SCREEN) -> list[Stage]:
    """The ceiling and the rate sweep, then (once they have run) the evolutions and learning tests they call for."""
    cost = len(OPTIONS) * len(RULES) * LIVES * 6 * TASK_STEPS
    stages = [Stage("ceiling: ideal followers composed, per option and rules", "measure", "", "EE-LS",
                    os.path.join(out, "ceiling"), float(cost))]
    points = len(RATE_OPTIONS) * len(list(itertools.product(*RATE_GRID.values())))
    stages.append(Stage("rates: the selector's rates and traces swept per option", "measure", "", "EE-LS",
                        os.path.join(out, "rates"), float(points * RATE_LIVES * 6 * TASK_STEPS)))
    stages.append(Stage("confirm: each option's best rates in fresh lives", "measure", "", "EE-LS",
                        os.path.join(out, "confirm"), float(len(RATE_OPTIONS) * LIVES * 6 * TASK_STEPS)))
    for variant, (_, names) in evolution_groups(out).items():
        for condition in names:
            folder = os.path.join(out, variant, condition)
            stages.append(Stage(f"evolve {variant} {condition}", "evolve", variant, condition,
                                os.path.join(folder, "evolve"), evolution_cost(scale, condition)))
            stages.append(Stage(f"learning test {variant} {condition}", "test", variant, condition,
                                os.path.join(folder, "test"), test_cost(scale, condition)))
    return stages


def stage_command(stage: Stage, out: str = OUT, scale: dict = SCREEN) -> tuple[list[str], dict | None]:
    """A stage's command line: this module's ceiling, or evolve / learning_test with the option's fields."""
    if stage.kind == "measure":
        root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
        path = os.pathsep.join(p for p in (root, os.environ.get("PYTHONPATH")) if p)
        which = os.path.basename(stage.out_dir)  # "ceiling", "rates" or "confirm": the subcommand writing there
        return ([sys.executable, "-m", "experiments.timescale", which, "--out", stage.out_dir],
                {**os.environ, "PYTHONPATH": path})
    preset = stage.variant.split("+")[0]
    if stage.kind == "evolve":
        sets = evolution_groups(out)[stage.variant][0]
        return evolve_command(scale, preset, stage.condition, stage.out_dir, sets=sets), None
    return test_command(scale, preset, stage.condition, os.path.join(os.path.dirname(stage.out_dir), "evolve"),
                        stage.out_dir), None


def _last_tenth(config, result):
    """Each lane's performance in the last tenth of each task (its last of 10 bins): the composition once learned."""
    import numpy as np

    return np.asarray(result.reward_curve)[..., -1] * 10 / np.asarray(config.theoretical_max())


def _write_measure(out_dir: str, name: str, rows: list[dict], lives: int, key: int, plot=None, **recorded) -> None:
    """A measure stage's outputs: NAME.csv, the figure NAME.png (if ``plot``), then result.json (the stage is done)."""
    from imrl_jax.checkpoint import git_commit

    os.makedirs(out_dir, exist_ok=True)
    with open(os.path.join(out_dir, f"{name}.csv"), "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    if plot is not None:
        plot(rows, os.path.join(out_dir, f"{name}.png"))
    with open(os.path.join(out_dir, MEASURED), "w") as f:
        json.dump(dict(command=f"python -m experiments.timescale {name} --out {out_dir} --lives {lives} --key {key}",
                       git_commit=git_commit(), **recorded, rows=rows), f, indent=2)


def measure_ceiling(out_dir: str, lives: int = LIVES, key: int = 0, task_steps: int = TASK_STEPS) -> list[dict]:
    """Stage 1: the composition ceiling of every option under every rule set; writes ceiling.csv, the figure,
    and result.json last."""
    import jax
    import numpy as np

    from imrl_jax.config import make_config
    from imrl_jax.controllers import composition_ceiling

    rows, total = [], len(OPTIONS) * len(RULES)
    for rules, values in RULES.items():
        for option, fields in OPTIONS.items():
            # 10 bins: the last one is the last tenth of each task.
            config = make_config("paper", condition="EE-LS", task_steps=task_steps, num_bins=10, **values, **fields)
            tick = time.perf_counter()
            result = composition_ceiling(jax.random.key(key), config, lives)
            fitness, top = np.asarray(result.fitness), _top_share(result)
            # The last tenth of each task (its last bin): how well the selector composes once it has learned.
            last = _last_tenth(config, result)
            rows.append(dict(rules=rules, option=option, lives=lives, task_steps=task_steps,
                             fitness=float(fitness.mean()), fitness_sd=float(fitness.std()),
                             last_tenth=float(last.mean()),
                             **{f"task_{t + 1}": float(v) for t, v in enumerate(np.asarray(result.performance).mean(0))},
                             top_share=top))
            print(f"ceiling ({len(rows)}/{total}) {rules:>6} {option:>9}: ideal followers {fitness.mean():.3f} "
                  f"(sd {fitness.std():.3f}; {time.perf_counter() - tick:.0f} s)", file=sys.stderr, flush=True)
    _write_measure(out_dir, "ceiling", rows, lives, key, plot_ceiling, options=OPTIONS, rules=RULES)
    return rows


def measure_rates(out_dir: str, lives: int = RATE_LIVES, key: int = 0, task_steps: int = TASK_STEPS) -> list[dict]:
    """Stage 2: the ceiling over a grid of the selector's trace decay and rates (:data:`RATE_GRID`), per option of
    :data:`RATE_OPTIONS`: one compiled program per option, every point living the same lanes with the same keys."""
    import jax
    import jax.numpy as jnp
    import numpy as np

    from imrl_jax import sweeps
    from imrl_jax.config import make_config
    from imrl_jax.controllers import perceptron_followers

    rows = []
    for index, option in enumerate(RATE_OPTIONS):
        config = make_config("paper", condition="EE-LS", task_steps=task_steps, num_bins=10, **OPTIONS[option])
        sweep = sweeps.grid(config, **RATE_GRID)
        genome = perceptron_followers(config).reshape(-1)
        tick = time.perf_counter()
        result = sweeps.make_lifetime_sweep(config)(jax.random.key(key), jnp.broadcast_to(genome, (lives,) + genome.shape),
                                                    sweep.points)
        fitness = np.asarray(result.fitness)  # (points, lives)
        last = _last_tenth(config, result).mean(axis=(1, 2))
        for settings, values, tenth in zip(sweep.settings, fitness, last):
            rows.append(dict(option=option, **settings, lives=lives, fitness=float(values.mean()),
                             fitness_sd=float(values.std()), last_tenth=float(tenth)))
        best = max(rows[-len(sweep.settings):], key=lambda r: r["fitness"])
        print(f"rates ({index + 1}/{len(RATE_OPTIONS)}) {option:>9}: best {best['fitness']:.3f} at lambda "
              f"{best['trace_lambda']}, selector actor {best['eta_selector_actor']}, critic {best['eta_selector_critic']} "
              f"({time.perf_counter() - tick:.0f} s)", file=sys.stderr, flush=True)
    _write_measure(out_dir, "rates", rows, lives, key, plot_rates, grid=RATE_GRID)
    return rows


def measure_confirm(out_dir: str, lives: int = LIVES, key: int = 1, task_steps: int = TASK_STEPS) -> list[dict]:
    """Stage 3: each option of :data:`RATE_OPTIONS` at its best point of the rate sweep (in the sibling ``rates``
    folder), in ``lives`` fresh lives of another key: the sweep's best of 54 points of 3 lives flatters itself."""
    import jax
    import numpy as np

    from imrl_jax.config import make_config
    from imrl_jax.controllers import composition_ceiling

    rates = read_rates(os.path.dirname(os.path.normpath(out_dir)))
    if rates is None:
        raise ValueError(f"{out_dir}: the rate sweep has not run (its result.json is missing)")
    rows = []
    for index, option in enumerate(RATE_OPTIONS):
        best = best_rates(rates, option)
        values = {field: best[field] for field in RATE_GRID}
        config = make_config("paper", condition="EE-LS", task_steps=task_steps, num_bins=10, **OPTIONS[option],
                             **values)
        result = composition_ceiling(jax.random.key(key), config, lives)
        fitness = np.asarray(result.fitness)
        last = _last_tenth(config, result)
        rows.append(dict(option=option, **values, lives=lives, fitness=float(fitness.mean()),
                         fitness_sd=float(fitness.std()), last_tenth=float(last.mean()), sweep_fitness=best["fitness"]))
        print(f"confirm ({index + 1}/{len(RATE_OPTIONS)}) {option:>9}: {fitness.mean():.3f} (sd {fitness.std():.3f}) "
              f"in {lives} fresh lives, {best['fitness']:.3f} in the sweep", file=sys.stderr, flush=True)
    _write_measure(out_dir, "confirm", rows, lives, key)
    return rows


def plot_rates(rows: list[dict], path: str) -> None:
    """Per option, the best point of the rate sweep for each trace decay (bars) and that point's last tenth."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from imrl_jax.plotting import wrap_title

    options = list(dict.fromkeys(r["option"] for r in rows))
    lambdas = list(dict.fromkeys(r["trace_lambda"] for r in rows))
    fig, ax = plt.subplots(figsize=(8.0, 4.0))
    width = 0.8 / len(lambdas)
    for i, lam in enumerate(lambdas):
        best = [best_rates(rows, option, lam) for option in options]
        xs = [j + (i - (len(lambdas) - 1) / 2) * width for j in range(len(options))]
        ax.bar(xs, [b["fitness"] for b in best], width, yerr=[b["fitness_sd"] for b in best], capsize=2,
               color=plt.cm.viridis(0.15 + 0.7 * i / max(len(lambdas) - 1, 1)), label=f"lambda {lam}: best rates")
        ax.plot(xs, [b["last_tenth"] for b in best], "v", color="black", ms=4,
                label="the last tenth of each task" if i == 0 else None)
    ax.set_xticks(range(len(options)), options)
    ax.set_ylabel(f"fitness (mean of {rows[0]['lives']} lives)")
    ax.set_ylim(0, 1.2)  # room for the legend above the bars
    ax.legend(fontsize=7, loc="upper left", ncol=4)
    ax.set_title(wrap_title(ax, "Ideal colour followers composed: the best selector rates for each option and trace "
                            "decay", 10), fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _top_share(result) -> float:
    """The mean share of a task's steps that its most used expert was in control (1: one expert does it all)."""
    import numpy as np

    selections = np.asarray(result.adult_selections).sum(axis=2)  # (lives, tasks, K)
    return float((selections.max(-1) / selections.sum(-1)).mean())


def plot_ceiling(rows: list[dict], path: str) -> None:
    """Bars of the ceiling per option, one group per rule set, with the hand-written composition's level."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from imrl_jax.plotting import wrap_title

    options = list(OPTIONS)
    fig, ax = plt.subplots(figsize=(8.0, 4.0))
    width = 0.8 / len(RULES)
    for i, rules in enumerate(RULES):
        values = {r["option"]: r for r in rows if r["rules"] == rules}
        xs = [j + (i - (len(RULES) - 1) / 2) * width for j in range(len(options))]
        colour = ("0.35", "tab:orange", "0.75")[i % 3]
        ax.bar(xs, [values[o]["fitness"] for o in options], width, yerr=[values[o]["fitness_sd"] for o in options],
               label=RULE_LABELS.get(rules, rules), color=colour, capsize=2)
        ax.plot(xs, [values[o]["last_tenth"] for o in options], "v", color="black", ms=4,
                label="the last tenth of each task" if i == 0 else None)
    ax.axhline(COMPOSES, color="0.5", lw=0.8, ls=":", label=f"composition pays ({COMPOSES})")
    ax.set_xticks(range(len(options)), options)
    ax.set_ylabel(f"fitness (mean of {rows[0]['lives']} lives)")
    ax.set_ylim(0, 1.2)  # room for the legend above the bars
    ax.legend(fontsize=7, loc="upper left", ncol=2)
    ax.set_title(wrap_title(ax, "Ideal colour followers composed by a learning selector, per option of the "
                            f"selector ({rows[0]['task_steps']:,} steps per task)", 10), fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


# ----------------------------------------------------------------------------- the evolutions' report

#: The per-step selector the evolutions are compared with: the reproduction's run of this rule set (10 x 100).
BASELINE = "skills"
#: The conditions evolved with an option; EE-ES and SLE are the reproduction's (see :func:`option_runs`).
OPTION_CONDITIONS = ("LE-LS", "EE-LS")
#: Where the report's tables go in docs/TIMESCALE.md.
REPORT_START = "<!-- timescale evolutions: python -m experiments.timescale --report -->"
REPORT_END = "<!-- end of timescale evolutions -->"


def option_runs(variant: str, out: str = OUT, reproduction: str = REPRODUCTION):
    """An option's row of runs: its own LE-LS and EE-LS (evolution and learning test), and the reproduction's
    EE-ES (``paper``'s: it learns nothing, its evolved selector chooses every step) and SLE (``skills``': no
    selector)."""
    from experiments.claims_study import RowRuns
    from experiments.reproduce import evolution_dir, test_dir

    evolutions = {c: os.path.join(out, variant, c, "evolve") for c in OPTION_CONDITIONS}
    tests = {c: os.path.join(out, variant, c, "test") for c in OPTION_CONDITIONS}
    evolutions["EE-ES"], tests["EE-ES"] = evolution_dir(reproduction, "paper", "EE-ES"), test_dir(reproduction, "paper",
                                                                                                    "EE-ES")
    tests["SLE"] = test_dir(reproduction, BASELINE, "SLE")
    return RowRuns(evolutions, tests, {"EE-ES": "paper"})


def _progress(folder: str) -> tuple[int, int] | None:
    """Generations done and seeds of an evolution folder (None before its first generation)."""
    from experiments.loading import read_evolution

    run = read_evolution(folder)
    return None if run is None else (len(run["best"]), int(run["best"].shape[1]))


def measure_evolutions(out: str = OUT, reproduction: str = REPRODUCTION, summary: dict | None = None) -> dict:
    """The per-step baseline's claims and each planned option's: {variant: measured or progress}.

    An option's finished evolutions are measured (their best genomes live fresh lives and are
    probed) as soon as they finish, a running one shows how far it is, and a claim that needs a
    run still to come is n/a.
    """
    from experiments.claims_study import BY_NAME, RowRuns, measure_rule, measure_runs

    summary = summary if summary is not None else _reproduction_summary()
    rows = {BASELINE: dict(measured=measure_rule(BY_NAME[BASELINE], summary, reproduction=reproduction),
                           label=f"{BASELINE}, per-step selector (the paper's)")}
    for variant in evolution_groups(out):
        runs = option_runs(variant, out, reproduction)
        progress = {c: _progress(runs.evolutions[c]) for c in OPTION_CONDITIONS}
        finished = {c for c, p in progress.items() if p is not None and p[0] >= SCREEN["generations"]}
        # only finished evolutions are measured: a running one's population is not its last
        done = RowRuns({c: d for c, d in runs.evolutions.items() if c in finished or c not in OPTION_CONDITIONS},
                       {c: d for c, d in runs.tests.items() if c in finished or c not in OPTION_CONDITIONS},
                       runs.reproduction)
        rows[variant] = dict(progress=progress, label=variant.replace("+", ", ") + " selector",
                             measured=measure_runs(variant, done, summary) if finished else None)
    return rows


def _reproduction_summary() -> dict:
    """The reproduction report's probes (docs/reproduction/summary.json)."""
    with open(os.path.join("docs", "reproduction", "summary.json")) as f:
        return json.load(f)


def report_table(rows: dict) -> str:
    """Markdown: per row and condition the recorded and fresh fitness and the steady state, then claims 1-7."""
    from experiments.claims import CLAIMS

    lines = ["| selector | condition | seeds x generations | final best fitness (recorded) | fresh lives of each "
             "seed's best | plateau generation | steady state (learning test) |", "|---|---|---|---|---|---|---|"]
    for variant, row in rows.items():
        measured = row["measured"]
        for condition in OPTION_CONDITIONS:
            if measured is None or condition not in measured["evolution"]:
                done = (row.get("progress") or {}).get(condition)
                size = "not started" if done is None else f"{done[1]} x {done[0]} of {SCREEN['generations']}, running"
                lines.append(f"| {row['label']} | {condition} | {size} | - | - | - | - |")
                continue
            e, t = measured["evolution"].get(condition), measured["learning_tests"].get(condition)
            f = measured["fresh"].get(condition)
            lines.append(f"| {row['label']} | {condition} | {len(e['final_best_per_seed'])} x {e['generations']} | {e['final_best_mean']:.3f} +- {e['final_best_sd']:.3f} | "
                         + ("-" if f is None else f"{f['fresh']:.3f} (sd {f['fresh_sd_over_seeds']:.3f} over seeds)")
                         + f" | {e['plateau_generation']} | "
                         + ("-" if t is None else f"{t['steady_mean']:.3f} +- {t['steady_sd']:.3f} "
                            f"({t['num_runs']} runs)") + " |")
    lines += ["", "| claim | " + " | ".join(row["label"] for row in rows.values()) + " |",
              "|---|" + "---|" * len(rows)]
    short = {"holds": "**holds**", "partly": "partly", "does not hold": "no", "n/a": "n/a"}
    for k in range(1, 8):
        cells = []
        for row in rows.values():
            claim = None if row["measured"] is None else row["measured"]["claims"][k]
            cells.append("not finished" if claim is None else f"{short[claim['verdict']]}: "
                                                               f"{claim['measured'].split(';')[0]}")
        lines.append(f"| {k}: {CLAIMS[k]} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def report_figure(out: str, path: str, reproduction: str = REPRODUCTION) -> str:
    """Fig. 3a and 3b side by side: best fitness per generation and the learning tests' curves, per-step (dashed)
    against each option (solid), LE-LS and EE-LS."""
    from matplotlib.ticker import MaxNLocator

    from experiments.claims_study import BY_NAME, rule_runs
    from experiments.figures import _band
    from experiments.loading import read_evolution, read_test
    from imrl_jax.plotting import new_figure, save, style_axis

    colours = {"LE-LS": "tab:blue", "EE-LS": "tab:orange"}
    sources = {f"{BASELINE}, per-step": (rule_runs(BY_NAME[BASELINE], reproduction=reproduction), "--")}
    for variant in evolution_groups(out):
        sources[variant.replace("+", ", ")] = (option_runs(variant, out, reproduction), "-")
    fig = new_figure(12.0, 4.0)
    evolution_ax, test_ax = fig.subplots(1, 2)
    style_axis(evolution_ax, "Best fitness per generation (best of a generation's lives; mean over seeds, +-1 sd)",
               "generation", "best fitness")
    style_axis(test_ax, "Learning tests of the best (mean over tests and tasks, +-1 sd over runs)",
               "cycles of the task", "performance per bin")
    for label, (runs, ls) in sources.items():
        for condition in OPTION_CONDITIONS:
            style = dict(color=colours[condition], ls=ls, lw=1.5)
            run = read_evolution(runs.evolutions[condition])
            best = None if run is None else run["best"][~np.isnan(run["best"]).any(1)]  # seeds may be partial
            if best is not None and len(best):
                x = np.arange(len(best))
                running = ", running" if len(best) < (run["config"] or {}).get("num_generations", 0) else ""
                evolution_ax.plot(x, best.mean(1), label=f"{condition}, {label} ({best.shape[1]} seeds{running})",
                                  **style)
                _band(evolution_ax, x, best.mean(1), best.std(1), style, set())
            test = read_test(runs.tests[condition])
            if test is not None:
                test_ax.plot(test["steps"], test["mean"], label=f"{condition}, {label}", **style)
                _band(test_ax, np.asarray(test["steps"]), np.asarray(test["mean"]), np.asarray(test["sd"]), style,
                      set())
    evolution_ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    for ax in (evolution_ax, test_ax):
        ax.set_ylim(0, 1)
        if ax.lines:
            ax.legend(fontsize=7, loc="lower right")
        else:
            ax.text(0.5, 0.5, "not run yet", transform=ax.transAxes, ha="center", va="center", color="0.4")
    fig.tight_layout()
    return save(fig, path)


def report(out: str = OUT, document: str = os.path.join("docs", "TIMESCALE.md"),
           reproduction: str = REPRODUCTION, summary: dict | None = None) -> int:
    """Measure what has finished; write evolutions.json and evolutions.png under ``out`` and the tables into
    ``document``."""
    from experiments.study import write_table

    if not evolution_groups(out):
        print(f"error: {out}: the measurements have not run, so no evolution is planned yet", file=sys.stderr)
        return 2
    mismatched = mismatched_runs(out)
    if mismatched:
        print(f"error: {mismatched[0]}", file=sys.stderr)
        return 2
    rows = measure_evolutions(out, reproduction, summary)
    with open(os.path.join(out, "evolutions.json"), "w") as f:
        json.dump({variant: dict(label=row["label"], progress=row.get("progress"),
                                 claims=None if row["measured"] is None else
                                 {str(k): v for k, v in row["measured"]["claims"].items()},
                                 fresh=None if row["measured"] is None else row["measured"]["fresh"])
                   for variant, row in rows.items()}, f, indent=2, default=str)
    drawn = report_figure(out, os.path.join(out, "evolutions.png"), reproduction)
    write_table(document, report_table(rows), REPORT_START, REPORT_END)
    print(f"wrote {os.path.join(out, 'evolutions.json')}, {drawn} and the tables of {document}")
    return 0


def all_stages(out: str = OUT) -> tuple[list[Stage], dict]:
    """Every stage planned so far (the evolutions once the measurements have run), and their scale."""
    return plan(out), SCREEN


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    measures = {"ceiling": (measure_ceiling, LIVES), "rates": (measure_rates, RATE_LIVES),
                "confirm": (measure_confirm, LIVES)}
    if argv[:1] and argv[0] in measures:
        measure, lives = measures[argv[0]]
        p = argparse.ArgumentParser(prog=f"python -m experiments.timescale {argv[0]}")
        p.add_argument("--out", default=os.path.join(OUT, argv[0]))
        p.add_argument("--lives", type=int, default=lives)
        p.add_argument("--key", type=int, default=1 if argv[0] == "confirm" else 0)
        p.add_argument("--task-steps", type=int, default=TASK_STEPS)
        args = p.parse_args(argv[1:])
        try:
            measure(args.out, args.lives, args.key, args.task_steps)
        except ValueError as error:
            print(f"error: {error}", file=sys.stderr)
            return 2
        return 0
    p = argparse.ArgumentParser(prog="python -m experiments.timescale", description=__doc__.split("\n\n")[0])
    p.add_argument("--out", default=OUT, help=f"results directory (default: {OUT})")
    p.add_argument("--list", action="store_true", help="print the stages and their commands, run nothing")
    p.add_argument("--measures-only", action="store_true",
                   help="run the ceiling, the rate sweep and its confirmation only (minutes, not hours)")
    p.add_argument("--report", action="store_true", help="measure the finished evolutions, draw their figure and "
                   "write docs/TIMESCALE.md's tables (runs nothing)")
    add_options(p)
    args = p.parse_args(argv)
    if args.report:
        return report(args.out)
    if args.list:
        for stage in plan(args.out):
            print(f"{stage.name}: {' '.join(stage_command(stage, args.out)[0][1:])}")
        if not evolution_groups(args.out):
            print("(the evolutions are planned from the measurements' results, once they have run)")
        return 0
    manifest, manifest_path = load_manifest(args.out, study="timescale", sizes=SCREEN)
    fan = from_options(args, args.out)
    code = run_stages(plan(args.out)[:3], SCREEN, manifest, manifest_path, lambda s: stage_command(s, args.out), **fan)
    if code or args.measures_only:
        return code
    mismatched = mismatched_runs(args.out)
    if mismatched:
        print(f"error: {mismatched[0]}", file=sys.stderr)
        return 2
    return run_stages(plan(args.out), SCREEN, manifest, manifest_path, lambda s: stage_command(s, args.out), **fan)


#: The studies of this module (python -m experiments finds them).
STUDIES = (Study("timescale", "timescale", "docs/TIMESCALE.md", 1),)


if __name__ == "__main__":
    sys.exit(main())
