"""The seven claims' verdict rules: pure functions from measured numbers to a verdict, and the rules in words."""

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


# ----------------------------------------------------------------------------- claim 8

#: The rule for the paper's remark on the number of experts (section 2), checked beside the seven claims.
EXPERTS_RULE = (f"For LE-LS and EE-LS, each with 4 and 6 experts against 3 (the same rule set): final best fitness "
                f"of a seed as in claim 2, and the steady state of each learning-test run as in claim 6. A comparison "
                f"is *unchanged* when the mean with more experts is within [{ABOUT[0]}, {ABOUT[1]}] of the mean with 3 "
                f"(claim 4's \"about\"); the difference and its standard error (as in claim 3) are shown. **holds** if "
                f"every comparison made is unchanged; **partly** if at least one is; **does not hold** if none is; "
                f"**n/a** without a comparison.")


def claim_experts(final: dict, steady: dict | None = None) -> dict:
    """Claim 8 from per-seed final best fitness ``final[(condition, experts)]`` and per-run steady states
    ``steady[(condition, experts)]``, each compared with the same condition's 3 experts."""
    compared, parts = {}, []
    for measure, values in (("final", final), ("steady", steady or {})):
        for (condition, k), numbers in sorted(values.items()):
            base = values.get((condition, 3))
            if k == 3 or base is None or numbers is None or not len(numbers) or not len(base):
                continue
            a, b = np.asarray(base, float), np.asarray(numbers, float)
            ratio = float(b.mean() / a.mean()) if a.mean() > 0 else None
            d, se = _difference(b, a)
            unchanged = ratio is not None and ABOUT[0] <= ratio <= ABOUT[1]
            compared[f"{condition} {measure} {k} vs 3"] = dict(ratio=ratio, difference=d, standard_error=se,
                                                              unchanged=unchanged)
            parts.append(f"{condition} {measure} {k}/3 experts {b.mean():.3f}/{a.mean():.3f} = {_fmt(ratio, 2)}")
    if not compared:
        return _claim(NOT_AVAILABLE, "-", compared=compared)
    return _tally({n: c["unchanged"] for n, c in compared.items()}, parts, "unchanged", compared=compared)


# ----------------------------------------------------------------------------- tasks never met in evolution

#: The rule for the paper's Discussion on tasks never met in evolution (docs/NOVEL_TASKS.md).
UNSEEN_RULE = (f"Learning's advantage of a condition on a set of tasks is its steady state minus EE-ES's on the same "
               f"tasks (EE-ES learns nothing), from the steady state of each learning-test run, with the standard "
               f"error of that difference as in claim 3. A condition's advantage is *stronger on unseen tasks* when "
               f"its advantage there exceeds its advantage on the tasks of its evolution by more than {ORDER_SE} "
               f"standard errors of the two together. **holds** if every learning condition compared is stronger on "
               f"unseen tasks; **partly** if at least one is; **does not hold** if none is; **n/a** without a "
               f"comparison.")


def advantage(per_run, ee_es_per_run) -> dict:
    """Learning's advantage: mean steady state of ``per_run`` minus EE-ES's on the same tasks, and its standard error."""
    a, b = np.asarray(per_run, float), np.asarray(ee_es_per_run, float)
    return dict(advantage=float(a.mean() - b.mean()), standard_error=_standard_error(a, b), steady=float(a.mean()),
                ee_es=float(b.mean()))


def claim_unseen(seen: dict, unseen: dict, num_se: float = ORDER_SE) -> dict:
    """The Discussion's expectation from ``seen[name]`` and ``unseen[name]`` (each an :func:`advantage`): is learning's
    advantage of every compared condition stronger on tasks never met in evolution?"""
    compared, parts = {}, []
    for name in sorted(set(seen) & set(unseen)):
        s, u = seen[name], unseen[name]
        difference = u["advantage"] - s["advantage"]
        error = math.hypot(s["standard_error"], u["standard_error"])
        compared[name] = dict(difference=difference, standard_error=error, stronger=difference > num_se * error)
        parts.append(f"{name}: {u['advantage']:+.3f} unseen vs {s['advantage']:+.3f} seen "
                     f"({difference:+.3f} +- {error:.3f})")
    if not compared:
        return _claim(NOT_AVAILABLE, "-", compared=compared)
    return _tally({n: c["stronger"] for n, c in compared.items()}, parts, "stronger unseen", compared=compared)


# ----------------------------------------------------------------------------- the paper's future work

#: The paper's four future-work questions as statements to judge (docs/FUTURE_WORK.md), one per condition.
FUTURE = {
    "a": "Evolving criteria that guide learning (reinforcers, LE-LS; evaluators, EV-LS) is much easier than "
         "evolving the behaviours themselves (actors, EE-LS).",
    "b": "Intrinsic motivation is needed: with skills learned from evolved reinforcers (LE-LS) the hierarchy learns "
         "much faster and ends higher than on the task's reward alone (EXT-LS).",
    "c": "Evolution finds the learning values that `skills` set by hand, rather than the paper's.",
    "d": "Three experts are enough: evolution keeps about three, and more do not pay.",
}
FEWEST_KEPT = 3.5  # (d): "keeps about three": the best's expressed experts, mean over seeds, at most this
FUTURE_RULES = {
    "a": f"For each criterion row against EE-LS: *much faster* = its plateau generation (claim 1's) is at most "
         f"1/{MUCH_FASTER:g} of EE-LS's; *higher* = its final best fitness (claim 2's, per seed) exceeds EE-LS's by "
         f"more than {ORDER_SE:g} standard errors (claim 3's). Easier = both. **holds** if every criterion row is "
         f"easier; **partly** if one is much faster or higher; **does not hold** otherwise. Genome sizes and "
         f"fresh-life fitness are shown, not judged.",
    "b": f"Steady states (claim 6's, per run): *higher* = LE-LS's exceeds EXT-LS's by more than {ORDER_SE:g} "
         f"standard errors. Speed, timed from where both start (start = the higher of the two mean curves' "
         f"first bins): level = start + {PLATEAU_FRACTION:.0%} of the way from it to the lower of the steady states "
         f"above it (a row whose steady state is not above the start never reaches it); cycles to it = the end of "
         f"the first bin of the mean learning curve at or above it; *much faster* = LE-LS needs at most "
         f"1/{MUCH_FASTER:g} of EXT-LS's cycles (or EXT-LS never reaches it). **holds** if both; **partly** "
         f"if one; **does not hold** (the hierarchy on the task's reward is enough) if neither. EXT-LS against SLE "
         "(the hierarchy against a flat learner, the same noise) is shown as claim 6's pairs are.",
    "c": "For each learning value on which `skills` and the paper differ: its position in its gene's range (the "
         "decoding map of MODEL.md, log scale for rates and for 1 - discount; 0-1) for each seed's best individual "
         "of the last generation, mean over seeds; *nearer skills* when that is nearer `skills`' position than the "
         "paper's. **holds** if every such value is nearer skills; **partly** if some; **does not hold** if none. "
         "The values on which they agree and the evolved childhood length are shown, not judged.",
    "d": f"*Keeps about three* = each seed's best individual of the last generation expresses at most "
         f"{FEWEST_KEPT:g} experts on average over seeds; *more do not pay* = the evolved-number row's final best "
         f"fitness is not above LE-LS's with 3 experts by more than {ORDER_SE:g} standard errors. **holds** if both; "
         f"**partly** if one; **does not hold** if neither. The comparison with 6 experts all expressed is shown.",
}


def _difference(a, b) -> tuple[float, float]:
    """mean(a) - mean(b) and its standard error (claim 3's)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float(a.mean() - b.mean()), _standard_error(a, b)


def claim_criteria_easier(criteria: dict, actors: dict | None) -> dict:
    """(a) from each criterion row's and EE-LS's evolution: ``dict(plateau, final_per_seed, fresh, genes)`` each."""
    if actors is None or not criteria:
        return _claim(NOT_AVAILABLE, "-")
    said = lambda name, row: (f"{name} ({row['genes']} genes): plateau {_fmt(row['plateau'])}, final "  # noqa: E731
                              f"{np.mean(row['final_per_seed']):.3f}, fresh {_fmt(row.get('fresh'))}")
    compared, parts = {}, [said("EE-LS", actors)]
    for name, row in criteria.items():
        d, se = _difference(row["final_per_seed"], actors["final_per_seed"])
        p, q = row["plateau"], actors["plateau"]
        faster = p is not None and q is not None and MUCH_FASTER * p <= q
        higher = d > ORDER_SE * se
        compared[name] = dict(difference=d, standard_error=se, much_faster=faster, higher=higher)
        easier = ("easier" if higher else "faster") if faster else "higher" if higher else "not easier"
        parts.append(said(name, row) + f"; d = {d:+.3f} +- {se:.3f} ({easier})")
    measured = "; ".join(parts)
    return _claim(_verdict(all(c["much_faster"] and c["higher"] for c in compared.values()),
                           any(c["much_faster"] or c["higher"] for c in compared.values())), measured,
                  compared=compared)


def claim_motivation_needed(extrinsic: dict | None, skilled: dict | None, flat: dict | None = None) -> dict:
    """(b) from EXT-LS's, LE-LS's and SLE's learning tests: ``dict(steps, mean, per_run)`` each (the mean curve)."""
    if extrinsic is None or skilled is None:
        return _claim(NOT_AVAILABLE, "-")
    curves = {"LE-LS": skilled, "EXT-LS": extrinsic}
    steady = {n: float(np.asarray(t["per_run"], float).mean()) for n, t in curves.items()}
    order = pair_order(skilled["per_run"], extrinsic["per_run"])
    # Timed from where both start, so that a level both curves are at in their first bin times nothing; a row
    # whose steady state is not above that start has learned nothing above it and never reaches a level.
    start = max(float(np.asarray(t["mean"], float)[0]) for t in curves.values())
    learned = [n for n in curves if steady[n] > start]
    level = start + PLATEAU_FRACTION * (min(steady[n] for n in learned) - start) if learned else None
    cycles = {n: first_reach(curves[n]["steps"], curves[n]["mean"], level) if n in learned else None for n in curves}
    own, theirs = cycles["LE-LS"], cycles["EXT-LS"]
    faster = own is not None and (theirs is None or MUCH_FASTER * own <= theirs)
    reach = f"cycles to {level:.3f}" if level is not None else f"neither learns above {start:.3f}"
    measured = (f"steady LE-LS {steady['LE-LS']:.3f} vs EXT-LS {steady['EXT-LS']:.3f} ({order}); start {start:.3f}, "
                f"{reach}: LE-LS {cycles['LE-LS'] or 'never'}, EXT-LS {cycles['EXT-LS'] or 'never'}")
    numbers = dict(order=order, start=start, level=level, cycles=cycles, much_faster=faster)
    if flat is not None:
        numbers["against_flat"] = pair_order(extrinsic["per_run"], flat["per_run"])
        said = {"in order": "EXT-LS higher", "reversed": "SLE higher"}.get(numbers["against_flat"], "tied")
        measured += f"; EXT-LS vs SLE {np.mean(flat['per_run']):.3f}: {said}"
    higher = order == "in order"
    return _claim(_verdict(faster and higher, faster or higher), measured, **numbers)


def map_position(name: str, value: float) -> float:
    """Where a learning value lies in its gene's range (:data:`imrl_jax.conditions.EVOLVED_PARAMETERS`): 0-1."""
    from imrl_jax.conditions import EVOLVED_PARAMETERS

    kind, lo, hi = next((kind, lo, hi) for n, kind, lo, hi in EVOLVED_PARAMETERS if n == name)
    x = {"log": lambda v: math.log10(max(v, 1e-300)), "1-log": lambda v: math.log10(max(1.0 - v, 1e-300)),
         "linear": lambda v: v}[kind](value)
    return min(max((x - lo) / (hi - lo), 0.0), 1.0)


def claim_hand_values(best_values: dict, skills: dict, paper: dict) -> dict:
    """(c) from each seed's best individual's evolved values ``best_values[name]`` (a list over seeds) and the
    values `skills` and the paper set by hand."""
    from imrl_jax.conditions import EVOLVED_FIELDS

    if not best_values:
        return _claim(NOT_AVAILABLE, "-")
    nearer, parts = {}, []
    for name in (n for n in EVOLVED_FIELDS if n in best_values and skills[n] != paper[n]):  # the values they differ on
        u = float(np.mean([map_position(name, v) for v in best_values[name]]))
        us, up = map_position(name, skills[name]), map_position(name, paper[name])
        nearer[name] = "skills" if abs(u - us) < abs(u - up) else "paper"
        parts.append(f"{name} {np.mean(best_values[name]):.3g} at {u:.2f} (skills {skills[name]:g} at {us:.2f}, "
                     f"paper {paper[name]:g} at {up:.2f}): {nearer[name]}")
    if "childhood_length" in best_values:
        parts.append(f"childhood length {np.mean(best_values['childhood_length']):,.0f} of "
                     f"{skills['childhood_length']:,.0f}")
    return _tally({n: v == "skills" for n, v in nearer.items()}, parts, "nearer skills", nearer=nearer)


def claim_three_enough(kept, evolved_final, three_final, six_final=None) -> dict:
    """(d) from each seed's best's expressed experts ``kept`` and the per-seed final best fitness of the evolved
    number, of 3 experts and (shown) of 6 all expressed."""
    if kept is None or not len(kept) or evolved_final is None or three_final is None:
        return _claim(NOT_AVAILABLE, "-")
    about_three = float(np.mean(kept)) <= FEWEST_KEPT
    d, se = _difference(evolved_final, three_final)
    no_gain = d <= ORDER_SE * se
    measured = (f"the best express {np.mean(kept):.2f} experts (mean over seeds); final best "
                f"{np.mean(evolved_final):.3f} vs 3 experts {np.mean(three_final):.3f}: d = {d:+.3f} +- {se:.3f}")
    numbers = dict(kept=float(np.mean(kept)), about_three=about_three, difference=d, standard_error=se,
                   no_gain=no_gain)
    if six_final is not None:
        d6, se6 = _difference(evolved_final, six_final)
        numbers.update(difference_six=d6, standard_error_six=se6)
        measured += f"; vs 6 all expressed {np.mean(six_final):.3f}: d = {d6:+.3f} +- {se6:.3f}"
    return _claim(_verdict(about_three and no_gain, about_three or no_gain), measured, **numbers)
