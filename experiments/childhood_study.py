"""Why childhood does not teach skills, and what does (docs/CHILDHOOD.md).

    python -m experiments run childhood       # run (or go on with) every stage, in order
    python -m experiments list childhood      # the stages, done or to run
    python -m experiments report childhood    # the evolutions' table, evolve.png and hand.png

Its evolutions (3 seeds x 30 generations at the paper's life lengths) are rows, found by their key in
``results/childhood/evolve``. Its measures (``python -m experiments.childhood_study [RUN...] --out OUT
STAGE``, STAGE one of :data:`STAGES`: hand, ceiling, speed, evolved, random, heritability, each its
``stage_NAME`` below; docs/CHILDHOOD.md's table says which measure runs which) each write OUT/NAME.csv,
NAME the folder's, then OUT/result.json, which names the CSV.

The measures made before the study was on the runner wrote their CSVs into ``results/childhood``; the
result.json of each of their folders (``measures/NAME``), written once from the committed files,
names that CSV (``"recorded"`` says so).
"""

from __future__ import annotations

import csv
import itertools
import json
import os
import sys
import time

import numpy as np

from experiments.harness.study import RESULTS, SCALES
from experiments.harness.table import Measure, Row, Table
from imrl_jax.config import ADULT_SELECTOR, CHILDHOOD_SELECTOR_REWARDS, CHILDHOOD_WALLS

#: The study's results: its evolutions (evolve/NAME), its measures' folders (measures/NAME) and figures.
OUT = os.path.join(RESULTS, "childhood")

#: The learning rules a childhood is tried with: the childhood values of LearningParams.
RULES = {
    "paper": dict(childhood_trace_lambda=0.0, childhood_eta_selector_actor=0.01, childhood_eta_selector_critic=0.01),
    "extension": {f"childhood_{name}": value for name, value in ADULT_SELECTOR.items()},
    # The selector does not learn: every expert gets a third of the steps, at random.
    "uniform": dict(childhood_trace_lambda=0.0, childhood_eta_selector_actor=0.0, childhood_eta_selector_critic=0.0),
}
#: Adult learning rules whose composition ceiling the study measures (LearningParams values).
CEILING_RULES = {
    "paper": {},
    "td0-fast-selector": dict(eta_selector_actor=3.0, eta_selector_critic=0.01),
    "extension": dict(ADULT_SELECTOR),
}


def measure(config, agent, records=None) -> dict:
    """The probes of an agent's experts and, given its childhood's ``records`` (selections,
    on-wall samples, respawns per piece; see :func:`imrl_jax.analysis.behaviour.make_childhoods`), control shares and walls."""
    from imrl_jax.analysis.behaviour import specialisation

    spec = specialisation(config, agent)
    own = np.diag(spec.takes)
    row = dict(own_takes=float(own.mean()), own_min=float(own.min()),
               own_followers=int(sum(int(spec.followed[k]) == k for k in range(3))),
               num_colours=spec.num_colours, speed=float(spec.speed.mean()),
               **{f"takes_{k + 1}_{c}": float(spec.takes[k, i]) for k in range(3) for i, c in enumerate("rgb")},
               **{f"followed_{k + 1}": int(spec.followed[k]) for k in range(3)})
    if records is not None:
        selections, on_wall, respawns = records
        quarter = selections[-len(selections) // 4:].sum(0)
        control = quarter / max(quarter.sum(), 1)
        row.update(max_control=float(control.max()), wall_share=float(on_wall.mean()),
                   wall_last_quarter=float(on_wall[-len(on_wall) // 4:].mean()), respawns=int(respawns.sum()),
                   **{f"control_{k + 1}": float(control[k]) for k in range(3)})
    return row


def finish(out: str, rows: list[dict], **summary) -> int:
    """A measure's rows into OUT/NAME.csv (floats with 4 decimals), then its result.json naming the CSV."""
    from experiments.harness.measures import write_measure  # atomic: a kill leaves the measure not done

    name = os.path.basename(os.path.normpath(out))
    write_measure(out, name, rows, "python -m experiments.childhood_study " + " ".join(sys.argv[1:]), 4,
                  csv=name + ".csv", **summary)
    return 0


def read_rows(folder: str) -> list[dict]:
    """A finished measure's rows (the CSV its result.json names), numbers as floats ("" where a row has none); none
    before it has run."""
    if not os.path.isfile(os.path.join(folder, "result.json")):
        return []
    with open(os.path.join(folder, "result.json")) as f:
        path = os.path.join(folder, json.load(f)["csv"])
    with open(path) as f:
        return [{k: v if k in ("walls", "reward", "rules", "run", "preset") or v == "" else float(v)
                 for k, v in r.items()}
                for r in csv.DictReader(f)]


def stage_hand(args) -> int:
    """Childhood alone with hand-made colour reinforcers, over the factors."""
    import jax

    from imrl_jax.analysis import behaviour
    from imrl_jax.evolution import sweeps
    from imrl_jax.config import make_config

    rows, start = [], time.perf_counter()
    lanes = [(rule, seed) for rule in args.rules.split(",") for seed in range(args.seeds)]
    for length, wall, reward in itertools.product([int(v) for v in args.lengths.split(",")], args.walls.split(","),
                                                  args.rewards.split(",")):
        config = make_config("paper", condition="LE-LS", childhood_steps=length, childhood_walls=wall,
                             childhood_selector_reward=reward, wall_respawn_steps=args.respawn_steps,
                             initial_speed_bias=args.speed_bias)
        points = sweeps.from_settings(config, [RULES[rule] for rule, _ in lanes]).points.params
        keys = jax.vmap(lambda s: jax.random.fold_in(jax.random.key(args.key), s))(
            jax.numpy.asarray([seed for _, seed in lanes]))
        agents, records = jax.device_get(behaviour.make_childhoods(config)(
            keys, points, jax.numpy.asarray(behaviour.colour_reinforcers(config))))
        rows += [dict(length=length, walls=wall, reward=reward, rules=rule, seed=seed,
                      **measure(config, jax.tree.map(lambda x: x[j], agents), tuple(x[j] for x in records)))
                 for j, (rule, seed) in enumerate(lanes)]
        print(f"childhood {length:,} walls={wall} reward={reward}: {time.perf_counter() - start:.0f} s", flush=True)
    return finish(args.out, rows, seconds=round(time.perf_counter() - start, 1), seeds=args.seeds,
                  settings=summarise(rows, ("length", "walls", "reward", "rules")))


def summarise(rows, keys) -> list[dict]:
    """Means (and ranges) over seeds of each setting."""
    out = []
    for setting in sorted({tuple(r[k] for k in keys) for r in rows}, key=str):
        group = [r for r in rows if tuple(r[k] for k in keys) == setting]
        entry = dict(zip(keys, setting))
        for name in ("own_takes", "own_followers", "num_colours", "max_control", "wall_share", "wall_last_quarter",
                     "respawns", "speed"):
            values = np.asarray([r[name] for r in group], float)
            entry.update({name: round(float(values.mean()), 3),
                          name + "_range": [round(float(values.min()), 3), round(float(values.max()), 3)]})
        out.append(dict(entry, seeds=len(group)))
    return out


def stage_ceiling(args) -> int:
    """Ideal colour followers composed by a learning selector, per adult rule set and task length."""
    import jax

    from imrl_jax.config import make_config
    from imrl_jax.analysis.controllers import composition_ceiling

    rows = []
    for task_steps, (name, rules) in itertools.product([int(v) for v in args.task_steps.split(",")],
                                                       CEILING_RULES.items()):
        config = make_config("paper", condition="EE-LS", task_steps=task_steps, num_bins=10, **rules)
        result = composition_ceiling(jax.random.key(args.key), config, args.lives)
        fitness = np.asarray(result.fitness)
        rows.append(dict(rules=name, task_steps=task_steps, lives=args.lives, fitness=float(fitness.mean()),
                         fitness_sd=float(fitness.std()),
                         **{f"task_{t + 1}": float(v) for t, v in enumerate(np.asarray(result.performance).mean(0))}))
        print(f"{name:>18} {task_steps:>7,} steps: ideal followers {fitness.mean():.3f}", flush=True)
    return finish(args.out, rows, rules=CEILING_RULES)


def best_of_run(run_dir: str, num_best: int):
    """A run's config, the ``num_best`` best genomes of each seed's last evaluated generation (one after the other,
    seed by seed) and a row for each: its run, seed, rank and fitness."""
    from imrl_jax.runs.rundir import RunDirError, best_genomes, load_run, read_config, read_kept_best

    if os.path.isfile(os.path.join(run_dir, "final_population.npz")):
        run = load_run(run_dir)
        config, seeds, genomes = run.config, run.seeds, best_genomes(run, num_best)
        fitness = -np.sort(-run.fitness, axis=1)[:, :num_best]
    else:
        # A reproduction's run directory keeps its best genomes in best_genomes.npz, three levels up
        # (RESULTS/VARIANT/evolve/COND), under VARIANT__COND__*.
        config, _ = read_config(run_dir)
        variant_dir = os.path.dirname(os.path.dirname(os.path.normpath(run_dir)))
        path = os.path.join(os.path.dirname(variant_dir), "best_genomes.npz")
        if not os.path.isfile(path):
            raise RunDirError(f"{run_dir}: no final_population.npz, and no reproduction's {path} keeps its best")
        kept = read_kept_best(path, os.path.basename(variant_dir), os.path.basename(os.path.normpath(run_dir)))
        seeds, genomes, fitness = kept.seeds, kept.genomes[:, :num_best], kept.fitness[:, :num_best]
    return config, genomes.reshape(-1, genomes.shape[-1]), [
        dict(run=os.path.basename(run_dir.rstrip("/")), seed=int(seeds[s]), rank=rank + 1,
             fitness=float(fitness[s, rank])) for s, rank in np.ndindex(fitness.shape)]


def probes(config, genomes, key: int) -> list[dict]:
    """Each genome's :func:`measure`: of the experts it ends childhood with (LE-LS: a fresh one, keys from ``key``)."""
    import jax

    from imrl_jax.analysis.behaviour import grown_agents

    agents, records = grown_agents(config, genomes, key)
    return [measure(config, jax.tree.map(lambda x: x[i], agents),
                    None if records is None else tuple(x[i] for x in records)) for i in range(len(genomes))]


def stage_evolved(args) -> int:
    """Probes of the best evolved individuals of run directories."""
    rows = []
    for run_dir in args.runs:
        config, genomes, best = best_of_run(run_dir, args.best)
        probed = probes(config, genomes, args.key)
        rows += [dict(row, **probe) for row, probe in zip(best, probed)]
        print(f"{run_dir}: individuals with 0-3 colours followed "
              f"{np.bincount([p['num_colours'] for p in probed], minlength=4).tolist()}", flush=True)
    return finish(args.out, rows)


def stage_random(args) -> int:
    """Random genomes (generation 0) under a preset: one life's fitness each and the probes of their experts."""
    import jax

    from imrl_jax.config import make_config
    from imrl_jax.agent.lifetime import make_evaluate

    config = make_config(args.preset, condition="LE-LS")
    genomes = jax.random.uniform(jax.random.key(args.key), (args.individuals, config.num_genes), minval=-1.0,
                                 maxval=1.0)
    fitness = np.asarray(make_evaluate(config)(jax.random.key(args.key + 1), config.learning_params(),
                                               genomes).fitness)
    return finish(args.out, [dict(preset=args.preset, individual=i, fitness=float(fitness[i]), **probe)
                             for i, probe in enumerate(probes(config, genomes, args.key + 2))])


def stage_heritability(args) -> int:
    """The best individuals of a run relived with fresh keys: how much of their fitness was luck."""
    import jax

    from imrl_jax.agent.lifetime import make_evaluate

    rows = []
    for run_dir in args.runs:
        config, genomes, best = best_of_run(run_dir, args.best)
        config = config.replace(lives_per_fitness=1)
        relived = np.asarray(make_evaluate(config)(jax.random.key(args.key), config.learning_params(),
                                                   np.repeat(genomes, args.lives, axis=0)).fitness)
        rows += [dict(row, relived_mean=float(lives.mean()), relived_sd=float(lives.std(ddof=1)),
                      **{f"life_{j + 1}": float(v) for j, v in enumerate(lives)})
                 for row, lives in zip(best, relived.reshape(-1, args.lives))]
    return finish(args.out, rows)


def stage_speed(args) -> int:
    """Hand-made colour reinforcers with experts that start fast: does the speed the childhood
    keeps decide what learned colour followers are worth in the tasks?"""
    import jax
    import jax.numpy as jnp

    from imrl_jax.world.arena import task_arrays
    from imrl_jax.analysis.behaviour import colour_reinforcers
    from imrl_jax.config import make_config
    from imrl_jax.agent.lifetime import childhood_task, lifetime_keys, random_pose, run_phase, task_spec, task_start
    from imrl_jax.agent.networks import decode
    from imrl_jax.agent.state import childhood_phase, for_phase, init_state
    from imrl_jax.world.env import at

    config = make_config(args.preset, condition="LE-LS")
    params = config.learning_params()
    genome = jnp.asarray(colour_reinforcers(config))
    _, _, best = task_arrays(config)

    def life(key, bias):
        keys = lifetime_keys(key, config.num_tasks)
        agent = decode(config, genome)
        agent = agent._replace(actor=agent.actor.at[:, 1, -1].set(bias))  # the speed unit's bias
        phase = childhood_phase(config)
        state = for_phase(config, phase, init_state(config, agent, at(random_pose(keys.pose, config))))
        state, _ = run_phase(keys.childhood, config, phase, params, childhood_task(config), state,
                             config.childhood_steps)

        def task(task_key, index):
            _, curves = run_phase(task_key, config, config.spec.adult, params, task_spec(config, index),
                                  task_start(config, state.agent, index), config.task_steps)
            return curves.reaches.sum()

        return state.agent, jax.vmap(task)(keys.tasks, jnp.arange(config.num_tasks)) / best

    lanes = [(float(b), i) for b in args.biases.split(",") for i in range(args.lives)]
    keys = jax.random.split(jax.random.key(args.key), len(lanes))
    grown, performance = jax.jit(jax.vmap(life))(keys, jnp.asarray([b for b, _ in lanes]))
    performance = np.asarray(performance)
    rows = []
    for j, (bias, i) in enumerate(lanes):
        probe = measure(config, jax.tree.map(lambda x: x[j], grown))
        rows.append(dict(speed_bias=bias, life=i, fitness=float(performance[j].mean()),
                         **{name: probe[name] for name in ("own_takes", "num_colours", "speed")},
                         **{f"task_{t + 1}": float(v) for t, v in enumerate(performance[j])}))
    return finish(args.out, rows, preset=args.preset)


def plot_hand(rows, path: str) -> str:
    """Own colour taken, largest control share and time on walls of every setting (mean bars, seed dots)."""
    from imrl_jax.analysis.plotting import new_figure, save

    walls, rewards, rules = ([v for v in known if any(r[name] == v for r in rows)] for name, known in (
        ("walls", CHILDHOOD_WALLS), ("reward", CHILDHOOD_SELECTOR_REWARDS), ("rules", RULES)))
    groups = list(itertools.product(sorted({int(r["length"]) for r in rows}), walls, rewards))
    metrics = (("own_takes", "own colour taken at junctions", 0.5),
               ("max_control", "largest control share, last quarter", 0.6),
               ("wall_share", "share of time on a wall", None))
    size = 1.2 + 0.42 * len(groups)  # the figure's height: a row of bars per setting
    fig = new_figure(12.0, size)
    fig.subplots_adjust(left=0.17, right=0.98, top=1 - 0.9 / size, bottom=0.06, wspace=0.08)
    axes = fig.subplots(1, len(metrics), sharey=True)
    height = 0.8 / len(rules)
    for ax, (name, title, target) in zip(axes, metrics):
        for (y, setting), (i, rule) in itertools.product(enumerate(groups), enumerate(rules)):
            values = [r[name] for r in rows if (r["length"], r["walls"], r["reward"], r["rules"]) == (*setting, rule)]
            yy = y - 0.4 + height * (i + 0.5)
            ax.barh(yy, np.mean(values), height=height * 0.9, color=f"C{i}", alpha=0.55, label=rule if y == 0 else None)
            ax.plot(values, [yy] * len(values), "k.", ms=2.5)
        if target is not None:
            ax.axvline(target, color="r", lw=0.8, ls="--")
        for y in range(len(rewards) * len(walls), len(groups), len(rewards) * len(walls)):
            ax.axhline(y - 0.5, color="0.5", lw=0.6)
        ax.set_xlim(0, 1)
        ax.set_title(title, fontsize=9)
        ax.grid(axis="x", alpha=0.3)
    axes[0].set_yticks(range(len(groups)), [f"{length // 1000}k steps, {wall}, {reward}"
                                            for length, wall, reward in groups], fontsize=8)
    axes[0].invert_yaxis()
    axes[-1].legend(title="childhood rules", fontsize=7, title_fontsize=7, loc="lower right")
    fig.suptitle("Childhood alone with hand-made colour reinforcers: length, walls, selector reward, rules "
                 f"({len({r['seed'] for r in rows})} seeds; dots: seeds; red: the study's targets)", fontsize=9)
    return save(fig, path)


#: The evolutions at the paper's life lengths: 3 seeds x 30 generations (150,000 + 6 x 100,000 steps).
EVOLVED = dict(SCALES["paper"], seeds=3, generations=30)
#: Each evolution (a row, not learning-tested): its condition, preset and sets; then its line of the evolutions'
#: table: what it is, its probes' measure and a note on its tasks.
EVOLUTIONS = {
    "LE-LS-skills": ("LE-LS", "skills", (), "LE-LS, `skills`", "evolved_skills", ""),
    "LE-LS-skills-no-speed-bias": ("LE-LS", "skills", ("initial_speed_bias=0",),
                                   "LE-LS, `skills` without the speed bias", "evolved_no_speed_bias", ""),
    "LE-LS-extension": ("LE-LS", "extension", (), "LE-LS, `extension`", "evolved_extension", ""),
    "EE-LS-extension": ("EE-LS", "extension", (), "EE-LS, `extension` (= `skills`: EE has no childhood)",
                        "evolved_ee_ls", ": one task of a pair near 0"),
    "LE-LS-skills-2lives": ("LE-LS", "skills", ("lives_per_fitness=2",), "LE-LS, `skills`, fitness the mean of 2 "
                            "lives, 15 generations (equal compute)", "evolved_skills_2lives", ""),
    "LE-LS-extension-speed-bias": ("LE-LS", "extension", ("initial_speed_bias=4",), "LE-LS, `extension` + "
                                   "`initial_speed_bias=4`", "evolved_extension_speed_bias",
                                   ": seed 2 solves task 1 at 0.00"),
    "LE-LS-skills-clamp": ("LE-LS", "skills", ("childhood_walls=clamp",), "LE-LS, `skills` with "
                           "`childhood_walls=clamp`", "evolved_skills_clamp", ""),
}


class ChildhoodTable(Table):
    """The study's table: its evolutions' final best, tasks and probes, evolve.png and the hand-made childhoods."""

    def report(self) -> int:
        from experiments.harness.loading import history_columns, read_evolution
        from experiments.harness.markdown import head, line
        from experiments.harness.study import markers, write_table
        from imrl_jax import conditions
        from imrl_jax.analysis.plotting import new_figure, save, style_axis

        folders = {m.name: self.measure_folder(m) for m in self.measures}
        lines = head("run", "final best (per seed)", "every task of the best",
                     "10 best x 3 seeds: individuals with 0 / 1 / 2 / 3 colours followed")
        fig = new_figure(8.8, 3.8)
        ax = fig.add_subplot()
        for i, (row, run_dir) in enumerate(self.evolutions().items()):
            *_, label, probed, note = EVOLUTIONS[row]
            run = read_evolution(run_dir)
            if run is None:
                lines.append(line(label, "not started", "-", "-"))
                continue
            lives = run["config"].get("lives_per_fitness", 1)
            x, mean, sd = lives * np.arange(len(run["best"])), np.nanmean(run["best"], 1), np.nanstd(run["best"], 1)
            dashed = not conditions.get(run["config"]["condition"]).learned_actors  # evolved experts
            ax.plot(x, mean, label=f"{row} ({len(run['seeds'])} seeds)", color=f"C{i}", ls="--" if dashed else "-",
                    marker="o", ms=2.5, lw=1.4)
            ax.fill_between(x, mean - sd, mean + sd, color=f"C{i}", alpha=0.12, lw=0)
            # each seed's best of the last generation: its fitness, then its performance on each of the paper's tasks
            last = history_columns(run_dir, ("best", *(f"best_task{t + 1}" for t in range(6))))[-1]
            colours = np.bincount([int(r["num_colours"]) for r in read_rows(folders[probed])], minlength=4)
            lines.append(line(label, f"{last[:, 0].mean():.3f} ({', '.join(f'{b:.3f}' for b in last[:, 0])})",
                              f"{last[:, 1:].min():.2f}-{last[:, 1:].max():.2f}{note}",
                              " / ".join(str(c) for c in colours)))
        ceiling, speed = read_rows(folders["ceiling"]), read_rows(folders["speed"])
        references = [(r["fitness"], "ideal colour followers, extension's selector") for r in ceiling
                      if r["rules"] == "extension" and r["task_steps"] == 100_000]
        references += [(float(np.mean(fitness)), "hand-made colour reinforcers under skills")
                       for fitness in [[r["fitness"] for r in speed if r["speed_bias"] == 4.0]] if fitness]
        for (value, label), style in zip(references, ("--", ":")):
            ax.axhline(value, color="0.35", lw=1.0, ls=style, label=f"{label}: {value:.2f}")
        ax.set_ylim(0, 1)
        style_axis(ax, "paper life lengths: best fitness (mean over seeds, +-1 sd)",
                   "generation (x lives per fitness: equal compute)", "best fitness")
        if ax.lines:
            ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.0, 1.0))
        fig.tight_layout()
        os.makedirs(self.out, exist_ok=True)
        drawn = [save(fig, os.path.join(self.out, "evolve.png"))]
        drawn += [plot_hand(read_rows(folders[name]), os.path.join(self.out, f"{name}.png"))
                  for name in ("hand", "hand_fast") if read_rows(folders[name])]
        write_table(self.document, "\n".join(lines), *markers(f"{self.name} table", self.name))
        print(f"{len(lines) - 2} evolutions; wrote {', '.join(drawn)} and the table of {self.document}")
        return 0


#: The measures' module: this one.
MODULE = "experiments.childhood_study"
TABLE = ChildhoodTable("childhood", "docs/CHILDHOOD.md", 10, out=OUT, scale=EVOLVED, rows=tuple(
    # 2 lives a fitness: half the generations (equal compute)
    Row(name, condition, preset, sets, test=False,
        scale=dict(EVOLVED, generations=15) if "lives_per_fitness=2" in sets else None)
    for name, (condition, preset, sets, *_) in EVOLUTIONS.items()), measures=(
    Measure("ceiling", "", ("ceiling",), MODULE),
    Measure("hand", "", ("hand",), MODULE),
    Measure("hand_fast", "", ("hand", "--lengths", "150000", "--walls", "respawn,clamp", "--rewards", "surprise",
                              "--rules", "paper", "--speed-bias", "4"), MODULE),
    Measure("speed", "", ("speed", "--biases", "0,1,2,3,4,6", "--lives", "6"), MODULE),
    # the best of the cpu reproduction's runs, found by their keys
    Measure("evolved_cpu", "", ("evolved", *(Row(f"cpu {variant} {condition}", condition, variant, scale=SCALES["cpu"])
                                            for condition in ("LE-LS", "EE-LS") for variant in ("paper", "extension"))),
            MODULE),
    *(Measure(probed, row, ("evolved",), MODULE) for row, (*_, probed, _) in EVOLUTIONS.items()),
    Measure("random_skills", "", ("random",), MODULE),
    # the study's own runs, named as rows: the measure waits for their evolutions
    Measure("heritability", "", ("heritability", *(f"{{{row}}}" for row in (
        "LE-LS-skills", "LE-LS-extension", "LE-LS-skills-no-speed-bias", "LE-LS-skills-2lives"))), MODULE),
    Measure("evolved_paper_scale", "", ("evolved", Row("skills LE-LS", "LE-LS", "skills", scale=SCALES["paper"])),
            MODULE),
))
all_stages = TABLE.all_stages
#: The studies of this module (python -m experiments finds them).
STUDIES = (TABLE.study("childhood_study"),)


#: Each stage, and its random key and lives (None: the stage has none) the committed measures were made with.
STAGES = {"hand": (stage_hand, 0, None), "ceiling": (stage_ceiling, 0, 8), "speed": (stage_speed, 3, 4),
          "evolved": (stage_evolved, 1, None), "random": (stage_random, 4, None),
          "heritability": (stage_heritability, 2, 4)}


def main(argv=None) -> int:
    """The study's command line (``python -m experiments run|report childhood``), or a measure's, given ``--out``."""
    argv = sys.argv[1:] if argv is None else list(argv)
    if any(a.startswith("--out") for a in argv):
        from experiments.childhood_measures import measure_main

        return measure_main(argv, measures())
    return TABLE.main(argv)


def measures():
    """What the measures' command line reads of this study (``experiments.childhood_measures.Study``)."""
    from experiments.childhood_measures import Study

    return Study(__doc__.split("\n\n")[0], STAGES, RULES, CEILING_RULES, best_of_run)


if __name__ == "__main__":
    sys.exit(main())
