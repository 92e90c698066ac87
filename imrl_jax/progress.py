"""A progress line for long runs: generation, fitness, elapsed time, ETA, throughput (and its events, events.py)."""

from __future__ import annotations

import sys
import time

from imrl_jax.events import EventLog, make_log


def _clock(seconds: float) -> str:
    seconds = int(max(seconds, 0))
    return f"{seconds // 3600:d}:{seconds // 60 % 60:02d}:{seconds % 60:02d}"


class Progress:
    """Redraws one line on a terminal, prints one line per update otherwise; silent if quiet.

    ``done`` units were finished before (a resumed run) in ``elapsed`` seconds. Units are
    named from ``first_index`` (evolve: generation 0 is the first), or with ``group`` (name, size) counted
    within groups (run 1 chunk 3/10). The first update of a process includes compilation: it shows no ETA or
    throughput; later ones measure from it. Each update, note and message is also an event of ``log``
    (default: :func:`imrl_jax.events.make_log`, the study runner's file when one reads it); when a runner reads
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
            timing = f"{_clock(self.elapsed())} elapsed, first {self.unit} with compilation"
        else:
            rate = (done - self.warm[0]) / (now - self.warm[1]) if now > self.warm[1] else 0.0
            eta_s = (self.total - done) / rate if rate > 0 else None
            eta = "?" if eta_s is None else _clock(eta_s)
            timing = f"{_clock(self.elapsed())} elapsed, ETA {eta} | {lane_steps_per_s / 1e6:.2f} M lane-steps/s"
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
