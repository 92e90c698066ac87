"""Why childhood does not teach skills, and what does (docs/CHILDHOOD.md).

Stages (each writes into ``--out``, default ``experiments/results/childhood``):

* ``hand``: childhood alone with hand-made colour reinforcers (reinforcer k pays for colour
  k under the retina's centre, :func:`imrl_jax.behaviour.colour_reinforcers`) over the
  factors: childhood length, how walls act, the selector's reward, the learning rules.
  Each childhood is measured by the junction probes of :func:`imrl_jax.behaviour.specialisation`,
  the experts' shares of control over its last quarter and the time on walls.
  Writes ``hand.csv``, ``hand.json`` and ``hand.png``.
* ``evolved``: the same probes on evolved best genomes (``--genomes`` npz files of
  ``best_genomes.npz`` form, or run directories), after a fresh childhood for LE-LS.
  Writes ``evolved.csv``.

    python experiments/childhood_study.py hand
    python experiments/childhood_study.py hand --lengths 30000 --seeds 2      # a quick look
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

from imrl_jax.config import ADULT_SELECTOR

#: The learning rules a childhood is tried with: the childhood values of LearningParams.
RULES = {
    "paper": dict(childhood_trace_lambda=0.0, childhood_eta_selector_actor=0.01, childhood_eta_selector_critic=0.01),
    "extension": {f"childhood_{name}": value for name, value in ADULT_SELECTOR.items()},
    # The selector does not learn: every expert gets a third of the steps, at random.
    "uniform": dict(childhood_trace_lambda=0.0, childhood_eta_selector_actor=0.0, childhood_eta_selector_critic=0.0),
}


def measure(config, agent, records=None) -> dict:
    """The probes of an agent's experts and, given its childhood's ``records`` (selections,
    on-wall samples, respawns per piece; see :func:`imrl_jax.behaviour.make_childhoods`), control shares and walls."""
    from imrl_jax.behaviour import specialisation

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


def stage_hand(args) -> int:
    """Childhood alone with hand-made colour reinforcers, over the factors."""
    from imrl_jax import behaviour
    import jax

    from imrl_jax import sweeps
    from imrl_jax.behaviour import colour_reinforcers
    from imrl_jax.checkpoint import git_commit
    from imrl_jax.config import make_config

    lengths = [int(v) for v in args.lengths.split(",")]
    walls = args.walls.split(",")
    rewards = args.rewards.split(",")
    rules = args.rules.split(",")
    rows = []
    start = time.perf_counter()
    combos = list(itertools.product(lengths, walls, rewards))
    for i, (length, wall, reward) in enumerate(combos):
        config = make_config("paper", condition="LE-LS", childhood_steps=length, childhood_walls=wall,
                             childhood_selector_reward=reward, wall_respawn_steps=args.respawn_steps,
                             initial_speed_bias=args.speed_bias)
        genome = jax.numpy.asarray(colour_reinforcers(config))
        lanes = [(rule, seed) for rule in rules for seed in range(args.seeds)]
        points = sweeps.from_settings(config, [RULES[rule] for rule, _ in lanes]).points.params
        keys = jax.vmap(lambda s: jax.random.fold_in(jax.random.key(args.key), s))(
            jax.numpy.asarray([seed for _, seed in lanes]))
        tick = time.perf_counter()
        agents, (selections, on_wall, respawns) = behaviour.make_childhoods(config)(keys, points, genome)
        agents, selections, on_wall, respawns = jax.device_get((agents, selections, on_wall, respawns))
        for j, (rule, seed) in enumerate(lanes):
            agent = jax.tree.map(lambda x: x[j], agents)
            row = dict(length=length, walls=wall, reward=reward, rules=rule, seed=seed)
            row.update(measure(config, agent, (selections[j], on_wall[j], respawns[j])))
            rows.append(row)
        done = time.perf_counter() - start
        print(f"[{i + 1}/{len(combos)}] childhood {length:,} walls={wall} reward={reward}: {len(lanes)} lanes in "
              f"{time.perf_counter() - tick:.0f} s; own-colour takes "
              + ", ".join(f"{rule} {np.mean([r['own_takes'] for r in rows[-len(lanes):] if r['rules'] == rule]):.2f}"
                          for rule in rules)
              + f"; ETA {done / (i + 1) * (len(combos) - i - 1):.0f} s", flush=True)

    os.makedirs(args.out, exist_ok=True)
    write_csv(os.path.join(args.out, args.name + ".csv"), rows)
    summary = dict(command="python experiments/childhood_study.py " + " ".join(sys.argv[1:]), git_commit=git_commit(),
                   seconds=round(time.perf_counter() - start, 1), seeds=args.seeds,
                   settings=summarise(rows, ("length", "walls", "reward", "rules")))
    with open(os.path.join(args.out, args.name + ".json"), "w") as f:
        json.dump(summary, f, indent=2)
    plot_hand(rows, os.path.join(args.out, args.name + ".png"))
    return 0


def summarise(rows, keys) -> list[dict]:
    """Means (and ranges) over seeds of each setting."""
    out = []
    for setting in sorted({tuple(r[k] for k in keys) for r in rows}, key=str):
        group = [r for r in rows if tuple(r[k] for k in keys) == setting]
        entry = dict(zip(keys, setting))
        for name in ("own_takes", "own_followers", "num_colours", "max_control", "wall_share", "wall_last_quarter",
                     "respawns", "speed"):
            values = np.asarray([r[name] for r in group], float)
            entry[name] = round(float(values.mean()), 3)
            entry[name + "_range"] = [round(float(values.min()), 3), round(float(values.max()), 3)]
        entry["seeds"] = len(group)
        out.append(entry)
    return out


def write_csv(path: str, rows: list[dict]) -> None:
    """Rows as CSV (floats with 4 decimals)."""
    with open(path, "w", newline="") as f:
        fields = list(dict.fromkeys(name for row in rows for name in row))  # rows may lack some (EE: no childhood)
        writer = csv.DictWriter(f, fieldnames=fields, restval="", lineterminator="\n")
        writer.writeheader()
        writer.writerows({k: (f"{v:.4f}" if isinstance(v, float) else v) for k, v in r.items()} for r in rows)


def plot_hand(rows, path: str) -> None:
    """Own colour taken, largest control share and time on walls of every setting (mean bars, seed dots)."""
    from imrl_jax.plotting import new_figure, save

    order = lambda values, first: sorted(set(values), key=lambda v: (v not in first, first.index(v) if v in first  # noqa: E731
                                                                     else 0, v))
    lengths = sorted({r["length"] for r in rows})
    walls = order([r["walls"] for r in rows], ["clamp", "respawn"])
    rewards = order([r["reward"] for r in rows], ["surprise", "progress"])
    rules = order([r["rules"] for r in rows], list(RULES))
    groups = [(length, wall, reward) for length in lengths for wall in walls for reward in rewards]
    metrics = (("own_takes", "own colour taken at junctions", 0.5),
               ("max_control", "largest control share, last quarter", 0.6),
               ("wall_share", "share of time on a wall", None))
    fig = new_figure(12.0, 1.2 + 0.42 * len(groups))
    fig.subplots_adjust(left=0.17, right=0.98, top=1 - 0.9 / (1.2 + 0.42 * len(groups)), bottom=0.06, wspace=0.08)
    axes = fig.subplots(1, len(metrics), sharey=True)
    height = 0.8 / len(rules)
    for ax, (name, title, target) in zip(axes, metrics):
        for y, (length, wall, reward) in enumerate(groups):
            for i, rule in enumerate(rules):
                values = [r[name] for r in rows if (r["length"], r["walls"], r["reward"], r["rules"])
                          == (length, wall, reward, rule)]
                if not values:
                    continue
                yy = y - 0.4 + height * (i + 0.5)
                ax.barh(yy, np.mean(values), height=height * 0.9, color=f"C{i}", alpha=0.55,
                        label=rule if y == 0 else None)
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
    save(fig, path)


def read_best(run_dir: str) -> np.ndarray:
    """Best fitness (seeds, generations) from a run's history.csv."""
    with open(os.path.join(run_dir, "history.csv")) as f:
        rows = list(csv.DictReader(f))
    seeds = sorted({int(r["seed"]) for r in rows})
    generations = max(int(r["generation"]) for r in rows) + 1
    best = np.full((len(seeds), generations), np.nan)
    for r in rows:
        best[seeds.index(int(r["seed"])), int(r["generation"])] = float(r["best"])
    return best


def plot_evolutions(out: str, path: str) -> None:
    """Best fitness per generation of the study's evolutions, with the ceilings they climb towards.

    The x axis is compute: a run scoring the mean of N lives is drawn at N x its generation.
    """
    from imrl_jax.config import Config
    from imrl_jax.plotting import new_figure, save, style_axis

    fig = new_figure(8.8, 3.8)
    ax = fig.add_subplot()
    for i, name in enumerate(name for name in EVOLUTIONS
                             if os.path.isfile(os.path.join(out, "evolve", name, "history.csv"))):
        with open(os.path.join(out, "evolve", name, "config.json")) as f:
            lives = Config.from_dict(json.load(f)["config"]).lives_per_fitness
        best = read_best(os.path.join(out, "evolve", name))
        x = lives * np.arange(best.shape[1])
        mean, sd = np.nanmean(best, 0), np.nanstd(best, 0)
        style = dict(color=f"C{i}", ls="--" if name.startswith("EE") else "-", marker="o", ms=2.5, lw=1.4)
        ax.plot(x, mean, label=f"{name} ({best.shape[0]} seeds)", **style)
        ax.fill_between(x, mean - sd, mean + sd, color=f"C{i}", alpha=0.12, lw=0)
    references = []
    with open(os.path.join(out, "ceiling.csv")) as f:
        references += [(float(r["fitness"]), "ideal colour followers, extension's selector")
                       for r in csv.DictReader(f) if r["rules"] == "extension" and r["task_steps"] == "100000"]
    with open(os.path.join(out, "speed.csv")) as f:
        fast = [float(r["fitness"]) for r in csv.DictReader(f) if float(r["speed_bias"]) == 4.0]
    references.append((float(np.mean(fast)), "hand-made colour reinforcers under skills"))
    for (value, label), style in zip(references, ("--", ":")):
        ax.axhline(value, color="0.35", lw=1.0, ls=style, label=f"{label}: {value:.2f}")
    ax.set_ylim(0, 1)
    style_axis(ax, "paper life lengths: best fitness (mean over seeds, +-1 sd)",
               "generation (x lives per fitness: equal compute)", "best fitness")
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.0, 1.0))
    fig.tight_layout()
    save(fig, path)


def stage_plot(args) -> int:
    """Redraw hand.png from hand.csv and evolve.png from the runs' histories."""
    with open(os.path.join(args.out, "hand.csv")) as f:
        rows = [{k: (float(v) if k not in ("walls", "reward", "rules") else v) for k, v in r.items()}
                for r in csv.DictReader(f)]
    for r in rows:
        r["length"] = int(r["length"])
    plot_hand(rows, os.path.join(args.out, "hand.png"))
    plot_evolutions(args.out, os.path.join(args.out, "evolve.png"))
    return 0


#: Adult learning rules whose composition ceiling the study measures (LearningParams values).
CEILING_RULES = {
    "paper": {},
    "td0-fast-selector": dict(eta_selector_actor=3.0, eta_selector_critic=0.01),
    "extension": dict(ADULT_SELECTOR),
}


def stage_ceiling(args) -> int:
    """Ideal colour followers composed by a learning selector, per adult rule set and task length."""
    import jax

    from imrl_jax.checkpoint import git_commit
    from imrl_jax.config import make_config
    from imrl_jax.controllers import composition_ceiling

    rows = []
    for task_steps in [int(v) for v in args.task_steps.split(",")]:
        for name, rules in CEILING_RULES.items():
            config = make_config("paper", condition="EE-LS", task_steps=task_steps, num_bins=10, **rules)
            tick = time.perf_counter()
            result = composition_ceiling(jax.random.key(args.key), config, args.lives)
            fitness = np.asarray(result.fitness)
            performance = np.asarray(result.performance).mean(0)
            rows.append(dict(rules=name, task_steps=task_steps, lives=args.lives, fitness=float(fitness.mean()),
                             fitness_sd=float(fitness.std()),
                             **{f"task_{t + 1}": float(v) for t, v in enumerate(performance)}))
            print(f"{name:>18} {task_steps:>7,} steps: ideal followers {fitness.mean():.3f} "
                  f"(sd {fitness.std():.3f}, {time.perf_counter() - tick:.0f} s)", flush=True)
    os.makedirs(args.out, exist_ok=True)
    write_csv(os.path.join(args.out, "ceiling.csv"), rows)
    with open(os.path.join(args.out, "ceiling.json"), "w") as f:
        json.dump(dict(command="python experiments/childhood_study.py " + " ".join(sys.argv[1:]),
                       git_commit=git_commit(), rules=CEILING_RULES, rows=rows), f, indent=2)
    return 0


def best_of_run(run_dir: str, num_best: int):
    """A run's config, seeds, and per seed the ``num_best`` best genomes of its last evaluated generation and their fitness."""
    from imrl_jax.rundir import best_genomes, load_run, read_config, read_kept_best

    if not os.path.isfile(os.path.join(run_dir, "final_population.npz")):
        # A reproduction's run directory keeps its best genomes in best_genomes.npz, three levels up
        # (RESULTS/VARIANT/evolve/COND), under VARIANT__COND__*.
        config, _ = read_config(run_dir)
        run_dir = os.path.normpath(run_dir)
        variant_dir = os.path.dirname(os.path.dirname(run_dir))
        kept = read_kept_best(os.path.join(os.path.dirname(variant_dir), "best_genomes.npz"),
                              os.path.basename(variant_dir), os.path.basename(run_dir))
        return config, np.asarray(kept.seeds), kept.genomes[:, :num_best], kept.fitness[:, :num_best]
    run = load_run(run_dir)
    return run.config, np.asarray(run.seeds), best_genomes(run, num_best), -np.sort(-run.fitness, axis=1)[:, :num_best]


def stage_evolved(args) -> int:
    """Probes of the best evolved individuals of run directories."""
    from imrl_jax import behaviour
    import jax

    rows = []
    for run_dir in args.runs:
        config, seeds, genomes, fitness = best_of_run(run_dir, args.best)
        flat = genomes.reshape(-1, genomes.shape[-1])
        tick = time.perf_counter()
        agents, records = behaviour.grown_agents(config, flat, args.key)
        for i in range(len(flat)):
            s, rank = divmod(i, args.best)
            agent = jax.tree.map(lambda x: x[i], agents)
            row = dict(run=os.path.basename(run_dir.rstrip("/")), seed=int(seeds[s]), rank=rank + 1,
                       fitness=float(fitness[s, rank]))
            row.update(measure(config, agent, None if records is None else tuple(x[i] for x in records)))
            rows.append(row)
        summary = [r["num_colours"] for r in rows[-len(flat):]]
        print(f"{run_dir}: {len(flat)} individuals in {time.perf_counter() - tick:.0f} s; distinct colours followed "
              f"{np.bincount(summary, minlength=4).tolist()} (individuals with 0, 1, 2, 3)", flush=True)
    os.makedirs(args.out, exist_ok=True)
    write_csv(os.path.join(args.out, args.name + ".csv"), rows)
    return 0


def stage_random(args) -> int:
    """Random genomes (generation 0) under a preset: one life's fitness each and the probes of their experts."""
    from imrl_jax import behaviour
    import jax

    from imrl_jax.config import make_config
    from imrl_jax.lifetime import make_evaluate

    config = make_config(args.preset, condition="LE-LS")
    genomes = jax.random.uniform(jax.random.key(args.key), (args.individuals, config.num_genes), minval=-1.0,
                                 maxval=1.0)
    tick = time.perf_counter()
    fitness = np.asarray(make_evaluate(config)(jax.random.key(args.key + 1), config.learning_params(),
                                               genomes).fitness)
    agents, records = behaviour.grown_agents(config, genomes, args.key + 2)
    rows = []
    for i in range(args.individuals):
        row = dict(preset=args.preset, individual=i, fitness=float(fitness[i]))
        row.update(measure(config, jax.tree.map(lambda x: x[i], agents), tuple(x[i] for x in records)))
        rows.append(row)
    colours = np.bincount([r["num_colours"] for r in rows], minlength=4).tolist()
    print(f"{args.individuals} random LE-LS genomes under {args.preset} in {time.perf_counter() - tick:.0f} s: "
          f"fitness {fitness.mean():.3f} (max {fitness.max():.3f}); individuals with 0-3 colours followed {colours}",
          flush=True)
    os.makedirs(args.out, exist_ok=True)
    write_csv(os.path.join(args.out, f"random_{args.preset}.csv"), rows)
    return 0


def stage_heritability(args) -> int:
    """The best individuals of a run relived with fresh keys: how much of their fitness was luck."""
    import jax

    from imrl_jax.lifetime import make_evaluate

    rows = []
    for run_dir in args.runs:
        config, seeds, genomes, fitness = best_of_run(run_dir, args.best)
        config = config.replace(lives_per_fitness=1)
        flat = np.repeat(genomes.reshape(-1, genomes.shape[-1]), args.lives, axis=0)
        tick = time.perf_counter()
        result = make_evaluate(config)(jax.random.key(args.key), config.learning_params(), flat)
        relived = np.asarray(result.fitness).reshape(len(seeds), args.best, args.lives)
        for s in range(len(seeds)):
            for rank in range(args.best):
                rows.append(dict(run=os.path.basename(run_dir.rstrip("/")), seed=int(seeds[s]), rank=rank + 1,
                                 fitness=float(fitness[s, rank]), relived_mean=float(relived[s, rank].mean()),
                                 relived_sd=float(relived[s, rank].std(ddof=1)),
                                 **{f"life_{j + 1}": float(v) for j, v in enumerate(relived[s, rank])}))
        group = rows[-len(seeds) * args.best:]
        original = np.array([r["fitness"] for r in group])
        mean = np.array([r["relived_mean"] for r in group])
        print(f"{run_dir}: {len(group)} x {args.lives} lives in {time.perf_counter() - tick:.0f} s: fitness "
              f"{original.mean():.3f} -> relived {mean.mean():.3f}; sd of one genome's lives "
              f"{np.mean([r['relived_sd'] for r in group]):.3f}; corr {np.corrcoef(original, mean)[0, 1]:.2f}",
              flush=True)
    os.makedirs(args.out, exist_ok=True)
    write_csv(os.path.join(args.out, "heritability.csv"), rows)
    return 0


def stage_speed(args) -> int:
    """Hand-made colour reinforcers with experts that start fast: does the speed the childhood
    keeps decide what learned colour followers are worth in the tasks?"""
    import jax
    import jax.numpy as jnp

    from imrl_jax.behaviour import colour_reinforcers, specialisation
    from imrl_jax.checkpoint import git_commit
    from imrl_jax.config import make_config
    from imrl_jax.lifetime import childhood_task, lifetime_keys, random_pose, run_phase, task_spec, task_start
    from imrl_jax.state import childhood_phase, for_phase, init_state
    from imrl_jax.arena import task_arrays
    from imrl_jax.networks import decode

    config = make_config(args.preset, condition="LE-LS")
    params = config.learning_params()
    genome = jnp.asarray(colour_reinforcers(config))
    _, _, best = task_arrays(config)

    def life(key, bias):
        keys = lifetime_keys(key, config.num_tasks)
        agent = decode(config, genome)
        agent = agent._replace(actor=agent.actor.at[:, 1, -1].set(bias))  # the speed unit's bias
        phase = childhood_phase(config)
        state = for_phase(config, phase, init_state(config, agent, random_pose(keys.pose, config)))
        state, _ = run_phase(keys.childhood, config, phase, params, childhood_task(config), state,
                             config.childhood_steps)
        grown = state.agent

        def task(task_key, index):
            _, curves = run_phase(task_key, config, config.spec.adult, params, task_spec(config, index),
                                  task_start(config, grown, index), config.task_steps)
            return curves.reaches.sum()

        reaches = jax.vmap(task)(keys.tasks, jnp.arange(config.num_tasks))
        return grown, reaches / best

    biases = [float(b) for b in args.biases.split(",")]
    lanes = [(b, i) for b in biases for i in range(args.lives)]
    keys = jax.random.split(jax.random.key(args.key), len(lanes))
    tick = time.perf_counter()
    grown, performance = jax.jit(jax.vmap(life))(keys, jnp.asarray([b for b, _ in lanes]))
    performance = np.asarray(performance)
    rows = []
    for j, (bias, i) in enumerate(lanes):
        spec = specialisation(config, jax.tree.map(lambda x: x[j], grown))
        rows.append(dict(speed_bias=bias, life=i, fitness=float(performance[j].mean()),
                         own_takes=float(np.diag(spec.takes).mean()), num_colours=spec.num_colours,
                         speed=float(spec.speed.mean()),
                         **{f"task_{t + 1}": float(v) for t, v in enumerate(performance[j])}))
    for bias in biases:
        group = [r for r in rows if r["speed_bias"] == bias]
        print(f"speed bias {bias:g}: fitness {np.mean([r['fitness'] for r in group]):.3f}, own colour taken "
              f"{np.mean([r['own_takes'] for r in group]):.2f}, {np.mean([r['speed'] for r in group]):.2f} cm/step",
              flush=True)
    print(f"{len(lanes)} lives in {time.perf_counter() - tick:.0f} s")
    os.makedirs(args.out, exist_ok=True)
    write_csv(os.path.join(args.out, "speed.csv"), rows)
    with open(os.path.join(args.out, "speed.json"), "w") as f:
        json.dump(dict(command="python experiments/childhood_study.py " + " ".join(sys.argv[1:]),
                       git_commit=git_commit(), preset=args.preset), f, indent=2)
    return 0


#: The paper-length evolutions of the study (3 seeds x 30 generations; 150,000 + 6 x 100,000 steps).
EVOLUTIONS = {
    "LE-LS-skills": ["--cond", "LE-LS", "--preset", "skills"],
    "LE-LS-skills-no-speed-bias": ["--cond", "LE-LS", "--preset", "skills", "--set", "initial_speed_bias=0"],
    "LE-LS-extension": ["--cond", "LE-LS", "--preset", "extension"],
    "EE-LS-extension": ["--cond", "EE-LS", "--preset", "extension"],
    "LE-LS-skills-2lives": ["--cond", "LE-LS", "--preset", "skills", "--set", "lives_per_fitness=2",
                            "--generations", "15"],
    "LE-LS-extension-speed-bias": ["--cond", "LE-LS", "--preset", "extension", "--set", "initial_speed_bias=4"],
    "LE-LS-skills-clamp": ["--cond", "LE-LS", "--preset", "skills", "--set", "childhood_walls=clamp"],
    "LE-LS-paper": ["--cond", "LE-LS", "--preset", "paper"],
}


def stage_evolve(args) -> int:
    """Run (or continue) the study's evolutions one after the other, each resumable."""
    import subprocess

    names = args.runs.split(",") if args.runs else list(EVOLUTIONS)
    for name in names:
        out = os.path.join(args.out, "evolve", name)
        command = [sys.executable, "-m", "imrl_jax.evolve", *EVOLUTIONS[name], "--seeds", str(args.seeds)]
        if "--generations" not in EVOLUTIONS[name]:
            command += ["--generations", str(args.generations)]
        command += ["--out", out, "--keep", "1"]
        if os.path.isdir(os.path.join(out, "checkpoints")):
            command.append("--resume")
        print(f"== {name}: {' '.join(command[1:])}", flush=True)
        code = subprocess.call(command)
        if code:
            return code
    return 0


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="stage", required=True)
    hand = sub.add_parser("hand", help="childhood with hand-made colour reinforcers over the factors")
    hand.add_argument("--out", default="experiments/results/childhood")
    hand.add_argument("--lengths", default="30000,150000,600000", help="childhood lengths (steps)")
    hand.add_argument("--walls", default="clamp,respawn")
    hand.add_argument("--rewards", default="surprise,progress")
    hand.add_argument("--rules", default="paper,extension,uniform", help=f"of {', '.join(RULES)}")
    hand.add_argument("--respawn-steps", type=int, default=20)
    hand.add_argument("--speed-bias", type=float, default=0.0, help="initial bias of the actors' speed unit")
    hand.add_argument("--name", default="hand", help="the name of the outputs (NAME.csv, .json, .png)")
    hand.add_argument("--seeds", type=int, default=4)
    hand.add_argument("--key", type=int, default=0)
    evolve = sub.add_parser("evolve", help="the study's paper-length evolutions (resumable)")
    evolve.add_argument("--out", default="experiments/results/childhood")
    evolve.add_argument("--runs", default="", help=f"comma-separated, of {', '.join(EVOLUTIONS)} (default: all)")
    evolve.add_argument("--seeds", type=int, default=3)
    evolve.add_argument("--generations", type=int, default=30)
    ceiling = sub.add_parser("ceiling", help="ideal colour followers composed, per adult rule set and task length")
    ceiling.add_argument("--out", default="experiments/results/childhood")
    ceiling.add_argument("--task-steps", default="20000,100000")
    ceiling.add_argument("--lives", type=int, default=8)
    ceiling.add_argument("--key", type=int, default=0)
    evolved = sub.add_parser("evolved", help="probes of the best individuals of evolutions")
    evolved.add_argument("runs", nargs="+", help="run directories")
    evolved.add_argument("--out", default="experiments/results/childhood")
    evolved.add_argument("--name", default="evolved", help="the CSV's name")
    evolved.add_argument("--best", type=int, default=10)
    evolved.add_argument("--key", type=int, default=1)
    heritability = sub.add_parser("heritability", help="the best individuals relived with fresh keys")
    heritability.add_argument("runs", nargs="+", help="run directories")
    heritability.add_argument("--out", default="experiments/results/childhood")
    heritability.add_argument("--best", type=int, default=10)
    heritability.add_argument("--lives", type=int, default=4)
    heritability.add_argument("--key", type=int, default=2)
    speed = sub.add_parser("speed", help="hand-made colour reinforcers with experts that start fast")
    speed.add_argument("--out", default="experiments/results/childhood")
    speed.add_argument("--preset", default="skills")
    speed.add_argument("--biases", default="0,2,4", help="initial bias of the actors' speed unit (0: the paper's)")
    speed.add_argument("--lives", type=int, default=4)
    speed.add_argument("--key", type=int, default=3)
    random = sub.add_parser("random", help="random LE-LS genomes (generation 0): fitness and probes")
    random.add_argument("--out", default="experiments/results/childhood")
    random.add_argument("--preset", default="skills")
    random.add_argument("--individuals", type=int, default=30)
    random.add_argument("--key", type=int, default=4)
    plot = sub.add_parser("plot", help="redraw the figures from the CSVs")
    plot.add_argument("--out", default="experiments/results/childhood")
    args = p.parse_args(argv)
    from imrl_jax.devices import use_host_cores

    from imrl_jax.cli import user_errors

    unknown = [r for r in getattr(args, "rules", "").split(",") if r and r not in RULES]
    runs = getattr(args, "runs", None)
    if unknown:
        p.error(f"--rules: unknown rules {unknown[0]!r} (choose from {', '.join(RULES)})")
    if isinstance(runs, str) and runs and any(r not in EVOLUTIONS for r in runs.split(",")):
        p.error(f"--runs: choose from {', '.join(EVOLUTIONS)}")
    for run in runs if isinstance(runs, list) else []:
        if not os.path.isfile(os.path.join(run, "config.json")):
            p.error(f"runs: not a run directory (no config.json): {run}")
    use_host_cores(1)
    stages = {"hand": stage_hand, "evolve": stage_evolve, "ceiling": stage_ceiling, "evolved": stage_evolved,
              "heritability": stage_heritability, "plot": stage_plot, "speed": stage_speed, "random": stage_random}
    try:
        return stages[args.stage](args)
    except user_errors() as error:  # e.g. --walls bounce, an unreadable run directory
        print(f"error: {error}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
