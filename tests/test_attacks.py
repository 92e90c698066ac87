"""Every command attacked as a hostile user would: hostile values for every option, hostile files it reads.

Each command's ``main`` runs in this process through ``tests/attack.attack``: ``cli.execute`` is stubbed, so a
plan that passes is not carried out (nothing compiles), and the folder it works in is compared byte for byte
before and after. The contract (``attack.assert_contract``): refused with exit code 2 and one line naming the
option or file (no traceback), or planned; nothing written either way. Hypothesis draws the attacks with a
fixed budget per command and a fixed seed (``derandomize``), so the default suite always runs the same
cases; ``-m slow`` runs a longer profile. The commands' own test files hold the listed regressions.
"""

from __future__ import annotations

import argparse
import os
import shutil
from typing import Callable, NamedTuple

import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from attack import (HOSTILE_FILE_BYTES, HOSTILE_FLOATS, HOSTILE_INTS, HOSTILE_TEXTS, assert_contract, assert_refused,
                    attack, damage, tree)

#: Cases drawn per command in the default suite, and under ``-m slow``.
DEFAULT_BUDGET = 60
SLOW_BUDGET = 400


class Command(NamedTuple):
    """A command to attack: its ``main``, its parser, and a command line it accepts (``RUN``: a finished run)."""

    name: str
    main: Callable[[list[str]], int]
    parser: Callable[[], argparse.ArgumentParser]
    base: tuple[str, ...]
    avoid: tuple[str, ...] = ()  # values not tried (runspec's root "/": a walk of the whole file system)


def _commands() -> list[Command]:
    from imrl_jax.commands import (baselines, bench, compare, demo, evolve, gpu_check, landscape_run, learning_test,
                                   render, runspec)
    from experiments import __main__ as experiments_main, circular_paths, selector_sweep
    from experiments.harness.study import studies
    from imrl_jax.commands.evolve_options import parser as evolve_parser
    from imrl_jax.commands.learning_test_options import parser as learning_test_parser

    return [
        Command("evolve", evolve.main, evolve_parser, ("--cond", "EE-LS", "--preset", "small", "--out", "out")),
        Command("evolve --sweep", evolve.main, evolve_parser,
                ("--cond", "EE-LS", "--preset", "small", "--sweep", "eta=0.1,0.2", "--out", "out")),
        Command("evolve --resume", evolve.main, evolve_parser, ("--resume", "--out", "RUN")),
        Command("evolve --world", evolve.main, evolve_parser,
                ("--cond", "LE-LS", "--preset", "small", "--world", "xland", "--out", "out")),
        Command("learning_test", learning_test.main, learning_test_parser,
                ("RUN", "--best", "2", "--tests", "1", "--task-steps", "200", "--bins", "2", "--steady-steps", "100",
                 "--chunks", "1", "--out", "out")),
        Command("learning_test --cond SLE", learning_test.main, learning_test_parser,
                ("--cond", "SLE", "--preset", "small", "--runs", "1", "--best", "1", "--tests", "1", "--task-steps",
                 "200", "--bins", "2", "--steady-steps", "100", "--chunks", "1", "--out", "out")),
        Command("render", render.main, render.parser, ("RUN", "--task", "1", "--steps", "4", "--out", "out.gif")),
        Command("landscape_run", landscape_run.main, landscape_run.parser,
                ("RUN", "--out", "out", "--generations", "0", "--lives", "2", "--parents", "2", "--mutants", "2",
                 "--walks", "2", "--walk-length", "2", "--random", "2", "--chunk", "2")),
        Command("baselines", baselines.main, baselines.parser, ("--steps", "1000", "--seeds", "1", "--out", "out")),
        Command("demo", demo.main, demo.parser, ("--out", "out")),
        Command("bench", bench.main, bench.parser, ("--json", "out/bench.json")),
        Command("compare", compare.main, compare.parser, ("HEAD",)),
        Command("gpu_check", gpu_check.main, gpu_check.parser, ("--dry", "--out", "out")),
        Command("runspec", runspec.main, runspec.parser, (".", "--record", "out/keys.json"), avoid=("/",)),
        Command("experiments", experiments_main.main, lambda: experiments_main.parser(studies()),
                ("list", "selector-sweep")),
        Command("experiments.circular_paths", circular_paths.main, circular_paths.parser,
                ("--out", "out", "--task-steps", "20")),
        Command("experiments.selector_sweep", selector_sweep.main, selector_sweep.parser,
                ("sweep", "--out", "out", "--task-steps", "20", "--seeds", "1")),
    ]


COMMANDS = {c.name: c for c in _commands()}


@pytest.fixture(scope="module")
def arena(tmp_path_factory, tiny_run):
    """A folder holding a finished tiny run (``RUN``), in which every attack of a command runs."""
    root = tmp_path_factory.mktemp("attacks")
    shutil.copytree(tiny_run, root / "RUN", ignore=shutil.ignore_patterns(".lock"))
    return str(root)


def _options(parser: argparse.ArgumentParser) -> list[argparse.Action]:
    return [a for a in parser._actions if not isinstance(a, argparse._HelpAction)]


def _flag(action: argparse.Action) -> str:
    return action.option_strings[0] if action.option_strings else (action.metavar or action.dest)


@st.composite
def hostile_value(draw, action: argparse.Action) -> str:
    """A hostile value for ``action``: chosen by its type, or any of the hostile kinds."""
    if action.type is int:
        pool = st.one_of(st.sampled_from(HOSTILE_INTS), st.integers(-2**70, 2**70).map(str))
    elif action.type is float:
        pool = st.one_of(st.sampled_from(HOSTILE_FLOATS), st.floats(allow_nan=True, allow_infinity=True).map(repr))
    else:
        pool = st.one_of(st.sampled_from(HOSTILE_TEXTS), st.text(min_size=0, max_size=12))
    if action.dest in ("set", "sweep", "strategy_set"):  # FIELD=VALUE: a real field with a hostile value, or junk
        from imrl_jax.runs.cli import settable_fields

        field = st.sampled_from(settable_fields() + ["eta", "trace_lambda", "no_such_field"])
        value = st.one_of(st.sampled_from(HOSTILE_FLOATS + HOSTILE_INTS + HOSTILE_TEXTS), st.text(max_size=8))
        pool = st.one_of(pool, st.builds(lambda f, v: f"{f}={v}", field, value))
    if action.dest == "world_set":  # a setting of XLand's with a hostile value, or junk
        from imrl_jax.runs.cli import settable_fields
        from imrl_jax.world.xland import XLandSettings

        field = st.sampled_from(settable_fields(XLandSettings) + ["colours", "no_such_setting"])
        value = st.one_of(st.sampled_from(HOSTILE_FLOATS + HOSTILE_INTS + HOSTILE_TEXTS), st.text(max_size=8))
        pool = st.one_of(pool, st.builds(lambda f, v: f"{f}={v}", field, value))
    return draw(pool)


@st.composite
def hostile_argv(draw, command: Command) -> tuple[list[str], str]:
    """The command's accepted line with one option (or positional) given a hostile value; the argv and the flag."""
    action = draw(st.sampled_from(_options(command.parser())))
    flag = _flag(action)
    argv = list(command.base)
    if not action.option_strings:  # a positional: the base's value replaced
        value = draw(hostile_value(action).filter(lambda v: v not in command.avoid))
        positionals = [a.dest for a in command.parser()._actions if not a.option_strings]
        positions = _positions(command.parser(), argv)
        k = positionals.index(action.dest)
        if k < len(positions):
            argv[positions[k]] = value
        else:  # the base gives none (learning_test from scratch): given
            argv = [value, *argv]
        return argv, flag
    if action.nargs == 0:  # a flag: given (twice, or alone)
        return argv + [flag] * draw(st.integers(1, 2)), flag
    if flag in argv:  # the option's own value replaced (its other occurrences kept)
        i = argv.index(flag)
        del argv[i:i + 2]
    value = draw(hostile_value(action).filter(lambda v: v not in command.avoid))
    return argv + [f"{flag}={value}"], flag  # --flag=VALUE: a value starting with '-' is still its value


def _fields(flag: str) -> tuple[str, ...]:
    """The config fields an option sets (a refusal of the field's value may name the field)."""
    from imrl_jax.commands.evolve_options import OPTION_FIELDS

    return (flag.lstrip("-").replace("-", "_"), *(f for f, option in OPTION_FIELDS.items() if option == flag))


def _positions(parser: argparse.ArgumentParser, argv: list[str]) -> list[int]:
    """Where the positional arguments of ``argv`` stand (an option's value is not one)."""
    takes_value = {o for a in parser._actions if a.nargs != 0 for o in a.option_strings}
    found, i = [], 0
    while i < len(argv):
        if argv[i] in takes_value:
            i += 2
            continue
        if not argv[i].startswith("-"):
            found.append(i)
        i += 1
    return found


#: Values no whole-number option may take: not a number, a fraction, nothing, past 64 bits.
NOT_COUNTS = ("nan", "1.5", "", "x", "18446744073709551616")


def _check(command: Command, root: str, argv: list[str], flag: str) -> str:
    outcome = attack(command.main, argv, root)
    # FIELD=VALUE options: the field named is the option named; argparse names an argument it does not know itself
    fields = [a.split("=", 2)[1] for a in argv if a.startswith(f"{flag}=") and a.count("=") >= 2]
    # an option whose value conflicts with another given may be refused naming the other
    given = {a.split("=")[0] for a in argv if a.startswith("--")}
    runs = ("RUN", "run_dir", "config.json") if "RUN" in argv else ()
    # a positional attacked: the refusal may name the path given (a file it lacks) or the argument
    positional = [a for a in argv if not a.startswith("-") and a not in command.base][:1] if flag[0] != "-" else []
    names = (flag, *_fields(flag), *fields, *given, *runs, *positional, "run_dir", "memory", "unrecognized arguments")
    result = assert_contract(outcome, *names, argv=argv)
    action = next((a for a in command.parser()._actions if flag in a.option_strings), None)
    if action is not None and action.type is int and argv[-1] in (f"{flag}={v}" for v in NOT_COUNTS):
        assert result == "refused", f"{argv[-1]} was planned"
    return result


def _attack_test(budget: int):
    @pytest.mark.parametrize("name", sorted(COMMANDS))
    def test(arena, name):
        command = COMMANDS[name]
        before = tree(arena)
        seen = {"refused": 0, "planned": 0}

        @settings(max_examples=budget, deadline=None, derandomize=True, database=None,
                  suppress_health_check=list(HealthCheck))
        @given(hostile_argv(command))
        def attacked(case):
            argv, flag = case
            seen[_check(command, arena, argv, flag)] += 1

        attacked()
        print(f"attacks of {name}: {seen['refused']} refused, {seen['planned']} planned")  # -s: docs/TESTING.md's counts
        assert tree(arena) == before  # the run it read is as it was
        assert seen["refused"] > 0, seen  # the attacks reached the checks

    return test


test_every_option_of_every_command_keeps_the_contract = _attack_test(DEFAULT_BUDGET)
test_every_option_of_every_command_keeps_the_contract_long = pytest.mark.slow(_attack_test(SLOW_BUDGET))


def test_the_base_command_lines_are_planned(arena):
    """Each command's accepted line reaches ``execute`` (else the attacks would only test one refusal)."""
    for command in COMMANDS.values():
        if command.name in ("baselines",) and not _has("brax"):
            continue
        outcome = attack(command.main, list(command.base), arena)
        assert outcome.planned and not outcome.changed, (command.name, outcome.stderr)


@pytest.mark.parametrize("char", list("\n\r\v\f\x1c\x1d\x1e\x85\u2028\u2029\x00"))
def test_a_refusal_is_one_line_whatever_the_value_holds(arena, char):
    """A value holding a line break (for Python or a terminal) or NUL is shown escaped: the refusal stays one line."""
    for name in ("evolve", "render", "landscape_run", "learning_test"):
        argv = [*COMMANDS[name].base, f"--register=x{char}y"]
        assert_refused(attack(COMMANDS[name].main, argv, arena), "--register", argv=argv)


def _has(module: str) -> bool:
    import importlib.util

    return importlib.util.find_spec(module) is not None


#: The files of a run, and the commands that read each (a command not listed does not read it).
RUN_FILES = ("config.json", "final_population.npz", "history.csv")
READERS = {"config.json": ("evolve --resume", "learning_test", "render", "landscape_run"),
           "final_population.npz": ("learning_test", "render", "landscape_run"),
           "history.csv": ()}  # read only where the final population was not kept (tests/test_landscape_run.py)


@pytest.mark.parametrize("how", [*HOSTILE_FILE_BYTES, "removed"])
@pytest.mark.parametrize("name", RUN_FILES)
def test_every_reader_of_a_damaged_run_file_is_one_line_naming_it(arena, tmp_path, name, how):
    """A run's file damaged every way: each command that reads it refuses naming it, nothing written."""
    root = tmp_path / "damaged"
    shutil.copytree(os.path.join(arena, "RUN"), root / "RUN")
    damage(str(root / "RUN" / name), how)
    for reader, command in COMMANDS.items():
        outcome = attack(command.main, list(command.base), str(root))
        result = assert_contract(outcome, name, "RUN", argv=[reader, name, how])
        # landscape_run measures a run whose final population was not kept from its history (generation 0 here)
        needed = reader in READERS[name] and (reader, name, how) != ("landscape_run", "final_population.npz",
                                                                      "removed")
        assert result == "refused" or not needed, (reader, name, how, outcome.stderr)


# ----------------------------------------------------------------------------- kill and resume

#: What a command's outputs may differ in between a killed-and-resumed run and an uninterrupted one: times, the
#: command line and what the resume itself records (JSON keys at any depth).
VOLATILE = {"seconds", "elapsed_seconds", "created", "command", "resumed_runs", "git_commit", "sweep", "source",
            "seconds_with_compile", "started", "finished", "run", "out"}
#: Files a resume rewrites with times or plots (compared by their numbers elsewhere, or not at all).
SKIPPED = (".png", ".gif", ".lock", "tensorboard")


def _outputs(root: str) -> dict:
    """Every output under ``root`` as comparable data: arrays of .npz, JSON without :data:`VOLATILE`, other bytes;
    checkpoints and plots left out (a resume writes its own, equal in what they hold)."""
    import json

    import numpy as np

    def strip(value):
        if isinstance(value, dict):
            return {k: strip(v) for k, v in value.items() if k not in VOLATILE}
        if isinstance(value, list):
            return [strip(v) for v in value]
        return value

    found = {}
    for path, data in tree(root).items():
        if data is None or "checkpoints" in path.split(os.sep) or path.endswith(SKIPPED) \
                or any(part in SKIPPED for part in path.split(os.sep)):
            continue
        if path.endswith(".npz"):
            with np.load(os.path.join(root, path)) as arrays:
                found[path] = {name: (arrays[name].dtype.str, arrays[name].shape, arrays[name].tobytes())
                               for name in arrays.files}
        elif path.endswith(".json"):
            found[path] = strip(json.loads(data))
        else:
            found[path] = data
    return found


def _kill_cases(tiny_run, sweep: str = "SWEEP") -> dict[str, tuple[list[str], list[str]]]:
    """Each resumable command: its command line writing ``OUT``, and the line that goes on with it (``sweep``: a
    finished sweep, whose points a sweep's learning test tests)."""
    from helpers import evolve_args

    evolution = evolve_args(seeds=2, population=4, parents=2, generations=4, task_steps=200, childhood_steps=200,
                            bins=1)
    test = ["--cond", "SLE", "--preset", "small", "--runs", "3", "--best", "1", "--tests", "2", "--task-steps", "400",
            "--bins", "4", "--steady-steps", "200", "--chunks", "2", "--quiet", "--out", "OUT"]
    sweep_test = [sweep, "--best", "1", "--tests", "2", "--task-steps", "400", "--bins", "4", "--steady-steps", "200",
                  "--chunks", "2", "--quiet", "--out", "OUT"]
    landscape = [tiny_run, "--out", "OUT", "--generations", "0,last", "--lives", "2", "--parents", "2",
                 "--mutants", "2", "--walks", "2", "--walk-length", "2", "--random", "4", "--chunk", "4"]
    return {
        "evolve": (["-m", "imrl_jax.evolve", *evolution, "--out", "OUT"],
                   ["-m", "imrl_jax.evolve", "--resume", "--out", "OUT", "--quiet"]),
        "evolve --sweep": (["-m", "imrl_jax.evolve", *evolution, "--sweep", "eta=0.1,0.2", "--out", "OUT"],
                           ["-m", "imrl_jax.evolve", "--resume", "--out", "OUT", "--quiet"]),
        "learning_test": (["-m", "imrl_jax.learning_test", *test], ["-m", "imrl_jax.learning_test", *test]),
        "learning_test SWEEP": (["-m", "imrl_jax.learning_test", *sweep_test],
                                ["-m", "imrl_jax.learning_test", *sweep_test]),
        "landscape_run": (["-m", "imrl_jax.landscape_run", *landscape],
                          ["-m", "imrl_jax.landscape_run", *landscape]),
    }


def _run(argv: list[str], out: str, cwd: str, kill_after: float | None = None) -> tuple[float, bool]:
    """``python argv`` with ``OUT`` replaced by ``out``: its seconds, and whether it was killed (SIGKILL) on the way."""
    import signal
    import subprocess
    import sys
    import time

    from helpers import TIMEOUT

    start = time.perf_counter()
    process = subprocess.Popen([sys.executable, *[out if a == "OUT" else a for a in argv]], cwd=cwd,
                               env={**os.environ, "JAX_PLATFORMS": "cpu"}, stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True)
    try:
        if kill_after is not None:
            try:
                process.wait(timeout=kill_after)
            except subprocess.TimeoutExpired:
                process.send_signal(signal.SIGKILL)
                process.communicate()
                return time.perf_counter() - start, True
        _, err = process.communicate(timeout=TIMEOUT)
    finally:
        process.kill()
    assert process.returncode == 0, f"{argv}: exit {process.returncode}\n{err[-3000:]}"
    return time.perf_counter() - start, False


def _kill_and_resume(tiny_run, tmp_path, name: str, points: int, seed: int, sweep: str = "SWEEP") -> None:
    import random

    first, again = _kill_cases(tiny_run, sweep)[name]
    reference = str(tmp_path / "reference")
    seconds, _ = _run(first, reference, str(tmp_path))
    draw = random.Random(seed)
    kills = 0
    for point in range(points):
        when = draw.uniform(0.05, 1.0) * seconds  # anywhere in an uninterrupted run's time, its start included
        out = str(tmp_path / f"killed-{point}")
        _, killed = _run(first, out, str(tmp_path), kill_after=when)
        kills += killed
        if killed and os.path.isdir(out):
            _run(again, out, str(tmp_path))
        elif killed:  # killed before it made its folder: the command is started again
            _run(first, out, str(tmp_path))
        assert _outputs(out) == _outputs(reference), f"{name}: killed after {when:.2f} s (seed {seed})"
    assert kills, f"{name}: every run ended before its kill (seed {seed})"


KILLED = sorted(("evolve", "evolve --sweep", "learning_test", "learning_test SWEEP", "landscape_run"))


@pytest.mark.slow
@pytest.mark.parametrize("name", KILLED)
def test_every_resumable_command_killed_anywhere_ends_as_an_uninterrupted_run(tiny_run, tmp_path, name):
    """SIGKILL at random moments (a seed per command, said on failure), then the resume: the outputs are those of an
    uninterrupted run, bitwise (the arrays, the CSVs, the JSON less times and command lines)."""
    sweep = str(tmp_path / "sweep")
    if name == "learning_test SWEEP":  # a finished sweep of 2 points to test
        from helpers import evolve_args

        from imrl_jax.commands import evolve

        assert evolve.main([*evolve_args(seeds=2, population=4, parents=2, generations=1, task_steps=200, bins=1),
                            "--sweep", "eta=0.1,0.2", "--out", sweep]) == 0
    _kill_and_resume(tiny_run, tmp_path, name, points=4, seed=KILLED.index(name), sweep=sweep)
