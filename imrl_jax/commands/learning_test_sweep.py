"""``python -m imrl_jax.learning_test SWEEP``: the learning test of each point of a sweep, one after the other.

A sweep's directory (``evolve --sweep``: each point a run directory ``SWEEP/KEY``) is tested point by
point into ``OUT/KEY``, each point as the test of its run directory alone would be (the points share one
program: they differ only in dynamic values). Every point is checked before any is tested: its run (at the
sweep's common generation, unless ``--allow-mixed-generations``), its ``OUT/KEY`` (new, empty, unfinished, or
tested before with the settings and model asked: then passed over, so that the same command after an
interruption goes on with the next point), and ``OUT`` itself (nothing but the points' folders and
``sweep_tests.json``). Once every point is tested, ``OUT/sweep_tests.json`` is written, last and atomically:
each point's settings, generation and steady state, as its ``steady.json`` holds them.
"""

from __future__ import annotations

import json
import os

from imrl_jax.runs.cli import UsageError
from imrl_jax.config import Config, ConfigError
from imrl_jax.runs.rundir import (RunDirError, check_unlocked, check_writable, entries, is_output, not_empty, read_json,
                             write_atomic)

#: What the test of a sweep writes beside its points' tests once all are done.
SWEEP_TESTS = "sweep_tests.json"
#: The numbers of a point's steady.json that sweep_tests.json repeats (and must agree with).
REPEATED = ("generation", "generations_done", "steady_mean", "steady_sd", "whole_test_mean")


def check_keys(run_dir: str, recorded: list[tuple[str, dict]]) -> list[str]:
    """The points' keys as the sweep records them, each a folder name of its own (raises RunDirError naming
    sweep.json: a key that is a path, or given twice, would test or write outside its point's folder)."""
    path = os.path.join(run_dir, "sweep.json")
    keys = [key for key, _ in recorded]
    if not keys:
        raise RunDirError(f"{path}: the sweep has no points")
    for key in keys:
        if key in ("", ".", "..") or os.sep in key or "/" in key or "\x00" in key or key == SWEEP_TESTS:
            raise RunDirError(f"{path}: a point's key {key!r} is not a folder name")
    if len(set(keys)) != len(keys):
        raise RunDirError(f"{path}: two points have one key")
    return keys


def check_out_root(out: str, keys: list[str]) -> None:
    """Refuse an ``--out`` of a sweep's test that holds anything but its points' folders and ``sweep_tests.json``,
    or that another process writes (nothing is written)."""
    check_writable(out)
    check_unlocked(out)
    found = entries(out)
    others = [name for name in found if not (name in keys and os.path.isdir(os.path.join(out, name))
                                             or is_output(name, (SWEEP_TESTS,)))]
    if others:
        raise not_empty(out, "learning test of this sweep", others)


def check_generations(args, run_dir: str, evolved: dict[str, dict]) -> int | None:
    """The generation every point is tested at (``evolved``: each key's generation record), or None where
    ``--allow-mixed-generations`` lets the points be tested each at its own (raises UsageError otherwise)."""
    done: dict[int, list[str]] = {}
    for key, record in evolved.items():
        done.setdefault(record["generations_done"], []).append(key)
    if len(done) == 1:
        return next(iter(evolved.values()))["generation"]
    if args.allow_mixed_generations:
        return None
    groups = "; ".join(f"{', '.join(keys[:3])}{', ...' if len(keys) > 3 else ''}: {count}"
                       for count, keys in sorted(done.items()))
    raise UsageError(f"run_dir: the points of {run_dir} have evaluated different numbers of generations ({groups}): "
                     f"a sweep's points are tested at one generation; evolve the others to {max(done)} "
                     f"(python -m imrl_jax.evolve --resume --out {run_dir} --generations {max(done)}), or pass "
                     f"--allow-mixed-generations to test each point at its own last generation")


def check_record(out: str, keys: list[str]) -> None:
    """Refuse an ``OUT/sweep_tests.json`` that does not agree with its points' ``steady.json`` (a mix of two tests:
    a point's test removed or made again since), in one line saying how to repair it."""
    path = os.path.join(out, SWEEP_TESTS)
    if not os.path.lexists(path):
        return
    repair = (f"remove {path} (and the folders of the points to test again) and run the same command again: it "
              f"tests the points without a test and writes the record anew")
    try:
        points = read_json(path, "")["points"]
        items = list(points.items())
    except (RunDirError, KeyError, TypeError, AttributeError) as error:
        raise RunDirError(f"--out: {path} is unreadable ({str(error) or type(error).__name__}); {repair}") from None
    for key, entry in items:
        if key not in keys:
            raise RunDirError(f"--out: {path} records a test of {key!r}, not a point of this sweep; {repair}")
        steady_path = os.path.join(out, key, "steady.json")
        if not os.path.isfile(steady_path):
            raise RunDirError(f"--out: {path} records the test of point {key}, but {steady_path} is missing; {repair}")
        steady = read_json(steady_path, "--out")
        differ = [name for name in REPEATED if isinstance(entry, dict) and name in entry
                  and (not isinstance(steady, dict) or entry[name] != steady.get(name))]
        if not isinstance(entry, dict) or differ:
            raise RunDirError(f"--out: {path} and {steady_path} disagree ({', '.join(differ) or 'not a record'}): "
                              f"one is of another test; {repair}")


def check_tested_before(args, out_dir: str, config: Config, evolved: dict, sizes: dict) -> None:
    """Refuse a point's earlier test (in a sweep's test) made with other settings, of another generation or of
    another model than ``config`` (``Config.model_differences``: another ``--set``)."""
    path = os.path.join(out_dir, "steady.json")
    steady = read_json(path, "--out")
    if not isinstance(steady, dict):
        raise RunDirError(f"--out: {path} is unreadable (not a test's summary); remove {out_dir} to test the point again")
    asked = dict(sizes, generations_done=evolved["generations_done"])
    differ = [f"{name} {steady.get(name)} (asked {value})" for name, value in asked.items()
              if steady.get(name) != value]
    try:
        tested = Config.from_dict(steady["config"]) if steady.get("config") else None
    except (ConfigError, TypeError, ValueError, AttributeError) as error:
        raise UsageError(f"--out: {path} is unreadable ({error}); remove {out_dir} to test the point again") from None
    differ += [f"{name} {getattr(tested, name)} (asked {getattr(config, name)})"  # a size said once, above
               for name in ([] if tested is None else tested.model_differences(config)) if name not in asked]
    if differ:
        raise UsageError(f"--out: {out_dir} holds a test of other settings: {', '.join(differ)}; choose another --out")


def sweep_summary(run_dir: str, out: str, recorded: list[tuple[str, dict]], generation: int | None,
                  sizes: dict) -> dict:
    """Each point's settings, generation and steady state, once every point of the sweep in ``run_dir`` is tested in
    ``out`` (written last, atomically, to ``out/sweep_tests.json``: a sweep's test is done when it is there)."""
    points = {}
    for key, settings in recorded:
        steady = read_json(os.path.join(out, key, "steady.json"), "")
        points[key] = dict(settings=settings, **{name: steady.get(name) for name in REPEATED})
    summary = dict(sweep=os.path.abspath(run_dir), generation=generation, test=sizes, points=points)
    write_atomic(os.path.join(out, SWEEP_TESTS), json.dumps(summary, indent=2).encode())
    return summary
