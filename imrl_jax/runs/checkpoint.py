"""Checkpoints of an evolution run with orbax-checkpoint (the GA of section 2, made resumable).

A checkpoint holds everything the next generation needs (the populations, the seeds' key
data, the generation count, the history so far, the last evaluated population and its
fitness) plus JSON metadata (config, package version, git commit). orbax writes each step
into a temporary directory and renames it when complete, so a kill during a save leaves
the previous checkpoint usable. :func:`restore_latest` falls back to an older step when
the newest cannot be read, and says so.
"""

from __future__ import annotations

import atexit
import contextlib
import gc
import glob
import logging
import os
import re
import shutil
import subprocess
import sys
import threading
import time
from typing import Any, NamedTuple, Sequence

import jax
import numpy as np

import imrl_jax


class History(NamedTuple):
    """Per-generation statistics of every seed; rows past ``generation`` are NaN."""

    best: np.ndarray  # (G, S) best fitness
    mean: np.ndarray  # (G, S) mean fitness of the population
    std: np.ndarray  # (G, S) standard deviation of the population's fitness
    best_performance: np.ndarray  # (G, S, tasks) task performances of the best individual


class RunState(NamedTuple):
    """Everything an evolution carries from one generation to the next."""

    generation: np.ndarray  # () generations done
    populations: jax.Array  # (S, P, genes) to be evaluated next
    evaluated: jax.Array  # (S, P, genes) the last evaluated populations
    fitness: jax.Array  # (S, P) their fitness
    key_data: np.ndarray  # (S, 2) jax.random.key_data of each seed's key
    history: History
    search: Any = ()  # each seed's search strategy state beyond the populations (the paper's GA: none)
    traits: Any = ()  # (G, S, traits, 2) the evolved values' population mean and the best's (networks.traits); or none


def empty_history(num_generations: int, num_seeds: int, num_tasks: int) -> History:
    nan = lambda *shape: np.full(shape, np.nan, np.float32)  # noqa: E731
    return History(nan(num_generations, num_seeds), nan(num_generations, num_seeds),
                   nan(num_generations, num_seeds), nan(num_generations, num_seeds, num_tasks))


def resize_history(history: History, num_generations: int) -> History:
    """``history`` with ``num_generations`` rows: cut, or padded with NaN rows (generations not yet run)."""
    def resize(x):
        x = np.asarray(x)
        pad = np.full((max(num_generations - len(x), 0),) + x.shape[1:], np.nan, x.dtype)
        return np.concatenate([x[:num_generations], pad])

    return History(*(resize(x) for x in history))


def resize_rows(x, num_generations: int):
    """Per-generation rows (generations first) cut or padded with NaN to ``num_generations``; () stays ()."""
    if not np.size(x):
        return x
    x = np.asarray(x)
    pad = np.full((max(num_generations - len(x), 0),) + x.shape[1:], np.nan, x.dtype)
    return np.concatenate([x[:num_generations], pad])


def git_commit() -> str:
    """The git commit of the package source, or 'unknown' outside a git checkout."""
    try:
        out = subprocess.run(["git", "rev-parse", "HEAD"], cwd=os.path.dirname(os.path.abspath(__file__)),
                             capture_output=True, text=True, timeout=5)
        return out.stdout.strip() or "unknown"
    except (OSError, subprocess.SubprocessError):
        return "unknown"


def package_versions(names: Sequence[str]) -> dict:
    """The installed version of each package in ``names`` (None where it is not installed)."""
    from importlib.metadata import PackageNotFoundError, version

    found = {}
    for name in names:
        try:
            found[name] = version(name)
        except PackageNotFoundError:
            found[name] = None
    return found


def unreadable_reason(error: BaseException, directory: str = "", limit: int = 160) -> str:
    """One short line saying why a checkpoint could not be read (no object reprs, paths relative, cut at a word)."""
    text = " ".join(str(error).split()) or type(error).__name__
    text = re.sub(r"\s*\[source locations=.*", "", text)
    text = re.sub(r"<[^<>]*? at 0x[0-9a-fA-F]+>", "(an object)", text)
    text = re.sub(r"<[^<>]*>", "(an object)", text)
    if directory:
        text = text.replace(os.path.join(directory, ""), "").replace(directory, ".")
    if len(text) > limit:
        text = text[:limit].rsplit(" ", 1)[0].rstrip(",;:") + " ..."
    return text


@contextlib.contextmanager
def _quiet_absl():
    """orbax logs each unreadable file on the absl logger; the caller reports it in one line instead."""
    logger = logging.getLogger("absl")
    level = logger.level
    logger.setLevel(logging.CRITICAL)
    try:
        yield
    finally:
        logger.setLevel(level)


def _closed_loop(error: BaseException | None) -> bool:
    return isinstance(error, RuntimeError) and str(error) == "Event loop is closed"


def _through_orbax(trace) -> bool:
    """Whether a traceback passes through orbax's code."""
    while trace is not None:
        if f"{os.sep}orbax{os.sep}" in trace.tb_frame.f_code.co_filename:
            return True
        trace = trace.tb_next
    return False


class _UnretrievedReads(logging.Filter):
    """asyncio's report of a task or future of orbax's whose error no one retrieved: dropped."""

    def filter(self, record: logging.LogRecord) -> bool:
        error = record.exc_info[1] if record.exc_info else None
        return not ("exception was never retrieved" in str(record.msg).split("\n", 1)[0] and error is not None
                    and _through_orbax(error.__traceback__))


def _silence_failed_reads() -> None:
    """From now on, drop the errors of orbax's reads of a checkpoint that could not be restored (its restore reports
    the failure in one line). A failed read is left unawaited, and whenever the garbage collector reaches it (during
    the restore or long after) its error of some 80 lines was printed: as unraisable, by asyncio's logger (a task's or
    future's exception never retrieved), or as the end of one of orbax's threads. Installed once, for each channel."""
    logger = logging.getLogger("asyncio")
    if not any(isinstance(f, _UnretrievedReads) for f in logger.filters):
        logger.addFilter(_UnretrievedReads())
    unraisable_hook, thread_hook = sys.unraisablehook, threading.excepthook
    if not getattr(unraisable_hook, "drops_failed_reads", False):
        def drop_unraisable(unraisable):
            if not (_through_orbax(unraisable.exc_traceback) or _closed_loop(unraisable.exc_value)):
                unraisable_hook(unraisable)

        drop_unraisable.drops_failed_reads = True
        sys.unraisablehook = drop_unraisable
        # Those still referenced at exit would be collected as the interpreter shuts down, by its default hook: now.
        atexit.register(gc.collect)
    if not getattr(thread_hook, "drops_failed_reads", False):
        def drop_thread_end(args):
            if not _through_orbax(args.exc_traceback):
                thread_hook(args)

        drop_thread_end.drops_failed_reads = True
        threading.excepthook = drop_thread_end


@contextlib.contextmanager
def _quiet_closed_loops():
    """tensorstore calls back into the event loop of a save or restore that failed, which orbax has closed: not worth
    a traceback. Such a callback's error is printed as unraisable, or (from tensorstore's own threads) through
    sys.excepthook."""
    unraisable_hook, except_hook = sys.unraisablehook, sys.excepthook

    def drop_unraisable(unraisable):
        if not _closed_loop(unraisable.exc_value):
            unraisable_hook(unraisable)

    def drop_excepthook(kind, error, trace):
        if not _closed_loop(error):
            except_hook(kind, error, trace)

    sys.unraisablehook, sys.excepthook = drop_unraisable, drop_excepthook
    try:
        yield
    finally:
        sys.unraisablehook, sys.excepthook = unraisable_hook, except_hook


def _ocp():
    import orbax.checkpoint as ocp

    return ocp


def _saved(state: RunState) -> dict:
    """The state as orbax saves it: the search state's leaves numbered in order (any pytree comes back as it
    went in), and no entry for a strategy without one (so the GA's checkpoints are as they always were)."""
    saved = state._asdict()
    leaves = jax.tree.leaves(saved.pop("search"))
    if leaves:
        saved["search"] = {f"{i:03d}": leaf for i, leaf in enumerate(leaves)}
    if not np.size(saved["traits"]):
        del saved["traits"]
    return saved


def _search_from_saved(template: Any, saved: dict | None) -> Any:
    """The search state rebuilt in the template's structure from its numbered leaves."""
    treedef = jax.tree.structure(template)
    if treedef.num_leaves == 0:
        return template
    if saved is None or len(saved) != treedef.num_leaves:
        raise ValueError(f"the checkpoint holds {0 if saved is None else len(saved)} search state arrays, "
                         f"the strategy {treedef.num_leaves}")
    return jax.tree.unflatten(treedef, [saved[name] for name in sorted(saved, key=int)])  # "1000" after "999"


class Checkpointer:
    """Saves and restores :class:`RunState` under ``directory`` (one sub-directory per step)."""

    def __init__(self, directory: str, keep: int = 3):
        ocp = _ocp()
        options = ocp.CheckpointManagerOptions(max_to_keep=keep, enable_async_checkpointing=False,
                                               create=True)
        self.directory = os.path.abspath(directory)
        self.manager = ocp.CheckpointManager(self.directory, options=options)

    def steps(self) -> list[int]:
        """Generations with a complete checkpoint, oldest first."""
        return sorted(self.manager.all_steps())

    def save(self, state: RunState, meta: dict) -> None:
        """Save the state after ``state.generation`` generations (blocks until written)."""
        ocp = _ocp()
        step = int(state.generation)
        meta = {**meta, "generation": step, "version": imrl_jax.__version__, "git_commit": git_commit()}
        if step in self.manager.all_steps():  # an unreadable step being redone after a fall-back
            self.manager.delete(step)
        before = set(threading.enumerate())
        # A failed save is logged by each of orbax's threads, with tracebacks; the caller reports it once.
        with _quiet_absl(), _quiet_closed_loops():
            try:
                self.manager.save(step, args=ocp.args.Composite(state=ocp.args.StandardSave(_saved(state)),
                                                                meta=ocp.args.JsonSave(meta)), force=True)
                self.manager.wait_until_finished()
            except Exception:
                deadline = time.monotonic() + 10.0  # the other writes of the step end (and log) while quiet
                for thread in set(threading.enumerate()) - before:
                    thread.join(max(deadline - time.monotonic(), 0.0))
                # What the failed save left (orbax's temporary folder of the step) goes: it may be what fills the disk.
                for leftover in glob.glob(os.path.join(glob.escape(self.directory), f"{step}.orbax-checkpoint-tmp*")):
                    shutil.rmtree(leftover, ignore_errors=True)
                raise

    def restore_latest(self, template: RunState, warn=print, at_most: int | None = None) -> tuple[RunState, dict] | None:
        """The newest readable checkpoint (state shaped like ``template``; of a generation up to ``at_most`` if
        given), or None if none is.

        The saved history may be shorter than the template's (a finished run extended to more
        generations): it is read at its own length, from the checkpoint's config, and padded
        with NaN rows. An unreadable newer step is reported through ``warn`` and skipped.
        """
        _silence_failed_reads()
        with _quiet_absl(), _quiet_closed_loops():
            return self._restore_latest(_ocp(), template, warn, at_most)

    def _restore_latest(self, ocp, template: RunState, warn, at_most: int | None) -> tuple[RunState, dict] | None:
        """:meth:`restore_latest` with orbax's logs and its failed reads' tracebacks silenced."""
        for step in reversed([s for s in self.steps() if at_most is None or s <= at_most]):
            try:
                saved_meta = self.manager.restore(step, args=ocp.args.Composite(meta=ocp.args.JsonRestore())).meta
                rows = int(saved_meta.get("config", {}).get("num_generations", len(template.history.best)))
                shaped = template._replace(history=resize_history(template.history, rows),
                                           traits=resize_rows(template.traits, rows))
                abstract = jax.tree.map(ocp.utils.to_shape_dtype_struct, _saved(shaped))
                restored = self.manager.restore(step, args=ocp.args.Composite(
                    state=ocp.args.StandardRestore(abstract), meta=ocp.args.JsonRestore()))
                state = restored.state
                history = state["history"]
                history = History(**history) if isinstance(history, dict) else History(*history)
                history = jax.tree.map(np.asarray, history)
                state["history"] = resize_history(history, max(len(template.history.best), step))
                state["generation"] = np.asarray(state["generation"])
                state["key_data"] = np.asarray(state["key_data"])
                state["search"] = _search_from_saved(template.search, state.get("search"))
                state["traits"] = resize_rows(np.asarray(state.get("traits", template.traits)),
                                              max(len(template.history.best), step))
                state = RunState(**state)
                if int(state.generation) != step or int(restored.meta.get("generation", -1)) != step:
                    raise ValueError(f"generation recorded as {int(state.generation)}")
                return state, dict(restored.meta)
            except Exception as error:  # noqa: BLE001 - any failure means "unreadable"
                reason = unreadable_reason(error, os.path.join(self.directory, str(step)))
                warn(f"checkpoint {os.path.join(self.directory, str(step))} is unreadable ({reason}); "
                     f"trying an older one")
        return None

    def close(self) -> None:
        self.manager.close()


__all__ = ["Checkpointer", "History", "RunState", "empty_history", "git_commit", "resize_history", "unreadable_reason"]
