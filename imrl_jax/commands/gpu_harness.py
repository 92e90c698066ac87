"""``gpu_check``'s harness: what each step does (:class:`Sizes`), the running check (:class:`Check`: the budget, the
stage a piece of work reached, the results so far and their files), and the compiling and timing the steps share.

A failure is named by the stage it had reached (:data:`STAGES`); the JSON is strict (:func:`finite`); a program that
several steps time is compiled once (:func:`compile_once`); what the generations measured picks the kernel and speed
of the steps after them (:func:`fastest_kernel`, :func:`fastest_rate`).
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import os
import time
import traceback
from typing import Callable

import numpy as np

#: The stages a piece of work goes through; a failure is named by the one it had reached.
STAGES = ("import", "api", "lowering", "compile", "run", "numbers")
#: The step kernels each step checks or times.
KERNELS = ("xla", "pallas")
#: What the check writes under ``--out``: the figures, their table, the figure.
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
    # The selector on its own time-scale (docs/TIMESCALE.md), lived under the first preset: (name, Config fields),
    # by the conditions of option_conditions (None: every one whose selector chooses). LE-LS, EE-ES and EXT-LS hold
    # every way an option meets learning: a childhood's and an adult learning selector, one that does not learn, and
    # experts learning beside it.
    selector_options: tuple = (("period", (("selector_period", 4),)),
                               ("colour", (("selector_period", 4), ("selector_termination", "colour"))))
    option_conditions: tuple[str, ...] | None = ("LE-LS", "EE-ES", "EXT-LS")
    float32_steps: int = 2000
    lanes: tuple[int, ...] = (3_000, 30_000, 300_000)
    life_task_steps: int = 2000  # the whole-life benchmark's task steps (childhood 1.5 times that)
    model_lanes: int = 30_000  # the adult lanes of each model's whole lives (the ``models`` step)
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


DRY = Sizes(life_steps=(60, 30, 3), presets=("paper",), conditions=("EE-LS",),
            selector_options=(("colour", (("selector_period", 4), ("selector_termination", "colour"))),),
            option_conditions=None,
            float32_steps=200,
            lanes=(6,), life_task_steps=20, model_lanes=6, phase_steps=20, repeats=1, generation_seeds=(2,),
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
