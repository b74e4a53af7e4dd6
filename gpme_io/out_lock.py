"""Output directories: whether a path can be one (checked before any work, creating nothing),
and one writer per output directory: a lock on <dir>/.gpme.lock held while a command writes
there, so two runs never interleave their files in one place.

The lock is filelock's FileLock (a well-kept, portable library: flock on POSIX, msvcrt on
Windows, instead of the fcntl-only lock this module had), taken without waiting; the
operating system releases it when the process ends, however it ends (no stale lock after a
kill).  The holder (pid, host, start time) is written beside it in <dir>/.gpme.lock.holder
for the message of the one refused (not into the lock file itself: a refused FileLock may
truncate it).  Whoever takes the lock removes the temporary files (``.*.tmp``,
gpme_io.atomic) that a killed writer left at the top of the directory.

The holder removes both files when it is done, so a finished run leaves no ``.gpme.lock``
in the user's folder.  Removing a lock file is safe only with a check on the taker's side,
which this module adds to filelock's: a process that opened the file just before the holder
removed it can lock the removed file once the holder lets go, while a third process creates
and locks a new one; so whoever takes the lock checks that the path still names the file it
locked (same inode) and otherwise lets go and takes the new one.  (The check reads
filelock's open descriptor, ``_context.lock_file_fd``, stable across filelock 3 and 4; when
it is not there, or on Windows where an open file cannot be removed, the files stay as
before.)  A killed holder still leaves them: the operating system releases the lock, and the
next run takes it and removes them when it finishes."""
import contextlib
import json
import os
import socket
import tempfile
import time
from pathlib import Path

from filelock import FileLock, Timeout

from gpme_core.errors import GpmeError

LOCK_NAME = ".gpme.lock"
HOLDER_NAME = ".gpme.lock.holder"


class OutputBusyError(GpmeError):
    """Another gpme process is writing to the same output directory."""


def _busy_message(directory, flag):
    return (f"{flag} {str(directory)!r} is being written by another gpme run "
            f"({_holder(Path(directory) / HOLDER_NAME)}); wait for it to finish or give "
            f"another {flag}")


def _lock(path):
    """A FileLock on ``path`` that one process cannot take twice (not reentrant: a second
    writer in the same process is refused like one in another)."""
    # the lock file stays (deleting it on release races with a process that opened it);
    # no soft fallback (a bare lock file left by a killed process would block every run)
    return FileLock(str(path), timeout=0, is_singleton=False, thread_local=False,
                    preserve_lock_file=True, fallback_to_soft=False)


# takes of a lock that turned out to be on a removed file before giving up (each means
# that another holder finished in between: more than a few is not a race but a bug)
MAX_TAKES = 5


def _locked_inode(lock):
    """The inode of the file ``lock`` holds, or None when filelock does not say."""
    fd = getattr(getattr(lock, "_context", None), "lock_file_fd", None)
    try:
        return os.fstat(fd).st_ino if isinstance(fd, int) else None
    except OSError:
        return None


def _names_file(path, inode):
    """Whether ``path`` is (still) the file of ``inode``."""
    try:
        return os.stat(path).st_ino == inode
    except OSError:
        return False


def _take(path, directory, flag):
    """(the FileLock held, the inode it holds or None): taken without waiting; retaken when
    the file it locked was removed by a holder that finished in between."""
    for _ in range(MAX_TAKES):
        lock = _lock(path)
        try:
            lock.acquire(timeout=0)
        except Timeout:
            raise OutputBusyError(_busy_message(directory, flag)) from None
        inode = _locked_inode(lock)
        if inode is None or _names_file(path, inode):
            return lock, inode
        lock.release()                  # a removed file: the path has a new one now
    raise OutputBusyError(f"{flag} {str(directory)!r}: its lock file was replaced {MAX_TAKES} "
                          "times while being taken; another gpme run is starting and "
                          "finishing there, try again")


@contextlib.contextmanager
def exclusive_output(directory, flag="--out"):
    """Hold the lock of ``directory`` (made if missing) for the ``with`` block; raises
    OutputBusyError naming the holder when another process holds it.  The lock and holder
    files are removed when the block ends (see the module docstring)."""
    path = Path(directory) / LOCK_NAME
    path.parent.mkdir(parents=True, exist_ok=True)
    lock, inode = _take(path, directory, flag)
    try:
        for stale in Path(directory).glob(".*.tmp"):      # gpme_io.atomic's temporary
            stale.unlink(missing_ok=True)   # files of a killed writer: no writer is alive now
        _write_holder(Path(directory) / HOLDER_NAME)
        yield
    finally:
        if inode is not None:           # removed while still held: see the docstring
            for name in (HOLDER_NAME, LOCK_NAME):
                with contextlib.suppress(OSError):
                    (Path(directory) / name).unlink(missing_ok=True)
        lock.release()


def _write_holder(path):
    """The holder's pid, host and start time, for the message of a refused writer; best
    effort (on a full disk the run's own writes say what failed)."""
    try:
        path.write_text(json.dumps({"pid": os.getpid(), "host": socket.gethostname(),
                                    "started": time.strftime("%Y-%m-%d %H:%M:%S")}))
    except OSError:
        pass


def busy_problem(directory, flag="--out"):
    """The message of :class:`OutputBusyError` when another process holds ``directory``'s
    lock now, else None; creates nothing (a check made before any work, e.g. a sweep's
    cost estimate; :func:`exclusive_output` still takes the lock for the writing)."""
    path = Path(directory) / LOCK_NAME
    if not path.is_file():
        return None
    lock = _lock(path)
    try:
        lock.acquire(timeout=0)
    except Timeout:
        return _busy_message(directory, flag)
    except OSError:
        return None                   # unreadable: exclusive_output will say
    lock.release()
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
