"""The whole reproduction of the paper's Fig. 3, resumable: evolutions, learning tests, report.

    python experiments/reproduce.py --scale paper   # make reproduce: the paper's sizes
    python experiments/reproduce.py --scale cpu     # make reproduce-cpu: 1 h 44 min on 2 CPU cores (measured)
    python experiments/reproduce.py --scale paper --kernel pallas   # on a GPU: the step as one kernel

Two variants of the learning rules are run side by side: ``paper`` (the rules as written)
and ``extension`` (MODEL.md's learning extensions at the values of the ``extension``
preset, found by ``experiments/selector_sweep.py``). For each variant: the three evolved
conditions (EE-ES learns nothing, so its evolution is the same under both variants and is
run once, under ``paper``), then the learning tests of LE-LS, EE-LS, EE-ES and SLE. Then
``python -m experiments.report`` writes docs/REPRODUCTION.md and its figures.

Every stage is a command of the package, printed before it runs. A finished stage is
skipped; an interrupted evolution resumes from its last checkpoint; an interrupted
learning test starts again. Run the same command again to go on after an interruption.

Scales (what ``cpu`` shrinks, and by how much, is the whole difference):

| | paper | cpu |
|---|---|---|
| seeds (runs) | 10 | 5 |
| generations | 100 | 40 |
| population, parents | 50, 10 | 50, 10 |
| childhood steps | 150,000 | 30,000 (1/5) |
| steps per adult task | 100,000 | 20,000 (1/5) |
| learning test: best x tests | 10 x 10 | 10 x 2 |
| learning test: cycles per task | 1,000,000 | 200,000 (1/5) |
| steady state: last cycles | 100,000 | 20,000 (1/5) |
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import time

SCALES = {
    "paper": dict(seeds=10, generations=100, childhood_steps=150_000, task_steps=100_000, bins=100,
                  best=10, tests=10, test_steps=1_000_000, test_bins=100, steady_steps=100_000),
    "cpu": dict(seeds=5, generations=40, childhood_steps=30_000, task_steps=20_000, bins=20,
                best=10, tests=2, test_steps=200_000, test_bins=100, steady_steps=20_000),
    # A smoke test of the pipeline itself (seconds of compute; results mean nothing).
    "tiny": dict(seeds=2, generations=2, childhood_steps=400, task_steps=400, bins=2,
                 best=2, tests=1, test_steps=800, test_bins=4, steady_steps=200, population=6, parents=2),
}
VARIANTS = ("paper", "extension")
EVOLVED = ("LE-LS", "EE-LS", "EE-ES")
TESTED = ("LE-LS", "EE-LS", "EE-ES", "SLE")


def evolution_dir(out: str, variant: str, condition: str) -> str:
    """Where a variant's evolution of a condition lives (EE-ES: one run shared by both variants)."""
    return os.path.join(out, "paper" if condition == "EE-ES" else variant, "evolve", condition)


def test_dir(out: str, variant: str, condition: str) -> str:
    return os.path.join(out, variant, "test", condition)


def _kernel_options(kernel: str) -> list[str]:
    return [] if kernel == "xla" else ["--set", f"step_kernel={kernel}"]


def evolve_command(scale: dict, variant: str, condition: str, out_dir: str, kernel: str = "xla") -> list[str]:
    command = [sys.executable, "-m", "imrl_jax.evolve", "--cond", condition, "--preset", variant,
               "--seeds", str(scale["seeds"]), "--generations", str(scale["generations"]),
               "--childhood-steps", str(scale["childhood_steps"]), "--task-steps", str(scale["task_steps"]),
               "--bins", str(scale["bins"]), "--out", out_dir, *_kernel_options(kernel)]
    if "population" in scale:
        command += ["--population", str(scale["population"]), "--parents", str(scale["parents"])]
    started = os.path.exists(os.path.join(out_dir, "config.json"))
    return command + (["--resume"] if started else [])


def evolution_done(out_dir: str, scale: dict) -> bool:
    path = os.path.join(out_dir, "final_population.npz")
    if not os.path.exists(path):
        return False
    import numpy as np

    with np.load(path) as data:
        return int(data["generation"]) >= scale["generations"]


def test_command(scale: dict, variant: str, condition: str, run_dir: str, out_dir: str,
                 kernel: str = "xla") -> list[str]:
    command = [sys.executable, "-m", "imrl_jax.learning_test"]
    if condition == "SLE":
        command += ["--cond", "SLE", "--preset", variant, "--runs", str(scale["seeds"]), *_kernel_options(kernel)]
    else:  # the test runs with its evolution's config, step kernel included
        command += [run_dir]
    return command + ["--best", str(scale["best"]), "--tests", str(scale["tests"]),
                      "--task-steps", str(scale["test_steps"]), "--bins", str(scale["test_bins"]),
                      "--steady-steps", str(scale["steady_steps"]), "--chunks", str(min(10, scale["test_bins"])),
                      "--out", out_dir]


def run_stage(name: str, command: list[str], manifest: dict, manifest_path: str, env: dict | None = None) -> None:
    print(f"\n== {name}\n$ {' '.join(command[1:] if command[0] == sys.executable else command)}", flush=True)
    start = time.perf_counter()
    subprocess.run(command, check=True, env=env)
    manifest["stages"][name] = dict(command=" ".join(["python"] + command[1:]), seconds=round(time.perf_counter() - start, 1))
    with open(manifest_path, "w") as f:
        json.dump(manifest, f, indent=2)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--scale", choices=sorted(SCALES), default="cpu")
    p.add_argument("--out", help="results directory (default: experiments/results/SCALE)")
    p.add_argument("--variants", default=",".join(VARIANTS), help="comma-separated: paper, extension")
    p.add_argument("--no-report", action="store_true", help="skip the report (python -m experiments.report)")
    p.add_argument("--kernel", choices=("xla", "pallas"), default="xla",
                   help="the step kernel (Config.step_kernel): pallas runs each bin of steps as one GPU kernel")
    args = p.parse_args(argv)
    scale = SCALES[args.scale]
    out = args.out or os.path.join("experiments", "results", args.scale)
    variants = args.variants.split(",")
    unknown = [v for v in variants if v not in VARIANTS]
    if unknown:
        print(f"error: --variants: unknown variant {unknown[0]!r} (choose from {', '.join(VARIANTS)})", file=sys.stderr)
        return 2
    os.makedirs(out, exist_ok=True)
    manifest_path = os.path.join(out, "manifest.json")
    manifest = dict(scale=args.scale, sizes=scale, variants=variants, kernel=args.kernel, stages={})
    if os.path.exists(manifest_path):
        with open(manifest_path) as f:
            manifest["stages"] = json.load(f).get("stages", {})
    from imrl_jax.checkpoint import git_commit

    manifest["git_commit"] = git_commit()
    start = time.perf_counter()
    try:
        for variant in variants:
            for condition in EVOLVED:
                run_dir = evolution_dir(out, variant, condition)
                if evolution_done(run_dir, scale):
                    print(f"== evolve {variant} {condition}: done ({run_dir})")
                    continue
                run_stage(f"evolve {'paper' if condition == 'EE-ES' else variant} {condition}",
                          evolve_command(scale, "paper" if condition == "EE-ES" else variant, condition, run_dir,
                                         args.kernel),
                          manifest, manifest_path)
        for variant in variants:
            for condition in TESTED:
                out_dir = test_dir(out, variant, condition)
                if os.path.exists(os.path.join(out_dir, "steady.json")):
                    print(f"== learning test {variant} {condition}: done ({out_dir})")
                    continue
                shutil.rmtree(out_dir, ignore_errors=True)  # an interrupted test starts again
                run_stage(f"learning test {variant} {condition}",
                          test_command(scale, variant, condition, evolution_dir(out, variant, condition), out_dir,
                                       args.kernel),
                          manifest, manifest_path)
        if not args.no_report:
            # The report is a module of the experiments package: the repository root goes on its path.
            root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
            path = os.pathsep.join(p for p in (root, os.environ.get("PYTHONPATH")) if p)
            run_stage("report", [sys.executable, "-m", "experiments.report", out], manifest, manifest_path,
                      env={**os.environ, "PYTHONPATH": path})
    except subprocess.CalledProcessError as error:
        print(f"error: stage failed with exit code {error.returncode}: {' '.join(error.cmd[1:])}", file=sys.stderr)
        return error.returncode or 1
    except KeyboardInterrupt:
        print("\ninterrupted: run the same command again to go on from here", file=sys.stderr)
        return 130
    print(f"\nall stages done in {time.perf_counter() - start:.0f} s; results in {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
