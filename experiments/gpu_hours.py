"""What a study takes on one GPU, from the speeds ``gpu_check`` measured there (docs/gpu/gpu_check.json).

A stage's lane-steps run at the speed its ``generation`` step measured, with the step kernel that
``step_kernel=auto`` would choose for the stage (:mod:`imrl_jax.kernel_choice`: its run's recorded model
where the run is done, else its condition's), at the number of individuals measured nearest the stage's,
and each stage pays one compilation as measured there. Writing checkpoints and histories is not counted.
"""

from __future__ import annotations

import json
import math
import os
from typing import NamedTuple

from experiments.reproduce import Stage

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
GPU_CHECK = os.path.join("docs", "gpu", "gpu_check.json")


class GpuSpeed(NamedTuple):
    """The generation speeds one gpu_check measured: {kernel: [(individuals, lane-steps/s, compile s)]}."""

    device: str
    rows: dict
    source: str


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
    rows: dict[str, list] = {}
    for step in data["steps"]:
        for row in step.get("rows", []) if isinstance(step, dict) and step.get("step") == "generation" else []:
            try:
                kernel, individuals = str(row["kernel"]), int(row["individuals"])
                rate, compile_s = float(row["lane_steps_per_s"]), float(row.get("compile_s", 0.0))
            except (KeyError, TypeError, ValueError):
                continue
            if individuals > 0 and math.isfinite(rate) and rate > 0 and math.isfinite(compile_s):
                rows.setdefault(kernel, []).append((individuals, rate, max(compile_s, 0.0)))
    machine = data.get("machine") if isinstance(data.get("machine"), dict) else {}
    return GpuSpeed(str(machine.get("device") or "a GPU"), rows, path) if rows else None


def stage_kernel(stage: Stage) -> str:
    """The step kernel ``auto`` lives ``stage`` with on a GPU: "pallas" or "xla"."""
    from imrl_jax import conditions, kernel_choice
    from imrl_jax.config import ConfigError, make_config
    from imrl_jax.rundir import RunDirError, read_config

    config = None
    if stage.kind == "evolve" and os.path.isfile(os.path.join(stage.out_dir, "config.json")):
        try:  # the model the run recorded (a time-scale option, a preset's values), its own choice set aside
            config = read_config(stage.out_dir)[0].replace(step_kernel="auto")
        except (ConfigError, RunDirError, OSError, ValueError):
            config = None
    if config is None:
        if stage.condition not in conditions.CONDITIONS:
            return "xla"  # a measure of several runs: the slower step, to be safe
        config = make_config("paper", condition=stage.condition)
    return kernel_choice.resolve(config, "gpu")[0].step_kernel


def stage_seconds(stage: Stage, scale: dict, speed: GpuSpeed) -> float:
    """Seconds ``stage`` takes whole on the measured GPU (0 for a stage that lives no lane-steps)."""
    if stage.cost <= 0:
        return 0.0
    measured = speed.rows.get(stage_kernel(stage)) or speed.rows.get("xla") or next(iter(speed.rows.values()))
    individuals = max(1, int(scale.get("seeds", 1)) * int(scale.get("population", 50)))
    _, rate, compile_s = min(measured, key=lambda row: abs(math.log(row[0] / individuals)))
    return stage.cost / rate + compile_s


def study_hours(stages: list[Stage], scale: dict, speed: GpuSpeed | None) -> float | None:
    """Hours a whole study takes on the measured GPU (None without a measurement)."""
    return None if speed is None else sum(stage_seconds(s, scale, speed) for s in stages) / 3600
