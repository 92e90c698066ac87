"""``python -m imrl_jax.learning_test SWEEP``: the learning test of each point of a sweep, one after the other.

A sweep's directory (``evolve --sweep``: each point a run directory ``SWEEP/KEY``) is tested point by
point into ``OUT/KEY``, each point as the test of its run directory alone would be (the points share one
program: they differ only in dynamic values). A point tested before (its ``steady.json``) is checked against
the settings and the model asked (``--set`` included) and passed over, so that the same command after an
interruption goes on with the next point; once every point is tested, ``OUT/sweep_tests.json`` holds each
point's settings and steady state.
"""

from __future__ import annotations

import json
import os
from typing import Callable

from imrl_jax.cli import UsageError
from imrl_jax.config import Config, ConfigError
from imrl_jax.rundir import load_run, read_json, recorded_points, write_atomic

#: What the test of a sweep writes beside its points' tests once all are done.
SWEEP_TESTS = "sweep_tests.json"


def run_points(args, points: list[str], test: Callable[[str, str], dict],
               config_of: Callable[[str], Config]) -> list[tuple[str, dict | None]]:
    """Each point's (out_dir, summary) once ``test(point_dir, out_dir)`` has tested those not tested before (their
    summary None; ``config_of(point_dir)``: the config its test would run, checked against theirs), and the sweep's
    summary written."""
    if args.best_genomes:
        raise UsageError(f"--best-genomes: {args.run_dir} is a sweep: its points' populations are kept")
    summaries = []
    for point in points:
        out_dir = os.path.join(args.out, os.path.basename(point))
        if os.path.isfile(os.path.join(out_dir, "steady.json")):
            check_tested_before(args, point, out_dir, config_of(point))
            summaries.append((out_dir, None))  # a point tested before: the sweep's test goes on after it
            continue
        summaries.append((out_dir, test(point, out_dir)))
    sweep_summary(args.run_dir, args.out)
    return summaries


def check_tested_before(args, run_dir: str, out_dir: str, config: Config) -> None:
    """Refuse a point's earlier test (in a sweep's test) made with other settings, of another generation or of
    another model than ``config`` (``Config.model_differences``: another ``--set``)."""
    steady = read_json(os.path.join(out_dir, "steady.json"), "")
    asked = dict(num_best=args.best, num_tests=args.tests, task_steps=args.task_steps, steady_steps=args.steady_steps,
                 seed=args.seed, generations_done=load_run(run_dir).generation)
    differ = [f"{name} {steady.get(name)} (asked {value})" for name, value in asked.items()
              if steady.get(name) != value]
    try:
        tested = Config.from_dict(steady["config"]) if steady.get("config") else None
    except ConfigError as error:
        raise UsageError(f"--out: {os.path.join(out_dir, 'steady.json')} is unreadable ({error})") from None
    differ += [f"{name} {getattr(tested, name)} (asked {getattr(config, name)})"  # a size said once, above
               for name in ([] if tested is None else tested.model_differences(config)) if name not in asked]
    if differ:
        raise UsageError(f"--out: {out_dir} holds a test of other settings: {', '.join(differ)}; choose another --out")


def sweep_summary(run_dir: str, out_dir: str) -> dict:
    """Each point's settings and steady state, once every point of the sweep in ``run_dir`` is tested in ``out_dir``
    (written to ``out_dir/sweep_tests.json``: a sweep's test is done when it is there)."""
    points = {}
    for key, settings in recorded_points(run_dir):
        steady = read_json(os.path.join(out_dir, key, "steady.json"), "")
        points[key] = dict(settings=settings, steady_mean=steady["steady_mean"], steady_sd=steady["steady_sd"],
                           whole_test_mean=steady["whole_test_mean"])
    summary = dict(sweep=os.path.abspath(run_dir), points=points)
    write_atomic(os.path.join(out_dir, SWEEP_TESTS), json.dumps(summary, indent=2).encode())
    return summary
