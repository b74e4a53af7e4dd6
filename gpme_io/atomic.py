"""Atomic file writing: a temporary file in the target directory moved into place with
os.replace, so an interrupted run never leaves a half-written file where a good one was.
Text, bytes, CSV tables and matplotlib figures (as compact PNGs, gpme_io.png); the engine
(gpme_core) writes no files, it returns data (issue 25)."""
import contextlib
import gzip
import os
import signal
import tempfile
from pathlib import Path

from gpme_core.errors import OutputWriteError

from .png import figure_png


def atomic_write_bytes(path, data):
    """Write ``data`` (bytes) to ``path`` atomically.  A failure of the file system (disk
    full, read-only, the folder removed, no permission) raises OutputWriteError naming the
    file and the space left; the temporary file is removed and ``path`` is unchanged."""
    path = Path(path)
    tmp = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with _signals_held():   # an interruption between mkstemp and `tmp =` left the file
            fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.",
                                       suffix=".tmp")
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)   # mkstemp makes 0600; a report is for reading
        os.replace(tmp, path)
    except BaseException as exc:
        if tmp is not None:
            try:
                os.unlink(tmp)
            except OSError:
                pass        # already moved into place, or its folder went away
        if isinstance(exc, OSError) and not isinstance(exc, OutputWriteError):
            raise OutputWriteError(path, exc) from None
        raise


# the signals gpme ends a command on (gpme.signals); held while a temporary file is created
# so that its name is known before an interruption can unwind past it
_HELD = tuple(getattr(signal, n) for n in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, n))


@contextlib.contextmanager
def _signals_held():
    """Signals held (blocked, then delivered) inside the block, where the platform allows
    it (POSIX pthread_sigmask); a no-op elsewhere."""
    mask = getattr(signal, "pthread_sigmask", None)
    if mask is None:
        yield
        return
    old = mask(signal.SIG_BLOCK, _HELD)
    try:
        yield
    finally:
        mask(signal.SIG_SETMASK, old)


def atomic_write_text(path, text):
    """Write UTF-8 ``text`` to ``path`` atomically."""
    atomic_write_bytes(path, text.encode("utf-8"))


# Significant digits of the run histories in a verify report (compressed=True of
# gpme_io.runs.write_run_outputs; `gpme simulate` keeps full precision).  The rounding, at most 5e-14 relative, is below what halving the step
# changes in every column of the paper's 10 s runs but three that agree to round-off
# (end-effector height, column angle, drive work; 2e-15..5e-14): measured
# 5e-15..5e-12 (rigid) and 2e-15..2e-5 (flexible); reports/README.md, "Precision of the run
# histories".  It makes the full report 9.4 MB instead of 10.1 MB.
HISTORY_DIGITS = 14


def atomic_write_csv(df, path, significant_digits=None):
    """Write a DataFrame as CSV (no index) atomically; gzip-compressed when ``path`` ends
    in ``.gz`` (no time stamp in the header: the same table gives the same bytes).  Floats
    are written as their shortest round-trip repr, so they read back bit-exact, or rounded
    to ``significant_digits`` significant digits (relative rounding <= 5 10^-digits; still
    as a float repr, so that 0 is "0.0" and a float column reads back as floats)."""
    float_format = None
    if significant_digits is not None:
        spec = f"%.{int(significant_digits)}g"

        def rounded(v):
            return repr(float(spec % v))
        float_format = rounded
    text = df.to_csv(index=False, lineterminator="\n", float_format=float_format)
    if str(path).endswith(".gz"):
        atomic_write_bytes(path, gzip.compress(text.encode("utf-8"), compresslevel=9,
                                               mtime=0))
    else:
        atomic_write_text(path, text)


def atomic_save_figure(fig, path, dpi=120):
    """Save a matplotlib figure as a compact PNG (:func:`figure_png`) atomically."""
    atomic_write_bytes(path, figure_png(fig, dpi))
