"""What the command lines share: the usage error, the help formatter and ``--set FIELD=VALUE``."""

from __future__ import annotations

import argparse
import dataclasses
import difflib
from typing import Sequence


class UsageError(Exception):
    """Bad input: reported as one line, exit code 2, nothing written."""


def user_errors() -> tuple[type[Exception], ...]:
    """The errors a command reports as one line with exit code 2: bad usage, config or run directory."""
    from imrl_jax.config import ConfigError
    from imrl_jax.rundir import RunDirError

    return UsageError, ConfigError, RunDirError


class HelpFormatter(argparse.ArgumentDefaultsHelpFormatter):
    """``--help`` with each option's default, except where there is none to show (None, a flag's False)."""

    def _get_help_string(self, action):
        text = action.help or ""
        if action.default is None or action.default is False or action.default is argparse.SUPPRESS \
                or action.required or "default" in text:
            return text
        return super()._get_help_string(action)


def _parse_value(field: dataclasses.Field, text: str):
    default = field.default if field.default is not dataclasses.MISSING else None
    if isinstance(default, bool):
        if text.lower() in ("1", "true", "yes"):
            return True
        if text.lower() in ("0", "false", "no"):
            return False
        raise ValueError(text)
    if isinstance(default, int):
        return int(text)
    if isinstance(default, float):
        return float(text)
    if isinstance(default, str):
        return text
    raise ValueError("not settable from the command line")


def settable_fields(settings=None) -> list[str]:
    """Fields of a settings dataclass (default: Config) that ``--set`` accepts (the scalar ones)."""
    if settings is None:
        from imrl_jax.config import Config as settings

    return [f.name for f in dataclasses.fields(settings) if isinstance(f.default, (bool, int, float, str))]


def parse_sets(items: Sequence[str] | None, settings=None) -> dict:
    """``--set FIELD=VALUE`` options as overrides of a settings dataclass (default: Config), each value of its
    field's type (raises UsageError)."""
    if settings is None:
        from imrl_jax.config import Config as settings

    fields = {f.name: f for f in dataclasses.fields(settings)}
    settable = settable_fields(settings)
    overrides = {}
    for item in items or []:
        name, sep, text = item.partition("=")
        if not sep:
            raise UsageError(f"--set {item}: expected FIELD=VALUE, e.g. --set eta_actor=0.02")
        if name not in settable:
            if name in fields:
                raise UsageError(f"--set {item}: {name} is not a scalar field; fields: {', '.join(settable)}")
            close = [f for f in settable if name and f.startswith(name)] or \
                difflib.get_close_matches(name, settable, n=1, cutoff=0.5)
            hint = f"did you mean {' or '.join(close)}? " if close else ""
            raise UsageError(f"--set {item}: {name} is not a {settings.__name__} field; {hint}fields: "
                             f"{', '.join(settable)}")
        try:
            overrides[name] = _parse_value(fields[name], text)
        except ValueError:
            raise UsageError(f"--set {item}: {name} cannot take the value {text!r}") from None
    return overrides
