"""Output directories: whether a path can be one (checked before any work, creating nothing),
and one writer per output directory: an advisory lock (fcntl.flock on <dir>/.gpme.lock) held
while a command writes there, so two runs never interleave their files in one place.  The
operating system releases it when the process ends, however it ends (no stale lock after a
kill); the lock file names the holder for the message of the one refused.  Whoever takes
the lock removes the temporary files (``.*.tmp``, gpme_io.atomic) that a killed writer
left at the top of the directory."""
import contextlib
import json
import os
import socket
import time
from pathlib import Path

from gpme_core.errors import GpmeError

LOCK_NAME = ".gpme.lock"


class OutputBusyError(GpmeError):
    """Another gpme process is writing to the same output directory."""


@contextlib.contextmanager
def exclusive_output(directory, flag="--out"):
    """Hold the lock of ``directory`` (made if missing) for the ``with`` block; raises
    OutputBusyError naming the holder when another process holds it."""
    import fcntl
    path = Path(directory) / LOCK_NAME
    path.parent.mkdir(parents=True, exist_ok=True)
    fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = _holder(path)
            raise OutputBusyError(
                f"{flag} {str(directory)!r} is being written by another gpme run ({holder}); "
                f"wait for it to finish or give another {flag}") from None
        for stale in Path(directory).glob(".*.tmp"):      # gpme_io.atomic's temporary
            stale.unlink(missing_ok=True)   # files of a killed writer: no writer is alive now
        os.ftruncate(fd, 0)
        os.write(fd, json.dumps({"pid": os.getpid(), "host": socket.gethostname(),
                                 "started": time.strftime("%Y-%m-%d %H:%M:%S")}).encode())
        yield
    finally:
        os.close(fd)        # releases the lock


def busy_problem(directory, flag="--out"):
    """The message of :class:`OutputBusyError` when another process holds ``directory``'s
    lock now, else None; creates nothing (a check made before any work, e.g. a sweep's
    cost estimate; :func:`exclusive_output` still takes the lock for the writing)."""
    import fcntl
    path = Path(directory) / LOCK_NAME
    try:
        fd = os.open(path, os.O_RDWR)
    except OSError:
        return None                   # no lock file (or unreadable: exclusive_output says)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        return (f"{flag} {str(directory)!r} is being written by another gpme run "
                f"({_holder(path)}); wait for it to finish or give another {flag}")
    finally:
        os.close(fd)                  # releases the lock if it was taken
    return None


def _holder(path):
    try:
        info = json.loads(path.read_text())
        return f"pid {info['pid']} on {info['host']}, started {info['started']}"
    except (OSError, ValueError, KeyError, TypeError):
        return "holder unknown"


def output_dir_problem(path, flag="--out", example="reports"):
    """Why ``path`` cannot be an output directory (None when it can), found before any work
    and without creating anything: an empty name, an existing file, a file on the way, a
    folder that cannot be written (a temporary file is tried in it or in the nearest
    existing folder above it)."""
    text = str(path)
    if not text.strip():
        return f"{flag} is empty; give a directory (e.g. {flag} {example})"
    target = Path(text)
    if target.exists() and not target.is_dir():
        return f"{flag} {text!r} exists and is not a directory; give a directory"
    return _unwritable(target, text, flag, "directory")


def output_file_problem(path, flag, example):
    """Why ``path`` cannot be written as the output file of ``flag`` (None when it can),
    found before any work and without creating anything."""
    text = str(path)
    if not text.strip():
        return f"{flag} is empty; give a file name (e.g. {flag} {example})"
    target = Path(text)
    if target.is_dir():
        return (f"{flag} {text!r} is a directory; give a file name (e.g. {flag} "
                f"{target / example})")
    return _unwritable(target.parent, text, flag, "folder")


def _unwritable(directory, text, flag, what):
    """Why ``directory`` (or the nearest existing folder above it) cannot take a new file:
    a file on the way, or no write permission (None when it can)."""
    import tempfile
    probe = directory
    while not probe.exists() and probe != probe.parent:
        probe = probe.parent
    if not probe.is_dir():
        return f"{flag} {text!r} cannot be created: {str(probe)!r} on its way is a file"
    try:
        with tempfile.TemporaryFile(dir=probe):
            pass
    except OSError as exc:
        where = "written" if probe == Path(text) else f"created in {str(probe)!r}"
        return f"{flag} {text!r} cannot be {where} ({exc.strerror or exc}); give a " \
               f"{what} you can write"
    return None
