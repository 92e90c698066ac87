"""What a study takes on one GPU, from the speeds ``gpu_check`` measured there (docs/gpu/gpu_check.json).

A stage's lane-steps run at the speed its ``generation`` step measured, with the step kernel that
``step_kernel=auto`` would choose for the stage (:mod:`imrl_jax.agent.kernel_choice`: its run's recorded model
where the run is done, else its condition's), at the number of individuals measured nearest the stage's,
and each stage pays one compilation as measured there. On the kernel, a condition whose whole lives the
``models`` step timed runs at that step's ratio to LE-LS's (the selector's options at theirs where measured).
Where the check's ``study`` step timed the stage's own program (:func:`imrl_jax.commands.gpu_study.program_key`:
the claims map's) or its learning test's phase, that speed is used instead. Writing checkpoints and histories is
not counted.
"""

from __future__ import annotations

import json
import math
import os
from typing import NamedTuple

from experiments.harness.reproduce import Stage
from experiments.harness.study import ROOT

GPU_CHECK = os.path.join("docs", "gpu", "gpu_check.json")


class GpuSpeed(NamedTuple):
    """The speeds one gpu_check measured: its generations' {kernel: [(individuals, lane-steps/s, compile s)]}, its
    study's programs {program key: (lane-steps/s, compile s)} and tests {condition: [(lanes, lane-steps/s,
    compile s)]}."""

    device: str
    rows: dict
    source: str
    programs: dict | None = None
    tests: dict | None = None
    models: dict | None = None  # the models step's {(condition, options): its lives' speed over LE-LS's}


def _speed(row: dict, **fields) -> tuple | None:
    """``row``'s ``fields``, each read as its type, then its speed and compilation seconds; None where one is missing
    or not of its type or number."""
    try:
        values = tuple(kind(row[f]) for f, kind in fields.items())
        rate, compile_s = float(row["lane_steps_per_s"]), float(row.get("compile_s") or 0.0)
    except (KeyError, TypeError, ValueError):
        return None
    return (*values, rate, max(compile_s, 0.0)) if math.isfinite(rate) and rate > 0 and math.isfinite(compile_s) \
        else None


def read_speed(path: str | None = None) -> GpuSpeed | None:
    """The speeds of ``path`` (relative to the project; default :data:`GPU_CHECK`), or None where it holds none
    (missing, unreadable, a dry run's)."""
    path = GPU_CHECK if path is None else path
    try:
        with open(os.path.join(ROOT, path), "rb") as f:
            data = json.loads(f.read(2**24))
    except (OSError, ValueError):
        return None
    if not isinstance(data, dict) or data.get("dry") or not isinstance(data.get("steps"), list):
        return None
    rows: dict[str, list] = {}  # the generation step's
    programs: dict[str, tuple] = {}  # the study step's
    tests: dict[str, list] = {}
    models: dict[tuple, float] = {}
    for step in data["steps"]:
        kind = step.get("step") if isinstance(step, dict) else None
        for row in step.get("rows", []) if kind == "models" else []:
            ratio = row.get("over_le_ls") if isinstance(row, dict) and row.get("status") == "ok" else None
            if isinstance(ratio, (int, float)) and math.isfinite(ratio) and ratio > 0:
                models[str(row.get("condition")), str(row.get("options") or "")] = float(ratio)
        for row in step.get("rows", []) if kind in ("generation", "study") else []:
            if not isinstance(row, dict) or kind == "study" and row.get("status") != "ok":
                continue
            if kind == "generation" and (found := _speed(row, kernel=str, individuals=int)) and found[1] > 0:
                rows.setdefault(found[0], []).append(found[1:])
            elif kind == "study" and row.get("part") == "evolution" and (found := _speed(row, program=str)):
                programs[found[0]] = found[1:]
            elif kind == "study" and row.get("part") == "test" and (found := _speed(row, condition=str, lanes=int)):
                tests.setdefault(found[0], []).append(found[1:])
    machine = data.get("machine") if isinstance(data.get("machine"), dict) else {}
    return (GpuSpeed(str(machine.get("device") or "a GPU"), rows, path, programs, tests, models)
            if rows or programs else None)


def stage_config(stage: Stage):
    """The model ``stage`` lives: its run's recorded one where it is done, else its condition's in its world (None for
    a measure of several runs, or a condition its world refuses)."""
    from imrl_jax import conditions
    from imrl_jax.config import ConfigError, make_config
    from imrl_jax.runs.rundir import RunDirError, read_config

    config = None
    if stage.kind == "evolve" and os.path.isfile(os.path.join(stage.out_dir, "config.json")):
        try:  # the model the run recorded (a time-scale option, a preset's values), its own choice set aside
            config = read_config(stage.out_dir)[0].replace(step_kernel="auto")
        except (ConfigError, RunDirError, OSError, ValueError):
            config = None
    if config is None:
        if stage.condition not in conditions.CONDITIONS:
            return None
        config = make_config("paper", condition=stage.condition)
        if stage.world != "arena":  # its world's (default settings): what auto decides by
            from imrl_jax.world import worlds

            try:
                config = worlds.configure(config, stage.world)
            except (ConfigError, ValueError):
                return None
    return config


def stage_kernel(stage: Stage) -> str:
    """The step kernel ``auto`` lives ``stage`` with on a GPU: "pallas" or "xla"."""
    return auto_kernel(stage_config(stage))


def auto_kernel(config) -> str:
    """The step kernel ``auto`` lives ``config`` (a stage's :func:`stage_config`) with on a GPU."""
    from imrl_jax.agent import kernel_choice

    if config is None:
        return "xla"  # a measure of several runs: the slower step, to be safe
    return kernel_choice.resolve(config, "gpu")[0].step_kernel


def studied_seconds(stage: Stage, scale: dict, speed: GpuSpeed, config) -> float | None:
    """Seconds ``stage`` (its model ``config``: :func:`stage_config`) takes at the speed the study step measured for
    its own program (an evolution) or its condition's test phase at the lane count nearest its own (a learning
    test); None where it measured neither."""
    from experiments.harness.reproduce import life_steps
    from imrl_jax.commands.gpu_study import program_key

    if stage.kind == "evolve" and speed.programs and config is not None:
        measured = speed.programs.get(program_key(config))
        return None if measured is None else stage.cost / measured[0] + measured[1]
    if stage.kind == "test" and (speed.tests or {}).get(stage.condition) and "test_steps" in scale:
        lanes = 6 * max(1.0, stage.cost / life_steps(scale, stage.condition, scale["test_steps"]))
        _, rate, compile_s = min(speed.tests[stage.condition], key=lambda row: abs(math.log(row[0] / lanes)))
        return stage.cost / rate + compile_s
    return None


def stage_seconds(stage: Stage, scale: dict, speed: GpuSpeed) -> float:
    """Seconds ``stage`` takes whole on the measured GPU (0 for a stage that lives no lane-steps)."""
    if stage.cost <= 0:
        return 0.0
    config = stage_config(stage)  # read once: a done run's config.json, or its condition in its world
    studied = studied_seconds(stage, scale, speed, config)
    if studied is not None:
        return studied
    if not speed.rows:  # a check of the study alone: its slowest program's speed, to be safe
        return stage.cost / min(rate for rate, _ in speed.programs.values())
    kernel = auto_kernel(config)
    measured = speed.rows.get(kernel) or speed.rows.get("xla") or next(iter(speed.rows.values()))
    individuals = max(1, int(scale.get("seeds", 1)) * int(scale.get("population", 50)))
    _, rate, compile_s = min(measured, key=lambda row: abs(math.log(row[0] / individuals)))
    return stage.cost / (rate * model_ratio(config, speed) if kernel == "pallas" else rate) + compile_s


def model_ratio(config, speed: GpuSpeed) -> float:
    """The speed of ``config``'s model (a stage's :func:`stage_config`) on the kernel over LE-LS's, as the
    ``models`` step measured it (1 where it did not: the generation step's LE-LS speed as it is)."""
    if not speed.models or config is None:
        return 1.0
    options = config.selector_termination if config.selector_options else ""
    return speed.models.get((config.condition, options), speed.models.get((config.condition, ""), 1.0))


def study_hours(stages: list[Stage], scale: dict, speed: GpuSpeed | None) -> float | None:
    """Hours a whole study takes on the measured GPU (None without a measurement)."""
    return None if speed is None else sum(stage_seconds(s, scale, speed) for s in stages) / 3600
