"""The paper's Fig. 3 and its seven claims (section 3), from a results directory of reproduce.py.

    python experiments/report.py experiments/results/cpu [--doc docs/REPRODUCTION.md] [--figures docs/reproduction]

Reads what ``experiments/reproduce.py`` wrote (the evolutions' histories and last
populations, the learning tests' curves and steady states, ``manifest.json``) and writes:

- into ``--figures``: Fig. 1 (arena and tasks), Fig. 3a and 3b per variant, Fig. 3c, the
  paths of the best evolved individuals coloured by the expert in control,
  ``summary.json``, ``specialisation.csv`` and ``claims.json``;
- into RESULTS_DIR: ``best_genomes.npz``, the 10 best genomes of each seed's last
  generation of every evolution, so that the paths can be drawn again without
  ``final_population.npz`` (which is not committed);
- ``--doc``: the markdown report, with every number labelled with the run's scale, the
  claims table with the rule that gave each verdict, and a "Discussion" section read from
  ``RESULTS_DIR/discussion.md`` (written by hand) when it exists.

The best individual of an evolution (the fittest of the last generation over all seeds)
lives again the very life that earned its fitness (:func:`imrl_jax.render.life_key`), then
drives each task for a while from the weights it ended that task with: those paths give
the trajectory figures, the expert-specialisation table (claim 7) and the stereotypy of
EE-ES (claim 4). That is one lifetime per evolved condition (about ten seconds each at the
cpu scale); ``--no-behaviour`` skips it.
"""

from __future__ import annotations

import argparse
import csv
import io
import json
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from reproduce import EVOLVED, SCALES, TESTED, VARIANTS, evolution_dir, test_dir  # noqa: E402

from imrl_jax.config import Config  # noqa: E402
from imrl_jax.learning_test import PAIR_LEVEL, pairs_both_ways, performance_curve, steady_bins  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

HOLDS, PARTLY, DOES_NOT, NOT_AVAILABLE = "holds", "partly", "does not hold", "n/a"

#: The claims as MODEL.md states them ("The paper's claims to reproduce").
CLAIMS = {
    1: "LE-LS reaches its steady best fitness in about 10 generations; EE-LS and EE-ES need about 100.",
    2: "LE-LS varies less across runs than EE-LS and EE-ES.",
    3: "EE-LS ends with a higher best fitness than LE-LS.",
    4: "EE-ES ends at about the best fitness of LE-LS, with a stereotyped (circular) path.",
    5: "In learning tests, LE-LS and EE-LS learn much faster than SLE (SLE needs about 4x longer to reach "
       "comparable performance).",
    6: "Steady state: EE-LS > SLE > LE-LS > EE-ES.",
    7: "Experts specialise in following one colour each; the selector composes them and picks a direction at "
       "junctions.",
}

# The measures behind the verdicts; RULES below states them in words for the report.
LAST_GENERATIONS = 5  # the final best fitness is the mean of this many last generations
PLATEAU_FRACTION = 0.9  # a curve has reached its plateau at this fraction of its final value
MUCH_FASTER = 2.0  # "much faster": at most half the generations or cycles
ABOUT = (0.8, 1.25)  # "about the same": a ratio in this range
NEARLY_ABOUT = (0.5, 2.0)
STEREOTYPED_TURNS = 0.75  # share of turning steps that turn the same way for a "circular" path
TURN_THRESHOLD_DEG = 1.0  # smaller heading changes are not turns
SPECIALISED_SHARE = 0.5  # an expert follows a colour: it sees it on more than half its readings
MIN_CONTROL_SHARE = 0.05  # experts in control on fewer steps are not judged
PAIRS_COMPOSED = 1 / 3  # "composes": at least this share of task pairs solved both ways
STEADY_ORDER = ("EE-LS", "SLE", "LE-LS", "EE-ES")

RULES = {
    1: f"Plateau generation = the first generation at which the best fitness (mean over seeds) reaches "
       f"{PLATEAU_FRACTION:.0%} of its final value (mean of the last {LAST_GENERATIONS} generations). "
       f"**holds** if LE-LS's is at most 1/{MUCH_FASTER:g} of both EE-LS's and EE-ES's and smaller than both; "
       f"**partly** if it is smaller than one of them; **does not hold** otherwise. (At reduced scale the "
       f"evolutions are shorter than the paper's 100 generations, so \"about 100\" shows as a plateau in the "
       f"last generations or none.)",
    2: f"Final best fitness of a seed = the mean of its last {LAST_GENERATIONS} generations' best fitness; "
       f"spread = its standard deviation over seeds. **holds** if LE-LS's spread is smaller than both EE-LS's and "
       f"EE-ES's; **partly** if smaller than one; **does not hold** otherwise.",
    3: "Difference d = mean final best fitness of EE-LS minus that of LE-LS, standard error "
       "se = sqrt(sd_EE-LS^2/n + sd_LE-LS^2/n) (sd over seeds, ddof 1). **holds** if d > 2 se; **partly** if "
       "0 < d <= 2 se; **does not hold** if d <= 0.",
    4: f"Ratio = mean final best fitness of EE-ES / that of LE-LS; \"about\" = ratio in [{ABOUT[0]}, {ABOUT[1]}]. "
       f"Stereotypy = of the steps of the best EE-ES individual's task paths that turn by more than "
       f"{TURN_THRESHOLD_DEG:g} deg, the share that turn the same way (1: always one way, as on a circle; "
       f"about 0.5: zigzags). \"circular\" = stereotypy >= {STEREOTYPED_TURNS}. **holds** if both; **partly** if "
       f"one; **does not hold** if neither.",
    5: f"For LE-LS and EE-LS in turn: level = {PLATEAU_FRACTION:.0%} of the condition's steady state; cycles to "
       f"it = the end of the first bin of the mean learning curve at or above the level, for the condition and "
       f"for SLE; ratio = SLE's cycles / the condition's (infinite when SLE never gets there). **holds** if "
       f"the ratio is >= {MUCH_FASTER:g} for both; **partly** if >= {MUCH_FASTER:g} for one or > 1 for both; "
       f"**does not hold** otherwise. (The paper's ratio is about 4.)",
    6: "Steady states (mean over runs) are compared in the six pairs the order EE-LS > SLE > LE-LS > EE-ES "
       "implies. **holds** if all 6 pairs are in that order; **partly** if 4 or 5; **does not hold** if 3 or "
       "fewer (3 of 6 is what an arbitrary order gets on average).",
    7: f"For the best LE-LS and EE-LS individuals (the paper: \"particularly true\" of them), on their adult task "
       f"paths: an expert in control on at least {MIN_CONTROL_SHARE:.0%} of the steps is *specialised* when one "
       f"colour covers more than {SPECIALISED_SHARE:.0%} of its central receptors' readings (colour_shares); "
       f"score = number of distinct colours among specialised experts (0-3). Composition: the share of (learning "
       f"test, task pair) in which both tasks of a pair reach a steady state of at least {PAIR_LEVEL:g} (the two "
       f"tasks of a pair look the same up to the first junction and turn the other way there, so any fixed "
       f"controller solves at most one: EE-ES is the control). **holds** if the score is 3 for both and the "
       f"LE-LS or EE-LS share is at least {PAIRS_COMPOSED:.2f}; **partly** if a score is at least 1 or that share "
       f"is reached; **does not hold** otherwise.",
}

#: What the paper reports for each claim (sections 3 and 4, Fig. 3).
PAPER = {
    1: "LE-LS ~10, EE-LS and EE-ES ~100 generations",
    2: "much smaller sd band for LE-LS (Fig. 3a)",
    3: "EE-LS above LE-LS at generation 100",
    4: "EE-ES at the level of LE-LS; circular path at full speed",
    5: "SLE needs nearly 4x the cycles",
    6: "EE-LS > SLE > LE-LS > EE-ES (Fig. 3c)",
    7: "one colour per expert; selector composes them per task (direct observation)",
}

PATH_STEPS = 1000  # steps each task is driven after its learning period (shares, stereotypy)
DRAWN_STEPS = 300  # of which the last ones are drawn
CHILDHOOD_DRAWN_STEPS = 1000
CHILDHOOD_TAIL = 0.25  # childhood shares: its last quarter, when the noise is nearly gone
NUM_BEST = 10  # genomes kept per seed in best_genomes.npz
SEEN = ("red", "green", "blue", "nothing")


# ----------------------------------------------------------------------------- reading


def read_json(path: str) -> dict | None:
    """A JSON file, or None when it does not exist."""
    if not os.path.isfile(path):
        return None
    with open(path) as f:
        return json.load(f)


def read_history(path: str) -> tuple[list[int], np.ndarray] | None:
    """A history.csv as (seeds, best fitness (generations, seeds)), or None when absent or empty."""
    if not os.path.isfile(path):
        return None
    with open(path) as f:
        rows = list(csv.DictReader(f))
    if not rows:
        return None
    seeds = sorted({int(r["seed"]) for r in rows})
    generations = max(int(r["generation"]) for r in rows) + 1
    best = np.full((generations, len(seeds)), np.nan)
    for r in rows:
        best[int(r["generation"]), seeds.index(int(r["seed"]))] = float(r["best"])
    return seeds, best


def read_curve(path: str) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """A learning test's curve.csv as (end cycle of each bin, mean over all tests, sd over runs)."""
    if not os.path.isfile(path):
        return None
    data = np.genfromtxt(path, delimiter=",", names=True)
    data = np.atleast_1d(data)
    return data["end_step"].astype(int), data["mean"].astype(float), data["sd_over_runs"].astype(float)


def variants_of(results: str, manifest: dict | None) -> list[str]:
    """The variants a results directory holds (the manifest's, else those with a directory)."""
    if manifest and manifest.get("variants"):
        return list(manifest["variants"])
    return [v for v in VARIANTS if os.path.isdir(os.path.join(results, v))]


def load(results: str) -> dict:
    """Everything the report reads from a results directory (missing parts are left out)."""
    manifest = read_json(os.path.join(results, "manifest.json"))
    data = dict(results=results, manifest=manifest, variants=variants_of(results, manifest), evolutions={},
                tests={})
    for variant in data["variants"]:
        for condition in EVOLVED:
            run_dir = evolution_dir(results, variant, condition)
            history = read_history(os.path.join(run_dir, "history.csv"))
            if history is not None:
                saved = read_json(os.path.join(run_dir, "config.json")) or {}
                data["evolutions"][variant, condition] = dict(dir=run_dir, seeds=history[0], best=history[1],
                                                              config=saved.get("config"),
                                                              git_commit=saved.get("git_commit"))
        for condition in TESTED:
            out_dir = test_dir(results, variant, condition)
            steady = read_json(os.path.join(out_dir, "steady.json"))
            curve = read_curve(os.path.join(out_dir, "curve.csv"))
            if steady is not None and curve is not None:
                data["tests"][variant, condition] = dict(dir=out_dir, steady=steady, steps=curve[0], mean=curve[1],
                                                         sd=curve[2], pairs_both_ways=steady.get("pairs_both_ways"))
                curves_path = os.path.join(out_dir, "curves.npz")
                if data["tests"][variant, condition]["pairs_both_ways"] is None and os.path.exists(curves_path):
                    # Tests written before steady.json kept this number: recompute it from every
                    # test's curves with the learning test's own statistics.
                    config = Config.from_dict(steady["config"])
                    with np.load(curves_path) as saved:
                        performance = performance_curve(config, saved["reaches"])
                    last = steady_bins(config, steady["steady_steps"])
                    data["tests"][variant, condition]["pairs_both_ways"] = pairs_both_ways(
                        performance[..., -last:].mean(-1))
    return data


# ----------------------------------------------------------------------------- measures (pure)


def final_best(best: np.ndarray, last: int = LAST_GENERATIONS) -> np.ndarray:
    """Each seed's final best fitness: the mean of the last ``last`` generations of best (generations, seeds)."""
    best = np.asarray(best, float)
    return best[-min(last, len(best)):].mean(0)


def plateau_generation(curve, fraction: float = PLATEAU_FRACTION, last: int = LAST_GENERATIONS) -> int | None:
    """The first generation at which ``curve`` reaches ``fraction`` of its final value (None if that is <= 0)."""
    curve = np.asarray(curve, float)
    final = curve[-min(last, len(curve)):].mean()
    if not final > 0:
        return None
    # Some of the last generations are at least their mean, so the level is always reached.
    return int(np.argmax(curve >= fraction * final))


def first_reach(steps, curve, level: float) -> int | None:
    """The end cycle of the first bin at which ``curve`` is at least ``level`` (None: never)."""
    hits = np.flatnonzero(np.asarray(curve, float) >= level)
    return int(np.asarray(steps)[hits[0]]) if len(hits) else None


def turn_consistency(headings_before, headings_after, breaks,
                     threshold_deg: float = TURN_THRESHOLD_DEG) -> float | None:
    """Of the steps that turn by more than ``threshold_deg``, the share turning the more common way (None: no turns).

    Steps after which the robot was put back at the start (``breaks``) are left out: their
    heading change is the reset, not a turn.
    """
    turn = (np.asarray(headings_after, float) - np.asarray(headings_before, float) + math.pi) % (2 * math.pi) - math.pi
    turning = turn[~np.asarray(breaks, bool) & (np.abs(turn) > math.radians(threshold_deg))]
    if not len(turning):
        return None
    left = float((turning > 0).mean())
    return max(left, 1.0 - left)


def mean_speed(positions_before, positions_after, breaks) -> float | None:
    """Mean distance moved per step (cm), leaving out the steps that ended with a reset to the start."""
    moved = np.linalg.norm(np.asarray(positions_after, float) - np.asarray(positions_before, float), axis=-1)
    moved = moved[~np.asarray(breaks, bool)]
    return float(moved.mean()) if len(moved) else None


def specialisation_score(shares, steps, min_share: float = MIN_CONTROL_SHARE,
                         specialised: float = SPECIALISED_SHARE) -> tuple[int, list]:
    """Distinct colours among specialised experts, and each expert's followed colour (None: not specialised).

    ``shares`` (K, 4: red, green, blue, nothing) and ``steps`` (K,) as from
    :func:`imrl_jax.behaviour.colour_shares`.
    """
    shares, steps = np.nan_to_num(np.asarray(shares, float)), np.asarray(steps, float)
    total = max(steps.sum(), 1.0)
    followed = []
    for row, n in zip(shares, steps):
        colour = int(np.argmax(row[:3]))
        followed.append(SEEN[colour] if n / total >= min_share and row[colour] > specialised else None)
    return len({c for c in followed if c is not None}), followed


# ----------------------------------------------------------------------------- verdicts (pure: numbers in, verdict out)


def _claim(verdict: str, measured: str, **numbers) -> dict:
    return dict(verdict=verdict, measured=measured, numbers=numbers)


def _fmt(value, digits: int = 3) -> str:
    if value is None:
        return "-"
    if isinstance(value, float) and math.isinf(value):
        return "never"
    return f"{value:.{digits}f}" if isinstance(value, float) else str(value)


def claim_evolvability(plateau: dict) -> dict:
    """Claim 1 from each evolved condition's plateau generation."""
    le, others = plateau.get("LE-LS"), [plateau.get(c) for c in ("EE-LS", "EE-ES")]
    measured = ", ".join(f"{c} {_fmt(plateau.get(c))}" for c in EVOLVED) + " (plateau generation)"
    if le is None or any(o is None for o in others):
        return _claim(NOT_AVAILABLE, measured, plateau=plateau)
    faster = [le < o for o in others]
    much = [f and MUCH_FASTER * le <= o for f, o in zip(faster, others)]
    verdict = HOLDS if all(much) else PARTLY if any(faster) else DOES_NOT
    return _claim(verdict, measured, plateau=plateau)


def claim_reliability(spread: dict) -> dict:
    """Claim 2 from each evolved condition's sd over seeds of the final best fitness."""
    measured = ", ".join(f"{c} {_fmt(spread.get(c))}" for c in EVOLVED) + " (sd over seeds)"
    le, others = spread.get("LE-LS"), [spread.get(c) for c in ("EE-LS", "EE-ES")]
    if le is None or any(o is None for o in others):
        return _claim(NOT_AVAILABLE, measured, spread=spread)
    smaller = sum(le < o for o in others)
    return _claim(HOLDS if smaller == 2 else PARTLY if smaller == 1 else DOES_NOT, measured, spread=spread)


def claim_ee_ls_higher(ee_ls, le_ls) -> dict:
    """Claim 3 from the per-seed final best fitness of EE-LS and LE-LS."""
    if ee_ls is None or le_ls is None or not len(ee_ls) or not len(le_ls):
        return _claim(NOT_AVAILABLE, "-")
    ee_ls, le_ls = np.asarray(ee_ls, float), np.asarray(le_ls, float)
    d = float(ee_ls.mean() - le_ls.mean())
    var = lambda x: float(x.var(ddof=1)) / len(x) if len(x) > 1 else 0.0  # noqa: E731
    se = math.sqrt(var(ee_ls) + var(le_ls))
    verdict = HOLDS if d > 2 * se else PARTLY if d > 0 else DOES_NOT
    return _claim(verdict, f"EE-LS {ee_ls.mean():.3f} vs LE-LS {le_ls.mean():.3f}: d = {d:+.3f}, se = {se:.3f}",
                  difference=d, standard_error=se, ee_ls=float(ee_ls.mean()), le_ls=float(le_ls.mean()))


def claim_ee_es_about(ee_es: float | None, le_ls: float | None, stereotypy: float | None,
                      speed: float | None = None) -> dict:
    """Claim 4 from the mean final best fitness of EE-ES and LE-LS and EE-ES's stereotypy (its speed is only shown)."""
    ratio = ee_es / le_ls if ee_es is not None and le_ls is not None and le_ls > 0 else None
    measured = (f"EE-ES / LE-LS final best fitness {_fmt(ee_es)} / {_fmt(le_ls)} = {_fmt(ratio, 2)}; "
                f"stereotypy {_fmt(stereotypy, 2)}" + ("" if speed is None else f", speed {speed:.2f} cm/step"))
    parts = [p for p in (None if ratio is None else ABOUT[0] <= ratio <= ABOUT[1],
                         None if stereotypy is None else stereotypy >= STEREOTYPED_TURNS) if p is not None]
    if not parts:
        return _claim(NOT_AVAILABLE, measured, ratio=ratio, stereotypy=stereotypy)
    verdict = HOLDS if len(parts) == 2 and all(parts) else PARTLY if any(parts) else DOES_NOT
    return _claim(verdict, measured, ratio=ratio, stereotypy=stereotypy)


def claim_learning_speed(curves: dict, steady: dict) -> dict:
    """Claim 5 from the learning curves ``curves[c] = (end cycles, mean)`` and the steady states ``steady[c]``."""
    ratios, cycles, texts = {}, {}, []
    if "SLE" not in curves:
        return _claim(NOT_AVAILABLE, "-")
    for c in ("LE-LS", "EE-LS"):
        if c not in curves or steady.get(c) is None or not steady[c] > 0:
            continue
        level = PLATEAU_FRACTION * steady[c]
        own, sle = first_reach(*curves[c], level), first_reach(*curves["SLE"], level)
        if own is None:  # only when curve.csv's rounding puts every bin under the level
            continue
        ratio = math.inf if sle is None else sle / own
        ratios[c], cycles[c] = ratio, dict(level=level, cycles=own, sle_cycles=sle)
        texts.append(f"{c} {own:,} vs SLE {'never' if sle is None else f'{sle:,}'} cycles to {level:.3f} "
                     f"(x{_fmt(ratio, 1)})")
    measured = "; ".join(texts) or "-"
    numbers = dict(ratio={c: (None if math.isinf(r) else r) for c, r in ratios.items()},
                   sle_never={c: math.isinf(r) for c, r in ratios.items()}, cycles=cycles)
    if len(ratios) < 2:
        return _claim(NOT_AVAILABLE, measured, **numbers)
    much = sum(r >= MUCH_FASTER for r in ratios.values())
    verdict = HOLDS if much == 2 else PARTLY if much == 1 or all(r > 1 for r in ratios.values()) else DOES_NOT
    return _claim(verdict, measured, **numbers)


def claim_ordering(steady: dict, order=STEADY_ORDER) -> dict:
    """Claim 6 from the steady states (mean over runs) of the four conditions."""
    if any(steady.get(c) is None for c in order):
        return _claim(NOT_AVAILABLE, "-")
    pairs = {f"{a} > {b}": bool(steady[a] > steady[b]) for i, a in enumerate(order) for b in order[i + 1:]}
    held = sum(pairs.values())
    ranked = sorted(order, key=lambda c: -steady[c])
    ranked = ranked[0] + "".join(f" {'=' if steady[a] == steady[b] else '>'} {b}" for a, b in zip(ranked, ranked[1:]))
    failed = [p for p, ok in pairs.items() if not ok]
    measured = (f"{ranked} (" + ", ".join(f"{c} {steady[c]:.3f}" for c in order) + f"); {held}/6 pairs hold"
                + (f"; not: {', '.join(failed)}" if failed else ""))
    verdict = HOLDS if held == 6 else PARTLY if held >= 4 else DOES_NOT
    return _claim(verdict, measured, pairs=pairs, pairs_held=held)


def claim_specialisation(scores: dict, pairs: dict | None = None) -> dict:
    """Claim 7: specialisation score (0-3 colours) of the best LS individuals; pairs solved both ways in their tests."""
    pairs = pairs or {}
    le, ee = scores.get("LE-LS"), scores.get("EE-LS")
    measured = f"distinct colours followed: LE-LS {_fmt(le)}/3, EE-LS {_fmt(ee)}/3"
    if pairs:
        measured += "; task pairs solved both ways: " + ", ".join(f"{c} {_fmt(v, 2)}" for c, v in pairs.items())
    if le is None and ee is None:
        return _claim(NOT_AVAILABLE, measured, scores=scores, pairs=pairs)
    known = [s for s in (le, ee) if s is not None]
    composed = [pairs[c] for c in ("LE-LS", "EE-LS") if pairs.get(c) is not None]
    composes = bool(composed) and max(composed) >= PAIRS_COMPOSED
    verdict = HOLDS if len(known) == 2 and all(s == 3 for s in known) and (composes or not pairs) \
        else PARTLY if any(s >= 1 for s in known) or composes else DOES_NOT
    return _claim(verdict, measured, scores=scores, pairs=pairs)


# ----------------------------------------------------------------------------- best genomes and their behaviour


def _key(variant: str, condition: str, field: str) -> str:
    return f"{variant}__{condition}__{field}"


def update_best_genomes(data: dict, num_best: int = NUM_BEST) -> dict:
    """The best genomes of every evolution, from final_population.npz where present (else from best_genomes.npz).

    Returns ``{(variant, condition): dict(genomes (S, B, G), fitness (S, B), index (S, B),
    seeds (S,), generations, config)}`` for the evolutions' own directories (EE-ES under ``paper``)
    and rewrites RESULTS_DIR/best_genomes.npz when anything came from a population.
    """
    path = os.path.join(data["results"], "best_genomes.npz")
    stored = {}
    if os.path.isfile(path):
        with np.load(path) as saved:
            stored = {name: saved[name] for name in saved.files}
    found, fresh = {}, False
    for (variant, condition), run in data["evolutions"].items():
        owner = "paper" if condition == "EE-ES" else variant
        if (owner, condition) in found:
            continue
        population = os.path.join(run["dir"], "final_population.npz")
        if os.path.isfile(population):
            with np.load(population) as pop:
                evaluated, fitness, generations = pop["evaluated"], pop["fitness"], int(pop["generation"])
                seeds = pop["seeds"]
            if generations < 1:
                continue
            order = np.argsort(-fitness, axis=1, kind="stable")[:, :num_best]
            entry = dict(genomes=np.take_along_axis(evaluated, order[:, :, None], 1),
                         fitness=np.take_along_axis(fitness, order, 1), index=order, seeds=np.asarray(seeds),
                         generations=np.asarray(generations))
            stored.update({_key(owner, condition, f): v for f, v in entry.items()})
            fresh = True
        elif _key(owner, condition, "genomes") not in stored:
            continue
        found[owner, condition] = {f: stored[_key(owner, condition, f)]
                                   for f in ("genomes", "fitness", "index", "seeds", "generations")}
        found[owner, condition]["config"] = run["config"]
    if fresh:
        buffer = io.BytesIO()
        np.savez_compressed(buffer, **stored)
        with open(path + ".tmp", "wb") as f:
            f.write(buffer.getvalue())
        os.replace(path + ".tmp", path)
    return found


def relive_best(config_dict: dict, best: dict) -> dict:
    """The fittest genome of ``best`` relives its evaluated life; then each task is driven from its final weights."""
    import jax
    import jax.numpy as jnp

    from imrl_jax.behaviour import childhood_trajectory, colour_shares, task_trajectories
    from imrl_jax.config import Config
    from imrl_jax.lifetime import live
    from imrl_jax.render import life_key

    config = Config.from_dict(config_dict)
    s = int(np.argmax(best["fitness"][:, 0]))
    genome = jnp.asarray(best["genomes"][s, 0], jnp.float32)
    seed, index, generation = int(best["seeds"][s]), int(best["index"][s, 0]), int(best["generations"]) - 1
    params = config.learning_params()
    key = life_key(config, seed, generation, index)
    result = jax.jit(live, static_argnums=1)(key, config, params, genome)
    tasks = task_trajectories(jax.random.fold_in(key, config.num_tasks + 1), config, params, result.adult_agents,
                              PATH_STEPS)
    num_experts = config.num_experts
    pooled = type(tasks[0])(*(np.stack(x) for x in zip(*tasks)))
    shares, steps = colour_shares(config, pooled, num_experts)
    out = dict(config=config, seed=seed, index=index, generation=generation, fitness=float(best["fitness"][s, 0]),
               relived_fitness=float(result.fitness), performance=[float(p) for p in result.performance],
               tasks=tasks, shares=shares, steps=steps, childhood=None,
               stereotypy=turn_consistency(pooled.seen_heading, pooled.heading, pooled.breaks),
               speed=mean_speed(pooled.seen_pos, pooled.pos, pooled.breaks),
               dominant_expert=float(np.bincount(pooled.k.reshape(-1), minlength=num_experts).max() / pooled.k.size))
    if config.condition == "LE-LS":
        childhood = childhood_trajectory(key, config, params, genome, config.childhood_steps)
        tail = childhood.window(int(config.childhood_steps * (1 - CHILDHOOD_TAIL)), config.childhood_steps)
        out["childhood"] = childhood.window(max(0, config.childhood_steps - CHILDHOOD_DRAWN_STEPS),
                                            config.childhood_steps)
        out["childhood_shares"], out["childhood_steps"] = colour_shares(config, tail, num_experts)
    return out


# ----------------------------------------------------------------------------- figures


def _curves_figure(series: dict, title: str, xlabel: str, ylabel: str, integer_x: bool = False):
    """Mean curves with a +-1 sd band, one per condition in the paper's line styles: {condition: (x, mean, sd, label)}."""
    from matplotlib.ticker import MaxNLocator

    from imrl_jax.plotting import CONDITION_STYLES, new_figure

    fig = new_figure(5.6, 3.5)
    ax = fig.add_subplot()
    banded = set()
    for condition, (x, mean, sd, label) in series.items():
        style = CONDITION_STYLES[condition]
        ax.plot(x, mean, label=label, **style)
        _band(ax, x, mean, sd, style, banded)
    ax.set_ylim(bottom=0)
    if integer_x:
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    else:
        ax.set_xlim(left=0)
    _style(ax, title, xlabel, ylabel)
    ax.legend(fontsize=7)
    fig.tight_layout()
    return fig


def fig_fitness(evolutions: dict, title: str):
    """Fig. 3a: best fitness per generation, mean over seeds with a +-1 sd band, one line per condition."""
    series = {c: (np.arange(len(best)), best.mean(1), best.std(1), f"{c} ({best.shape[1]} seeds)")
              for c, best in evolutions.items()}
    return _curves_figure(series, title, "generation", "best fitness", integer_x=True)


def fig_learning(tests: dict, title: str):
    """Fig. 3b: performance per bin of the learning tests (mean over all tests, +-1 sd over runs), x in cycles."""
    series = {c: (t["steps"], t["mean"], t["sd"], c) for c, t in tests.items()}
    return _curves_figure(series, title, "cycles of the task", "performance per bin")


def fig_steady(steady: dict, variants: list[str], title: str):
    """Fig. 3c: steady state per condition, mean over runs (dark, +-1 sd) and best run (light); a panel per variant."""
    from imrl_jax.plotting import new_figure

    fig = new_figure(3.0 * len(variants) + 0.6, 3.3)
    axes = fig.subplots(1, len(variants), sharey=True, squeeze=False)[0]
    x = np.arange(len(TESTED))
    for ax, variant in zip(axes, variants):
        rows = [steady.get((variant, c)) for c in TESTED]
        mean = [r["steady_mean"] if r else np.nan for r in rows]
        sd = [r["steady_sd"] if r else 0.0 for r in rows]
        best = [r["steady_best_run"] if r else np.nan for r in rows]
        ax.bar(x - 0.19, mean, 0.38, yerr=sd, color="0.35", capsize=3, label="mean over runs")
        ax.bar(x + 0.19, best, 0.38, color="0.75", label="best run")
        ax.set_xticks(x, TESTED, fontsize=7)
        _style(ax, variant, "", "steady-state performance" if ax is axes[0] else "")
        ax.grid(False, axis="x")
    axes[0].set_ylim(bottom=0)
    axes[-1].legend(fontsize=7)
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    return fig


def fig_paths(life: dict, title: str):
    """Each task's path after learning coloured by the expert in control, the last childhood steps, what experts see."""
    from matplotlib.patches import Circle

    from imrl_jax.plotting import EXPERT_COLOURS, SEEN_COLOURS, draw_arena, draw_path, expert_legend, new_figure

    config = life["config"]
    fig = new_figure(12.8, 7.4)
    axes = fig.subplots(2, 4).ravel()
    panels = [axes[1], axes[2], axes[3], axes[5], axes[6], axes[7]]
    for i, (ax, trajectory) in enumerate(zip(panels, life["tasks"])):
        draw_arena(ax, config)
        shown = trajectory.window(len(trajectory.k) - DRAWN_STEPS, len(trajectory.k))
        draw_path(ax, shown.pos, shown.k, shown.breaks)
        task = config.tasks[i]
        ax.plot(*task.start, "o", color="black", ms=4, zorder=5)
        ax.add_patch(Circle(task.target, config.target_radius, fc="none", ec="black", lw=1.2, zorder=5))
        ax.set_title(f"task {i + 1}: performance {life['performance'][i]:.2f} in the life\n"
                     f"after it: {int(trajectory.reached.sum())} reaches / {len(trajectory.k):,} steps", fontsize=7.5)
    ax = axes[0]
    draw_arena(ax, config, tasks=life["childhood"] is None)
    if life["childhood"] is not None:
        draw_path(ax, life["childhood"].pos, life["childhood"].k, life["childhood"].breaks, lw=0.8)
        ax.set_title(f"last {len(life['childhood'].k):,} childhood steps", fontsize=8)
    else:
        ax.set_title("arena and tasks (no childhood)", fontsize=8)
    expert_legend(ax, config.num_experts)
    ax = axes[4]
    shares = np.nan_to_num(np.asarray(life["shares"], float))
    width = 0.2
    for j, (name, colour) in enumerate(zip(SEEN, SEEN_COLOURS)):
        ax.bar(np.arange(len(shares)) + (j - 1.5) * width, shares[:, j], width, color=colour, edgecolor="black",
               lw=0.4, label=name)
    ax.set_xticks(range(len(shares)), [f"expert {e + 1}\n{int(n):,} steps" for e, n in enumerate(life["steps"])],
                  fontsize=7)
    for e, label in enumerate(ax.get_xticklabels()):
        label.set_color(EXPERT_COLOURS[e % len(EXPERT_COLOURS)])
    ax.set_ylim(0, 1)
    _style(ax, "what each expert sees (central receptors)", "", "share of readings")
    ax.legend(fontsize=6, ncol=2)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    return fig


def _band(ax, x, mean, sd, style: dict, banded: set) -> None:
    """A +-1 sd band; for a second condition drawn in the same colour, thin edge lines in its own line style."""
    colour = style.get("color", "0.5")
    if colour in banded:
        for edge in (mean - sd, mean + sd):
            ax.plot(x, edge, color=colour, lw=0.6, ls=style.get("ls", "-"), alpha=0.6)
    else:
        ax.fill_between(x, mean - sd, mean + sd, color=colour, alpha=0.13, lw=0)
        banded.add(colour)


def _style(ax, title: str, xlabel: str, ylabel: str) -> None:
    from imrl_jax.plotting import style_axis

    style_axis(ax, title, xlabel, ylabel)


# ----------------------------------------------------------------------------- the document


def scale_label(manifest: dict | None) -> str:
    """The sizes the numbers were measured at, in one short line (every table and figure names it)."""
    if not manifest:
        return "unknown scale (no manifest.json)"
    sizes = manifest.get("sizes", {})
    number = lambda name: f"{sizes[name]:,}" if isinstance(sizes.get(name), int) else "?"  # noqa: E731
    return (f"{manifest.get('scale', '?')} scale: {number('seeds')} seeds x {number('generations')} generations, "
            f"lives of {number('childhood_steps')} + 6 x {number('task_steps')} steps, learning tests of "
            f"{number('test_steps')} cycles per task")


def sizes_table(data: dict) -> str:
    """The run's sizes beside the paper's, with the fraction of the paper's where they differ."""
    manifest = data["manifest"] or {}
    sizes, paper = manifest.get("sizes", {}), SCALES["paper"]
    config = next((run["config"] for run in data["evolutions"].values() if run.get("config")), None) or {}
    population = (config.get("population_size", sizes.get("population")),
                  config.get("num_parents", sizes.get("parents")))

    def cell(value, reference):
        if value is None:
            return "?"
        if isinstance(value, tuple):
            return ", ".join("?" if v is None else f"{v:,}" for v in value)
        ratio = value / reference
        return f"{value:,}" + ("" if ratio == 1 else f" ({_fraction(ratio)})")

    rows = [("seeds (runs)", "seeds"), ("generations", "generations"), ("childhood steps", "childhood_steps"),
            ("steps per adult task (6 tasks)", "task_steps"), ("learning test: best individuals per run", "best"),
            ("learning test: tests per individual", "tests"), ("learning test: cycles per task", "test_steps"),
            ("steady state: last cycles", "steady_steps")]
    body = [[name, cell(sizes.get(key), paper[key]), f"{paper[key]:,}"] for name, key in rows]
    body.insert(2, ["population, parents", cell(population, None), "50, 10"])
    return table(["", f"this run ({manifest.get('scale', 'unknown')} scale)", "paper"], body)


def _fraction(ratio: float) -> str:
    inverse = 1 / ratio
    return f"1/{inverse:g}" if ratio < 1 and abs(inverse - round(inverse)) < 1e-9 else f"x{ratio:.3g}"


def pipeline_command(results: str, manifest: dict | None) -> str:
    """The command that (re)makes a results directory."""
    if not manifest:
        return "python experiments/reproduce.py (scale unknown)"
    scale = manifest.get("scale", "?")
    command = f"python experiments/reproduce.py --scale {scale}"
    default = os.path.join(ROOT, "experiments", "results", scale)
    if os.path.abspath(results) != os.path.abspath(default):
        command += f" --out {results}"
    if list(manifest.get("variants", VARIANTS)) != list(VARIANTS):
        command += f" --variants {','.join(manifest['variants'])}"
    target = {"cpu": "make reproduce-cpu", "paper": "make reproduce"}.get(scale)
    plain = command == f"python experiments/reproduce.py --scale {scale}"
    return f"`{target}` (`{command}`)" if target and plain else f"`{command}`"


def table(header: list[str], rows: list[list]) -> str:
    """A markdown table."""
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(lines)


def measure(data: dict, lives: dict) -> dict:
    """Every number of the report: per variant, the evolutions' and tests' statistics and the claims."""
    out = {}
    for variant in data["variants"]:
        evolution = {}
        for condition in EVOLVED:
            run = data["evolutions"].get((variant, condition))
            if run is None:
                continue
            final = final_best(run["best"])
            evolution[condition] = dict(
                final_best_mean=float(final.mean()), final_best_sd=float(final.std()),
                final_best_per_seed=[float(v) for v in final], seeds=run["seeds"], generations=len(run["best"]),
                last_generations_averaged=min(LAST_GENERATIONS, len(run["best"])),
                plateau_generation=plateau_generation(run["best"].mean(1)),
                best_per_generation_mean=[float(v) for v in run["best"].mean(1)],
                best_per_generation_sd=[float(v) for v in run["best"].std(1)])
        tests = {}
        for condition in TESTED:
            test = data["tests"].get((variant, condition))
            if test is None:
                continue
            s = test["steady"]
            tests[condition] = {k: s.get(k) for k in ("steady_mean", "steady_sd", "steady_best_run", "best_run",
                                                      "steady_per_run", "steady_per_task", "whole_test_mean",
                                                      "num_runs", "num_best", "num_tests", "task_steps",
                                                      "steady_steps", "num_bins")}
            tests[condition]["pairs_both_ways"] = test.get("pairs_both_ways")
        get = lambda d, c, k: d[c][k] if c in d else None  # noqa: E731
        steady = {c: get(tests, c, "steady_mean") for c in TESTED}
        ee_es_life = lives.get(("paper", "EE-ES"))
        scores = {}
        for condition in ("LE-LS", "EE-LS"):
            life = lives.get((variant, condition))
            if life is not None:
                scores[condition] = specialisation_score(life["shares"], life["steps"])[0]
        claims = {
            1: claim_evolvability({c: get(evolution, c, "plateau_generation") for c in EVOLVED}),
            2: claim_reliability({c: get(evolution, c, "final_best_sd") for c in EVOLVED}),
            3: claim_ee_ls_higher(get(evolution, "EE-LS", "final_best_per_seed"),
                                  get(evolution, "LE-LS", "final_best_per_seed")),
            4: claim_ee_es_about(get(evolution, "EE-ES", "final_best_mean"), get(evolution, "LE-LS", "final_best_mean"),
                                 ee_es_life["stereotypy"] if ee_es_life else None,
                                 ee_es_life["speed"] if ee_es_life else None),
            5: claim_learning_speed({c: (data["tests"][variant, c]["steps"], data["tests"][variant, c]["mean"])
                                     for c in TESTED if (variant, c) in data["tests"]}, steady),
            6: claim_ordering(steady),
            7: claim_specialisation(scores, {c: data["tests"][variant, c]["pairs_both_ways"] for c in EVOLVED
                                             if data["tests"].get((variant, c), {}).get("pairs_both_ways") is not None}),
        }
        out[variant] = dict(evolution=evolution, learning_tests=tests, claims=claims)
    return out


def specialisation_rows(lives: dict) -> list[dict]:
    """One row per expert of each best individual and phase (adult tasks; LE-LS also the end of childhood)."""
    rows = []
    for (variant, condition), life in lives.items():
        phases = [("adult tasks", life["shares"], life["steps"])]
        if life.get("childhood_shares") is not None:
            phases.append((f"childhood, last {CHILDHOOD_TAIL:.0%}", life["childhood_shares"], life["childhood_steps"]))
        for phase, shares, steps in phases:
            followed = specialisation_score(shares, steps)[1]
            total = max(int(np.sum(steps)), 1)
            for e, (row, n) in enumerate(zip(shares, steps)):
                rows.append(dict(variant="both" if condition == "EE-ES" else variant, condition=condition, phase=phase,
                                 seed=life["seed"], generation=life["generation"], expert=e + 1, steps=int(n),
                                 control_share=round(int(n) / total, 4),
                                 **{name: (None if not np.isfinite(v) else round(float(v), 4))
                                    for name, v in zip(SEEN, row)},
                                 follows=followed[e] or ""))
    return rows


def write_document(path: str, figures: str, data: dict, numbers: dict, lives: dict, spec_rows: list[dict],
                   written: dict) -> None:
    """The markdown report."""
    from imrl_jax.checkpoint import git_commit

    manifest, results = data["manifest"], data["results"]
    label = scale_label(manifest)
    reduced = not manifest or manifest.get("scale") != "paper"
    doc_dir = os.path.dirname(os.path.abspath(path))
    rel = lambda name: os.path.relpath(os.path.join(figures, name), doc_dir)  # noqa: E731
    out = ["# Reproduction of Schembri, Mirolli & Baldassarre (2007): Fig. 3 and the seven claims", ""]
    inside = os.path.abspath(results).startswith(ROOT + os.sep)
    out += [f"Written by `experiments/report.py` from `{os.path.relpath(results, ROOT) if inside else results}`. "
            f"**All numbers below are at the {label}.**", "", sizes_table(data)]
    if reduced:
        out += ["", "This is a **reduced-scale** reproduction: fewer seeds and generations and shorter lives and "
                    "learning tests than the paper's (10 seeds, 100 generations, 150,000 childhood steps, 100,000 "
                    "steps per task, tests of 10 best x 10 tests x 1,000,000 cycles). Its numbers are not the "
                    "paper's numbers; the claims are judged on the shapes and orders the paper reports."]
    commits = sorted({c for c in [run.get("git_commit") for run in data["evolutions"].values()]
                      + [t["steady"].get("git_commit") for t in data["tests"].values()] if c})
    out += ["", f"- Command: {pipeline_command(results, manifest)}",
            f"- Results made at commit `{(manifest or {}).get('git_commit', 'unknown')}`"
            + (f" (stages ran at {', '.join(f'`{c[:10]}`' for c in commits)})" if len(commits) > 1 else ""),
            f"- Report written at commit `{git_commit()}`" + (" (with uncommitted changes)" if _dirty() else ""),
            f"- Variants: {', '.join(data['variants'])} (`paper`: the learning rules as written; `extension`: "
            f"MODEL.md's learning extensions at the `extension` preset). EE-ES learns nothing, so its one evolution "
            f"serves both."]
    if manifest and manifest.get("stages"):
        out += ["", "<details><summary>Stages (commands and seconds)</summary>", "",
                table(["stage", "command", "seconds"],
                      [[name, f"`{s['command']}`", s.get("seconds", "")] for name, s in manifest["stages"].items()]),
                "", "</details>"]

    out += ["", "## The arena and the tasks (Fig. 1)", "", f"![arena and tasks]({rel(written['arena'])})"]

    out += ["", "## Fig. 3a: evolution of the best fitness", "",
            f"Best fitness per generation, mean over seeds with a band of +-1 sd ({label})."]
    for variant in data["variants"]:
        if variant in written["fig3a"]:
            out += ["", f"**{variant}**", "", f"![Fig. 3a, {variant}]({rel(written['fig3a'][variant])})"]
    rows = []
    expected = ((manifest or {}).get("sizes") or {}).get("generations")
    for variant in data["variants"]:
        for condition, e in numbers[variant]["evolution"].items():
            life = lives.get(("paper" if condition == "EE-ES" else variant, condition))
            rows.append([variant, condition, f"{e['final_best_mean']:.3f} +- {e['final_best_sd']:.3f}",
                         ", ".join(f"{v:.3f}" for v in e["final_best_per_seed"]), _fmt(e["plateau_generation"]),
                         e["generations"] if e["generations"] == expected else f"{e['generations']} of {expected}",
                         "-" if life is None else f"seed {life['seed']}, gen {life['generation']}: "
                                                  f"{life['fitness']:.3f} (relived {life['relived_fitness']:.3f})"])
    out += ["", f"Final best fitness = mean of each seed's last {LAST_GENERATIONS} generations; mean +- sd over "
                f"seeds. Plateau = first generation at {PLATEAU_FRACTION:.0%} of the final value of the mean curve. "
                f"({label})", "",
            table(["variant", "condition", "final best fitness", "per seed", "plateau generation", "generations",
                   "best individual (fitness)"], rows)]

    out += ["", "## Fig. 3b: learning tests", "",
            f"Performance per bin (reaches / the bin's theoretical maximum), mean over all tests and tasks, band "
            f"+-1 sd over runs ({label}). LE-LS tests start with a fresh childhood; EE-ES does not learn; SLE "
            f"learns from scratch."]
    for variant in data["variants"]:
        if variant in written["fig3b"]:
            out += ["", f"**{variant}**", "", f"![Fig. 3b, {variant}]({rel(written['fig3b'][variant])})"]

    out += ["", "## Fig. 3c: steady state", ""]
    if written.get("fig3c"):
        out += [f"![Fig. 3c]({rel(written['fig3c'])})", ""]
    rows = []
    for variant in data["variants"]:
        for condition, t in numbers[variant]["learning_tests"].items():
            rows.append([variant, condition, f"{t['steady_mean']:.3f} +- {t['steady_sd']:.3f}",
                         f"{t['steady_best_run']:.3f} (run {t['best_run']})",
                         ", ".join(f"{v:.2f}" for v in t["steady_per_task"]), f"{t['whole_test_mean']:.3f}",
                         f"{t['num_runs']} x {t['num_best']} x {t['num_tests']}"])
    out += [f"Steady state = mean performance over the last cycles of each test (see the scale); mean +- sd over "
            f"runs, best run, per task (mean over runs). ({label})", "",
            table(["variant", "condition", "steady state (mean +- sd over runs)", "best run", "per task 1-6",
                   "whole test", "runs x best x tests"], rows)]

    out += ["", "## Behaviour of the best evolved individuals", "",
            f"The fittest individual of the last generation over all seeds of each evolution relives the life that "
            f"earned its fitness (\"relived\" above: the same keys), then drives each task for {PATH_STEPS:,} steps "
            f"from the weights it ended that task with (its selector still learning, as in adulthood). Drawn: the "
            f"last {DRAWN_STEPS} of them per task, coloured by the expert in control; for LE-LS also the last "
            f"{CHILDHOOD_DRAWN_STEPS:,} childhood steps. The bars show, per expert, the share of its control steps "
            f"on which the retina's central receptors see red, green, blue or nothing ({label}). The genomes are "
            f"kept in `best_genomes.npz` beside the results, so that these paths can be drawn again."]
    if not written["paths"]:
        out += ["", "(not drawn: no population or best_genomes.npz, or `--no-behaviour`)"]
    for (variant, condition), name in written["paths"].items():
        life = lives[variant, condition]
        header = "EE-ES (both variants)" if condition == "EE-ES" else f"{condition}, {variant}"
        out += ["", f"**{header}**: stereotypy (share of turns the same way) {_fmt(life['stereotypy'], 2)}, "
                    f"speed {_fmt(life['speed'], 2)} cm/step (at most {life['config'].max_speed:g}), most-used "
                    f"expert in control {life['dominant_expert']:.0%} of the steps", "",
                f"![paths {header}]({rel(name)})"]

    out += ["", "### Expert specialisation", "",
            f"Share of each expert's control steps' central readings by colour (`imrl_jax.behaviour.colour_shares`); "
            f"*follows* names the colour of a specialised expert (in control on at least {MIN_CONTROL_SHARE:.0%} of "
            f"the steps, one colour on more than {SPECIALISED_SHARE:.0%} of its readings). Also in "
            f"`{os.path.basename(written['specialisation'])}`. ({label})", ""]
    if spec_rows:
        out.append(table(["variant", "condition", "phase", "expert", "control", *SEEN, "follows"],
                         [[r["variant"], r["condition"], r["phase"], r["expert"], f"{r['control_share']:.0%}",
                           *(_fmt(r[name], 2) for name in SEEN), r["follows"] or "-"] for r in spec_rows]))
    else:
        out.append("(no individual was simulated)")

    out += ["", "## The seven claims", "", f"Measured at the {label}. The verdicts follow the rules below, "
                                           "computed by `experiments/report.py` (also in `claims.json`).", ""]
    rows = []
    for n, text in CLAIMS.items():
        for variant in data["variants"]:
            c = numbers[variant]["claims"][n]
            rows.append([n, text if variant == data["variants"][0] else "", variant, c["measured"], PAPER[n],
                         f"**{c['verdict']}**"])
    out.append(table(["#", "claim", "variant", "measured", "paper", "verdict"], rows))
    out += ["", "### Rules", ""] + [f"{n}. {rule}" for n, rule in RULES.items()]

    discussion = os.path.join(results, "discussion.md")
    out += ["", "## Discussion", ""]
    if os.path.isfile(discussion):
        with open(discussion) as f:
            out.append(f.read().strip())
    else:
        out.append("(no discussion written yet)")
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    with open(path, "w") as f:
        f.write("\n".join(out) + "\n")


def _dirty() -> bool:
    """Whether the code that makes the report differs from its commit (the commit alone would not remake it).

    Only the package and the experiment scripts count: the report's own outputs and the
    results it reads are tracked files too, and rewriting them must not flag the report.
    """
    import subprocess

    try:
        out = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no", "--", "imrl_jax",
                              "experiments/*.py"], cwd=ROOT, capture_output=True, text=True, timeout=10)
        return bool(out.stdout.strip())
    except (OSError, subprocess.SubprocessError):
        return False


# ----------------------------------------------------------------------------- main


def _jsonable(value):
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def run(results: str, doc: str, figures: str, behaviour: bool = True) -> dict:
    """Write the figures, the summaries and the document; return the paths written."""
    from imrl_jax.config import make_config
    from imrl_jax.plotting import plot_arena, save

    data = load(results)
    if not data["evolutions"] and not data["tests"]:
        raise FileNotFoundError(f"{results}: no evolution or learning test found "
                                f"(not a results directory of experiments/reproduce.py?)")
    os.makedirs(figures, exist_ok=True)
    label = scale_label(data["manifest"])
    short = (data["manifest"] or {}).get("scale", "unknown") + " scale"
    written = dict(fig3a={}, fig3b={}, paths={})

    written["arena"] = save(plot_arena(make_config("paper"), "the arena and the six tasks"),
                            os.path.join(figures, "fig1_arena.png"))
    for variant in data["variants"]:
        evolutions = {c: data["evolutions"][variant, c]["best"] for c in EVOLVED if (variant, c) in data["evolutions"]}
        if evolutions:
            written["fig3a"][variant] = save(fig_fitness(evolutions, f"Fig. 3a, {variant} rules ({short})"),
                                             os.path.join(figures, f"fig3a_{variant}.png"))
        tests = {c: data["tests"][variant, c] for c in TESTED if (variant, c) in data["tests"]}
        if tests:
            written["fig3b"][variant] = save(fig_learning(tests, f"Fig. 3b, {variant} rules ({short})"),
                                             os.path.join(figures, f"fig3b_{variant}.png"))
    steady = {k: t["steady"] for k, t in data["tests"].items()}
    if steady:
        variants = [v for v in data["variants"] if any((v, c) in steady for c in TESTED)]
        written["fig3c"] = save(fig_steady(steady, variants, f"Fig. 3c: steady state ({short})"),
                                os.path.join(figures, "fig3c.png"))

    best = update_best_genomes(data)
    lives = {}
    if behaviour:
        for (variant, condition), entry in best.items():
            if entry["config"] is None:
                continue
            print(f"reliving the best {condition} individual ({variant})", flush=True)
            life = lives[variant, condition] = relive_best(entry["config"], entry)
            name = f"paths_{condition}.png" if condition == "EE-ES" else f"paths_{variant}_{condition}.png"
            title = (f"{condition}{'' if condition == 'EE-ES' else f', {variant} rules'}: best individual (seed "
                     f"{life['seed']}, generation {life['generation']}, fitness {life['fitness']:.3f}, relived "
                     f"{life['relived_fitness']:.3f}); {short}\npaths: the last {DRAWN_STEPS} of {PATH_STEPS:,} "
                     f"steps driven after each task's learning period, coloured by the expert in control")
            written["paths"][variant, condition] = save(fig_paths(life, title), os.path.join(figures, name))

    numbers = measure(data, lives)
    spec_rows = specialisation_rows(lives)
    written["specialisation"] = os.path.join(figures, "specialisation.csv")
    with open(written["specialisation"], "w", newline="") as f:
        fields = ["variant", "condition", "phase", "seed", "generation", "expert", "steps", "control_share", *SEEN,
                  "follows"]
        writer = csv.DictWriter(f, fields)
        writer.writeheader()
        writer.writerows(spec_rows)

    manifest = data["manifest"] or {}
    from imrl_jax.checkpoint import git_commit

    summary = dict(scale=manifest.get("scale", "unknown"), scale_label=label, sizes=manifest.get("sizes"),
                   variants=data["variants"], command=pipeline_command(results, data["manifest"]).replace("`", ""),
                   results_commit=manifest.get("git_commit"), report_commit=git_commit(),
                   stages=manifest.get("stages", {}),
                   evolution={v: numbers[v]["evolution"] for v in numbers},
                   learning_tests={v: numbers[v]["learning_tests"] for v in numbers},
                   best_individuals={f"{v}/{c}": dict(seed=life["seed"], index=life["index"],
                                                      generation=life["generation"], fitness=life["fitness"],
                                                      relived_fitness=life["relived_fitness"],
                                                      performance=life["performance"],
                                                      stereotypy=life["stereotypy"], speed=life["speed"],
                                                      dominant_expert_share=life["dominant_expert"])
                                     for (v, c), life in lives.items()})
    claims = dict(scale=summary["scale"], scale_label=label, rules={str(n): r for n, r in RULES.items()},
                  claims={str(n): dict(text=text, paper=PAPER[n],
                                       variants={v: numbers[v]["claims"][n] for v in numbers})
                          for n, text in CLAIMS.items()})
    for name, content in (("summary.json", summary), ("claims.json", claims)):
        written[name] = os.path.join(figures, name)
        with open(written[name], "w") as f:
            json.dump(_jsonable(content), f, indent=2)
            f.write("\n")
    write_document(doc, figures, data, numbers, lives, spec_rows, written)
    written["doc"] = doc
    return written


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("results", metavar="RESULTS_DIR", help="a results directory of experiments/reproduce.py")
    p.add_argument("--doc", default=os.path.join(ROOT, "docs", "REPRODUCTION.md"), help="the markdown report")
    p.add_argument("--figures", default=os.path.join(ROOT, "docs", "reproduction"),
                   help="directory of the figures and summaries")
    p.add_argument("--no-behaviour", action="store_true", help="skip reliving the best individuals (paths, claim 7)")
    args = p.parse_args(argv)
    if not os.path.isdir(args.results):
        print(f"error: RESULTS_DIR: {args.results} is not a directory", file=sys.stderr)
        return 2
    try:
        written = run(args.results, args.doc, args.figures, behaviour=not args.no_behaviour)
    except FileNotFoundError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    print(f"wrote {written['doc']} and the figures and summaries in {args.figures}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
