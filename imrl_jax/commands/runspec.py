"""``python -m imrl_jax.runspec ROOT [--record PATH]``: every run under a results folder with its content key
(the keys: :mod:`imrl_jax.runs.runspec`)."""

from __future__ import annotations

import json
import os

from imrl_jax.runs import cli
from imrl_jax.runs.cli import Parser, UsageError, check_out, exit_codes
from imrl_jax.runs.rundir import check_writable, write_atomic
from imrl_jax.runs.runspec import index


def parser():
    """The runspec command line's parser."""
    p = Parser(prog="python -m imrl_jax.runspec", description=main.__doc__.split(": ", 1)[1])
    p.add_argument("root", help="a results folder (for instance experiments/results)")
    p.add_argument("--record", help="also write {directory: key} to this JSON file")
    return p


def main(argv=None) -> int:
    """``python -m imrl_jax.runspec ROOT [--record PATH]``: every run under ROOT with its key."""
    @exit_codes
    def listed(argv) -> int:
        args = parser().parse_args(argv)
        if not os.path.isdir(args.root):
            raise UsageError(f"root: {args.root!r} is not a folder")
        if args.record is not None:
            check_out(args.record, "--record")
            if os.path.isdir(args.record):
                raise UsageError(f"--record: {args.record} is a directory")
            check_writable(os.path.dirname(os.path.abspath(args.record)), "--record")
        known = sorted(index(args.root).items(), key=lambda item: item[1])

        def record() -> int:
            for key, folder in known:
                print(f"{key}  {folder}")
            if args.record:
                os.makedirs(os.path.dirname(os.path.abspath(args.record)), exist_ok=True)
                write_atomic(args.record, (json.dumps({folder: key for key, folder in known}, indent=1)
                                           + "\n").encode())
            return 0

        return cli.execute(cli.Call(record, known=known))

    return listed(argv)


if __name__ == "__main__":
    raise SystemExit(main())
