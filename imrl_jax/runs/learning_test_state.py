"""A learning test's ``--out``: the runs kept while the test goes on, its outputs, and the checks before writing.

The runs a test has finished are kept in ``partial/`` under a fingerprint of what they depend on, so that
the same command after an interruption goes on from the first unfinished run with the results of an
uninterrupted test; the outputs (``curves.npz``, ``curve.csv``, ``learning_curve.png``, ``steady.json``
last) are written once every run is done, and ``partial/`` is then removed. ``--out`` is checked (new,
empty or such an unfinished test; no other writer) and locked before anything is written into it.
:mod:`imrl_jax.commands.learning_test` runs the tests and :mod:`imrl_jax.commands.learning_test_sweep` a sweep's points.
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import json
import os
import shutil
import zipfile
from typing import Callable, Iterator

import numpy as np

from imrl_jax.runs.cli import UsageError
from imrl_jax.config import COMPUTE_FIELDS, Config
from imrl_jax.runs.rundir import (RunDirError, RunWriteError, check_npz, check_unlocked, check_writable, entries, is_output,
                             lock_run_dir, make_dir, not_empty, read_text, write_atomic, write_errno)

#: The folder of ``--out`` that keeps each finished run of an unfinished test.
PARTIAL = "partial"
#: The files a learning test writes into ``--out`` (its last, steady.json, marks it finished).
OUTPUTS = ("curves.npz", "curve.csv", "learning_curve.png", "steady.json")


# ----------------------------------------------------------------------------- the runs kept while a test goes on


def fingerprint(config: Config, genomes: np.ndarray, num_tests: int, seed: int) -> str:
    """What a test's results depend on, hashed: a resumed test continues only a test of the same.

    Only the config fields away from their defaults count, so that a field added to ``Config``
    later (its default keeping the old behaviour) does not stop an older test from resuming; the
    compute choices (step kernel, unroll) do not count.
    """
    default = Config().to_dict()
    changed = {name: value for name, value in config.to_dict().items()
               if value != default.get(name) and name not in COMPUTE_FIELDS}  # how, not what: a test resumes
    digest = hashlib.sha256(json.dumps(dict(config=changed, num_tests=num_tests, seed=seed),
                                       sort_keys=True, default=str).encode())
    digest.update(np.ascontiguousarray(genomes, np.float32).tobytes())
    return digest.hexdigest()[:16]


def finished_runs(partial: str, stamp: str, num_runs: int, warn: Callable[[str], None] = print,
                  limit: int | None = None) -> dict:
    """The runs kept in ``partial`` by an interrupted test of the same fingerprint: {run: (reaches, selections)}
    (``limit``: the bytes a run's arrays take at most; a larger file is tested again)."""
    if not os.path.isdir(partial):
        return {}
    spec_path = os.path.join(partial, "spec.json")
    found = None
    if os.path.exists(spec_path):
        try:
            found = json.loads(read_text(spec_path, ""))["fingerprint"]
        except (RunDirError, ValueError, KeyError, TypeError, RecursionError) as error:
            raise UsageError(f"--out: {spec_path} cannot be read ({type(error).__name__}), so the runs kept beside it "
                             f"cannot be checked; remove {partial} to start the test over") from None
    if found != stamp:
        raise UsageError(f"--out: {partial} holds an unfinished learning test of other settings or individuals; "
                         f"remove it or choose another directory")
    done = {}
    for r in range(num_runs):
        path = os.path.join(partial, f"run_{r:03d}.npz")
        if os.path.exists(path):
            try:
                if limit is not None:
                    check_npz(path, "", limit)
                with np.load(path) as data:
                    done[r] = (data["reaches"], data["selections"])
            except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile) as error:  # RunDirError: a ValueError
                warn(f"warning: {path} cannot be read ({type(error).__name__}); run {r} is tested again")
    return done


def start_partial(partial: str, stamp: str, command: str, key: str | None = None) -> None:
    """Make ``partial`` and record in its ``spec.json`` the fingerprint (and command) of the runs it will keep, and
    a test from scratch's key (``runspec.test_key``: the studies find it by that while it runs)."""
    os.makedirs(partial, exist_ok=True)
    spec = dict(fingerprint=stamp, command=command, **({} if key is None else dict(key=key)))
    write_atomic(os.path.join(partial, "spec.json"), json.dumps(spec).encode())


def keep_run(partial: str, run: int, reaches: np.ndarray, selections: np.ndarray) -> None:
    """Keep a finished run's curves in ``partial/run_RRR.npz``."""
    write_atomic(os.path.join(partial, f"run_{run:03d}.npz"), _curves_npz(reaches, selections))


def _curves_npz(reaches: np.ndarray, selections: np.ndarray) -> bytes:
    buffer = io.BytesIO()
    np.savez_compressed(buffer, reaches=reaches.astype(np.int32), selections=selections.astype(np.int32))
    return buffer.getvalue()


# ----------------------------------------------------------------------------- --out


#: The longest name of a file or folder (Linux's NAME_MAX): a longer --out could not be made.
NAME_MAX = 255
#: What else an unfinished test's ``--out`` may hold: its progress for TensorBoard (``--log tensorboard``).
TEST_FOLDERS = ("tensorboard",)


def _kept_run(name: str) -> bool:
    """Whether an entry of ``partial/`` is one a test keeps there (or a temporary file of one)."""
    stem = name.split(".tmp-")[0]
    return is_output(name, ("spec.json",)) or (stem.startswith("run_") and stem.endswith(".npz")
                                                  and stem[4:-4].isdigit())


def check_out_dir(out_dir: str) -> None:
    """Refuse an ``--out`` that is neither new, nor empty, nor an unfinished learning test (raises a user error)."""
    if os.path.exists(out_dir) and not os.path.isdir(out_dir):
        raise UsageError(f"--out: {out_dir} is not a directory")
    if os.path.exists(os.path.join(out_dir, "steady.json")):
        raise UsageError(f"--out: {out_dir} already holds a learning test; choose another directory")
    found = entries(out_dir)
    if not found:
        return
    partial = os.path.join(out_dir, PARTIAL)
    kept = os.listdir(partial) if os.path.isdir(partial) and not os.path.islink(partial) else None
    unfinished = kept is not None and ("spec.json" in kept or not kept)
    # An interrupted test may also have written some outputs (and a temporary file) before steady.json.
    others = [name for name in found if name != PARTIAL and not is_output(name, OUTPUTS)
              and not (name in TEST_FOLDERS and os.path.isdir(os.path.join(out_dir, name)))]
    others += [os.path.join(PARTIAL, name) for name in kept or [] if not _kept_run(name)]
    if not unfinished or others:
        raise not_empty(out_dir, "unfinished learning test", others or found)


def check_out_before(out_dir: str) -> None:
    """Every check of ``--out`` before the test is carried out: writable, unlocked, new, empty or an unfinished test;
    nothing is written (``--log``'s folder: ``events.check_log``)."""
    too_long = [part for part in out_dir.split(os.sep) if len(os.fsencode(part)) > NAME_MAX]
    if too_long:
        raise UsageError(f"--out: the name {too_long[0][:40]}... is longer than {NAME_MAX} bytes")
    check_writable(out_dir)
    check_unlocked(out_dir)
    check_out_dir(out_dir)


@contextlib.contextmanager
def locked_out_dir(out_dir: str) -> Iterator[None]:
    """Hold ``out_dir`` (:func:`imrl_jax.runs.rundir.lock_run_dir`) once it is checked and made; the checks raise user errors."""
    check_out_before(out_dir)  # before the directory is made or locked: nothing is written into another's
    make_dir(out_dir)
    with lock_run_dir(out_dir):
        check_out_dir(out_dir)  # again, locked: another test may have written there in between
        yield


@contextlib.contextmanager
def write_errors(out_dir: str) -> Iterator[None]:
    """Report a failed write the user can fix (a full disk, an unwritable file) as a one-line RunWriteError."""
    try:
        yield
    except OSError as error:
        if write_errno(error) is None:
            raise
        raise RunWriteError(f"cannot write {error.filename or out_dir} ({error.strerror}); free space or fix "
                            f"permissions, then run the same command again (the finished runs are kept in "
                            f"{os.path.join(out_dir, PARTIAL)})") from None


# ----------------------------------------------------------------------------- outputs


def curve_csv(curve: np.ndarray, bin_steps: int) -> str:
    """Performance per bin from each run's mean ``curve`` (runs, bins): the mean, its sd over runs, each run's."""
    lines = ["bin,end_step,mean,sd_over_runs," + ",".join(f"run_{r}" for r in range(curve.shape[0]))]
    for b in range(curve.shape[1]):
        lines.append(f"{b},{(b + 1) * bin_steps},{curve[:, b].mean():.5f},{curve[:, b].std():.5f},"
                     + ",".join(f"{v:.5f}" for v in curve[:, b]))
    return "\n".join(lines) + "\n"


def write_outputs(out_dir: str, config: Config, reaches: np.ndarray, selections: np.ndarray, curve: np.ndarray,
                  summary: dict) -> None:
    """Write a finished test's outputs from its counts and performance ``curve`` (both (runs, best, tests, tasks,
    bins)) and ``summary``; steady.json last (it marks the test finished), then remove ``partial/``."""
    from imrl_jax.analysis.charts import plot_learning_test
    from imrl_jax.analysis.plotting import save

    write_atomic(os.path.join(out_dir, "curves.npz"), _curves_npz(reaches, selections))
    write_atomic(os.path.join(out_dir, "curve.csv"),
                 curve_csv(curve.mean((1, 2, 3)), config.task_steps // config.num_bins).encode())
    save(plot_learning_test(config, curve), os.path.join(out_dir, "learning_curve.png"))
    write_atomic(os.path.join(out_dir, "steady.json"), json.dumps(summary, indent=2).encode())  # marks completion
    shutil.rmtree(os.path.join(out_dir, PARTIAL))  # curves.npz now holds every run
