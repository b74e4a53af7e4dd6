"""Numbers in URDF attribute text: ``xyz="0 0 1"``, ``value="2.5"``, an element's <origin>.

Invalid text is never raised on: the problem (the attribute, the text, what would be valid)
is appended to the caller's list and a default is returned, so one read reports every
problem of a file.
"""
import numpy as np
from numpy.typing import NDArray

from gpme_core import transforms as tf

# |axis| - 1 accepted for a unit vector written in decimal (a FlexibleLink axis; a joint
# <axis xyz> further off is normalised and noted): round-off of a normalised vector is
# ~1e-16; 1e-9 allows 9-digit text.
_UNIT_TOL = 1e-9


def _floats(text, count, label, problems, default, infinite=False):
    """(count,) floats of an attribute's text (``default`` when absent or invalid: the
    problem, naming the attribute, the text and what would be valid, is appended);
    ``infinite``: +-inf is valid (limits), NaN never is."""
    if text is None:
        return np.array(default, dtype=float)
    try:
        v = np.array([float(s) for s in text.split()], dtype=float)
    except ValueError:
        v = None
    if v is None or v.shape != (count,) or \
            not np.all(~np.isnan(v) if infinite else np.isfinite(v)):
        shown = repr(text) if len(text) <= 80 else f"{text[:80]!r}... ({len(text)} characters)"
        if count == 1:
            what = "number (inf allowed)" if infinite else "finite number"
            problems.append(f"{label}: expected 1 {what}, got {shown}")
        else:
            problems.append(f"{label}: expected {count} finite numbers, got {shown} (write "
                            f"{count} decimal numbers separated by spaces)")
        return np.array(default, dtype=float)
    return v


def _origin_transform(el, label, problems) -> NDArray[np.float64]:
    """(4, 4) parent -> child transform of an element's <origin> (identity if absent;
    xyz in m, rpy in rad)."""
    o = el.find("origin")
    if o is None:
        return np.eye(4)
    xyz = _floats(o.get("xyz"), 3, f"{label} <origin xyz>", problems, (0, 0, 0))
    rpy = _floats(o.get("rpy"), 3, f"{label} <origin rpy>", problems, (0, 0, 0))
    return tf.homogeneous(tf.rpy_to_rotation(*rpy), xyz)
