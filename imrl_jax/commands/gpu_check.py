"""``python -m imrl_jax.gpu_check``: the engine on a GPU, checked and timed in one prepared command.

    PYTHONPATH=. python3 -m imrl_jax.gpu_check --out DIR [--budget-min 8] [--dry]

Made for a machine where JAX with CUDA is already installed and nothing can be downloaded:
it needs jax, numpy and matplotlib (for its figure), not brax or evosax. Each step reports
its own failure, named by the stage it had reached (import, api, lowering, compile, run,
numbers), and the check goes on to the next. The steps, most important first:

1. ``lives``: short lives on the device with the XLA step and with the Pallas kernel
   (compiled by Triton on a GPU), for every condition and preset (XLA alone where the kernel
   does not implement the condition), in float64 against the NumPy reference and against
   each other with the CPU tests' tolerances; and the float32 adult phase of the float32 CPU
   test, both kernels, against the reference with that test's tolerances;
2. ``life``: whole LE-LS lives (PERFORMANCE.md's headline) at 3,000, 30,000 and 300,000 adult
   lanes, both kernels: lane-steps per second, compile time, memory;
3. ``generation``: one paper-scale LE-LS generation of 10 seeds (both kernels) and of 100;
4. ``sweep``: one paper-scale generation of ``evolve --sweep``'s program (6 points x 10 seeds), against the single run's;
5. ``study``: one generation of each distinct program of the claims map and each kind of its learning tests,
   and the whole map's hours extrapolated against the one-hour target (:mod:`imrl_jax.commands.gpu_study`);
6. ``phases``: every phase of ``imrl_jax.commands.bench``, both kernels, at the same lane counts.

Within a time budget (``--budget-min``, default 8), checked before each piece of work: what
would not fit is skipped and said so. ``gpu_check.json`` (every figure, the device and the
versions) and ``gpu_check.txt`` (the same as a table) are rewritten after every step, so what
finished is kept if the command is stopped; ``gpu_check.png`` is drawn at the end. ``--dry``
runs every step at tiny sizes on any backend (the test suite runs it on CPU); without it, a
machine with no GPU is refused.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import os
import platform
import sys
import time
import traceback
from typing import Callable

import numpy as np

from imrl_jax import files
from imrl_jax.commands.gpu_study import program_key, study

#: The stages a piece of work goes through; a failure is named by the one it had reached.
STAGES = ("import", "api", "lowering", "compile", "run", "numbers")
#: The CPU tests' tolerances: float64 lives against the reference (tests/test_reference.py), the kernel
#: against the XLA step (tests/test_kernel.py), the float32 adult phase against the reference.
TOLERANCES = {"reference": dict(rtol=1e-8, atol=1e-10), "kernels": dict(rtol=1e-9, atol=1e-9),
              "float32": dict(rtol=1e-4, atol=1e-5), "float32_pose_cm": 1e-3}
KERNELS = ("xla", "pallas")
FILES = ("gpu_check.json", "gpu_check.txt", "gpu_check.png")


@dataclasses.dataclass(frozen=True)
class Sizes:
    """How much each step does (the real check's, or ``--dry``'s tiny ones)."""

    life_steps: tuple[int, int, int] = (1200, 300, 3)  # childhood steps, task steps, bins of the checked lives
    # A 40 cm target in the checked lives: with random genomes a 10 cm one is seldom reached in 300 steps, and a
    # reach (its reset and what is learned from it) is what a window must hold to check it.
    life_target_radius: float = 40.0
    presets: tuple[str, ...] = ("paper", "extension", "faithful", "skills")
    conditions: tuple[str, ...] | None = None  # None: every row of the condition table
    float32_steps: int = 2000
    lanes: tuple[int, ...] = (3_000, 30_000, 300_000)
    life_task_steps: int = 2000  # the whole-life benchmark's task steps (childhood 1.5 times that)
    phase_steps: int = 1000
    repeats: int = 3
    generation_seeds: tuple[int, ...] = (10, 100)
    generation_condition: str = "LE-LS"  # of the timed generation and sweep
    generation_sizes: tuple = ()  # Config overrides of the timed generation (none: the paper's scale)
    sweep: tuple = (("trace_lambda", (0.0, 0.9, 0.98)), ("eta_selector_actor", (0.01, 0.3)))
    sweep_seeds: int = 10
    scale: float = 1.0  # of the time estimates that the budget is checked against
    study_limit: int | None = None  # the study's programs (and kinds of test) timed (None: all)
    study_seeds: int | None = None  # at most this many seeds of each program timed (None: its own)
    study_test_steps: int = 2000  # the steps a learning test's phase is timed for
    study_test_lanes: int | None = None  # at most this many lanes of a test timed (None: its own)


DRY = Sizes(life_steps=(60, 30, 3), presets=("paper",), conditions=("EE-LS",), float32_steps=200,
            lanes=(6,), life_task_steps=20, phase_steps=20, repeats=1, generation_seeds=(2,),
            generation_condition="EE-LS",
            generation_sizes=(("childhood_steps", 40), ("task_steps", 20), ("num_bins", 2), ("population_size", 4),
                              ("num_parents", 2)),
            sweep=(("trace_lambda", (0.0, 0.9)),), sweep_seeds=2, scale=0.0, study_limit=1, study_seeds=2,
            study_test_steps=20, study_test_lanes=6)


class Check:
    """The running check: the budget, the stage reached, the results so far and their files."""

    def __init__(self, out_dir: str, budget_s: float, sizes: Sizes, log: Callable[[str], None] = print):
        self.out_dir, self.sizes, self.log = out_dir, sizes, log
        self.deadline = time.monotonic() + budget_s
        self.stage = "import"
        self.results: dict = {"budget_s": budget_s, "dry": sizes.scale == 0.0, "steps": []}
        self.lines: list[str] = []
        self.compiled: dict = {}  # programs compiled so far, by what they are made of (steps share them)

    def remaining(self) -> float:
        """Seconds left of the budget."""
        return self.deadline - time.monotonic()

    # What a step in a module of its own uses (imrl_jax.commands.gpu_study): through the check, not an import of this module.
    def compile_once(self, key: tuple, fn, *args):
        """:func:`compile_once` of this check."""
        return compile_once(self, key, fn, *args)

    def timed(self, executable, args, repeats: int) -> tuple[float, float]:
        """:func:`timed`."""
        return timed(executable, args, repeats)

    def fastest_rate(self) -> float | None:
        """:func:`fastest_rate` of this check."""
        return fastest_rate(self)

    def share_left(self, share: float) -> float:
        """The budget's remaining seconds at which a step that may use ``share`` of the budget from now must stop."""
        return self.remaining() - share * self.results["budget_s"]

    def fits(self, seconds: float) -> bool:
        """Whether work expected to take ``seconds`` (at the real sizes) fits in what is left."""
        return self.remaining() > seconds * self.sizes.scale and self.remaining() > 0

    def say(self, line: str) -> None:
        """Print a line and keep it for the text table."""
        self.lines.append(line)
        self.log(line)

    @contextlib.contextmanager
    def piece(self, row: dict, rows: list | None = None):
        """One piece of a step (a case, a kernel, a lane count): a failure is written into ``row``, and the step
        goes on to its next piece."""
        try:
            yield
        except Exception as error:  # noqa: BLE001 - a piece's failure is its result
            row.update(status="failed", stage=self.stage, error=one_line(error))
            self.say(f"  FAILED at {self.stage}: {row['error']}")
        finally:
            if rows is not None:
                rows.append(row)

    def run_step(self, name: str, fn: Callable[["Check"], dict], seconds: float) -> dict:
        """Run one step, recording its figures or its failure (stage and one line); never raises."""
        record = {"step": name}
        if not self.fits(seconds):
            record.update(status="skipped", error=f"budget: {self.remaining():.0f} s left, about {seconds:.0f} s "
                                                  "needed")
            self.say(f"[{name}] skipped: {record['error']}")
        else:
            self.stage, start = "import", time.perf_counter()
            self.say(f"[{name}] ({self.remaining():.0f} s of the budget left)")
            try:
                record.update(status="ok", **fn(self))
            except Exception as error:  # noqa: BLE001 - every failure is this step's result, and the check goes on
                record.update(status="failed", stage=self.stage, error=one_line(error),
                              traceback=traceback.format_exc().splitlines()[-15:])
                self.say(f"[{name}] FAILED at {self.stage}: {record['error']}")
            record["step_seconds"] = round(time.perf_counter() - start, 2)
            record.setdefault("failures", [])
            record["failures"] += [describe(row) for row in record.get("rows", []) if row.get("status") == "failed"]
            if record["status"] == "ok" and record["failures"]:
                record["status"] = "failed"
                record.setdefault("stage", "numbers")
                self.say(f"[{name}] FAILED: {'; '.join(record['failures'])}")
            record["peak_device_bytes"] = device_peak_bytes()
            self.say(f"[{name}] {record['status']} in {record['step_seconds']:.1f} s")
        self.results["steps"].append(record)
        self.write()
        return record

    def write(self) -> None:
        """Rewrite the JSON and the text table (atomically: a stop leaves the last whole ones)."""
        from imrl_jax.runs.rundir import write_atomic

        text = json.dumps(finite(self.results), indent=1, default=float, allow_nan=False)
        write_atomic(os.path.join(self.out_dir, FILES[0]), text.encode())
        write_atomic(os.path.join(self.out_dir, FILES[1]), ("\n".join(self.lines) + "\n").encode())


def finite(value):
    """``value`` with every float that is not finite as None (strict JSON has no NaN or infinity)."""
    if isinstance(value, dict):
        return {k: finite(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [finite(v) for v in value]
    if isinstance(value, (float, np.floating)):
        return float(value) if np.isfinite(value) else None
    return value


def describe(row: dict) -> str:
    """A failed piece in a few words: what it was and where it failed."""
    what = " ".join(str(row[k]) for k in ("condition", "preset", "phase", "kernel", "lanes", "seeds") if k in row)
    return f"{what}: {row.get('stage', 'numbers')}: {row.get('error', 'outside tolerance')}"


def one_line(error: BaseException) -> str:
    """An exception as one line: its type and the first line of its message (at most 300 characters)."""
    text = str(error).strip().splitlines()
    return f"{type(error).__name__}: {text[0] if text else ''}"[:300]


def device_peak_bytes() -> int | None:
    """The first device's peak memory in use so far (None where the backend does not say)."""
    import jax

    try:
        return (jax.devices()[0].memory_stats() or {}).get("peak_bytes_in_use")
    except Exception:  # noqa: BLE001 - a backend without memory statistics
        return None


def compile_program(check: Check, fn, *args):
    """``fn`` jitted, traced, lowered and compiled for ``args`` (the check's stage follows): (executable, seconds)."""
    import jax

    check.stage = "api"
    traced = jax.jit(fn).trace(*args)
    check.stage = "lowering"
    start = time.perf_counter()
    lowered = traced.lower()
    check.stage = "compile"
    executable = lowered.compile()
    check.stage = "run"
    return executable, time.perf_counter() - start


def compile_once(check: Check, key: tuple, fn, *args):
    """:func:`compile_program`, or the program compiled before under ``key`` (what it is made of, its inputs'
    shapes): steps that time the same program compile it once (the seconds are its first compilation's)."""
    if key not in check.compiled:
        check.compiled[key] = compile_program(check, fn, *args)
    check.stage = "run"
    return check.compiled[key]


def program_bytes(executable) -> int | None:
    """The compiled program's memory: temporaries, arguments and outputs."""
    try:
        memory = executable.memory_analysis()
        return int(memory.temp_size_in_bytes + memory.argument_size_in_bytes + memory.output_size_in_bytes)
    except Exception:  # noqa: BLE001 - not every backend analyses memory
        return None


def timed(executable, args, repeats: int) -> tuple[float, float]:
    """Median and shortest seconds of ``repeats`` calls after a first one (the first alone when it took over 5 s:
    compiled ahead, it holds no compilation, and a long program is not run again)."""
    from imrl_jax.commands.bench import _time

    return _time(executable, *args, repeats=repeats, once_over=5.0)


@contextlib.contextmanager
def float64():
    """64-bit floats inside the block (the reference comparisons)."""
    import jax

    enable = jax.enable_x64 if hasattr(jax, "enable_x64") else __import__("jax.experimental", fromlist=["x"]).enable_x64
    with enable(True):
        yield


# ----------------------------------------------------------------------------- steps


def environment(check: Check) -> dict:
    """The device, its memory and the versions of everything the engine uses."""
    import jax

    from imrl_jax.runs.checkpoint import package_versions

    check.stage = "api"
    device = jax.devices()[0]
    versions = package_versions(("jax", "jaxlib", "numpy", "optax", "orbax-checkpoint", "matplotlib", "brax", "evosax",
                                 "triton"))
    stats = device_memory = None
    with contextlib.suppress(Exception):
        stats = device.memory_stats() or {}
        device_memory = stats.get("bytes_limit")
    info = {"backend": jax.default_backend(), "device": getattr(device, "device_kind", str(device)),
            "num_devices": len(jax.devices()), "device_memory_bytes": device_memory, "cpu_count": os.cpu_count(),
            "machine": platform.machine(), "python": platform.python_version(), "versions": versions}
    with contextlib.suppress(Exception):
        info["environment"] = jax.print_environment_info(return_string=True)
    check.results["machine"] = info
    check.say(f"  {info['device']} x {info['num_devices']} ({info['backend']}), jax {versions['jax']}, "
              f"jaxlib {versions['jaxlib']}, python {info['python']}; device memory {device_memory}")
    return {}


def life_cases(sizes: Sizes):
    """(condition, preset, config) of every condition under every preset that makes another model
    (``Config.model_differences``), with the kernel's reason where it does not implement the condition."""
    from imrl_jax import conditions
    from imrl_jax.agent import kernel
    from imrl_jax.config import make_config

    childhood, task, bins = sizes.life_steps
    cases = []
    for name in sizes.conditions or conditions.NAMES:
        seen = []
        for preset in sizes.presets:
            config = make_config(preset, condition=name, childhood_steps=childhood, task_steps=task, num_bins=bins,
                                 target_radius=sizes.life_target_radius)
            if any(not config.model_differences(other) for other in seen):
                continue  # the same lives as a preset before it
            seen.append(config)
            cases.append((name, preset, config, kernel.unsupported(config)))
    # The kernel's cases first: the XLA-only ones check what the CPU tests check already.
    return sorted(cases, key=lambda case: case[3] is not None)


def weights_excess(got, want: dict, rtol: float, atol: float) -> tuple[float, float]:
    """(max |got - want|, max of |got - want| - (atol + rtol |want|)) over the networks both have (ok: second <= 0)."""
    from imrl_jax.agent.reference import WEIGHT_KEYS

    largest, excess = 0.0, -np.inf
    for name in WEIGHT_KEYS:
        value = getattr(got, name) if not isinstance(got, dict) else got.get(name)
        if value is None or name not in want:
            continue
        diff = np.abs(np.asarray(value, np.float64) - np.asarray(want[name], np.float64))
        largest = max(largest, float(diff.max(initial=0.0)))
        excess = max(excess, float((diff - atol - rtol * np.abs(np.asarray(want[name], np.float64))).max(initial=-1)))
    return largest, excess


def compare_with_reference(life, ref: dict, num_tasks: int, tolerance: dict) -> dict:
    """A JAX life against the reference's: reaches equal, weights after childhood and every task within tolerance."""
    import jax

    reaches_equal = bool(np.array_equal(np.asarray(life.reaches), ref["reaches"]))
    largest, excess = weights_excess(life.agent, ref["childhood_weights"], **tolerance)
    for t in range(num_tasks):
        task_largest, task_excess = weights_excess(jax.tree.map(lambda x: x[t], life.adult_agents),
                                                   ref["task_weights"][t], **tolerance)
        largest, excess = max(largest, task_largest), max(excess, task_excess)
    return {"ok": reaches_equal and excess <= 0, "reaches_equal": reaches_equal, "max_weight_diff": largest,
            "reaches": int(np.sum(ref["reaches"]))}


def compare_kernels(pallas, xla, tolerance: dict) -> dict:
    """The kernel's life against the XLA step's: every event count equal, weights within tolerance."""
    events = ("reaches", "timeouts", "reward_curve", "adult_selections", "childhood_selections")
    equal = all(np.array_equal(np.asarray(getattr(pallas, n)), np.asarray(getattr(xla, n))) for n in events)
    largest, excess = 0.0, -np.inf
    for name in ("agent", "adult_agents"):
        want = {k: v for k, v in getattr(xla, name)._asdict().items() if v is not None}
        part_largest, part_excess = weights_excess(getattr(pallas, name), want, **tolerance)
        largest, excess = max(largest, part_largest), max(excess, part_excess)
    return {"ok": equal and excess <= 0, "events_equal": equal, "max_weight_diff": largest}


#: The share of the budget the ``lives`` step may use, so that the speed steps after it get the rest.
LIVES_SHARE = 0.3


def lives(check: Check) -> dict:
    """Short float64 lives of every case, XLA and Pallas, against the reference and each other."""
    import jax
    import jax.numpy as jnp

    from imrl_jax.agent import kernel_choice, lifetime, reference
    from imrl_jax.config import Config, LearningParams

    rows, programs = [], {}
    stop = check.share_left(LIVES_SHARE)
    for name, preset, config, reason in life_cases(check.sizes):
        row = {"condition": name, "preset": preset, "kernels": list(KERNELS if reason is None else ("xla",)),
               "auto": kernel_choice.chosen(config)}  # what the default lives it with on this machine
        if reason:
            row["pallas"] = reason
        if check.remaining() < stop and check.sizes.scale:
            rows.append({**row, "status": "skipped (the step's share of the budget)"})
            continue
        with check.piece(row, rows), float64():
            check.stage = "api"
            key = jax.random.key(11)
            genome = jax.random.uniform(jax.random.key(12), (config.num_genes,), jnp.float64, -1.0, 1.0)
            params = jax.tree.map(lambda v: jnp.asarray(v, jnp.float64), config.learning_params())
            # Presets that differ only in learning values share one program (the values are its arguments).
            static = config.replace(**dict(zip(LearningParams._fields, Config().learning_params())))
            got = {}
            for kernel in row["kernels"]:
                program = static.replace(step_kernel=kernel)
                if program not in programs:
                    fn = lambda k, p, g, c=program: lifetime.live(k, c, p, g)  # noqa: E731
                    programs[program] = compile_program(check, fn, key, params, genome)
                executable, compile_s = programs[program]
                check.stage = "run"
                got[kernel] = jax.block_until_ready(executable(key, params, genome))
                row[f"{kernel}_compile_s"] = round(compile_s, 2)
            check.stage = "numbers"
            ref = reference.live_with(config, genome, lifetime.life_draws(key, config, jnp.float64))
            for kernel in got:
                row[f"{kernel}_vs_reference"] = compare_with_reference(got[kernel], ref, config.num_tasks,
                                                                       TOLERANCES["reference"])
            if len(got) == 2:
                row["pallas_vs_xla"] = compare_kernels(got["pallas"], got["xla"], TOLERANCES["kernels"])
            checks = {k: v for k, v in row.items() if isinstance(v, dict)}
            row["status"] = "ok" if all(v["ok"] for v in checks.values()) else "failed"
            if row["status"] == "failed":
                row["error"] = "outside tolerance: " + ", ".join(k for k, v in checks.items() if not v["ok"])
            check.say(f"  {name:10s} {preset:9s} {row['status']:6s} reaches {ref['reaches'].sum():4d}; "
                      + ", ".join(f"{k} {v['max_weight_diff']:.1e}" for k, v in checks.items()))
    return {"rows": rows}


def float32_phase(check: Check) -> dict:
    """The float32 CPU test's adult phase (EE-LS, hand-made experts, one short task) on both kernels."""
    import jax
    import jax.numpy as jnp

    from imrl_jax.agent import lifetime as L
    from imrl_jax.agent import reference
    from imrl_jax.config import Task, make_config
    from imrl_jax.agent.networks import decode
    from imrl_jax.agent.state import draw_many

    steps = check.sizes.float32_steps
    config = make_config("paper", condition="EE-LS", tasks=(Task(**reference.SHORT_TASK_FIELDS),), task_steps=steps,
                         num_bins=1)
    check.stage = "api"
    agent = decode(config, jnp.zeros((config.num_genes,)))._replace(
        actor=jnp.asarray(reference.hand_experts(config.num_inputs + 1), jnp.float32))
    task, key, params = L.task_spec(config, 0), jax.random.key(0), config.learning_params()
    state = L.init_state(config, agent, task.start)
    draws = draw_many(key, steps, config.draw_block)
    weights = {k: np.asarray(v, np.float64) for k, v in agent._asdict().items() if v is not None}
    ref = reference.run_phase(config, "adult-ls", weights, (*reference.SHORT_TASK_FIELDS["start"], 0.0),
                              np.asarray(draws.u, np.float64), np.asarray(draws.z, np.float64), task=0)
    rows, want = [], int(ref["reached"].sum())
    for kernel in KERNELS:
        row = {"kernel": kernel, "steps": steps, "reference_reaches": want}
        with check.piece(row, rows):
            c = config.replace(step_kernel=kernel)
            fn = lambda k, p, s, c=c: L.run_phase(k, c, c.spec.adult, p, task, s, steps)  # noqa: E731
            executable, _ = compile_program(check, fn, key, params, state)
            final, curves = jax.block_until_ready(executable(key, params, state))
            check.stage = "numbers"
            pose = np.asarray(final.pose.pos, np.float64)
            largest, excess = weights_excess(final.agent, ref["weights"], **TOLERANCES["float32"])
            row.update(reaches=int(curves.reaches.sum()), max_weight_diff=largest,
                       pose_diff_cm=float(np.abs(pose - [ref["x"][-1], ref["y"][-1]]).max()))
            ok = row["reaches"] == want and row["pose_diff_cm"] <= TOLERANCES["float32_pose_cm"] and excess <= 0
            row["status"] = "ok" if ok else "failed"
            if not ok:
                row["error"] = "outside the float32 test's tolerance"
            check.say(f"  float32 {kernel:6s} reaches {row['reaches']} (reference {want}), pose "
                      f"{row['pose_diff_cm']:.1e} cm, weights {largest:.1e}: {row['status']}")
    return {"rows": rows}


def whole_lives(check: Check) -> dict:
    """Whole LE-LS lives (bench's headline) at every lane count, both kernels."""
    from imrl_jax.commands import bench

    rows, last = [], {}
    for kernel in KERNELS:
        for lanes in check.sizes.lanes:
            row = {"kernel": kernel, "lanes": lanes}
            # At most in proportion to the lanes (a first run, then the repeats when it is short).
            if not check.fits(15 + last.get(kernel, 1.0) * (1 + check.sizes.repeats) * lanes / last.get(
                    (kernel, "lanes"), lanes)):
                rows.append({**row, "status": "skipped (budget)"})
                continue
            with check.piece(row, rows):
                check.stage = "api"
                program = bench.lifetime_program(lanes, check.sizes.life_task_steps, step_kernel=kernel)
                executable, compile_s = compile_program(check, program.fn, *program.args)
                seconds, shortest = timed(executable, program.args, check.sizes.repeats)
                individuals = program.args[2].shape[0]
                row.update(lanes=individuals * program.config.num_tasks, individuals=individuals,
                           childhood_steps=program.config.childhood_steps, task_steps=program.config.task_steps,
                           compile_s=compile_s, seconds=seconds, lane_steps_per_s=program.lane_steps / seconds,
                           best_lane_steps_per_s=program.lane_steps / shortest,
                           program_bytes=program_bytes(executable), status="ok")
                last.update({kernel: seconds, (kernel, "lanes"): lanes})
                check.say(f"  life {kernel:6s} {row['lanes']:8,d} lanes: {row['lane_steps_per_s']:14,.0f} "
                          f"lane-steps/s, compile {compile_s:5.1f} s, {seconds:.3f} s a life")
    return {"rows": rows}


def generation_inputs(config, num_seeds: int):
    """The keys, learning values, populations and index of generation 0 of seeds 0..num_seeds-1."""
    import jax
    import jax.numpy as jnp

    from imrl_jax.evolution.ga import init_population

    seeds = jax.vmap(jax.random.key)(jnp.arange(num_seeds, dtype=jnp.uint32))
    populations = jax.vmap(lambda k: init_population(jax.random.fold_in(k, 0), config))(seeds)
    keys = jax.vmap(lambda k: jax.random.fold_in(k, 1))(seeds)
    return keys, config.learning_params(), populations, jnp.int32(0)


def generations(check: Check) -> dict:
    """One paper-scale generation (LE-LS; compilation apart) per kernel and seed count."""
    import jax

    from imrl_jax.config import make_config
    from imrl_jax.evolution.ga import make_generation

    rows, last = [], {}
    for seeds in check.sizes.generation_seeds:
        for kernel in reversed(KERNELS):  # the kernel first: the XLA step's generation may take a minute
            row = {"kernel": kernel, "seeds": seeds}
            # A generation's time grows with the seeds at most in proportion: the last one bounds this one.
            if not check.fits(30 + last.get(kernel, 30) * seeds / last.get((kernel, "seeds"), seeds)):
                rows.append({**row, "status": "skipped (budget)"})
                continue
            with check.piece(row, rows):
                check.stage = "api"
                config = make_config("paper", condition=check.sizes.generation_condition, step_kernel=kernel,
                                     **dict(check.sizes.generation_sizes))
                args = generation_inputs(config, seeds)
                executable, compile_s = compile_program(check, make_generation(config), *args)
                start = time.perf_counter()
                _, stats = jax.block_until_ready(executable(*args))
                seconds = time.perf_counter() - start
                individuals = seeds * config.population_size
                row.update(individuals=individuals, compile_s=compile_s, seconds=seconds,
                           lane_steps_per_s=individuals * config.lifetime_steps / seconds,
                           evolution_minutes=seconds * config.num_generations / 60,
                           best_fitness=float(np.asarray(stats.fitness).max()),  # generation 0's best noisy life
                           num_generations=config.num_generations, status="ok")
                last.update({kernel: seconds, (kernel, "seeds"): seeds})
                check.say(f"  generation {kernel:6s} {seeds:3d} seeds: {seconds:7.2f} s (compile {compile_s:.1f} s), "
                          f"{config.num_generations} generations {row['evolution_minutes']:.1f} min")
    return {"rows": rows}


def fastest_kernel(check: Check) -> str:
    """The kernel whose generation of the fewest seeds was quickest (the XLA step if none ran)."""
    steps = [s for s in check.results["steps"] if s["step"] == "generation" and s["status"] == "ok"]
    rows = [r for s in steps for r in s["rows"] if r.get("status") == "ok"]
    if not rows:
        return "xla"
    fewest = min(r["seeds"] for r in rows)
    return min((r for r in rows if r["seeds"] == fewest), key=lambda r: r["seconds"])["kernel"]


def fastest_rate(check: Check) -> float | None:
    """The lane-steps per second of the fastest kernel's generation of the fewest seeds (None if none ran)."""
    kernel = fastest_kernel(check)
    rows = [r for s in check.results["steps"] if s["step"] == "generation" and s["status"] == "ok"
            for r in s["rows"] if r.get("status") == "ok" and r["kernel"] == kernel]
    return min(rows, key=lambda r: r["seeds"])["lane_steps_per_s"] if rows else None


def sweep(check: Check) -> dict:
    """One generation of ``evolve --sweep``'s program (every point and seed in one batch), with the fastest kernel,
    against the generation of as many seeds of a single run timed before it (the ratio: at most the points)."""
    import itertools

    import jax

    from imrl_jax.commands import evolve_sweep
    from imrl_jax.config import make_config
    from imrl_jax.evolution.devices import make_mesh, population_sharding, replicated, to_global
    from imrl_jax.runs.run_state import evolution_keys, initial_state

    kernel = fastest_kernel(check)
    check.stage = "api"
    config = make_config("paper", condition=check.sizes.generation_condition, step_kernel=kernel,
                         **dict(check.sizes.generation_sizes))
    names, values = zip(*check.sizes.sweep)
    settings = [dict(zip(names, combo)) for combo in itertools.product(*values)]
    seeds = list(range(check.sizes.sweep_seeds))
    points = evolve_sweep.make_points(config, seeds, settings)
    mesh = make_mesh()
    sharding = population_sharding(mesh, len(points) * len(seeds), config.population_size)
    state = initial_state(config, seeds, population_sharding(mesh, len(seeds), config.population_size))
    keys = to_global(evolution_keys(np.tile(state.key_data, (len(points), 1))), replicated(mesh))
    params, ga = evolve_sweep.batched_values(points, len(seeds))
    populations = to_global(np.tile(np.asarray(state.populations), (len(points), 1, 1)), sharding)
    step = evolve_sweep.make_sweep_step(config, sharding)
    key = ("sweep", program_key(config), kernel, len(points), len(seeds))
    executable, compile_s = compile_once(check, key, step, keys, params, ga, populations, 0)
    start = time.perf_counter()
    _, stats = jax.block_until_ready(executable(keys, params, ga, populations, 0))
    seconds = time.perf_counter() - start
    individuals = len(points) * len(seeds) * config.population_size
    single = [r for s in check.results["steps"] if s["step"] == "generation" and s["status"] == "ok" for r in s["rows"]
              if r.get("status") == "ok" and r["kernel"] == kernel and r["seeds"] == len(seeds)]
    ratio = seconds / (len(points) * single[0]["seconds"]) if single else None
    check.say(f"  sweep ({kernel}) {len(points)} points x {len(seeds)} seeds: {seconds:.2f} s a generation "
              f"(compile {compile_s:.1f} s)" + (f"; over {len(points)} single generations: {ratio:.2f}" if ratio else ""))
    return {"kernel": kernel, "points": len(points), "seeds": len(seeds), "individuals": individuals,
            "compile_s": compile_s, "seconds": seconds, "over_single_generations": ratio,
            "lane_steps_per_s": individuals * config.lifetime_steps / seconds,
            "best_fitness": np.asarray(stats.fitness).max(-1).reshape(len(points), len(seeds)).tolist()}


def phases(check: Check) -> dict:
    """Every phase of the benchmark, both kernels, at every lane count."""
    from imrl_jax.commands import bench
    from imrl_jax import conditions
    from imrl_jax.agent import kernel_work

    rows, counted = [], {}
    for name, condition, phase, _ in bench.PHASES:
        if check.sizes.conditions and condition not in check.sizes.conditions:
            continue
        for kernel in KERNELS:
            for lanes in check.sizes.lanes:
                row = {"phase": name, "kernel": kernel, "lanes": lanes}
                if not check.fits(10 + lanes / 30_000):
                    rows.append({**row, "status": "skipped (budget)"})
                    continue
                with check.piece(row, rows):
                    check.stage = "api"
                    program = bench.phase_program(condition, phase, lanes, check.sizes.phase_steps,
                                                  step_kernel=kernel)
                    key = ("phase", condition, phase, lanes, check.sizes.phase_steps, kernel)
                    executable, compile_s = compile_once(check, key, program.fn, *program.args)
                    seconds, shortest = timed(executable, program.args, check.sizes.repeats)
                    row.update(steps=check.sizes.phase_steps, compile_s=compile_s,
                               lane_steps_per_s=program.lane_steps / seconds,
                               best_lane_steps_per_s=program.lane_steps / shortest,
                               program_bytes=program_bytes(executable), status="ok")
                    if kernel == "pallas":  # the issue rate it reaches (PERFORMANCE.md "How far from the hardware")
                        if (condition, phase) not in counted:
                            counted[condition, phase] = kernel_work.loop_work(
                                program.config, getattr(conditions, phase))["warp_instructions"]
                        row.update(warp_instructions=counted[condition, phase],
                                   warp_instructions_per_s=row["lane_steps_per_s"] * counted[condition, phase])
                    check.say(f"  {name:22s} {kernel:6s} {lanes:8,d} lanes: {row['lane_steps_per_s']:14,.0f} "
                              f"lane-steps/s, compile {compile_s:5.1f} s")
    return {"rows": rows}


#: (name, function, seconds it needs at the real sizes before it is worth starting)
STEPS = (("environment", environment, 0), ("lives", lives, 30), ("float32", float32_phase, 20),
         ("life", whole_lives, 30), ("generation", generations, 60), ("sweep", sweep, 60), ("study", study, 60),
         ("phases", phases, 20))


def figure(results: dict, path: str, cpu_bench: str | None = None) -> bool:
    """Lane-steps per second against lanes (whole lives, each phase) and a generation's seconds, per kernel:
    a panel for each of these steps that measured something (False, and no file, when none did)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from imrl_jax.commands import bench

    steps = {s["step"]: s for s in results["steps"]}
    done = {name: [r for r in steps.get(name, {}).get("rows", []) if r.get("status") == "ok"]
            for name in ("life", "phases", "generation")}
    sweep_done = steps.get("sweep", {}).get("status") == "ok"
    panels = [name for name in done if done[name] or (name == "generation" and sweep_done)]
    if not panels:
        return False
    fig, axes = plt.subplots(1, len(panels), figsize=(5 * len(panels), 4.4), squeeze=False)
    axes = dict(zip(panels, axes[0]))
    colours = {"xla": "tab:blue", "pallas": "tab:red"}
    if "life" in axes:
        ax = axes["life"]
        for kernel in KERNELS:
            rows = [r for r in done["life"] if r["kernel"] == kernel]
            if rows:
                ax.plot([r["lanes"] for r in rows], [r["lane_steps_per_s"] for r in rows], "o-",
                        color=colours[kernel], label=f"{kernel} on the device")
        if cpu_bench and os.path.exists(cpu_bench):
            with open(cpu_bench) as f:
                cpu = json.load(f).get("lifetimes", [])
            ax.plot([r["lanes"] for r in cpu], [r["lane_steps_per_s"] for r in cpu], "s--", color="0.4",
                    label="xla, 2-core CPU (docs/bench)")
        ax.set(xscale="log", yscale="log", xlabel="adult lanes (6 per individual)", ylabel="lane-steps per second",
               title="Whole LE-LS lives")
    if "phases" in axes:
        ax = axes["phases"]
        styles = dict(zip([p[0] for p in bench.PHASES], ("o-", "s-", "^-", "v-")))
        for kernel in KERNELS:
            for phase, style in styles.items():
                rows = [r for r in done["phases"] if r["kernel"] == kernel and r["phase"] == phase]
                if rows:
                    ax.plot([r["lanes"] for r in rows], [r["lane_steps_per_s"] for r in rows], style,
                            color=colours[kernel], label=f"{phase} ({kernel})", ms=4, lw=1)
        ax.set(xscale="log", yscale="log", xlabel="lanes", ylabel="lane-steps per second", title="Each phase")
    if "generation" in axes:
        ax = axes["generation"]
        rows = done["generation"]
        labels = [f"{r['kernel']}\n{r['seeds']} seeds" for r in rows]
        values = [r["seconds"] for r in rows]
        bar_colours = [colours[r["kernel"]] for r in rows]
        if sweep_done:
            s = steps["sweep"]
            labels.append(f"sweep ({s['kernel']})\n{s['points']} points\nx {s['seeds']} seeds")
            values.append(s["seconds"])
            bar_colours.append(colours[s["kernel"]])
        ax.bar(range(len(values)), values, color=bar_colours)
        for i, v in enumerate(values):
            ax.text(i, v, f"{v:.1f} s", ha="center", va="bottom", fontsize=8)
        ax.set_xticks(range(len(values)), labels, fontsize=7)
        ax.set(ylabel="seconds (compilation apart)", title="One paper-scale generation")
    for name in ("life", "phases"):
        if name in axes:
            axes[name].legend(fontsize=7, loc="best")
    machine = results.get("machine", {})
    fig.suptitle(f"gpu_check on {machine.get('device', '?')}, jax {machine.get('versions', {}).get('jax', '?')}"
                 + (" (--dry: tiny sizes, not speeds)" if results.get("dry") else ""), fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return True


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
