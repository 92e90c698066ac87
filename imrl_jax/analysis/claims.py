"""The paper's seven claims (sections 3 and 4): the measures behind them and their verdict rules, pure functions from
measured numbers to a verdict, and the rules in words."""

from __future__ import annotations

import math

import numpy as np

from imrl_jax.conditions import PAPER as TESTED, PAPER_EVOLVED as EVOLVED
from imrl_jax.analysis.steady_state import PAIR_LEVEL

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
STEREOTYPED_TURNS = 0.75  # share of turning steps that turn the same way for a "circular" path
TURN_THRESHOLD_DEG = 1.0  # smaller heading changes are not turns
SPECIALISED_SHARE = 0.5  # an expert follows a colour: it sees it on more than half its readings
MIN_CONTROL_SHARE = 0.05  # experts in control on fewer steps are not judged
PAIRS_COMPOSED = 1 / 3  # "composes": at least this share of task pairs solved both ways
STEADY_ORDER = ("EE-LS", "SLE", "LE-LS", "EE-ES")
MUCH_SMALLER = 0.5  # claim 2: "much smaller" spread, at most this fraction of the other's
ORDER_SE = 2.0  # claim 6: a pair is ordered when the difference exceeds this many standard errors
SPECIALISED_MAJORITY = 0.5  # claim 7: share of probed individuals that must follow 3 colours
NUM_BEST = 10  # claim 7: the best individuals of each seed that are probed (those kept in best_genomes.npz)

RULES = {
    1: f"Plateau generation = the first generation at which the best fitness (mean over seeds) reaches "
       f"{PLATEAU_FRACTION:.0%} of its final value (mean of the last {LAST_GENERATIONS} generations). "
       f"**holds** if LE-LS's is at most 1/{MUCH_FASTER:g} of both EE-LS's and EE-ES's and smaller than both; "
       f"**partly** if it is smaller than one of them; **does not hold** otherwise. (At reduced scale the "
       f"evolutions are shorter than the paper's 100 generations, so \"about 100\" shows as a plateau in the "
       f"last generations or none.)",
    2: f"Final best fitness of a seed = the mean of its last {LAST_GENERATIONS} generations' best fitness; "
       f"spread = its standard deviation over seeds. \"Much smaller\" = at most {MUCH_SMALLER:g} of the other's. "
       f"**holds** if LE-LS's spread is at most {MUCH_SMALLER:g} of both EE-LS's and EE-ES's; **partly** if at most "
       f"{MUCH_SMALLER:g} of one, or smaller than both; **does not hold** otherwise.",
    3: "Difference d = mean final best fitness of EE-LS minus that of LE-LS, standard error "
       "se = sqrt(sd_EE-LS^2/n + sd_LE-LS^2/n) (sd over seeds, ddof 1). **holds** if d > 2 se; **partly** if "
       "0 < d <= 2 se; **does not hold** if d <= 0.",
    4: f"Ratio = mean final best fitness of EE-ES / that of LE-LS; \"about\" = ratio in [{ABOUT[0]}, {ABOUT[1]}]. "
       f"Stereotypy of a task = of the steps of the best EE-ES individual's path in that task that turn by more "
       f"than {TURN_THRESHOLD_DEG:g} deg, the share that turn the same way (1: always one way, as on a circle; "
       f"about 0.5: zigzags), per task, so that a circle in one task is not averaged away with the others. "
       f"\"circular\" = stereotypy >= {STEREOTYPED_TURNS} in at least one task. **holds** if both; **partly** if "
       f"one; **does not hold** if neither.",
    5: f"SLE's action noise must anneal over a fixed number of cycles of a task (`sle_noise_steps`; the pipeline "
       f"uses the adult task length), not over the whole test: otherwise SLE gets good only at the test's end "
       f"whatever its length, and the comparison is **n/a**. For LE-LS and EE-LS in turn: level = "
       f"{PLATEAU_FRACTION:.0%} of the condition's steady state; cycles to it = the end of the first bin of the "
       f"mean learning curve at or above the level, for the condition and for SLE; ratio = SLE's cycles / the "
       f"condition's. When SLE never reaches the level it is reported as \"never reached\" (the ratio is only "
       f"bounded below by the test's length). **holds** if SLE reaches both levels and the ratio is >= "
       f"{MUCH_FASTER:g} for both; **partly** if a measured ratio is >= {MUCH_FASTER:g}, or both measured ratios "
       f"are > 1, or SLE never reaches a level; **does not hold** otherwise. (The paper's ratio is about 4.) "
       f"In the claims study (docs/CLAIMS.md) the paper's own reading, SLE's noise annealed over the whole "
       f"1,000,000-cycle test, is measured at that length rather than called n/a: the test's length is the paper's, "
       f"so the ratio is what the paper's SLE would show, though it would change with another length.",
    6: f"Steady states (mean over runs) are compared in the six pairs the order EE-LS > SLE > LE-LS > EE-ES "
       f"implies. A pair is *in order* when the difference exceeds {ORDER_SE:g} standard errors (se = "
       f"sqrt(sd_a^2/n_a + sd_b^2/n_b), sd over runs, ddof 1), *reversed* when it is below -{ORDER_SE:g} se, "
       f"*tied* otherwise. **holds** if all 6 pairs are in order; **partly** if 4 or 5; **does not hold** if 3 or "
       f"fewer (3 of 6 is what an arbitrary order gets on average).",
    7: f"For the {NUM_BEST} best LE-LS and EE-LS individuals of every seed (LE-LS after a fresh childhood with its "
       f"run's config): each expert is driven alone from fixed starts before junctions "
       f"(`imrl_jax.analysis.behaviour.specialisation`) and follows colour c when it takes c at >= 75 % of the junctions "
       f"offering it; colours = distinct colours its experts follow (0-3); *specialised* individual = 3 colours. "
       f"Composition: the share of (learning test, task pair) in which both tasks of a pair reach a steady state "
       f"of at least {PAIR_LEVEL:g} (the two tasks of a pair look the same up to the first junction and turn the "
       f"other way there, so any fixed controller solves at most one: EE-ES is the control). **holds** if at least "
       f"{SPECIALISED_MAJORITY:.0%} of the individuals are specialised in both LE-LS and EE-LS and the LE-LS or "
       f"EE-LS share is at least {PAIRS_COMPOSED:.2f}; **partly** if that many are specialised in one of them, or "
       f"the mean number of colours is >= 2 in one, or that share is reached; **does not hold** otherwise.",
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

SEEN = ("red", "green", "blue", "nothing")


# ----------------------------------------------------------------------------- measures


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
    :func:`imrl_jax.analysis.behaviour.colour_shares`.
    """
    shares, steps = np.nan_to_num(np.asarray(shares, float)), np.asarray(steps, float)
    total = max(steps.sum(), 1.0)
    followed = [SEEN[colour] if n / total >= min_share and row[colour] > specialised else None
                for row, n, colour in zip(shares, steps, (int(np.argmax(row[:3])) for row in shares))]
    return len({c for c in followed if c is not None}), followed


# ----------------------------------------------------------------------------- verdicts (numbers in, verdict out)


def _claim(verdict: str, measured: str, **numbers) -> dict:
    return dict(verdict=verdict, measured=measured, numbers=numbers)


def _verdict(holds, partly) -> str:
    """**holds** if ``holds``, else **partly** if ``partly``, else **does not hold**."""
    return HOLDS if holds else PARTLY if partly else DOES_NOT


def _tally(kept: dict, parts: list, what: str, **numbers) -> dict:
    """A claim over several comparisons, ``kept[name]`` whether each keeps to it: holds if all do, partly if some."""
    held = sum(kept.values())
    return _claim(NOT_AVAILABLE if not kept else _verdict(held == len(kept), held),
                  "; ".join(parts) + f" ({held} of {len(kept)} {what})", **numbers)


def _le_ls_against_ee(values: dict, what: str):
    """LE-LS's value, EE-LS's and EE-ES's, and the measured text of every evolved condition's (``what`` it is)."""
    return (values.get("LE-LS"), [values.get(c) for c in ("EE-LS", "EE-ES")],
            ", ".join(f"{c} {_fmt(values.get(c))}" for c in EVOLVED) + f" ({what})")


def _standard_error(a: np.ndarray, b: np.ndarray) -> float:
    """The standard error of mean(a) - mean(b): sqrt(sd_a^2/n_a + sd_b^2/n_b), sd with ddof 1 (0 for one value)."""
    var = lambda x: float(x.var(ddof=1)) / len(x) if len(x) > 1 else 0.0  # noqa: E731
    return math.sqrt(var(a) + var(b))


def _difference(a, b) -> tuple[float, float]:
    """mean(a) - mean(b) and its standard error (claim 3's)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float(a.mean() - b.mean()), _standard_error(a, b)


def _fmt(value, digits: int = 3) -> str:
    if value is None:
        return "-"
    if isinstance(value, float) and math.isinf(value):
        return "never"
    return f"{value:.{digits}f}" if isinstance(value, float) else str(value)


def claim_evolvability(plateau: dict) -> dict:
    """Claim 1 from each evolved condition's plateau generation."""
    le, others, measured = _le_ls_against_ee(plateau, "plateau generation")
    if None in (le, *others):
        return _claim(NOT_AVAILABLE, measured, plateau=plateau)
    return _claim(_verdict(all(le < o and MUCH_FASTER * le <= o for o in others), any(le < o for o in others)),
                  measured, plateau=plateau)


def claim_reliability(spread: dict) -> dict:
    """Claim 2 from each evolved condition's sd over seeds of the final best fitness."""
    le, others, measured = _le_ls_against_ee(spread, "sd over seeds")
    if None in (le, *others):
        return _claim(NOT_AVAILABLE, measured, spread=spread)
    much = sum(le <= MUCH_SMALLER * o for o in others)
    measured += f"; LE-LS's sd is at most {MUCH_SMALLER:g}x that of {much} of the 2 EE conditions"
    return _claim(_verdict(much == 2, much == 1 or all(le < o for o in others)), measured, spread=spread,
                  much_smaller=much)


def claim_ee_ls_higher(ee_ls, le_ls) -> dict:
    """Claim 3 from the per-seed final best fitness of EE-LS and LE-LS."""
    if ee_ls is None or le_ls is None or not len(ee_ls) or not len(le_ls):
        return _claim(NOT_AVAILABLE, "-")
    d, se = _difference(ee_ls, le_ls)
    ee_ls, le_ls = float(np.mean(ee_ls)), float(np.mean(le_ls))
    return _claim(_verdict(d > 2 * se, d > 0), f"EE-LS {ee_ls:.3f} vs LE-LS {le_ls:.3f}: d = {d:+.3f}, se = {se:.3f}",
                  difference=d, standard_error=se, ee_ls=ee_ls, le_ls=le_ls)


def claim_ee_es_about(ee_es: float | None, le_ls: float | None, stereotypy, speed: float | None = None) -> dict:
    """Claim 4 from the mean final best fitness of EE-ES and LE-LS and EE-ES's stereotypy per task (speed only shown).

    ``stereotypy``: one value per task (None for a task without turns), or None when no path was measured.
    """
    ratio = ee_es / le_ls if ee_es is not None and le_ls is not None and le_ls > 0 else None
    known = [s for s in (stereotypy or []) if s is not None]
    circular = sum(s >= STEREOTYPED_TURNS for s in known)
    per_task = "-" if stereotypy is None else ", ".join(_fmt(s, 2) for s in stereotypy)
    measured = (f"EE-ES / LE-LS final best fitness {_fmt(ee_es)} / {_fmt(le_ls)} = {_fmt(ratio, 2)}; "
                f"stereotypy per task {per_task}" + (f" ({circular} of {len(stereotypy)} circular)" if known else "")
                + ("" if speed is None else f", speed {speed:.2f} cm/step"))
    about = ratio is not None and ABOUT[0] <= ratio <= ABOUT[1]
    # without a ratio, n/a: the path alone cannot say whether EE-ES is at LE-LS's level
    verdict = NOT_AVAILABLE if ratio is None else _verdict(about and circular >= 1, about or circular >= 1)
    return _claim(verdict, measured, ratio=ratio, stereotypy=stereotypy, circular_tasks=circular)


def claim_learning_speed(curves: dict, steady: dict, sle_noise_steps: int | None = 0, whole_test: bool = False) -> dict:
    """Claim 5 from the learning curves ``curves[c] = (end cycles, mean)``, the steady states ``steady[c]`` and
    SLE's noise horizon (its test config's ``sle_noise_steps``; 0 or None: over the whole test, not comparable,
    unless ``whole_test``: the paper's reading, measured at the test's length, which the paper fixes)."""
    ratios, cycles, texts = {}, {}, []
    if "SLE" not in curves:
        return _claim(NOT_AVAILABLE, "-")
    if not sle_noise_steps and not whole_test:
        return _claim(NOT_AVAILABLE, "not comparable: SLE's noise anneals over the whole test (sle_noise_steps 0), "
                                     "so when SLE gets good depends on the test's length", sle_noise_steps=0)
    end = int(np.asarray(curves["SLE"][0])[-1])
    for c in ("LE-LS", "EE-LS"):
        if c not in curves or steady.get(c) is None or not steady[c] > 0:
            continue
        level = PLATEAU_FRACTION * steady[c]
        own, sle = first_reach(*curves[c], level), first_reach(*curves["SLE"], level)
        if own is None:  # only when curve.csv's rounding puts every bin under the level
            continue
        ratio = None if sle is None else sle / own
        ratios[c], cycles[c] = ratio, dict(level=level, cycles=own, sle_cycles=sle)
        texts.append(f"{c} {own:,} vs SLE {sle:,} cycles to {level:.3f} (x{ratio:.1f})" if sle is not None else
                     f"{c} {own:,} cycles to {level:.3f}, SLE never reached it in {end:,} (x > {end / own:.1f})")
    horizon = (f"{sle_noise_steps:,} cycles" if sle_noise_steps else
               f"the whole test of {end:,} cycles, the paper's length")
    measured = "; ".join(texts) + f" (SLE's noise over {horizon})" if texts else "-"
    never = {c: r is None for c, r in ratios.items()}
    measured_ratios = [r for r in ratios.values() if r is not None]
    much = sum(r >= MUCH_FASTER for r in measured_ratios)
    verdict = _verdict(much == 2, much == 1 or any(never.values()) or all(r > 1 for r in measured_ratios))
    return _claim(NOT_AVAILABLE if len(ratios) < 2 else verdict, measured, ratio=ratios, sle_never=never,
                  cycles=cycles, sle_noise_steps=sle_noise_steps)


def pair_order(a, b, num_se: float = ORDER_SE) -> str:
    """"in order" if mean(a) - mean(b) > num_se standard errors, "reversed" if < -num_se se, else "tied"."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    d, se = float(a.mean() - b.mean()), _standard_error(a, b)
    return "in order" if d > num_se * se else "reversed" if d < -num_se * se else "tied"


def claim_ordering(per_run: dict, order=STEADY_ORDER) -> dict:
    """Claim 6 from the steady states of the four conditions, one value per run (``per_run[c]``)."""
    if any(per_run.get(c) is None or not len(per_run[c]) for c in order):
        return _claim(NOT_AVAILABLE, "-")
    mean = {c: float(np.mean(per_run[c])) for c in order}
    outcome = {f"{a} > {b}": pair_order(per_run[a], per_run[b]) for i, a in enumerate(order) for b in order[i + 1:]}
    pairs = {p: o == "in order" for p, o in outcome.items()}
    held = sum(pairs.values())
    ranked = sorted(order, key=lambda c: -mean[c])
    ranked = ranked[0] + "".join(f" {'=' if mean[a] == mean[b] else '>'} {b}" for a, b in zip(ranked, ranked[1:]))
    listed = {said: [p for p, o in outcome.items() if o == said] for said in ("tied", "reversed")}
    measured = (f"{ranked} (" + ", ".join(f"{c} {mean[c]:.3f}" for c in order) + f"); {held}/6 pairs in order "
                f"(> {ORDER_SE:g} se)" + "".join(f"; {said}: {', '.join(p)}" for said, p in listed.items() if p))
    return _claim(_verdict(held == 6, held >= 4), measured, pairs=pairs, outcome=outcome, pairs_held=held, mean=mean)


def claim_specialisation(colours: dict, pairs: dict | None = None) -> dict:
    """Claim 7 from the colours followed (``Specialisation.num_colours``) by each probed LS individual, and the
    share of task pairs solved both ways in their learning tests."""
    pairs = pairs or {}
    probed = {c: np.asarray(colours[c]) for c in ("LE-LS", "EE-LS") if colours.get(c) is not None and len(colours[c])}
    counts = {c: np.bincount(v.astype(int), minlength=4)[:4].tolist() for c, v in probed.items()}
    specialised = {c: float((v == 3).mean()) for c, v in probed.items()}
    mean = {c: float(v.mean()) for c, v in probed.items()}
    measured = "individuals following 0/1/2/3 colours: " + (", ".join(
        f"{c} {'/'.join(map(str, n))} (3: {specialised[c]:.0%})" for c, n in counts.items()) or "-")
    if pairs:
        measured += "; task pairs solved both ways: " + ", ".join(f"{c} {_fmt(v, 2)}" for c, v in pairs.items())
    numbers = dict(counts=counts, specialised=specialised, mean_colours=mean, pairs=pairs)
    composed = [pairs[c] for c in ("LE-LS", "EE-LS") if pairs.get(c) is not None]
    composes = bool(composed) and max(composed) >= PAIRS_COMPOSED
    majority = [specialised[c] >= SPECIALISED_MAJORITY for c in probed]
    verdict = _verdict(len(probed) == 2 and all(majority) and composes,
                       any(majority) or any(m >= 2 for m in mean.values()) or composes)
    return _claim(verdict if probed else NOT_AVAILABLE, measured, **numbers)


def evolved_claims(done: dict, per_run: dict, path: dict | None) -> dict:
    """Claims 1-4 and 6, those a search decides: from each finished evolution's numbers ``done[c]`` (as
    :func:`measure` gives them), each condition's steady state per run and the best EE-ES's path (None: not relived)."""
    get = lambda c, k: done[c][k] if c in done else None  # noqa: E731
    return {1: claim_evolvability({c: get(c, "plateau_generation") for c in EVOLVED}),
            2: claim_reliability({c: get(c, "final_best_sd") for c in EVOLVED}),
            3: claim_ee_ls_higher(get("EE-LS", "final_best_per_seed"), get("LE-LS", "final_best_per_seed")),
            4: claim_ee_es_about(get("EE-ES", "final_best_mean"), get("LE-LS", "final_best_mean"),
                                 path["stereotypy_per_task"] if path else None, path["speed"] if path else None),
            6: claim_ordering(per_run)}


def measure(data: dict, lives: dict, probes: dict | None = None, sle_whole_test=False) -> dict:
    """Every number of the report: per variant, the evolutions' and tests' statistics and the claims.

    ``lives[(variant, condition)]``: the relived best individuals (claim 4's paths);
    ``probes[(variant, condition)]``: the colours followed by each probed individual (claim 7);
    ``sle_whole_test``: claim 5 measured under SLE's noise over the whole test (the claims study's reading):
    True for every variant, or the variants it is for (a collection of names).
    """
    probes = probes or {}
    planned = ((data.get("manifest") or {}).get("sizes") or {}).get("generations")
    out = {}
    for variant in data["variants"]:
        evolution = {}
        for condition in EVOLVED:
            if (run := data["evolutions"].get((variant, condition))) is None:
                continue
            best, final = run["best"], final_best(run["best"])
            evolution[condition] = dict(
                finished=planned is None or len(best) >= planned, final_best_mean=float(final.mean()),
                final_best_sd=float(final.std()), final_best_per_seed=final.tolist(), seeds=run["seeds"],
                generations=len(best), last_generations_averaged=min(LAST_GENERATIONS, len(best)),
                plateau_generation=plateau_generation(best.mean(1)), best_per_generation_mean=best.mean(1).tolist(),
                best_per_generation_sd=best.std(1).tolist())
        found = {c: t for c in TESTED if (t := data["tests"].get((variant, c))) is not None}
        tests = {c: {**{k: t["steady"].get(k) for k in ("steady_mean", "steady_sd", "steady_best_run", "best_run",
                                                         "steady_per_run", "steady_per_task", "whole_test_mean",
                                                         "num_runs", "num_best", "num_tests", "task_steps",
                                                         "steady_steps", "num_bins")},
                     "pairs_both_ways": t.get("pairs_both_ways")} for c, t in found.items()}
        done = {c: e for c, e in evolution.items() if e["finished"]}  # claims judge finished evolutions only
        of_tests = lambda key: {c: tests[c][key] if c in tests else None for c in TESTED}  # noqa: E731
        claims = evolved_claims(done, of_tests("steady_per_run"), lives.get(("paper", "EE-ES")))
        claims[5] = claim_learning_speed(
            {c: (t["steps"], t["mean"]) for c, t in found.items()}, of_tests("steady_mean"),
            (found["SLE"]["steady"].get("config") or {}).get("sle_noise_steps", 0) if "SLE" in found else None,
            sle_whole_test if isinstance(sle_whole_test, bool) else variant in sle_whole_test)
        claims[7] = claim_specialisation({c: probes.get((variant, c)) for c in ("LE-LS", "EE-LS")},
                                         {c: tests[c]["pairs_both_ways"] for c in EVOLVED
                                          if tests.get(c, {}).get("pairs_both_ways") is not None})
        out[variant] = dict(evolution=evolution, learning_tests=tests, claims=dict(sorted(claims.items())))
    return out
