"""The suite's attacks on the commands: hostile values and files, and the check-then-write contract checked.

A command is built as parse, plan, :func:`imrl_jax.runs.cli.execute` (``imrl_jax/runs/cli.py``). :func:`attack` runs a
command's ``main`` in this process with ``cli.execute`` stubbed (so that a plan that passes is not carried out:
no compilation, no lives), with a byte-for-byte snapshot of a folder before and after, and returns what
happened. The contract (:func:`assert_contract`): either the command refuses, with exit code 2 and one line
``error: ...`` naming the option or file (no traceback), or it reaches ``execute`` with a plan; either way,
nothing under the folder changed. :func:`assert_refused` asks for the refusal.

``hostile_values`` are the values every option is attacked with (out of bounds, NaN, infinities, huge
integers, empty, wrong type, path tricks); ``hostile_files`` the damaged forms of a file a command reads.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
from typing import Callable, NamedTuple, Sequence

#: What an integer option is attacked with: out of bounds, past 32 and 64 bits, not an integer.
HOSTILE_INTS = ("0", "-1", "-0", "2147483648", "18446744073709551616", "100000000", "1e8", "nan", "inf", "-inf",
                "", "x", "1.5", "0x10", " ")
#: What a float option is attacked with.
HOSTILE_FLOATS = ("nan", "inf", "-inf", "-1", "1e308", "1e-320", "-0", "", "x", "1e400")
#: What a text option (a name, a list, a path) is attacked with: empty, path tricks, control characters, long.
HOSTILE_TEXTS = ("", " ", "../../x", "/", "/dev/null", "nan", "-1", ",", ",,", "a" * 300, "\x00", "\n", "=",
                 "x=y=z", "1e8", "0,0", "-0,0")
#: The damaged forms of a file: name -> bytes (None: the file removed; a folder: made a folder).
HOSTILE_FILE_BYTES = {"empty": b"", "truncated": None, "not json": b"{not json", "null": b"null",
                      "a list": b"[1, 2]", "NaN": b'{"x": NaN}', "binary": bytes(range(256))}


class Outcome(NamedTuple):
    """What one command line did: its exit code, what it printed on stderr, whether it reached ``execute``, the
    plan it reached it with, and the files under the watched folder that changed (added, removed or rewritten)."""

    code: int | None
    stderr: str
    planned: bool
    plan: object
    changed: list[str]


def tree(root: str) -> dict[str, bytes | None]:
    """Every file and folder under ``root``: relative path -> bytes (None for a folder); a symlink by its target."""
    found: dict[str, bytes | None] = {}
    for folder, dirs, names in os.walk(root):
        for name in dirs:
            path = os.path.join(folder, name)
            found[os.path.relpath(path, root)] = (b"-> " + os.readlink(path).encode()) if os.path.islink(path) \
                else None
        for name in names:
            path = os.path.join(folder, name)
            if os.path.islink(path):
                found[os.path.relpath(path, root)] = b"-> " + os.readlink(path).encode()
                continue
            with open(path, "rb") as f:
                found[os.path.relpath(path, root)] = f.read()
    return found


def changes(before: dict, after: dict) -> list[str]:
    """The paths added, removed or rewritten between two :func:`tree` snapshots."""
    return sorted(p for p in set(before) | set(after) if before.get(p, 0) != after.get(p, 0))


def attack(main: Callable[[Sequence[str]], int], argv: Sequence[str], root: str, monkeypatch=None) -> Outcome:
    """Run ``main(argv)`` in this process with ``cli.execute`` stubbed and ``root`` watched; what happened.

    The current directory is ``root`` meanwhile, so that a default output folder lands where it is watched.
    """
    from imrl_jax.runs import cli

    reached = []

    def stub(plan):
        reached.append(plan)
        return 0

    before = tree(root)
    err = io.StringIO()
    saved_execute, saved_cwd = cli.execute, os.getcwd()
    cli.execute = stub
    os.chdir(root)
    try:
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
            try:
                code = main(list(argv))
            except SystemExit as stop:  # --help, or a command that exits by itself
                code = stop.code if isinstance(stop.code, int) else (0 if stop.code is None else 1)
    finally:
        cli.execute = saved_execute
        os.chdir(saved_cwd)
    return Outcome(code, err.getvalue(), bool(reached), reached[0] if reached else None, changes(before, tree(root)))


def error_lines(outcome: Outcome) -> list[str]:
    """The lines of stderr that are not notes or warnings (what a refusal says)."""
    return [line for line in outcome.stderr.splitlines()
            if line.strip() and not line.startswith(("note:", "warning:"))]


def assert_refused(outcome: Outcome, *names: str, argv: Sequence[str] = ()) -> None:
    """Exit code 2, one line ``error: ...`` naming one of ``names`` (an option, a field or a file), no traceback,
    nothing reached ``execute``, nothing changed."""
    where = f" for {' '.join(map(repr, argv))}" if argv else ""
    assert "Traceback" not in outcome.stderr, f"a traceback{where}:\n{outcome.stderr[-3000:]}"
    assert outcome.code == 2, f"exit code {outcome.code}{where} (want 2); stderr:\n{outcome.stderr[-2000:]}"
    lines = error_lines(outcome)
    assert len(lines) == 1 and lines[0].startswith("error: "), f"not one error line{where}:\n{outcome.stderr}"
    if names:
        assert any(name in lines[0] for name in names), f"{lines[0]!r} names none of {names}{where}"
    assert not outcome.planned, f"planned, and refused{where}"
    assert not outcome.changed, f"refused{where}, but changed {outcome.changed}"


def assert_contract(outcome: Outcome, *names: str, argv: Sequence[str] = ()) -> str:
    """Either refused as :func:`assert_refused` says, or planned with nothing written: "refused" or "planned"."""
    where = f" for {' '.join(map(repr, argv))}" if argv else ""
    if outcome.planned:
        assert "Traceback" not in outcome.stderr, f"a traceback{where}:\n{outcome.stderr[-3000:]}"
        assert outcome.code == 0, f"planned{where}, then exit code {outcome.code}:\n{outcome.stderr[-2000:]}"
        assert not outcome.changed, f"the plan{where} wrote before execute: {outcome.changed}"
        return "planned"
    assert_refused(outcome, *names, argv=argv)
    return "refused"


def damage(path: str, how: str) -> None:
    """Damage the file at ``path`` as :data:`HOSTILE_FILE_BYTES` names (``truncated``: its first half kept)."""
    if how == "truncated":
        with open(path, "rb") as f:
            data = f.read()
        data = data[:len(data) // 2]
    elif how == "removed":
        os.remove(path)
        return
    else:
        data = HOSTILE_FILE_BYTES[how]
    with open(path, "wb") as f:
        f.write(data)


def edit_json(path: str, change: Callable[[dict], object]) -> None:
    """Rewrite the JSON file at ``path`` with ``change`` applied to its content (which it may edit in place)."""
    with open(path) as f:
        data = json.load(f)
    changed = change(data)
    with open(path, "w") as f:
        json.dump(data if changed is None else changed, f)
