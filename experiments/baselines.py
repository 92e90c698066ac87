"""The committed brax baselines (docs/BASELINES.md): PPO and ES on the six tasks at two budgets, then a figure.

    python experiments/baselines.py [--out experiments/results/baselines] [--tests experiments/results/cpu]

Every stage is a ``python -m imrl_jax.baselines`` command, printed before it runs; a stage
whose ``summary.json`` exists is skipped, so the same command goes on after an
interruption. Then ``comparison.png`` puts the baselines beside the learning tests of a
results directory of ``experiments.reproduction`` (``--tests``; the paper scale's when it
has any, else the cpu scale's), labelled with that directory's scale.

The budgets: 1,000,000 cycles per task (the paper's learning test) on 5 seeds, and
5,000,000 on 3 seeds. On the 2-core CPU this took under an hour in all (docs/BASELINES.md).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time

from experiments.study import RESULTS
from imrl_jax import conditions

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

#: (directory, arguments of python -m imrl_jax.baselines)
STAGES = (
    ("ppo_1M", ["--agent", "ppo", "--steps", "1000000", "--seeds", "5", "--evals", "11"]),
    ("es_1M", ["--agent", "es", "--steps", "1000000", "--seeds", "5", "--evals", "11"]),
    ("ppo_5M", ["--agent", "ppo", "--steps", "5000000", "--seeds", "3", "--evals", "21"]),
    ("es_5M", ["--agent", "es", "--steps", "5000000", "--seeds", "3", "--evals", "21"]),
)


def default_tests() -> str:
    """The paper scale's results where its learning tests exist, else the cpu scale's."""
    paper = os.path.join(ROOT, RESULTS, "paper")
    if any(os.path.isfile(os.path.join(paper, v, "test", c, "steady.json"))
           for v in ("skills", "paper", "extension") for c in conditions.PAPER):
        return paper
    return os.path.join(ROOT, RESULTS, "cpu")


def draw(out: str, tests_dir: str) -> str:
    """comparison.png: the baselines in ``out`` beside the learning tests of ``tests_dir``."""
    from experiments.document import scale_label
    from experiments.figures import fig_baselines
    from experiments.loading import read_baselines
    from experiments.reproduction import TABLES
    from imrl_jax.plotting import save

    table = next((t for t in TABLES.values() if os.path.abspath(t.out) == os.path.abspath(tests_dir)), None)
    data = table.data() if table is not None else dict(tests={}, manifest=None)
    title = (f"brax.training baselines beside the paper's architecture\n(its learning tests at the "
             f"{scale_label(data['manifest'])})")
    fig = fig_baselines(read_baselines(out), data["tests"], title if data["tests"] else "brax.training baselines")
    return save(fig, os.path.join(out, "comparison.png"))


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", default=os.path.join(ROOT, RESULTS, "baselines"),
                   help="where the baselines are written")
    p.add_argument("--tests", default=None, help="a reproduction's results directory to compare with "
                                                 "(default: paper scale if it has learning tests, else cpu scale)")
    args = p.parse_args(argv)
    started = time.perf_counter()
    for i, (name, options) in enumerate(STAGES, 1):
        out_dir = os.path.join(args.out, name)
        command = [sys.executable, "-m", "imrl_jax.baselines", *options, "--out", out_dir]
        if os.path.isfile(os.path.join(out_dir, "summary.json")):
            print(f"stage {i}/{len(STAGES)} {name}: done, skipped", flush=True)
            continue
        print(f"stage {i}/{len(STAGES)} {name} ({time.perf_counter() - started:,.0f} s elapsed): "
              f"{' '.join(command[1:])}", flush=True)
        if subprocess.run(command, cwd=ROOT).returncode:
            print(f"error: stage {name} failed", file=sys.stderr)
            return 1
    print(f"wrote {draw(args.out, args.tests or default_tests())}")
    return 0


if __name__ == "__main__":
    sys.path.insert(0, ROOT)  # run as a script from anywhere: the experiments package
    sys.exit(main())
