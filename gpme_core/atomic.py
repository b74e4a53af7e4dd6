"""Atomic file writing: a temporary file in the target directory moved into place with
os.replace, so an interrupted run never leaves a half-written file where a good one was."""
import os
import tempfile
from pathlib import Path


def atomic_write_bytes(path, data):
    """Write ``data`` (bytes) to ``path`` atomically."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)   # mkstemp makes 0600; a report is for reading
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def atomic_write_text(path, text):
    """Write UTF-8 ``text`` to ``path`` atomically."""
    atomic_write_bytes(path, text.encode("utf-8"))


def atomic_write_csv(df, path):
    """Write a DataFrame as CSV (no index) atomically."""
    atomic_write_text(path, df.to_csv(index=False))


def atomic_save_figure(fig, path, dpi=120):
    """Save a matplotlib figure as PNG atomically."""
    import io
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi, bbox_inches="tight")
    atomic_write_bytes(path, buf.getvalue())
