"""A progress line for long runs: generation, fitness, elapsed time, ETA, throughput."""

from __future__ import annotations

import sys
import time


def _clock(seconds: float) -> str:
    seconds = int(max(seconds, 0))
    return f"{seconds // 3600:d}:{seconds // 60 % 60:02d}:{seconds % 60:02d}"


class Progress:
    """Redraws one line on a terminal, prints one line per update otherwise; silent if quiet."""

    def __init__(self, total: int, done: int = 0, quiet: bool = False, stream=None, unit: str = "gen"):
        self.total, self.start_done, self.unit = total, done, unit
        self.quiet = quiet
        self.stream = stream or sys.stderr
        self.tty = hasattr(self.stream, "isatty") and self.stream.isatty()
        self.start = time.perf_counter()

    def update(self, done: int, best: float, mean: float, lane_steps_per_s: float, scores: str | None = None) -> str:
        """Report that ``done`` of ``total`` units (generations) are finished; return the line."""
        elapsed = time.perf_counter() - self.start
        rate = (done - self.start_done) / elapsed if elapsed > 0 else 0.0
        eta = (self.total - done) / rate if rate > 0 else float("nan")
        scores = f"best {best:.4f} mean {mean:.4f}" if scores is None else scores
        line = (f"{self.unit} {done:>4d}/{self.total} | {scores} | "
                f"{_clock(elapsed)} elapsed, ETA {_clock(eta) if eta == eta else '?'} | "
                f"{lane_steps_per_s / 1e6:.2f} M lane-steps/s")
        if not self.quiet:
            if self.tty:
                self.stream.write("\r" + line + ("\n" if done >= self.total else ""))
            else:
                self.stream.write(line + "\n")
            self.stream.flush()
        return line

    def message(self, text: str) -> None:
        """A line of its own (a warning or a note), even in quiet mode."""
        if self.tty:
            self.stream.write("\n")
        self.stream.write(text + "\n")
        self.stream.flush()
