"""Tables of numbers: markdown rows for the studies' documents, a run's history.csv columns, a measure's CSV."""

from __future__ import annotations

import csv
import json
import os

import numpy as np


def line(*cells) -> str:
    """One markdown table row."""
    return "| " + " | ".join(str(c) for c in cells) + " |"


def head(*names) -> list[str]:
    """A markdown table's header row and its rule."""
    return [line(*names), "|" + "---|" * len(names)]


def mean_sd(mean: float, sd: float, digits: int = 3) -> str:
    """"mean +- sd", each to ``digits`` decimals."""
    return f"{mean:.{digits}f} +- {sd:.{digits}f}"


def history_columns(run_dir: str | None, names) -> np.ndarray | None:
    """The columns ``names`` of a run's history.csv as (generations, seeds, names) (NaN where a seed has not written
    a generation); None without the file or any row."""
    path = os.path.join(run_dir or "", "history.csv")
    if not os.path.isfile(path):
        return None
    with open(path) as f:
        rows = list(csv.DictReader(f))
    if not rows:
        return None
    seeds = sorted({int(r["seed"]) for r in rows})
    values = np.full((max(int(r["generation"]) for r in rows) + 1, len(seeds), len(names)), np.nan)
    for r in rows:
        values[int(r["generation"]), seeds.index(int(r["seed"]))] = [float(r[n]) for n in names]
    return values


def write_measure(out_dir: str, name: str, table: list[dict], command: str, digits: int | None = None,
                  **recorded) -> None:
    """A measure's rows (``table``) as ``out_dir/NAME.csv`` (floats to ``digits`` decimals, if given; a row may lack
    a column), then its result.json, which makes the measure done: its command, commit and ``recorded``."""
    from experiments.reproduce import MEASURED
    from imrl_jax.checkpoint import git_commit

    os.makedirs(out_dir, exist_ok=True)
    with open(os.path.join(out_dir, f"{name}.csv"), "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(dict.fromkeys(k for r in table for k in r)), restval="",
                                lineterminator="\n")
        writer.writeheader()
        writer.writerows({k: f"{v:.{digits}f}" if digits is not None and isinstance(v, float) else v
                          for k, v in r.items()} for r in table)
    with open(os.path.join(out_dir, MEASURED), "w") as f:
        json.dump(dict(command=command, git_commit=git_commit(), **recorded), f, indent=2)
