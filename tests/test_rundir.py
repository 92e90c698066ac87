"""Run directories: one writer (the lock), stale locks, writes that fail cleanly."""

import errno
import json
import os
import socket
import subprocess

import pytest
from helpers import write_lock

from imrl_jax.runs import rundir
from imrl_jax.runs.rundir import LOCK, RunDirError, lock_run_dir


def _dead_pid() -> int:
    """The pid of a process that has ended (and been reaped)."""
    process = subprocess.Popen(["true"])
    process.wait()
    return process.pid


def test_the_lock_names_its_writer_and_goes_at_the_end_also_on_ctrl_c(tmp_path):
    with lock_run_dir(str(tmp_path)):
        with open(tmp_path / LOCK) as f:
            held = json.load(f)
        assert (held["pid"], held["host"]) == (os.getpid(), socket.gethostname())
        with pytest.raises(RunDirError, match=f"is being written by pid {os.getpid()} on {socket.gethostname()}"):
            with lock_run_dir(str(tmp_path)):
                pass
    assert os.listdir(tmp_path) == []
    with pytest.raises(KeyboardInterrupt):
        with lock_run_dir(str(tmp_path)):
            raise KeyboardInterrupt
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("holder", ["dead", "reused"])
def test_a_stale_lock_is_taken_over_with_one_line(tmp_path, holder):
    """Its process has ended, or its pid now belongs to a later process (another start time)."""
    pid, start = (_dead_pid(), 0) if holder == "dead" else (os.getpid(), 1)
    lock = write_lock(str(tmp_path), pid, start=start)
    said = []
    with lock_run_dir(str(tmp_path), say=said.append):
        with open(lock) as f:
            assert json.load(f)["pid"] == os.getpid()
    assert said == [f"warning: {lock}: took over the stale lock of pid {pid} on {socket.gethostname()} "
                    f"(no longer running)"]
    assert os.listdir(tmp_path) == []


def test_a_lock_of_another_host_is_refused_saying_how_to_clear_it(tmp_path):
    lock = write_lock(str(tmp_path), 1234, host="elsewhere")
    for check in (rundir.check_unlocked, lambda path: lock_run_dir(path).__enter__()):
        with pytest.raises(RunDirError) as error:
            check(str(tmp_path))
        assert str(error.value) == (f"--out: {tmp_path} is being written by pid 1234 on elsewhere (another host; "
                                    f"if nothing writes there any more, remove {lock})")
    assert os.listdir(tmp_path) == [LOCK]


def test_a_failed_write_leaves_no_temporary_file_and_names_the_file(tmp_path, monkeypatch):
    def full(source, destination):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(rundir.os, "replace", full)
    with pytest.raises(OSError) as error:
        rundir.write_atomic(str(tmp_path / "history.csv"), b"rows")
    assert (error.value.errno, error.value.filename) == (errno.ENOSPC, str(tmp_path / "history.csv"))
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("error, code", [
    (OSError(errno.ENOSPC, "No space left on device"), errno.ENOSPC),
    (PermissionError(errno.EACCES, "Permission denied"), errno.EACCES),
    (ValueError("RESOURCE_EXHAUSTED: Error writing local file \"x/manifest.ocdbt\": No space left on device "
                "[os_error_code='28']"), errno.ENOSPC),  # how orbax (tensorstore) reports it
    (OSError(errno.EIO, "Input/output error"), None),
    (ValueError("a bug"), None),
])
def test_write_errors_the_user_can_fix(error, code):
    assert rundir.write_errno(error) == code
