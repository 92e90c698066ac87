"""Run directories and output files: reading an evolution's run, checking and writing outputs atomically, one writer."""

from __future__ import annotations

import contextlib
import csv
import errno
import io
import json
import os
import re
import socket
import sys
import tempfile
import time
import zipfile
from typing import Callable, Iterator, NamedTuple

import numpy as np

from imrl_jax import files
from imrl_jax.config import Config, ConfigError


class RunDirError(ValueError):
    """A run directory (or output path) that cannot be read or written; the message names it."""


class RunWriteError(Exception):
    """Writing a run's files failed mid-run (a full disk, an unwritable file): one line, exit code 1."""


#: Errors of writing that the user fixes (space, permissions, a read-only mount): reported as one line.
WRITE_ERRNOS = frozenset({errno.ENOSPC, errno.EDQUOT, errno.EACCES, errno.EPERM, errno.EROFS})


def write_errno(error: BaseException) -> int | None:
    """The errno of a failed write that the user can fix (:data:`WRITE_ERRNOS`), or None.

    orbax reports the OS error of a failed checkpoint inside the text of a ValueError
    (tensorstore's ``[os_error_code='28']``), so the text is read too.
    """
    code = error.errno if isinstance(error, OSError) else None
    if code is None:
        found = re.search(r"os_error_code='?(\d+)", str(error))
        code = int(found.group(1)) if found else None
    return code if code in WRITE_ERRNOS else None


class Run(NamedTuple):
    """What a run directory of ``python -m imrl_jax.evolve`` holds about its last evaluated generation."""

    config: Config
    seeds: list[int]
    generation: int  # generations evaluated
    evaluated: np.ndarray  # (seeds, population, genes) the last evaluated populations
    fitness: np.ndarray  # (seeds, population) their fitness


#: The largest JSON file a command reads (a run's config.json, a lock, a task set, a test's spec.json): 1 MiB.
MAX_JSON_BYTES = 2**20
#: The largest .npz of best genomes a report keeps that a command reads (its arrays uncompressed).
MAX_KEPT_BEST_BYTES = 2**28


_named = files.named  # the same wording as a file read there

def read_text(path: str, what: str, limit: int = MAX_JSON_BYTES, error: type[Exception] = None) -> str:
    """:func:`imrl_jax.files.read_text`, raising RunDirError unless told another ``error``."""
    return files.read_text(path, what, limit, error or RunDirError)


def parse_json(text: str, what: str, path: str, error: type[Exception] = None):
    """``text`` parsed as JSON (raises ``error``, default RunDirError, in one line naming ``what`` and the file)."""
    error = error or RunDirError
    try:
        return json.loads(text)
    except RecursionError:
        raise error(f"{_named(what)}{path} is not JSON (nested too deeply)") from None
    except ValueError as failure:  # a JSONDecodeError, or a number of more digits than int() takes
        where = f"{failure.msg}, line {failure.lineno}" if isinstance(failure, json.JSONDecodeError) else \
            str(failure).split(";")[0]
        raise error(f"{_named(what)}{path} is not JSON ({where})") from None


def read_json(path: str, what: str, limit: int = MAX_JSON_BYTES, error: type[Exception] = None):
    """A JSON file read safely (:func:`read_text`, :func:`parse_json`)."""
    return parse_json(read_text(path, what, limit, error), what, path, error)


def check_npz(path: str, what: str, limit: int) -> None:
    """Raise RunDirError naming ``what`` unless ``path`` is an .npz whose arrays take at most ``limit`` bytes
    uncompressed (checked before any is read: a file of other data is refused, not unpickled or decompressed)."""
    try:
        with zipfile.ZipFile(path) as archive:
            size = sum(info.file_size for info in archive.infolist())
    except (OSError, zipfile.BadZipFile, ValueError) as failure:
        reason = getattr(failure, "strerror", None) or "not an .npz file of arrays"
        raise RunDirError(f"{_named(what)}{path} is unreadable ({reason})") from None
    if size > limit:
        raise RunDirError(f"{_named(what)}{path} holds {size:,} bytes of arrays, above the limit of {limit:,} (is it the "
                          f"right file?)")


def write_atomic(path: str, data: bytes) -> None:
    """Write ``data`` to ``path`` through a temporary file, so a reader never sees half of it (none is left on failure)."""
    tmp = f"{path}.tmp-{os.getpid()}"
    try:
        with open(tmp, "wb") as f:
            f.write(data)
        os.replace(tmp, path)
    except OSError as error:
        with contextlib.suppress(OSError):
            os.remove(tmp)
        # A failed write() names no file and a failed open() the temporary one: name the file being written.
        raise OSError(error.errno, error.strerror, path) from error


def csv_bytes(rows: list[dict]) -> bytes:
    """Rows as the bytes of a CSV file: a header of the first row's fields, then a line per row."""
    out = io.StringIO()
    writer = csv.DictWriter(out, list(rows[0]), lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    return out.getvalue().encode()


def check_writable(path: str, flag: str = "--out") -> None:
    """Raise RunDirError naming ``flag`` unless ``path`` (a directory, existing or not) can be written in.

    Nothing is created: the nearest existing folder on the path is probed with a temporary file.
    """
    folder = os.path.abspath(path)
    while not os.path.exists(folder):
        folder = os.path.dirname(folder)
    if not os.path.isdir(folder):
        raise RunDirError(f"{flag}: cannot write to {path} ({folder} is not a directory)")
    try:
        with tempfile.TemporaryFile(dir=folder):
            pass
    except OSError as error:
        raise RunDirError(f"{flag}: cannot write to {path} ({folder}: {error.strerror or error})") from None


def is_output(name: str, outputs: tuple[str, ...]) -> bool:
    """Whether a directory entry is one of ``outputs`` or a temporary file an interrupted write of one left."""
    # write_atomic leaves ``x.tmp-PID``; matplotlib's save, ``.x.tmp-PID.png``
    return any(name == out or name.startswith(f"{out}.tmp-") or name.startswith(f".{os.path.splitext(out)[0]}.tmp-")
               for out in outputs)


def not_empty(path: str, kind: str, found: list[str], missing: str = "") -> RunDirError:
    """The refusal of an ``--out`` holding ``found``, none of it a ``kind`` (``missing``: the file that would say so)."""
    shown = ", ".join(found[:3]) + (", ..." if len(found) > 3 else "")
    why = f"no {missing}; " if missing else ""
    return RunDirError(f"--out: {path} is not empty and holds no {kind} ({why}it holds {shown}); choose a new or empty "
                       f"directory")


def make_dir(path: str) -> None:
    """Create the ``--out`` directory ``path`` if it is new (raises RunDirError naming it)."""
    try:
        os.makedirs(path, exist_ok=True)
    except OSError as error:
        raise RunDirError(f"--out: cannot create {path} ({error.strerror or error})") from None


def check_outputs_dir(path: str, outputs: tuple[str, ...], kind: str, overwrite: bool = False) -> None:
    """Refuse (RunDirError) an output directory holding anything but a ``kind``'s ``outputs``, or those without ``overwrite``."""
    found = entries(path)
    ours = [name for name in found if is_output(name, outputs)]
    others = [name for name in found if name not in ours]
    if others:
        raise not_empty(path, kind, others)
    if ours and not overwrite:
        raise RunDirError(f"--out: {path} already holds a {kind} (pass --overwrite to replace it)")


def read_config(run_dir: str) -> tuple[Config, list[int]]:
    """The config and seeds recorded in a run's ``config.json`` (raises RunDirError naming the file)."""
    path = os.path.join(run_dir, "config.json")
    saved = read_json(path, "")
    try:
        config, seeds = Config.from_dict(saved["config"]), [int(s) for s in saved["seeds"]]
    except ConfigError as error:
        if error.field == "condition":  # a row of one's own, not registered in this process
            made_with = " ".join(f"--register {spec}" for spec in saved.get("register", [])) or \
                "--register MODULE:ATTRIBUTE naming its row"
            raise RunDirError(f"{path}: condition {saved['config']['condition']!r} is not a row of the condition table; "
                              f"add it with {made_with}") from None
        raise RunDirError(f"{path} is unreadable ({error})") from None
    except (ValueError, KeyError, TypeError) as error:
        raise RunDirError(f"{path} is unreadable ({error})") from None
    if config.world != "arena":  # a world, its settings and sizes that belong together (a damaged file's may not)
        from imrl_jax.world.worlds import world_of

        try:
            world_of(config)
        except ConfigError as error:
            raise RunDirError(f"{path} is unreadable ({error})") from None
    return config, seeds


def load_run(run_dir: str) -> Run:
    """A run directory's config, seeds and last evaluated generation (raises RunDirError naming the file)."""
    if not os.path.isdir(run_dir):
        raise RunDirError(f"run_dir: {run_dir!r} is not a directory (give an evolution's run directory)")
    for name in ("config.json", "final_population.npz"):
        if not os.path.isfile(os.path.join(run_dir, name)):
            raise RunDirError(f"{os.path.join(run_dir, name)}: not found (is {run_dir} a run of "
                             f"python -m imrl_jax.evolve?)")
    config, seeds = read_config(run_dir)
    path = os.path.join(run_dir, "final_population.npz")
    lanes = len(seeds) * config.population_size
    check_npz(path, "", 4 * lanes * (2 * config.num_genes + 1) + 8 * len(seeds) + 2**16)  # + headers
    try:
        with np.load(path) as data:
            generation, evaluated, fitness = int(data["generation"]), data["evaluated"], data["fitness"]
    except (OSError, ValueError, KeyError, TypeError) as error:  # TypeError: a generation that is not one number
        raise RunDirError(f"{path} is unreadable ({error})") from None
    if generation < 1:
        raise RunDirError(f"{path}: no generation has been evaluated yet")
    if evaluated.shape[:2] != fitness.shape or fitness.shape[0] != len(seeds) or evaluated.ndim != 3:
        raise RunDirError(f"{path}: arrays do not match the {len(seeds)} seed(s) of config.json")
    if evaluated.shape[1:] != (config.population_size, config.num_genes):
        raise RunDirError(f"{path}: its population is {evaluated.shape[1]} genomes of {evaluated.shape[2]} genes, "
                          f"config.json's {config.population_size} of {config.num_genes}")
    if not (np.isfinite(fitness).all() and np.isfinite(evaluated).all()):  # the best would be arbitrary
        raise RunDirError(f"{path}: its fitness or genomes hold NaN or infinite values")
    return Run(config, seeds, generation, evaluated, fitness)


class KeptBest(NamedTuple):
    """The best genomes of one run that a report keeps in its ``best_genomes.npz``."""

    genomes: np.ndarray  # (seeds, best, genes) fittest first
    seeds: list[int]
    fitness: np.ndarray | None  # (seeds, best) their fitness, where the file keeps it


def read_kept_best(path: str, variant: str, condition: str) -> KeptBest:
    """The best genomes a report's ``best_genomes.npz`` keeps of its ``variant``'s ``condition`` run, under
    ``VARIANT__CONDITION__genomes`` (``__seeds``, ``__fitness``) (raises RunDirError naming the file)."""
    check_npz(path, "--best-genomes", MAX_KEPT_BEST_BYTES)
    try:
        with np.load(path) as kept:
            arrays = {name: kept[name] for name in kept.files}
    except (OSError, ValueError) as error:
        raise RunDirError(f"--best-genomes: {path} is unreadable ({error})") from None
    key = f"{variant}__{condition}"
    if f"{key}__genomes" not in arrays:
        found = sorted({name.rsplit("__", 1)[0].replace("__", "/") for name in arrays})
        raise RunDirError(f"--best-genomes: {path} holds no {variant}/{condition} (it holds {', '.join(found)})")
    if f"{key}__seeds" not in arrays:
        raise RunDirError(f"--best-genomes: {path} holds no {key}__seeds beside {key}__genomes")
    genomes, fitness = arrays[f"{key}__genomes"], arrays.get(f"{key}__fitness")
    try:
        seeds = [int(s) for s in np.asarray(arrays[f"{key}__seeds"]).reshape(-1)]
    except (TypeError, ValueError) as error:
        raise RunDirError(f"--best-genomes: {path}: {key}__seeds are not integers ({error})") from None
    if genomes.ndim != 3 or genomes.shape[0] != len(seeds) or not np.isfinite(genomes).all():
        raise RunDirError(f"--best-genomes: {path}: {key}__genomes is not (seeds, best, genes) of finite values for "
                          f"its {len(seeds)} seed(s)")
    return KeptBest(genomes, seeds, fitness)


def load_kept_best(run_dir: str, path: str, num_best: int) -> tuple[Config, list[int], np.ndarray]:
    """A run's config and the ``num_best`` best genomes of each seed kept in a report's ``best_genomes.npz``
    (for a run whose final population was not kept); its key is the run's ``VARIANT/evolve/CONDITION`` path."""
    config, _ = read_config(run_dir)
    variant = os.path.basename(os.path.dirname(os.path.dirname(os.path.abspath(run_dir))))
    genomes, seeds, _ = read_kept_best(path, variant, config.condition)
    if not 1 <= num_best <= genomes.shape[1]:
        raise RunDirError(f"--best: must be between 1 and the {genomes.shape[1]} kept in {path}")
    if genomes.shape[-1] != config.num_genes:
        raise RunDirError(f"--best-genomes: {variant}__{config.condition} has {genomes.shape[-1]} genes, the run's "
                          f"config {config.num_genes}")
    return config, seeds, genomes[:, :num_best]


def best_genomes(run: Run, num_best: int) -> np.ndarray:
    """The ``num_best`` fittest genomes of each seed, fittest first: (seeds, num_best, genes)."""
    if not 1 <= num_best <= run.evaluated.shape[1]:
        raise RunDirError(f"--best: must be between 1 and the population size {run.evaluated.shape[1]}")
    order = np.argsort(-run.fitness, axis=1, kind="stable")[:, :num_best]
    return np.take_along_axis(run.evaluated, order[:, :, None], axis=1)


# ----------------------------------------------------------------------------- one writer per directory

#: The file in a run directory that names the process writing it.
LOCK = ".lock"


class LockHolder(NamedTuple):
    """The process a lock file names."""

    pid: int
    host: str
    start: int  # the process's start time (clock ticks after boot, /proc), 0 where unknown: tells a reused pid


class ProcStat(NamedTuple):
    """What /proc tells of a process."""

    state: str  # its state letter ("Z": killed but not yet reaped)
    start: int  # its start time (clock ticks after boot)


def _proc_stat(pid: int) -> ProcStat | None:
    """A process's state letter and start time from /proc (None off Linux or if it is gone)."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()  # the name before ")" may hold spaces
        return ProcStat(fields[0], int(fields[19]))
    except (OSError, IndexError, ValueError):
        return None


def _me() -> LockHolder:
    stat = _proc_stat(os.getpid())
    return LockHolder(os.getpid(), socket.gethostname(), stat.start if stat else 0)


def read_lock(path: str, tries: int = 20) -> LockHolder | None:
    """The holder a lock file names; None if it is gone or unreadable (waits a little for one being written)."""
    for attempt in range(tries):
        try:
            with open(path, "rb") as f:
                info = json.loads(f.read(MAX_JSON_BYTES).decode("utf-8"))
            return LockHolder(int(info["pid"]), str(info["host"]), int(info.get("start", 0)))
        except FileNotFoundError:
            return None
        except (OSError, ValueError, KeyError, TypeError, RecursionError):
            time.sleep(0.05)  # created but not yet written: its writer is between open() and write()
    return None


def holder_alive(holder: LockHolder) -> bool | None:
    """Whether the holder still runs: None where that cannot be told (another host)."""
    if holder.host != socket.gethostname():
        return None
    try:
        os.kill(holder.pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        pass  # another user's process: it exists
    stat = _proc_stat(holder.pid)
    if stat is not None and (stat.state == "Z" or (holder.start and stat.start != holder.start)):
        return False  # killed but not yet reaped, or the pid now belongs to a later process
    return True


def _refusal(path: str, holder: LockHolder) -> RunDirError:
    where = f"pid {holder.pid} on {holder.host}"
    if holder_alive(holder) is None:
        return RunDirError(f"--out: {path} is being written by {where} (another host; if nothing writes there any "
                           f"more, remove {os.path.join(path, LOCK)})")
    return RunDirError(f"--out: {path} is being written by {where}; wait for it to end or stop it")


def check_unlocked(path: str) -> None:
    """Raise RunDirError naming the live process that holds ``path``'s lock, if one does (nothing is written)."""
    holder = read_lock(os.path.join(path, LOCK))
    if holder is not None and holder != _me() and holder_alive(holder) is not False:
        raise _refusal(path, holder)


def unfinished(run_dir: str, run: Run) -> str:
    """Why ``run`` is not a finished evolution ("" if it is): generations left, or a live writer."""
    holder = read_lock(os.path.join(run_dir, LOCK))
    writing = holder is not None and holder_alive(holder) is not False
    if run.generation >= run.config.num_generations and not writing:
        return ""
    return (f"{run_dir} has {run.generation} of its {run.config.num_generations} generations evaluated"
            + (f" and is being written by pid {holder.pid} on {holder.host}" if writing else ""))


@contextlib.contextmanager
def lock_run_dir(path: str, say: Callable[[str], None] | None = None) -> Iterator[None]:
    """Hold ``path/.lock`` (pid and host, as JSON) while the block runs, so that a directory has one writer.

    The lock is created with O_CREAT | O_EXCL (atomic) and removed at the end, on errors and
    Ctrl-C too. A live holder is refused (RunDirError naming it); the lock of a process that
    no longer runs on this host is taken over, said through ``say`` (default: stderr).
    """
    say = say or (lambda text: print(text, file=sys.stderr, flush=True))
    lock, me = os.path.join(path, LOCK), _me()
    for attempt in range(5):
        try:
            fd = os.open(lock, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
        except FileExistsError:
            holder = read_lock(lock)
            if holder is not None and holder_alive(holder) is not False:
                raise _refusal(path, holder) from None
            # Stale: moved aside, not removed, so that of two processes taking it over only one succeeds.
            aside = f"{lock}.stale-{os.getpid()}"
            try:
                os.rename(lock, aside)
            except FileNotFoundError:
                continue
            if read_lock(aside, tries=1) != holder:  # a fresh lock of a third process: put it back
                with contextlib.suppress(OSError):
                    os.link(aside, lock)
            else:
                name = f"pid {holder.pid} on {holder.host}" if holder else "an unreadable lock"
                say(f"warning: {lock}: took over the stale lock of {name} (no longer running)")
            with contextlib.suppress(OSError):
                os.remove(aside)
            continue
        except OSError as error:
            raise RunDirError(f"--out: cannot create {lock} ({error.strerror or error})") from None
        try:
            with os.fdopen(fd, "w") as f:
                json.dump(dict(me._asdict(), since=time.strftime("%Y-%m-%dT%H:%M:%S%z")), f)
        except OSError as error:
            with contextlib.suppress(OSError):
                os.remove(lock)
            raise RunDirError(f"--out: cannot write {lock} ({error.strerror or error})") from None
        break
    else:
        raise RunDirError(f"--out: cannot take {lock} (other processes keep taking it)")
    try:
        yield
    finally:
        if read_lock(lock, tries=1) == me:
            with contextlib.suppress(OSError):
                os.remove(lock)


#: A sweep's own record in its directory (``evolve --sweep``; each point is a run directory beside it).
SWEEP_FILE = "sweep.json"


def is_sweep(out_dir: str) -> bool:
    """Whether ``out_dir`` holds a sweep (its sweep.json)."""
    return os.path.isfile(os.path.join(out_dir, SWEEP_FILE))


def recorded_points(out_dir: str) -> list[tuple[str, dict]] | None:
    """Each point's key and settings as the sweep in ``out_dir`` records them (its directory is ``out_dir/KEY``),
    or None if ``out_dir`` holds no sweep (raises RunDirError naming an unreadable sweep.json)."""
    if not is_sweep(out_dir):
        return None
    path = os.path.join(out_dir, SWEEP_FILE)
    try:
        return [(str(p["key"]), dict(p["settings"])) for p in read_json(path, "")["points"]]
    except (KeyError, TypeError, ValueError) as error:
        raise RunDirError(f"{path} is unreadable ({error})") from None


def sweep_points(run_dir: str) -> list[str] | None:
    """A sweep's point directories (``evolve --sweep``, in its order), or None if ``run_dir`` is not a sweep."""
    points = recorded_points(run_dir)
    return None if points is None else [os.path.join(run_dir, key) for key, _ in points]


def saved_steps(directory: str) -> list[int]:
    """The generations a checkpoints folder holds, oldest first, read from its folders' names (no orbax)."""
    return sorted(int(d) for d in os.listdir(directory) if d.isdigit()) if os.path.isdir(directory) else []


def entries(path: str) -> list[str]:
    """What a directory holds besides its lock and a stale lock set aside (nothing if it does not exist)."""
    if not os.path.isdir(path):
        return []
    return sorted(name for name in os.listdir(path) if name != LOCK and not name.startswith(f"{LOCK}.stale-"))
