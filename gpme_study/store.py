"""The resume store of a sweep: one small JSON file per finished point,
``<out>/points/<key>.json``, written atomically (gpme_io.atomic), so an interrupted sweep
restarts without recomputing finished points and never finds a half-written one."""
import json
from pathlib import Path

import numpy as np

from gpme_io.atomic import atomic_write_text


def _plain(value):
    if isinstance(value, np.bool_):
        return bool(value)
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.floating):
        return float(value)
    raise TypeError(f"cannot store {type(value).__name__} {value!r} in a point file")


class ResultStore:
    """Finished points of one sweep directory, keyed by gpme_study.point.point_key."""

    def __init__(self, out_dir):
        self.directory = Path(out_dir) / "points"

    def path(self, key):
        return self.directory / f"{key}.json"

    def keys(self):
        """Keys of every stored point."""
        if not self.directory.is_dir():
            return set()
        return {p.stem for p in self.directory.glob("*.json")}

    def save(self, row):
        """Store one row (dict with a 'key'); NaN is kept as JSON NaN."""
        atomic_write_text(self.path(row["key"]), json.dumps(row, default=_plain, indent=1))

    def load(self, key):
        """The stored row of ``key`` (dict), or None when missing or unreadable (a file
        from a crashed writer of another tool: the point is then recomputed)."""
        try:
            return json.loads(self.path(key).read_text(encoding="utf-8"))
        except (OSError, ValueError):
            return None
