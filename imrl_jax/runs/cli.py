"""What the command lines share: check-then-write, the usage error, the parser and help formatter, ``--set``, size limits.

Every command is built the same way, so that a refusal can never leave a file changed:

1. **parse** its arguments (:class:`Parser`: a bad option is a :class:`UsageError`);
2. **plan**: build from the arguments and the files it reads everything it will do, every value bounded,
   every file read safely, the memory of the whole run estimated, and raise a user error
   (:func:`user_errors`) at the first thing wrong. A plan writes nothing: no folder, no lock, no file;
3. **execute** the plan through :func:`execute`, the one place where a command may begin to write: it
   takes its lock, checks again what another process may have changed meanwhile, and only then writes,
   each file atomically (``rundir.write_atomic``), in an order after which a kill leaves the old or the
   new record.

``main`` is ``exit_codes``-wrapped, so a user error anywhere is one line and exit code 2. The suite's
attacks (``tests/attack.py``) stub :func:`execute` and throw hostile values and files at every
command's plan: whatever they give, nothing may change on disk before :func:`execute`.
"""

from __future__ import annotations

import argparse
import dataclasses
import difflib
import functools
import os
import sys
from typing import Callable, Mapping, Protocol, Sequence

from imrl_jax import config as config_bounds  # imports no JAX
from imrl_jax.config import WORLD_FIELDS, UsageError  # defined below every layer that raises it; every command's error


def user_errors() -> tuple[type[Exception], ...]:
    """The errors a command reports as one line with exit code 2: bad usage, config or run directory."""
    from imrl_jax.config import ConfigError
    from imrl_jax.runs.rundir import RunDirError

    return UsageError, ConfigError, RunDirError


def exit_codes(main: Callable[..., int]) -> Callable[..., int]:
    """A command's ``main``, whose bad input (:func:`user_errors`) is one line and exit code 2, and a write the user
    can fix (``RunWriteError``: a full disk) one line and exit code 1; nothing else is caught."""
    @functools.wraps(main)
    def reported(*args, **kwargs) -> int:
        from imrl_jax.runs.rundir import RunWriteError

        try:
            return main(*args, **kwargs)
        except user_errors() as error:
            print(f"error: {one_line(error)}", file=sys.stderr)
            return 2
        except RunWriteError as error:
            print(f"error: {one_line(error)}", file=sys.stderr)
            return 1

    return reported


class Plan(Protocol):
    """What a command will do, built and checked from its arguments and files: nothing written yet."""

    def execute(self) -> int:
        """Take the lock, check again what may have changed, write; the command's exit code."""


#: What ends a line for Python (``str.splitlines``) or a terminal, and the NUL byte: shown escaped in a message.
LINE_BREAKS = "\n\r\v\f\x1c\x1d\x1e\x85\u2028\u2029\x00"


def one_line(error: BaseException) -> str:
    """An error's message on one line: a value the user typed with a line break in it is shown escaped."""
    return str(error).translate({ord(c): repr(c)[1:-1] for c in LINE_BREAKS})


class Call:
    """A plan that is one call, for a command whose checks are all made before it (its arguments are the plan)."""

    def __init__(self, run: Callable[[], int], **checked):
        self.run, self.checked = run, checked  # checked: what the plan was built from, for tests to read

    def execute(self) -> int:
        """Make the call."""
        return self.run()


def execute(plan: Plan) -> int:
    """Carry out a checked plan: the one place a command begins to write (the suite's attacks stop here)."""
    return plan.execute()


class Parser(argparse.ArgumentParser):
    """An argument parser whose errors are UsageErrors, so that the command reports them as its other bad input."""

    def error(self, message: str):
        raise UsageError(message)


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

    return [f.name for f in dataclasses.fields(settings) if isinstance(f.default, (bool, int, float, str))
            and f.name not in WORLD_FIELDS]



def parse_sets(items: Sequence[str] | None, settings=None, flag: str = "--set") -> dict:
    """``--set FIELD=VALUE`` options (``flag``) as overrides of a settings dataclass (default: Config), each value of
    its field's type (raises UsageError)."""
    if settings is None:
        from imrl_jax.config import Config as settings

    fields = {f.name: f for f in dataclasses.fields(settings)}
    settable = settable_fields(settings)
    overrides = {}
    example = "--set eta_actor=0.02" if flag == "--set" else f"{flag} {settable[0]}={fields[settable[0]].default}"
    for item in items or []:
        name, sep, text = item.partition("=")
        if not sep:
            raise UsageError(f"{flag} {item}: expected FIELD=VALUE, e.g. {example}")
        if name not in settable:
            if name in WORLD_FIELDS and settings.__name__ == "Config":
                raise UsageError(f"{flag} {item}: the world is not set field by field (another world than the arena: "
                                 f"imrl_jax.world.worlds.configure, docs/WORLDS.md)")
            if name in fields:
                raise UsageError(f"{flag} {item}: {name} is not a scalar field; fields: {', '.join(settable)}")
            close = [f for f in settable if name and f.startswith(name)] or \
                difflib.get_close_matches(name, settable, n=1, cutoff=0.5)
            hint = f"did you mean {' or '.join(close)}? " if close else ""
            raise UsageError(f"{flag} {item}: {name} is not a {settings.__name__} field; {hint}fields: "
                             f"{', '.join(settable)}")
        try:
            overrides[name] = _parse_value(fields[name], text)
        except ValueError:
            raise UsageError(f"{flag} {item}: {name} cannot take the value {text!r}") from None
    return overrides


def refuse_option_fields(items: Sequence[str] | None, options: Mapping[str, str]) -> None:
    """Raise UsageError for a ``--set`` of a field that an option of the command line sets (``options``: field -> flag)."""
    for item in items or []:
        name = item.partition("=")[0]
        if name in options:
            raise UsageError(f"--set {item}: {name} is set by {options[name]}; use {options[name]} instead")


#: The largest sizes the commands accept, checked before anything is allocated (a typo such as
#: --generations 2147483648 would otherwise start allocating gigabytes); the config's own are its fields' bounds.
MAX_GENERATIONS = config_bounds.MAX_GENERATIONS
MAX_SEEDS = 10_000  # seeds of an evolution, runs, best and tests of a learning test
MAX_POPULATION = config_bounds.MAX_POPULATION
MAX_STEPS = config_bounds.MAX_STEPS  # per task and per childhood
MAX_BINS = config_bounds.MAX_BINS
MAX_LANES = 1_000_000  # lives evaluated at once: seeds x population, best x tests
#: CPU devices per core that --cpu-devices may ask for: each device holds its own runtime (100,000 took 19 GB).
CPU_DEVICES_PER_CORE = 4


def check_out(value: str | None, flag: str = "--out") -> None:
    """Raise UsageError if an output path is given but empty (it would silently mean the current directory)."""
    if value is not None and not value.strip():
        raise UsageError(f"{flag}: empty path; give a directory")


def check_cpu_devices(count: int) -> None:
    """Raise UsageError unless ``count`` (0: one per core) is at most :data:`CPU_DEVICES_PER_CORE` devices a core."""
    cores = os.cpu_count() or 1
    if count < 0:
        raise UsageError("--cpu-devices: must be 0 (one per core) or more")
    limit = CPU_DEVICES_PER_CORE * cores
    if count > limit:
        raise UsageError(f"--cpu-devices: {count:,} is above the limit of {limit:,} ({CPU_DEVICES_PER_CORE} per core "
                         f"of this machine's {cores})")


def add_register(parser: argparse.ArgumentParser) -> None:
    """The ``--register MODULE:ATTRIBUTE`` option: rows of the condition table of one's own (:func:`register`)."""
    parser.add_argument("--register", action="append", metavar="MODULE:ATTRIBUTE",
                        help="import MODULE (from the current directory or the path) and add its ATTRIBUTE, a "
                             "conditions.Condition or a list of them, to the condition table first (repeatable); "
                             "give it again to resume, render or test a run of such a row")


def register(specs: Sequence[str] | None) -> list[str]:
    """Add the rows ``MODULE:ATTRIBUTE`` names to the condition table; the specs (raises UsageError naming one).

    A row already in the table as it is (its module registered it on import, or it was given twice) is kept."""
    import importlib
    import sys

    from imrl_jax import conditions

    if "" not in sys.path and os.getcwd() not in sys.path:  # as ``python -m`` does: modules of the current directory
        sys.path.insert(0, os.getcwd())
    for spec in specs or []:
        module_name, sep, attribute = spec.partition(":")
        if not sep or not module_name or not attribute:
            raise UsageError(f"--register {spec}: expected MODULE:ATTRIBUTE, e.g. --register my_rows:ROWS")
        try:
            module = importlib.import_module(module_name)
        except (Exception, SystemExit) as error:  # noqa: BLE001 - whatever the module raises (or exits with), one line
            raise UsageError(f"--register {spec}: cannot import {module_name} ({type(error).__name__}: "
                             f"{str(error).splitlines()[0] if str(error) else ''})") from None
        if not hasattr(module, attribute):
            raise UsageError(f"--register {spec}: {module_name} has no attribute {attribute}")
        rows = getattr(module, attribute)
        rows = [rows] if isinstance(rows, conditions.Condition) else rows
        if not isinstance(rows, (list, tuple)) or not all(isinstance(r, conditions.Condition) for r in rows):
            raise UsageError(f"--register {spec}: {attribute} is not a conditions.Condition or a list of them")
        for row in rows:
            if conditions.CONDITIONS.get(row.name) == row:
                continue
            try:
                conditions.register(row)
            except ValueError as error:
                raise UsageError(f"--register {spec}: {error}") from None
    return list(specs or [])


def add_world(parser: argparse.ArgumentParser, what: str = "the world the agent lives in") -> None:
    """The ``--world NAME`` and ``--world-set FIELD=VALUE`` options (:func:`apply_world`; docs/WORLDS.md)."""
    from imrl_jax.world.worlds import WORLDS  # names only: a world's library is imported when it is made

    parser.add_argument("--world", metavar="NAME",
                        help=f"{what}: {', '.join(WORLDS)} (default: arena, the paper's; or the run's own; "
                             f"docs/WORLDS.md)")
    parser.add_argument("--world-set", action="append", metavar="FIELD=VALUE",
                        help="set one of the world's own settings, e.g. --world-set task_set=xland-novel "
                             "(repeatable; with --world)")


def apply_world(config, args):
    """``config`` in the world ``args.world`` with the ``--world-set`` settings; raises UsageError.

    Without ``--world`` the config's own world (a run's), whose settings ``--world-set`` changes; ``--world`` naming
    the config's world starts from its settings too. Another world than the arena brings its tasks: ``--task-set``
    (the arena's) is refused there."""
    from imrl_jax.config import ConfigError
    from imrl_jax.world import worlds

    name, items = getattr(args, "world", None), getattr(args, "world_set", None)
    if name is None and not items:
        return config
    if name is None and config.world == "arena":
        raise UsageError(f"--world-set {items[0]}: give the world too (--world NAME)")
    name = config.world if name is None else name
    if name not in worlds.WORLDS:
        raise UsageError(f"--world: unknown world {name!r} (choose from {', '.join(worlds.WORLDS)})")
    if name != "arena" and getattr(args, "task_set", None) is not None:
        raise UsageError(f"--task-set: the {name} world's tasks are its own (choose them with --world-set task_set=NAME)")
    try:
        settings_type = worlds.settings_type(name)
    except ImportError as error:  # an optional library that is not installed: its install command, in one line
        raise UsageError(f"--world {name}: {one_line(error)}") from None
    if items and settings_type is None:
        raise UsageError(f"--world-set {items[0]}: the {name} world has no settings of its own (its geometry is the "
                         f"config's: --set)")
    settings = dict(config.world_settings) if name == config.world else {}
    settings.update(parse_sets(items, settings_type, "--world-set") if items else {})
    try:
        return worlds.configure(config, name, **settings)
    except ConfigError as error:
        raise UsageError(f"--world {name}: {one_line(error)}") from None


def add_task_set(parser: argparse.ArgumentParser, what: str, default: str | None = None) -> None:
    """The ``--task-set NAME|FILE`` option every command that runs tasks shares (:mod:`imrl_jax.world.tasks`)."""
    parser.add_argument("--task-set", default=default, metavar="NAME|FILE",
                        help=f"{what}: paper (the six), novel (six never met in evolution: docs/NOVEL_TASKS.md) "
                             f"or a .json file")


def apply_task_set(config, args):
    """``config`` with the tasks of ``args.task_set`` (None: its own), checked on its geometry (raises ConfigError).

    ``config`` may be a function of config changes that makes it: the task set's tasks are then among them from the
    start, so that the target radius is checked against these tasks (and not refused by the tasks they replace).
    """
    make = config.replace if hasattr(config, "replace") else config
    if args.task_set is None:
        return make()
    from imrl_jax.config import ConfigError
    from imrl_jax.world.tasks import check, read

    tasks = read(args.task_set)
    try:
        made = make(tasks=tasks)
    except ConfigError as error:
        if error.field in ("tasks", "target_radius"):  # the set's tasks do not fit this config
            raise ConfigError(f"--task-set: {args.task_set}: {error}", error.field) from None
        raise
    return made.replace(tasks=check(made, tasks, args.task_set))


def check_at_most(flag: str, value: int | None, limit: int) -> None:
    """Raise UsageError naming ``flag`` and the limit if ``value`` (None: not given) is above ``limit``."""
    if value is not None and value > limit:
        raise UsageError(f"{flag}: {value:,} is above the limit of {limit:,}")


#: The largest seed or key: jax.random.key takes a uint32 (a larger one wraps round without a word).
MAX_KEY = 2**32 - 1


def check_key(flag: str, value: int | None, most: int = MAX_KEY) -> None:
    """Raise UsageError naming ``flag`` unless ``value`` (None: not given) is a key from 0 to ``most``."""
    check_at_least(flag, value, 0)
    check_at_most(flag, value, most)


def check_at_least(flag: str, value: int | None, least: int = 1) -> None:
    """Raise UsageError naming ``flag`` if ``value`` (None: not given) is below ``least``."""
    if value is not None and value < least:
        raise UsageError(f"{flag}: must be at least {least} (got {value})")


def ignored_notes(config, sets: Mapping[str, object]) -> list[str]:
    """A note for each ``--set`` of a field that ``config``'s condition never reads."""
    ignored = config.spec.ignored_fields()
    return [f"note: --set {name}={value}: {config.condition} does not read {name} (it changes nothing)"
            for name, value in sets.items() if name in ignored]


def device_warnings(config, cpu_devices: int = 0) -> list[str]:
    """Warnings about the machine: the GPU step kernel off a GPU, more CPU devices than cores (starts JAX's backend)."""
    import jax

    warnings = []
    if config.step_kernel == "pallas" and jax.default_backend() != "gpu":
        warnings.append(f"warning: step_kernel=pallas without a GPU (backend {jax.default_backend()}): the kernel runs "
                        f"in Pallas's interpreter, several times slower than step_kernel=xla")
    cores = os.cpu_count() or 1
    if cpu_devices > cores:
        warnings.append(f"warning: --cpu-devices {cpu_devices} is more than this machine's {cores} cores: "
                        f"the devices share them (no faster, likely slower)")
    return warnings
