"""``python -m imrl_jax.gpu_check``: the engine on a GPU, checked and timed in one prepared command.

    PYTHONPATH=. python3 -m imrl_jax.gpu_check --out DIR [--budget-min 8] [--dry]

Made for a machine where JAX with CUDA is already installed and nothing can be downloaded:
it needs jax, numpy and matplotlib (for its figure), not brax or evosax. Each step reports
its own failure, named by the stage it had reached (import, api, lowering, compile, run,
numbers), and the check goes on to the next. The steps, most important (and least measured before) first:

1. ``lives``: short lives on the device with the XLA step and with the Pallas kernel
   (compiled by Triton on a GPU), for every condition and preset and the selector's options
   (XLA alone where the kernel does not implement a model), in float64 against the NumPy reference and against
   each other with the CPU tests' tolerances; and the float32 adult phase of the float32 CPU
   test, both kernels, against the reference with that test's tolerances;
2. ``models``: whole lives of every row of the condition table and of the selector's options on the kernel at
   30,000 adult lanes, each one's speed beside LE-LS's;
3. ``generation``: one paper-scale LE-LS generation of 10 seeds (both kernels) and of 100; ``devices``: where
   there are several GPUs, that generation of 100 seeds on all of them against one (the same fitness, the speed-up);
4. ``sweep``: one paper-scale generation of ``evolve --sweep``'s program (6 points x 10 seeds), against the
   single run's;
5. ``study``: one generation of each distinct program of the claims map and each kind of its learning tests,
   and the whole map's hours extrapolated against the one-hour target (:mod:`imrl_jax.commands.gpu_study`);
6. ``phases``: every phase of ``imrl_jax.commands.bench``, both kernels, at the same lane counts, and the kernel
   observing by points (``kernel_retina``) at the most;
7. ``life``: whole LE-LS lives (PERFORMANCE.md's headline, measured on the H200 before) at 3,000, 30,000 and
   300,000 adult lanes, both kernels: lane-steps per second, compile time, memory.

Within a time budget (``--budget-min``, default 8), checked before each piece of work: what
would not fit is skipped and said so. ``gpu_check.json`` (every figure, the device and the
versions) and ``gpu_check.txt`` (the same as a table) are rewritten after every step, so what
finished is kept if the command is stopped; ``gpu_check.png`` is drawn at the end. ``--dry``
runs every step at tiny sizes on any backend (the test suite runs it on CPU); without it, a
machine with no GPU is refused.

This module is the command: its options, the plan of steps and :func:`run`. The steps are
:mod:`imrl_jax.commands.gpu_steps`' (``study``: :mod:`imrl_jax.commands.gpu_study`'s), the check that runs
them (budget, stages, results, compiling and timing) :mod:`imrl_jax.commands.gpu_harness`'s, and the figure
:mod:`imrl_jax.commands.gpu_figure`'s.
"""

from __future__ import annotations

import dataclasses
import os
import sys

from imrl_jax import files
from imrl_jax.commands.gpu_figure import figure
from imrl_jax.commands.gpu_harness import DRY, FILES, Check, Sizes, one_line
from imrl_jax.commands.gpu_steps import (devices, environment, float32_phase, generations, lives, models, phases,
                                         sweep, whole_lives)
from imrl_jax.commands.gpu_study import study

#: (name, function, seconds it needs at the real sizes before it is worth starting)
STEPS = (("environment", environment, 0), ("lives", lives, 30), ("float32", float32_phase, 20), ("models", models, 60),
         ("generation", generations, 60), ("devices", devices, 0), ("sweep", sweep, 60), ("study", study, 60),
         ("phases", phases, 20), ("life", whole_lives, 30))


def run(out_dir: str, budget_s: float = 480.0, sizes: Sizes = Sizes(), log=print, steps=STEPS) -> dict:
    """Every step in order within the budget; the results (also written under ``out_dir``)."""
    os.makedirs(out_dir, exist_ok=True)
    check = Check(out_dir, budget_s, sizes, log)
    for name, fn, seconds in steps:
        check.run_step(name, fn, seconds)
    failed = [s["step"] for s in check.results["steps"] if s["status"] == "failed"]
    skipped = [s["step"] for s in check.results["steps"] if s["status"] == "skipped"]
    check.results["summary"] = {"failed": failed, "skipped": skipped}
    try:
        cpu = os.path.join(files.REPO, "docs", "bench", "cpu-2core.json")
        if not figure(check.results, os.path.join(out_dir, FILES[2]), cpu):
            check.say("[figure] none: no step measured a speed")
    except Exception as error:  # noqa: BLE001 - the figure is the last thing; the figures in the JSON stand
        check.say(f"[figure] FAILED: {one_line(error)}")
    check.say(f"done: {len(check.results['steps']) - len(failed) - len(skipped)} steps ok, failed: "
              f"{', '.join(failed) or 'none'}, skipped: {', '.join(skipped) or 'none'}")
    check.write()
    return check.results


def main(argv=None) -> int:
    from imrl_jax.runs import cli

    return cli.exit_codes(_main)(argv)


def parser():
    """The GPU check's command line parser."""
    from imrl_jax.runs import cli

    p = cli.Parser(prog="python -m imrl_jax.gpu_check", description=__doc__.split("\n")[0])
    p.add_argument("--out", required=True, help="folder for gpu_check.json, .txt and .png (new, or without them)")
    p.add_argument("--budget-min", type=float, default=8.0, help="minutes the check may take")
    p.add_argument("--dry", action="store_true", help="tiny sizes on any backend (tests the check itself)")
    p.add_argument("--only", help="comma-separated steps (default: all): " + ", ".join(n for n, *_ in STEPS))
    p.add_argument("--conditions", help="comma-separated conditions whose lives and phases to check (default: all)")
    return p


def _main(argv=None) -> int:
    """The command: parse, check every option (nothing written), then run the check through ``cli.execute``."""
    from imrl_jax.runs import cli

    args = parser().parse_args(argv)

    if not args.out.strip():
        raise cli.UsageError("--out: empty")
    if not (0 < args.budget_min <= 600):  # NaN too
        raise cli.UsageError(f"--budget-min: must be above 0 and at most 600, got {args.budget_min:g}")
    names = [n for n, *_ in STEPS]
    only = names if args.only is None else [n.strip() for n in args.only.split(",")]
    unknown = [n for n in only if n not in names]
    if unknown or not only:
        raise cli.UsageError(f"--only: unknown step {unknown[0] if unknown else ''!r} (choose from {', '.join(names)})")
    from imrl_jax.conditions import NAMES

    conditions = None if args.conditions is None else tuple(n.strip() for n in args.conditions.split(","))
    if conditions is not None and any(n not in NAMES for n in conditions):
        bad = next(n for n in conditions if n not in NAMES)
        raise cli.UsageError(f"--conditions: unknown condition {bad!r} (choose from {', '.join(NAMES)})")
    existing = [f for f in FILES if os.path.exists(os.path.join(args.out, f))]
    if existing:
        raise cli.UsageError(f"--out: {os.path.join(args.out, existing[0])} exists (choose a new folder)")
    if os.path.exists(args.out) and not os.path.isdir(args.out):
        raise cli.UsageError(f"--out: {args.out} is not a folder")
    from imrl_jax.runs.rundir import check_writable

    check_writable(args.out)
    if not args.dry:
        import jax

        if jax.default_backend() != "gpu":
            raise cli.UsageError(f"no GPU: jax {jax.__version__} sees {jax.default_backend()} devices only "
                        f"({jax.devices()[0].device_kind}); run where one is, or use --dry")
    sizes = DRY if args.dry else Sizes()
    if conditions is not None:
        sizes = dataclasses.replace(sizes, conditions=conditions)
    chosen = [s for s in STEPS if s[0] in only]

    def check() -> int:
        results = run(args.out, args.budget_min * 60, sizes, steps=chosen)
        return 1 if results["summary"]["failed"] else 0

    return cli.execute(cli.Call(check, sizes=sizes, steps=only))


if __name__ == "__main__":
    sys.exit(main())
