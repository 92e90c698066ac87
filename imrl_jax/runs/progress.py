"""A progress line for long runs: generation, fitness, elapsed time, ETA, throughput (and its events, events.py)."""

from __future__ import annotations

import json
import math
import os
import sys
import time

from imrl_jax import files
from imrl_jax.runs.events import EventLog, make_log


def clock(seconds: float) -> str:
    """``seconds`` as H:MM:SS (none below 0)."""
    seconds = int(max(seconds, 0))
    return f"{seconds // 3600:d}:{seconds // 60 % 60:02d}:{seconds % 60:02d}"


class Progress:
    """Redraws one line on a terminal, prints one line per update otherwise; silent if quiet.

    ``done`` units were finished before (a resumed run) in ``elapsed`` seconds. Units are
    named from ``first_index`` (evolve: generation 0 is the first), or with ``group`` (name, size) counted
    within groups (run 1 chunk 3/10). The first update of a process includes compilation: it shows no ETA or
    throughput; later ones measure from it. Each update, note and message is also an event of ``log``
    (default: :func:`imrl_jax.runs.events.make_log`, the study runner's file when one reads it); when a runner reads
    them, the progress lines are its to show and are not printed here.
    """

    def __init__(self, total: int, done: int = 0, quiet: bool = False, stream=None, unit: str = "gen",
                 elapsed: float = 0.0, first_index: int = 1, group: tuple[str, int] | None = None,
                 log: EventLog | None = None):
        self.total, self.unit, self.first_index, self.group = total, unit, first_index, group
        self.log = make_log() if log is None else log
        self.quiet = quiet
        self.stream = stream or sys.stderr
        self.tty = hasattr(self.stream, "isatty") and self.stream.isatty()
        self.before = elapsed
        self.start = time.perf_counter()
        self.warm = None  # (done, time) at the first update: the rate is measured from there

    def elapsed(self) -> float:
        """Seconds spent on the run, in earlier processes too."""
        return self.before + time.perf_counter() - self.start

    def update(self, done: int, best: float, mean: float, lane_steps_per_s: float, scores: str | None = None) -> str:
        """Report that ``done`` of ``total`` units (generations) are finished; return the line."""
        now = time.perf_counter()
        eta_s, compiling = None, self.warm is None
        if self.warm is None:
            self.warm = (done, now)
            timing = f"{clock(self.elapsed())} elapsed, first {self.unit} with compilation"
        else:
            rate = (done - self.warm[0]) / (now - self.warm[1]) if now > self.warm[1] else 0.0
            eta_s = (self.total - done) / rate if rate > 0 else None
            eta = "?" if eta_s is None else clock(eta_s)
            timing = f"{clock(self.elapsed())} elapsed, ETA {eta} | {lane_steps_per_s / 1e6:.2f} M lane-steps/s"
        scores = f"best {best:.4f} mean {mean:.4f}" if scores is None else scores
        if self.group is None:
            line = f"{self.unit} {self.first_index + done - 1} ({done}/{self.total}) | {scores} | {timing}"
        else:  # units counted within groups of ``size`` (a learning test's chunks within its runs)
            group, size = self.group
            index = done - 1
            line = (f"{group} {index // size + self.first_index} {self.unit} {index % size + 1}/{size} "
                    f"({done}/{self.total}) | {scores} | {timing}")
        self.log.emit("progress", unit=self.unit, index=self.first_index + done - 1, done=done, total=self.total,
                      best=best, mean=mean, lane_steps_per_s=None if compiling else lane_steps_per_s,
                      elapsed_s=round(self.elapsed(), 3), eta_s=eta_s, line=line)
        if not self.quiet and not self.log.read_by_runner:
            if self.tty:
                self.stream.write("\r\033[K" + line + ("\n" if done >= self.total else ""))
            else:
                self.stream.write(line + "\n")
            self.stream.flush()
        return line

    def note(self, text: str) -> None:
        """A line of its own (a header, a note), left out in quiet mode."""
        if not self.quiet:
            self.log.emit("note", text=text)
            self._print(text)

    def message(self, text: str) -> None:
        """A line of its own (a warning), even in quiet mode."""
        self.log.emit("warning", text=text)
        self._print(text)

    def _print(self, text: str) -> None:
        if self.tty:
            self.stream.write("\n")
        self.stream.write(text + "\n")
        self.stream.flush()


#: Where the benchmark's measured speeds are committed (``python -m imrl_jax.bench --json docs/bench/NAME.json``).
BENCH_DIR = os.path.join(files.REPO, "docs", "bench")


def bench_files(backend: str, folder: str | None = None):
    """(file name, its JSON object) of each benchmark file of ``folder`` (default :data:`BENCH_DIR`) measured on
    ``backend``; a file that is not one is passed over."""
    folder = folder or BENCH_DIR
    for name in sorted(os.listdir(folder)) if os.path.isdir(folder) else []:
        try:
            with open(os.path.join(folder, name), "rb") as f:
                data = json.loads(f.read(2**20)) if name.endswith(".json") else None
        except (OSError, ValueError):
            continue
        if isinstance(data, dict) and data.get("backend") == backend:
            yield name, data


def measured_speed(backend: str, individuals: int, folder: str | None = None,
                   world: str = "arena") -> tuple[float, str] | None:
    """The speed of whole lives (lane-steps per second) the benchmark measured on ``backend`` with the number of
    individuals nearest ``individuals``, and the file that says so; None if no file of ``folder`` does.

    In another ``world`` than the arena: the speed ``bench --world`` measured of an agent's adult task there (its
    lanes nearest ``individuals``), the most of a life."""
    found = None
    for name, data in bench_files(backend, folder):
        for rate, measured in _rates(data, world):
            if math.isfinite(rate) and rate > 0 and measured > 0:
                distance = abs(math.log(measured / max(individuals, 1)))
                if found is None or distance < found[0]:
                    found = (distance, rate, os.path.join("docs", "bench", name))
    return None if found is None else found[1:]


def world_factor(world: str, backend: str = "cpu", folder: str | None = None) -> float | None:
    """How fast the agent lives in ``world`` against the arena on ``backend``, as ``bench --world`` measured both
    (the same phases at the same lanes, each world's default settings): the geometric mean of the agent's rate
    there over its rate in the arena, at the most lanes both measured; 1 for the arena, None where no file says."""
    if world == "arena":
        return 1.0
    rates: dict[str, dict] = {world: {}, "arena": {}}
    for _, data in bench_files(backend, folder):
        for name in rates:
            rates[name].update(world_rows(data, name))
    both = set(rates.get(world, {})) & set(rates.get("arena", {}))
    if not both:
        return None
    most = max(lanes for _, lanes in both)
    ratios = [rates[world][key] / rates["arena"][key] for key in sorted(both) if key[1] == most]
    return math.exp(sum(math.log(r) for r in ratios) / len(ratios))


def world_rows(data: dict, world: str) -> dict[tuple[str, int], float]:
    """{(phase, lanes): the agent's lane-steps per second} of a bench file's ``bench --world`` section for ``world``
    at its default settings (nothing where it holds none, or a row does not parse)."""
    section = data.get("world")
    if not isinstance(section, dict) or section.get("name") != world or section.get("settings"):
        return {}
    rows = {}
    for row in section.get("rows") or []:
        try:
            rate, key = float(row["agent_lane_steps_per_s"]), (str(row["phase"]), int(row["lanes"]))
        except (KeyError, TypeError, ValueError):
            continue
        if math.isfinite(rate) and rate > 0:
            rows[key] = rate
    return rows


def _rates(data: dict, world: str) -> list[tuple[float, int]]:
    """(lane-steps per second, individuals) of a bench file's whole lives (the arena), or of its ``world`` section's
    agent in an adult task (another world: :func:`world_rows`); nothing that does not parse."""
    if world != "arena":
        return [(rate, lanes) for (phase, lanes), rate in world_rows(data, world).items() if "adulthood" in phase]
    found = []
    for row in data.get("lifetimes") if isinstance(data.get("lifetimes"), list) else []:
        try:
            found.append((float(row["lane_steps_per_s"]), int(row["individuals"])))
        except (KeyError, TypeError, ValueError):
            continue
    return found


def _amount(count: int) -> str:
    """A count in words a reader takes in at a glance: 19,200, 7.2 M, 1.25 G."""
    return f"{count:,}" if count < 10**6 else f"{count / 1e6:,.1f} M" if count < 10**9 else f"{count / 1e9:,.2f} G"


def cost_line(what: str, individuals: int, lane_steps: int, generations: int, backend: str,
              memory: int | None = None, unit: str = "generation", world: str = "arena") -> str:
    """What a run will cost, in one line: its lives and lane-steps, its time at the speed the benchmark measured on
    ``backend`` (if it did; in its ``world``), compilation aside, and the ``memory`` (bytes) its check estimated, if
    given."""
    total = lane_steps * generations
    line = f"{what}: {individuals:,} lives a {unit}, {_amount(lane_steps)} lane-steps a {unit}, {_amount(total)} in all"
    speed = measured_speed(backend, individuals, world=world)
    if speed is None:
        where = "" if world == "arena" else f" in world {world}"
        line += f"; no speed measured on {backend}{where} in docs/bench to estimate its time"
    else:
        rate, source = speed
        line += (f"; about {clock(total / rate)} at the {rate / 1e6:.1f} M lane-steps/s {source} measured on "
                 f"{backend}, compilation aside")
    return line + (f"; at most about {memory / 2**30:.1f} GiB of memory (an estimate)" if memory is not None else "")
