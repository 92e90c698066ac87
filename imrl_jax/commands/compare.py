"""The speed of this checkout against an earlier git revision, in one process (the speed goals of the README).

    python -m imrl_jax.compare REV [--phase adult|adult-es|sle|childhood|life] [--lanes 3000] [--steps 1000] [--pairs 20]

On a shared machine one process's speed drifts by tens of percent within minutes, so two
benchmark runs made minutes apart cannot show a change of 5%. This command compiles the
same program from both versions in one process and alternates their timed runs (A B,
then B A), so that both see the same machine. It prints the median lane-steps per second
of each and the median ratio of the pairs (this checkout over REV), with how many pairs
this checkout won.

REV's package is taken with ``git archive`` and imported under another name; both programs
are built by this checkout's benchmark (``bench.phase_program``, ``bench.lifetime_program``)
from each version's modules, through the API every recent revision has (``make_config``,
``lifetime.run_phase``, ``lifetime.make_evaluate``).
"""

from __future__ import annotations

import io
import os
import re
import shutil
import statistics
import subprocess
import sys
import tarfile
import tempfile
import time

from imrl_jax.files import REPO

PHASES = {"adult": ("LE-LS", "ADULT_LEARNING_SELECTOR"), "adult-es": ("EE-ES", "ADULT_EVOLVED_SELECTOR"),
          "sle": ("SLE", "ADULT_SINGLE_EXPERT"), "childhood": ("LE-LS", "CHILDHOOD"), "life": ("LE-LS", None)}


def export_package(revision: str | None, name: str, into: str) -> str:
    """Write imrl_jax of ``revision`` (None: this checkout) under ``into`` as package ``name``."""
    target = os.path.join(into, name)
    if revision is None:
        shutil.copytree(os.path.join(REPO, "imrl_jax"), target, ignore=shutil.ignore_patterns("__pycache__"))
    else:
        archive = subprocess.run(["git", "-C", REPO, "archive", "--format=tar", revision, "imrl_jax"],
                                 capture_output=True)
        if archive.returncode:
            raise ValueError(f"REV: git cannot export imrl_jax at {revision!r}: "
                             f"{archive.stderr.decode().strip().splitlines()[-1] if archive.stderr else 'no output'}")
        with tarfile.open(fileobj=io.BytesIO(archive.stdout)) as tar:
            # The "data" filter (Python >= 3.11.4) refuses links and paths out of ``into``.
            tar.extractall(into, **({"filter": "data"} if hasattr(tarfile, "data_filter") else {}))
        os.rename(os.path.join(into, "imrl_jax"), target)
    for folder, _, files in os.walk(target):
        for file in files:
            if file.endswith(".py"):
                path = os.path.join(folder, file)
                with open(path) as f:
                    text = f.read()
                with open(path, "w") as f:
                    f.write(re.sub(r"\bimrl_jax\b", name, text))
    return target


def build(package: str, phase: str, lanes: int, steps: int):
    """One version's program (:class:`imrl_jax.commands.bench.Program`), compiled and run once."""
    import jax

    from imrl_jax.commands.bench import lifetime_program, phase_program

    if phase == "life":
        program = lifetime_program(lanes, steps, package)
    else:
        program = phase_program(*PHASES[phase], lanes, steps, package)
    jax.block_until_ready(program.fn(*program.args))
    return program


def compare(revision: str, phase: str, lanes: int, steps: int, pairs: int, log=print) -> dict:
    """Median rates of REV (a) and this checkout (b), and the median of the pairs' ratios b / a."""
    import jax

    with tempfile.TemporaryDirectory() as folder:
        export_package(revision, "imrl_compare_a", folder)
        export_package(None, "imrl_compare_b", folder)
        sys.path.insert(0, folder)
        try:
            programs = [build(name, phase, lanes, steps) for name in ("imrl_compare_a", "imrl_compare_b")]
        finally:
            sys.path.remove(folder)
            for module in [m for m in sys.modules if m.startswith("imrl_compare_")]:
                del sys.modules[module]
    rates = ([], [])
    for i in range(pairs):
        for which in ((0, 1) if i % 2 == 0 else (1, 0)):
            program = programs[which]
            start = time.perf_counter()
            jax.block_until_ready(program.fn(*program.args))
            rates[which].append(program.lane_steps / (time.perf_counter() - start))
        log(f"pair {i + 1}/{pairs}: {rates[0][-1] / 1e6:.2f} M vs {rates[1][-1] / 1e6:.2f} M lane-steps/s")
    ratios = [b / a for a, b in zip(*rates)]
    return {"revision": revision, "phase": phase, "lanes": lanes, "steps": steps, "pairs": pairs,
            "base_lane_steps_per_s": statistics.median(rates[0]),
            "lane_steps_per_s": statistics.median(rates[1]),
            "median_ratio": statistics.median(ratios), "pairs_won": sum(r > 1 for r in ratios)}


def main(argv=None) -> int:
    from imrl_jax.runs import cli

    return cli.exit_codes(_main)(argv)


def parser():
    """The compare command line's parser."""
    from imrl_jax.runs import cli

    p = cli.Parser(prog="python -m imrl_jax.compare", description=__doc__.split("\n")[0])
    p.add_argument("revision", metavar="REV", help="git revision to compare this checkout with")
    p.add_argument("--phase", choices=sorted(PHASES), default="adult",
                   help="adulthood of LE-LS (adult), EE-ES or SLE, LE-LS childhood, or whole LE-LS lives "
                        "of lanes / 6 individuals")
    p.add_argument("--lanes", type=int, default=3000, help="lanes (adult lanes for life)")
    p.add_argument("--steps", type=int, default=1000, help="steps per timed run (per task for life)")
    p.add_argument("--pairs", type=int, default=20, help="alternating pairs of timed runs")
    p.add_argument("--cpu-devices", type=int, default=0, help="CPU devices (0: one per core)")
    return p


def _main(argv=None) -> int:
    """The command: parse, check every option and the revision (nothing written), then time through ``cli.execute``."""
    from imrl_jax.runs import cli
    from imrl_jax.runs.cli import UsageError

    args = parser().parse_args(argv)
    for name, limit in (("lanes", cli.MAX_LANES), ("steps", cli.MAX_STEPS), ("pairs", 10_000)):
        cli.check_at_least(f"--{name}", getattr(args, name))
        cli.check_at_most(f"--{name}", getattr(args, name), limit)
    if args.phase == "life" and args.steps % 10:
        raise UsageError("--steps: must be a multiple of 10 for --phase life (10 bins)")
    cli.check_cpu_devices(args.cpu_devices)  # at most 4 per core: each device holds its own runtime
    if not args.revision.strip() or args.revision.startswith("-") or not args.revision.isprintable():
        raise UsageError(f"REV: {args.revision!r} is not a revision of {REPO}")
    check = subprocess.run(["git", "-C", REPO, "rev-parse", "--verify", "--quiet", args.revision + "^{commit}"],
                           capture_output=True)
    if check.returncode:
        raise UsageError(f"REV: {args.revision!r} is not a revision of {REPO}")
    return cli.execute(cli.Call(lambda: timed(args), revision=args.revision))


def timed(args) -> int:
    """The comparison the command line checked, printed."""
    from imrl_jax.evolution.devices import use_host_cores

    use_host_cores(args.cpu_devices or None)
    result = compare(args.revision, args.phase, args.lanes, args.steps, args.pairs)
    print(f"{args.phase}, {args.lanes} lanes: {args.revision} {result['base_lane_steps_per_s'] / 1e6:.2f} M, "
          f"this checkout {result['lane_steps_per_s'] / 1e6:.2f} M lane-steps/s (medians of {args.pairs}); "
          f"ratio {result['median_ratio']:.3f} (median of pairs), this checkout faster in "
          f"{result['pairs_won']}/{args.pairs}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
