"""A run's progress as one structured stream of events: stage, generation, fitness, ETA, throughput.

Every long command reports through :class:`imrl_jax.runs.progress.Progress`, which writes each update
as an event to the sinks of an :class:`EventLog`:

* a JSON-lines file named by the environment variable ``IMRL_EVENTS`` (the study runner sets it
  for each stage, with ``IMRL_EVENTS_READER=1``, and reads the stage's progress from it,
  :class:`Reader`; the command then leaves its progress lines to the runner, which shows them
  beside the whole study's; set by hand without the reader mark, the lines are printed too);
* TensorBoard (``--log tensorboard`` of evolve and learning_test: scalars under ``OUT/tensorboard``,
  through tensorboardX, an optional dependency imported when asked for).

An event is a dict with ``kind`` (``progress``, ``note`` or ``warning``), ``time`` (seconds since
the epoch) and its fields; a progress event has ``unit``, ``index`` (the unit's name: generation 0
is the first), ``done``, ``total``, ``best``, ``mean``, ``lane_steps_per_s``, ``elapsed_s``,
``eta_s`` (None before a rate is measured) and ``line`` (the progress line as printed).
"""

from __future__ import annotations

import json
import os
import time

#: The environment variable naming the JSON-lines file a command appends its events to.
ENV = "IMRL_EVENTS"
#: Set (to 1) by a runner that reads those events and shows the progress lines itself.
READER = "IMRL_EVENTS_READER"
#: Scalars of a progress event that TensorBoard draws, with their tags.
SCALARS = (("best", "fitness/best"), ("mean", "fitness/mean"), ("lane_steps_per_s", "speed/lane_steps_per_s"))


class JsonLines:
    """Events appended to a file, one JSON object a line (flushed at once: a reader sees each as it comes)."""

    def __init__(self, path: str):
        self.path = path
        os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
        self.file = open(path, "a")

    def write(self, event: dict) -> None:
        self.file.write(json.dumps(event, default=float) + "\n")
        self.file.flush()

    def close(self) -> None:
        self.file.close()


class TensorBoard:
    """Progress events as TensorBoard scalars (tensorboardX), one step per unit."""

    def __init__(self, log_dir: str, first_step: int = 0):
        try:
            from tensorboardX import SummaryWriter
        except ImportError:
            raise ImportError("--log tensorboard needs tensorboardX: pip install tensorboardX") from None
        # A resumed run writes again the steps from ``first_step`` on (those after its checkpoint): TensorBoard is told
        # to drop what earlier processes wrote from there, so that each step is shown once.
        self.writer = SummaryWriter(log_dir, purge_step=first_step or None)

    def write(self, event: dict) -> None:
        if event["kind"] != "progress":
            return
        for field, tag in SCALARS:
            if event.get(field) is not None:
                self.writer.add_scalar(tag, event[field], event["index"])
        self.writer.flush()

    def close(self) -> None:
        self.writer.close()


class EventLog:
    """Where a command's events go: any number of sinks (none: events are dropped)."""

    def __init__(self, sinks=()):
        self.sinks = list(sinks)

    @property
    def read_by_runner(self) -> bool:
        """Whether a study runner reads these events (and shows the progress lines itself)."""
        return any(isinstance(s, JsonLines) for s in self.sinks) and os.environ.get(READER) == "1"

    def emit(self, kind: str, **fields) -> dict:
        """Write one event to every sink; return it."""
        event = {"kind": kind, "time": round(time.time(), 3), **fields}
        for sink in self.sinks:
            sink.write(event)
        return event

    def close(self) -> None:
        for sink in self.sinks:
            sink.close()


def make_log(tensorboard_dir: str | None = None) -> EventLog:
    """The event log of a command: ``IMRL_EVENTS``'s file if set, and TensorBoard under ``tensorboard_dir`` if given."""
    sinks = []
    if os.environ.get(ENV):
        sinks.append(JsonLines(os.environ[ENV]))
    if tensorboard_dir:
        sinks.append(TensorBoard(tensorboard_dir))
    return EventLog(sinks)


class Reader:
    """Reads a JSON-lines event file as it grows (the runner's side): each call returns the events since the last."""

    def __init__(self, path: str):
        self.path, self.offset, self.partial = path, 0, ""

    def read(self) -> list[dict]:
        """The whole events written since the last call (a line still being written waits for the next)."""
        try:
            with open(self.path) as f:
                f.seek(self.offset)
                text = f.read()
                self.offset = f.tell()
        except FileNotFoundError:
            return []
        lines = (self.partial + text).split("\n")
        self.partial = lines.pop()
        events = []
        for line in lines:
            try:
                events.append(json.loads(line))
            except ValueError:  # not an event (the file is the runner's to name: nothing else should write it)
                continue
        return events


#: The values of the commands' ``--log`` option.
LOGS = ("tensorboard",)


def check_log(name: str | None, out_dir: str | None = None) -> None:
    """Refuse a ``--log`` that cannot be written (before anything is): ValueError naming the option; with
    ``out_dir``, its folder there (``OUT/tensorboard``) must be a folder one can make or write in (nothing is made)."""
    if name is None:
        return
    if name not in LOGS:
        raise ValueError(f"--log: unknown log {name!r} (choose from {', '.join(LOGS)})")
    try:
        import tensorboardX  # noqa: F401
    except ImportError:
        raise ValueError("--log tensorboard: needs tensorboardX (pip install tensorboardX)") from None
    if out_dir is not None:
        from imrl_jax.runs.rundir import check_writable

        check_writable(log_folder(name, out_dir), f"--log {name}")


def log_folder(name: str, out_dir: str) -> str:
    """The folder ``--log NAME`` writes under ``out_dir``."""
    return os.path.join(out_dir, name)


def log_for(name: str | None, out_dir: str) -> EventLog:
    """The event log of a command given ``--log NAME`` (None: the runner's file only) writing under ``out_dir``."""
    log = make_log()
    add_log(log, name, out_dir)
    return log


def add_log(log: EventLog, name: str | None, out_dir: str, first_step: int = 0) -> None:
    """Add the sink of ``--log NAME`` (None: none) to ``log``: once a resumed command knows its ``first_step``."""
    if name == "tensorboard":
        log.sinks.append(TensorBoard(log_folder(name, out_dir), first_step))
