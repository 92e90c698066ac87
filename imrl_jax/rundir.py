"""Run directories and output files: reading an evolution's run, checking and writing outputs atomically."""

from __future__ import annotations

import json
import os
import tempfile
from typing import NamedTuple

import numpy as np

from imrl_jax.config import Config, ConfigError


class RunDirError(ValueError):
    """A run directory (or output path) that cannot be read or written; the message names it."""


class Run(NamedTuple):
    """What a run directory of ``python -m imrl_jax.evolve`` holds about its last evaluated generation."""

    config: Config
    seeds: list[int]
    generation: int  # generations evaluated
    evaluated: np.ndarray  # (seeds, population, genes) the last evaluated populations
    fitness: np.ndarray  # (seeds, population) their fitness


def write_atomic(path: str, data: bytes) -> None:
    """Write ``data`` to ``path`` through a temporary file, so a reader never sees half of it."""
    tmp = f"{path}.tmp-{os.getpid()}"
    with open(tmp, "wb") as f:
        f.write(data)
    os.replace(tmp, path)


def check_writable(path: str, flag: str = "--out") -> None:
    """Raise RunDirError naming ``flag`` unless ``path`` (a directory, existing or not) can be written in.

    Nothing is created: the nearest existing folder on the path is probed with a temporary file.
    """
    folder = os.path.abspath(path)
    while not os.path.exists(folder):
        folder = os.path.dirname(folder)
    if not os.path.isdir(folder):
        raise RunDirError(f"{flag}: cannot write to {path} ({folder} is not a directory)")
    try:
        with tempfile.TemporaryFile(dir=folder):
            pass
    except OSError as error:
        raise RunDirError(f"{flag}: cannot write to {path} ({folder}: {error.strerror or error})") from None


def read_config(run_dir: str) -> tuple[Config, list[int]]:
    """The config and seeds recorded in a run's ``config.json`` (raises RunDirError naming the file)."""
    path = os.path.join(run_dir, "config.json")
    try:
        with open(path) as f:
            saved = json.load(f)
        return Config.from_dict(saved["config"]), [int(s) for s in saved["seeds"]]
    except (OSError, ValueError, KeyError, TypeError, ConfigError) as error:
        raise RunDirError(f"{path} is unreadable ({error})") from None


def load_run(run_dir: str) -> Run:
    """A run directory's config, seeds and last evaluated generation (raises RunDirError naming the file)."""
    if not os.path.isdir(run_dir):
        raise RunDirError(f"{run_dir}: not a directory (give an evolution's run directory)")
    for name in ("config.json", "final_population.npz"):
        if not os.path.isfile(os.path.join(run_dir, name)):
            raise RunDirError(f"{os.path.join(run_dir, name)}: not found (is {run_dir} a run of "
                             f"python -m imrl_jax.evolve?)")
    config, seeds = read_config(run_dir)
    path = os.path.join(run_dir, "final_population.npz")
    try:
        with np.load(path) as data:
            generation, evaluated, fitness = int(data["generation"]), data["evaluated"], data["fitness"]
    except (OSError, ValueError, KeyError) as error:
        raise RunDirError(f"{path} is unreadable ({error})") from None
    if generation < 1:
        raise RunDirError(f"{path}: no generation has been evaluated yet")
    if evaluated.shape[:2] != fitness.shape or fitness.shape[0] != len(seeds):
        raise RunDirError(f"{path}: arrays do not match the {len(seeds)} seed(s) of config.json")
    return Run(config, seeds, generation, evaluated, fitness)


def best_genomes(run: Run, num_best: int) -> np.ndarray:
    """The ``num_best`` fittest genomes of each seed, fittest first: (seeds, num_best, genes)."""
    if not 1 <= num_best <= run.evaluated.shape[1]:
        raise RunDirError(f"--best: must be between 1 and the population size {run.evaluated.shape[1]}")
    order = np.argsort(-run.fitness, axis=1, kind="stable")[:, :num_best]
    return np.take_along_axis(run.evaluated, order[:, :, None], axis=1)
