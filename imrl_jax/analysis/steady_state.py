"""A learning test's numbers (section 3, Fig. 3b and 3c): performance per bin, the steady state, task pairs."""

from __future__ import annotations

import numpy as np

from imrl_jax.config import Config, ConfigError
from imrl_jax.world.worlds import task_maxima

PAIR_LEVEL = 0.2  # a task counts as solved in a test at this steady-state performance


def performance_curve(config: Config, reaches: np.ndarray) -> np.ndarray:
    """Reaches per bin (..., tasks, bins) as task performance per bin (the paper's normalised reward)."""
    per_bin = task_maxima(config) / config.num_bins
    return np.asarray(reaches, float) / per_bin[:, None]


def steady_bins(config: Config, steady_steps: int) -> int:
    """Number of final bins that make up the last ``steady_steps`` cycles."""
    bin_steps = config.task_steps // config.num_bins
    if steady_steps % bin_steps or not 0 < steady_steps <= config.task_steps:
        raise ConfigError(f"steady_steps: {steady_steps} is not a whole number of bins of {bin_steps} steps "
                          f"within a task of {config.task_steps}")
    return steady_steps // bin_steps


def summarise(config: Config, reaches: np.ndarray, steady_steps: int) -> dict:
    """Fig. 3c numbers from reaches (runs, best, tests, tasks, bins): steady state per run, mean, best run."""
    curve = performance_curve(config, reaches)
    steady = curve[..., -steady_bins(config, steady_steps):].mean(-1)  # (runs, best, tests, tasks)
    per_run = steady.mean((1, 2, 3))
    return dict(
        steady_mean=float(per_run.mean()), steady_sd=float(per_run.std()), best_run=int(per_run.argmax()),
        steady_best_run=float(per_run.max()), steady_per_run=[float(v) for v in per_run],
        steady_per_task=[float(v) for v in steady.mean((0, 1, 2))],
        whole_test_mean=float(curve.mean()),
        pairs_both_ways=pairs_both_ways(steady),
    )


def pairs_both_ways(performance, level: float = PAIR_LEVEL) -> float:
    """Share of (test, task pair) with both tasks of the pair at performance ``level`` or more.

    ``performance`` (..., tasks): each test's steady state per task. Tasks 2i and 2i+1 look
    the same up to their first junction and turn the other way there, so a fixed controller
    solves at most one of them: solving both takes choices learned for each task.
    """
    performance = np.asarray(performance, float)
    pairs = performance.reshape(performance.shape[:-1] + (-1, 2))
    return float((pairs >= level).all(-1).mean())
