"""``gpu_check``'s ``study`` step: one generation of each distinct program of the claims map, and the map's hours.

The claims map (``experiments.claims_study``: its rule sets x conditions) evolves runs that are found by
what they compute; runs whose configs differ only in dynamic values (:data:`imrl_jax.evolution.sweeps.DYNAMIC_FIELDS`:
the same :func:`imrl_jax.evolution.sweeps.static_part`) and seed count are one program, timed once as a sweep of all
of them (``evolve --sweep``'s program). Each program's generation is timed at the paper's sizes, or at a
measured fraction of its life lengths when a whole one would not fit the step's share of the budget (a
generation's time is linear in its sequential steps). The learning tests are timed as their adult phase at
their own lane counts. :func:`extrapolate` turns these into the whole map's hours, against the issue's
target of one hour on one GPU.
"""

from __future__ import annotations

import hashlib
import math
import time
from typing import NamedTuple

import numpy as np

from imrl_jax.commands.gpu_harness import compile_once, fastest_rate, timed

#: The target: the whole claims map within this many hours on one GPU (issue 57).
TARGET_HOURS = 1.0
#: The share of the check's budget the study step may use from its start.
STUDY_SHARE = 0.4
#: The shortest fraction of a life a program is timed at (a shorter one measures the launch, not the steps).
MIN_FRACTION = 0.02
#: The phase program that times a learning test of each condition: (bench condition, phase name).
TEST_PHASES = {"LE-LS": ("EE-LS", "ADULT_LEARNING_SELECTOR"), "EE-LS": ("EE-LS", "ADULT_LEARNING_SELECTOR"),
               "EE-ES": ("EE-ES", "ADULT_EVOLVED_SELECTOR"), "SLE": ("SLE", "ADULT_SINGLE_EXPERT")}


class Program(NamedTuple):
    """One compiled program of the claims map: the runs (each its rows' names and dynamic values) it evolves."""

    key: str  # :func:`program_key` of its runs' configs
    condition: str
    config: object  # the static part (every dynamic value at its default), at the paper's sizes
    runs: tuple  # ((row names, {dynamic field: value}), ...), one per distinct run
    seeds: int
    generations: int


def program_key(config) -> str:
    """What a run's compiled generation is made of: a hash of its model with every dynamic value at its default
    (compute choices, run length and fields the condition never reads left out, as a run's key leaves them)."""
    from imrl_jax.runs import runspec
    from imrl_jax.evolution import sweeps

    return hashlib.sha256(runspec.canonical(runspec.model(sweeps.static_part(config))).encode()).hexdigest()[:12]


def dynamic_values(config) -> dict:
    """The dynamic values of ``config`` (the arguments of its program), by field."""
    from imrl_jax.evolution.sweeps import DYNAMIC_FIELDS

    return {f: float(getattr(config, f)) for f in DYNAMIC_FIELDS if f != "eta"}  # "eta" sets several at once


def claims_programs(table=None) -> list[Program]:
    """The claims map's evolutions as distinct programs, those of several runs (sweeps) first."""
    from experiments.claims_study import SCREEN_TABLE
    from experiments.harness.table import evolution_spec
    from imrl_jax.evolution import sweeps

    table = SCREEN_TABLE if table is None else table
    runs: dict[str, list] = {}  # run key -> [spec, row names]: rows sharing a run evolve it once
    for row in table.rows:
        if row.evolved:
            spec = evolution_spec(row, table.scale_of(row))
            runs.setdefault(spec.key(), [spec, []])[1].append(row.name)
    groups: dict[tuple, list] = {}
    for spec, names in runs.values():
        group = (program_key(spec.config), len(spec.seeds), spec.config.num_generations)
        groups.setdefault(group, []).append((tuple(names), dynamic_values(spec.config), spec.config))
    programs = [Program(key, members[0][2].condition, sweeps.static_part(members[0][2]),
                        tuple((names, values) for names, values, _ in members), seeds, generations)
                for (key, seeds, generations), members in groups.items()]
    return sorted(programs, key=lambda p: -len(p.runs))  # stable: the map's order within


def claims_tests(table=None) -> list[dict]:
    """The claims map's learning tests (one a stage): condition, lane-steps and adult lanes of each."""
    from experiments.claims_study import SCREEN_TABLE
    from experiments.harness.reproduce import life_steps

    table = SCREEN_TABLE if table is None else table
    stages, scale = table.all_stages()
    tests = []
    for stage in (s for s in stages if s.kind == "test"):
        individuals = round(stage.cost / life_steps(scale, stage.condition, scale["test_steps"]))
        tests.append({"stage": stage.name, "condition": stage.condition, "lane_steps": stage.cost,
                      "lanes": individuals * 6})  # each individual's six tasks side by side
    return tests


def extrapolate(programs: list[dict], tests: list[dict], target_hours: float = TARGET_HOURS) -> dict:
    """The whole map's hours from the timed programs (generations x a whole generation of all their runs and
    seeds, plus one compilation each) and tests (lane-steps at their measured speed, plus one compilation each);
    ``complete`` only when every program and test has a speed, and only then is the target judged."""
    evolution = [p["generations"] * p["generation_s"] + p["compile_s"] for p in programs
                 if p.get("generation_s") is not None]
    testing = [t["lane_steps"] / t["lane_steps_per_s"] + t["compile_s"] for t in tests
               if t.get("lane_steps_per_s")]
    complete = len(evolution) == len(programs) and len(testing) == len(tests)
    hours = (math.fsum(evolution) + math.fsum(testing)) / 3600
    return {"evolution_hours": math.fsum(evolution) / 3600, "test_hours": math.fsum(testing) / 3600,
            "hours": hours, "complete": complete, "target_hours": target_hours,
            "meets_target": (hours < target_hours) if complete else None}


def sized(check, config, fraction: float):
    """``config`` at the check's sizes (``--dry``'s tiny ones), its life lengths times ``fraction``."""
    config = config.replace(**dict(check.sizes.generation_sizes))
    if fraction >= 1.0:
        return config
    bins = config.num_bins
    whole = lambda steps: max(bins, int(steps * fraction) // bins * bins) if steps else 0  # noqa: E731 - whole bins
    return config.replace(task_steps=whole(config.task_steps), childhood_steps=whole(config.childhood_steps))


def time_program(check, program: Program, fraction: float) -> dict:
    """One generation of ``program`` (every run x seed in one sweep) at ``fraction`` of its lives' lengths."""
    import jax

    from imrl_jax.commands import evolve_sweep
    from imrl_jax.agent import kernel_choice
    from imrl_jax.evolution.devices import make_mesh, population_sharding, replicated, to_global
    from imrl_jax.evolution.search import evolution_keys
    from imrl_jax.runs.run_state import initial_state

    check.stage = "api"
    seeds = list(range(min(program.seeds, check.sizes.study_seeds or program.seeds)))
    config = sized(check, program.config, fraction)
    points = evolve_sweep.make_points(config, seeds, [values for _, values in program.runs])
    mesh, batch = make_mesh(), len(points) * len(seeds)
    sharding = population_sharding(mesh, batch, config.population_size)
    state = initial_state(config, seeds, population_sharding(mesh, len(seeds), config.population_size))
    keys = to_global(evolution_keys(np.tile(state.key_data, (len(points), 1))), replicated(mesh))
    params, ga = evolve_sweep.batched_values(points, len(seeds))
    populations = to_global(np.tile(np.asarray(state.populations), (len(points), 1, 1)), sharding)
    kernel = kernel_choice.chosen(config)
    key = ("sweep", program_key(config), kernel, len(points), len(seeds))  # the sweep step's, if it is the same
    executable, compile_s = compile_once(check, key, evolve_sweep.make_sweep_step(config, sharding), keys, params,
                                         ga, populations, 0)
    start = time.perf_counter()
    jax.block_until_ready(executable(keys, params, ga, populations, 0))
    seconds = time.perf_counter() - start
    rate = batch * config.population_size * config.lifetime_steps / seconds
    # The whole generation at the program's own sizes: every run and seed, the paper's population and lives.
    full = len(program.runs) * program.seeds * program.config.population_size * program.config.lifetime_steps
    return {"kernel": kernel, "timed_points": len(points), "timed_seeds": len(seeds),
            "timed_lifetime_steps": config.lifetime_steps, "fraction": fraction, "compile_s": compile_s,
            "seconds": seconds, "lane_steps_per_s": rate, "generation_s": full / rate, "status": "ok"}


def time_test(check, condition: str, lanes: int) -> dict:
    """The learning test's adult phase of ``condition`` on ``lanes`` lanes (the kernel ``auto`` picks for it)."""
    from imrl_jax.commands import bench
    from imrl_jax.agent import kernel_choice
    from imrl_jax.config import make_config

    check.stage = "api"
    bench_condition, phase = TEST_PHASES[condition]
    kernel = kernel_choice.chosen(make_config("paper", condition=bench_condition))
    program = bench.phase_program(bench_condition, phase, lanes, check.sizes.study_test_steps, step_kernel=kernel)
    # the phases step's key too (its kernel observing as by default)
    key = ("phase", bench_condition, phase, lanes, check.sizes.study_test_steps, kernel,
           "entries" if kernel == "pallas" else None)
    executable, compile_s = compile_once(check, key, program.fn, *program.args)
    seconds, _ = timed(executable, program.args, check.sizes.repeats)
    return {"kernel": kernel, "steps": check.sizes.study_test_steps, "compile_s": compile_s,
            "lane_steps_per_s": program.lane_steps / seconds, "status": "ok"}


def fraction_for(check, program: Program, rate: float | None, stop: float, left: int) -> float:
    """The share of its lives a program is timed at: whole unless the last measured speed says that a whole
    generation would take more than its part of what is left of the step's share."""
    if rate is None or not check.sizes.scale:
        return 1.0
    whole = len(program.runs) * program.seeds * program.config.population_size * program.config.lifetime_steps / rate
    allowance = max(check.remaining() - stop, 0.0) / max(left, 1) / 2  # half for its compilation
    return 1.0 if whole <= allowance else max(MIN_FRACTION, allowance / whole)


def study(check) -> dict:
    """The ``study`` step: each distinct program of the claims map and each kind of learning test timed, and the
    map's hours extrapolated (the figures of the programs not timed are missing, and the estimate incomplete)."""
    check.stage = "api"
    programs, tests = claims_programs(), claims_tests()
    stop, limit = check.share_left(STUDY_SHARE), check.sizes.study_limit
    rows, rate = [], fastest_rate(check)
    for i, program in enumerate(programs):
        row = {"part": "evolution", "program": program.key, "condition": program.condition,
               "runs": [list(names) for names, _ in program.runs], "seeds": program.seeds,
               "generations": program.generations}
        if (limit is not None and i >= limit) or (check.sizes.scale and check.remaining() < stop):
            rows.append({**row, "status": "skipped (dry)" if limit is not None and i >= limit else "skipped (budget)"})
            continue
        with check.piece(row, rows):
            row.update(time_program(check, program, fraction_for(check, program, rate, stop, len(programs) - i)))
            rate = row["lane_steps_per_s"]
            check.say(f"  {program.key} {program.condition:6s} {len(program.runs)} run(s) x {program.seeds} seeds "
                      f"({row['kernel']}): {row['generation_s']:.2f} s a generation (timed at {row['fraction']:.2f} "
                      f"of it, compile {row['compile_s']:.1f} s)")
    timings: dict[tuple, dict] = {}
    for test in tests:
        lanes = min(test["lanes"], check.sizes.study_test_lanes or test["lanes"])
        kind = (TEST_PHASES[test["condition"]], lanes)
        if kind not in timings:
            timings[kind] = row = {"part": "test", "condition": test["condition"], "lanes": lanes}
            if (limit is not None and len(timings) > limit) or (check.sizes.scale and check.remaining() < stop):
                row["status"] = "skipped (dry)" if limit is not None and len(timings) > limit else "skipped (budget)"
            else:
                with check.piece(row):
                    row.update(time_test(check, test["condition"], lanes))
                    check.say(f"  test {test['condition']:6s} {lanes:7,d} lanes ({row['kernel']}): "
                              f"{row['lane_steps_per_s']:14,.0f} lane-steps/s")
        measured = timings[kind]
        test.update(lane_steps_per_s=measured.get("lane_steps_per_s"), compile_s=measured.get("compile_s", 0.0))
    rows += list(timings.values())
    estimate = extrapolate([r for r in rows if r["part"] == "evolution"], tests)
    check.say(f"  claims map: {len(programs)} programs ({sum(len(p.runs) for p in programs)} runs), {len(tests)} "
              f"tests: {estimate['hours']:.2f} h ({'complete' if estimate['complete'] else 'incomplete'}; target "
              f"under {TARGET_HOURS:g} h: {estimate['meets_target']})")
    return {"rows": rows, "tests": tests, "programs": len(programs), "runs": sum(len(p.runs) for p in programs),
            **estimate}
