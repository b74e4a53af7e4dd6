"""Read an input file (model file, URDF, side file, sweep file) that nobody has checked.

`gpme verify` and `gpme simulate --model` run in CI on files that arrive in pull requests.
Before a byte is read, :func:`check_input_file` makes sure the path names a regular file
(a symlink to one is fine) no larger than the limit for its kind: a FIFO would block the
reader forever, /dev/zero would fill the memory, a 2 GB "URDF" is not a robot.  Then
:func:`read_input_file` reads it with a bounded read (at most limit + 1 bytes), so a file
that grows between the check and the read is still refused, not read whole.

Every refusal is one :class:`InputFileError` (a ModelFileError: exit status 2 on the
command line) naming the file, what it is (its size and the limit) and nothing else; its
``reason`` is the same text without the file's name, for callers that name it already.
"""
import os
import stat
from pathlib import Path
from typing import Optional

from gpme_core.errors import ModelFileError

# bytes.  A model file is a page of TOML (examples/ and models/ are below 5 kB); 1 MB is
# 200 times that, far beyond any hand-written file and small enough to parse at once.
MODEL_FILE_LIMIT = 1_000_000
# bytes.  Real URDFs, with inline meshes' names, materials and many links, are at most a few
# MB (example-robot-data's largest are ~0.5 MB); 50 MB leaves room for generated ones.
URDF_LIMIT = 50_000_000
# bytes.  A side file is a JSON record per joint, drive and RFEM link (~1 kB for the crane).
SIDE_FILE_LIMIT = 1_000_000
# bytes.  A sweep file (TOML or YAML) lists parameters and run settings (< 2 kB in tests/).
SWEEP_FILE_LIMIT = 1_000_000

# st_mode file type -> how the message names it
_KINDS = ((stat.S_ISDIR, "a directory"), (stat.S_ISFIFO, "a FIFO (named pipe)"),
          (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
          (stat.S_ISSOCK, "a socket"))


class InputFileError(ModelFileError):
    """An input file cannot be read: missing, not a regular file, or above its size limit.

    path   : the path as given
    reason : what is wrong, without the file's name ("is a directory, not a regular file")
    """

    def __init__(self, what: str, path, reason: str):
        self.path = Path(path)
        self.reason = reason
        super().__init__(f"{what} {str(path)!r} {reason}")


def size_text(n_bytes: int) -> str:
    """A size in bytes as text in decimal units: '812 bytes', '1 MB', '2.1 GB'."""
    for unit, scale in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n_bytes >= scale:
            return f"{n_bytes / scale:.3g} {unit}"
    return f"{n_bytes} byte" + ("" if n_bytes == 1 else "s")


def _too_large(what: str, size: int, limit_bytes: int) -> str:
    shown, limit = size_text(size), size_text(limit_bytes)
    if shown == limit:                     # just above the limit: the exact numbers differ
        shown, limit = f"{size:,} bytes", f"{limit_bytes:,} bytes"
    return f"is {shown}, above the limit of {limit} for a {what}"


def _kind_problem(mode: int) -> Optional[str]:
    if stat.S_ISREG(mode):
        return None
    kind = next((name for test, name in _KINDS if test(mode)), "not a regular file")
    return f"is {kind}, not a regular file" if kind != "not a regular file" else \
        "is not a regular file"


def _stat(what: str, path: Path) -> os.stat_result:
    """os.stat of ``path`` (through symlinks), InputFileError when it cannot be taken."""
    try:
        return os.stat(path)
    except FileNotFoundError as exc:
        raise InputFileError(what, path, f"does not exist ({exc.strerror})") from None
    except OSError as exc:
        raise InputFileError(what, path, f"cannot be read ({exc.strerror or exc})") from None


def check_input_file(path, what: str, limit_bytes: int) -> os.stat_result:
    """Refuse ``path`` unless it is a regular file of at most ``limit_bytes`` bytes; nothing
    is opened (a FIFO is never opened).

    path        : str or Path, relative to the current folder
    what        : the kind of file for the message ("model file", "URDF", "side file")
    limit_bytes : bytes, the largest size accepted

    Returns the os.stat_result of the file (symlinks followed); raises InputFileError.
    """
    st = _stat(what, Path(path))
    bad = _kind_problem(st.st_mode)
    if bad is None and st.st_size > limit_bytes:
        bad = _too_large(what, st.st_size, limit_bytes)
    if bad is not None:
        resolved = Path(path).resolve()
        if resolved != Path(path).absolute():
            bad += f" (the path resolves to {str(resolved)!r})"
        raise InputFileError(what, path, bad)
    return st


def read_input_file(path, what: str, limit_bytes: int) -> bytes:
    """The bytes of the regular file ``path`` (at most ``limit_bytes``), after
    :func:`check_input_file`.

    The file is opened non-blocking and checked again through the open descriptor (same
    file as the one checked, still regular), so a FIFO swapped in after the check neither
    blocks nor is read; at most limit_bytes + 1 bytes are read, so a file that grew past
    the limit is refused too.  Raises InputFileError.
    """
    path = Path(path)
    before = check_input_file(path, what, limit_bytes)
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
    except OSError as exc:
        raise InputFileError(what, path, f"cannot be read ({exc.strerror or exc})") from None
    with os.fdopen(fd, "rb") as fh:
        now = os.fstat(fh.fileno())
        if (now.st_dev, now.st_ino) != (before.st_dev, before.st_ino) or \
                not stat.S_ISREG(now.st_mode):
            raise InputFileError(what, path, "was replaced while it was being opened "
                                             "(it changed between the check and the read)")
        try:
            data = fh.read(limit_bytes + 1)
        except OSError as exc:
            raise InputFileError(what, path, f"cannot be read ({exc.strerror or exc})") \
                from None
    if len(data) > limit_bytes:
        raise InputFileError(what, path, _too_large(what, len(data), limit_bytes)
                             .replace("is ", "grew to at least ", 1))
    return data
