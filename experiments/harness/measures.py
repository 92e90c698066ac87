"""What the studies' measure commands share: their outputs written atomically, their --out and sizes checked.

A measure (``python -m experiments.MODULE ... --out DIR``) plans first: every value bounded, every file it reads
checked, its --out able to take its files and holding nothing else; then writes NAME.csv and last result.json, which
tells the stage runner it is done, each through a temporary file (a kill leaves the stage not done, no half file).
"""

from __future__ import annotations

import numpy as np

from experiments.harness.study import write_measure  # noqa: F401 - the measures' writer, atomic
from imrl_jax.runs import cli
from imrl_jax.runs.cli import UsageError


def check_out_dir(out: str, outputs: tuple[str, ...], kind: str) -> None:
    """Refuse (one line naming --out) a measure's folder that is empty, unwritable, or holds anything but
    ``outputs`` (a measure run again replaces its own files)."""
    from imrl_jax.runs import rundir

    cli.check_out(out)
    if any(ord(c) < 32 for c in out):  # a NUL or a line break: no folder can be made of it
        raise UsageError(f"--out: {out!r} holds a control character")
    rundir.check_writable(out)
    rundir.check_outputs_dir(out, outputs, kind, overwrite=True)


def check_counts(options, limits: dict) -> None:
    """Raise UsageError naming ``--NAME`` unless each count ``NAME`` of ``limits`` in ``options`` (a namespace or a
    dict; None: not given) is at least 1 and at most its limit."""
    values = options if isinstance(options, dict) else vars(options)
    for name, limit in limits.items():
        cli.check_at_least(f"--{name.replace('_', '-')}", values.get(name))
        cli.check_at_most(f"--{name.replace('_', '-')}", values.get(name), limit)


def listed(flag: str, text: str, kind=int) -> list:
    """A comma-separated option's values of ``kind`` (raises UsageError naming ``flag``): no empty one, no NaN."""
    try:
        values = [kind(v) for v in text.split(",")]
    except ValueError:
        raise UsageError(f"{flag}: not a comma-separated list of {kind.__name__}s: {text!r}") from None
    if kind is float and not all(np.isfinite(values)):
        raise UsageError(f"{flag}: {text!r} holds a value that is not a finite number")
    return values


def checked_config(flag: str, preset: str, **fields):
    """A config made of a preset and ``fields`` (a ConfigError names ``flag`` and the field)."""
    from imrl_jax.config import ConfigError, make_config

    try:
        return make_config(preset, **fields)
    except ConfigError as error:
        raise UsageError(f"{flag}: {error}") from None
