"""One writer per output directory: an advisory lock (fcntl.flock on <dir>/.gpme.lock) held
while a command writes there, so two runs never interleave their files in one place.  The
operating system releases it when the process ends, however it ends (no stale lock after a
kill); the lock file names the holder for the message of the one refused.  Whoever takes
the lock removes the temporary files (``.*.tmp``, gpme_core.atomic) that a killed writer
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
        for stale in Path(directory).glob(".*.tmp"):      # gpme_core.atomic's temporary
            stale.unlink(missing_ok=True)   # files of a killed writer: no writer is alive now
        os.ftruncate(fd, 0)
        os.write(fd, json.dumps({"pid": os.getpid(), "host": socket.gethostname(),
                                 "started": time.strftime("%Y-%m-%d %H:%M:%S")}).encode())
        yield
    finally:
        os.close(fd)        # releases the lock


def _holder(path):
    try:
        info = json.loads(path.read_text())
        return f"pid {info['pid']} on {info['host']}, started {info['started']}"
    except (OSError, ValueError, KeyError, TypeError):
        return "holder unknown"
