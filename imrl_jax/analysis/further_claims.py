"""The claims beyond the paper's seven, judged as they are: its remark on the number of experts (section 2, claim 8),
its Discussion's tasks never met in evolution, and its four future-work questions."""

from __future__ import annotations

import math

import numpy as np

from imrl_jax.analysis.claims import (ABOUT, MUCH_FASTER, NOT_AVAILABLE, ORDER_SE, PLATEAU_FRACTION, _claim,
                                      _difference, _fmt, _standard_error, _tally, _verdict, first_reach, pair_order)
from imrl_jax.conditions import EVOLVED_FIELDS, EVOLVED_PARAMETERS

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
    kind, lo, hi = next((kind, lo, hi) for n, kind, lo, hi in EVOLVED_PARAMETERS if n == name)
    x = {"log": lambda v: math.log10(max(v, 1e-300)), "1-log": lambda v: math.log10(max(1.0 - v, 1e-300)),
         "linear": lambda v: v}[kind](value)
    return min(max((x - lo) / (hi - lo), 0.0), 1.0)


def claim_hand_values(best_values: dict, skills: dict, paper: dict) -> dict:
    """(c) from each seed's best individual's evolved values ``best_values[name]`` (a list over seeds) and the
    values `skills` and the paper set by hand."""
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

