"""The one comparison helper of the harness: every check goes through :func:`compare`.

A comparison of a gpme quantity x with an engine's y (same shape) passes when

    max |x - y| <= tol_abs + tol_rel * max(|y|)          (normwise, infinity norm)

and reports abs_error = max |x - y|, rel_error = abs_error / max(|y|) (inf-norm relative
error; NaN when y is all zero), the entry where the largest difference sits, both values
there, the tolerances and their stated reason.  One tidy row per comparison.
"""
from dataclasses import dataclass

import numpy as np

COLUMNS = ("engine", "model", "quantity", "case", "entry", "gpme_value", "engine_value",
           "abs_error", "rel_error", "scale", "tol_abs", "tol_rel", "passed", "reason")


@dataclass(frozen=True)
class Tolerance:
    """Absolute (in the quantity's unit) and relative tolerance with its reason."""

    abs: float
    rel: float
    reason: str


def _entry_label(index, labels):
    if labels is None:
        return str(tuple(int(i) for i in index)) if len(index) > 1 else str(int(index[0])) \
            if len(index) == 1 else ""
    if len(index) == 1:
        return str(labels[0][index[0]]) if isinstance(labels[0], (list, tuple)) else str(labels[index[0]])
    return "[" + ", ".join(str(lab[i]) for lab, i in zip(labels, index)) + "]"


def compare(engine, model, quantity, case, gpme_value, engine_value, tol, labels=None):
    """One tidy row (dict) comparing gpme_value with engine_value.

    labels: for a vector, a sequence of entry names; for a matrix, a pair of sequences
    (row names, column names).  Raises ValueError on a shape mismatch, which is a harness
    bug, not a discrepancy.
    """
    x = np.atleast_1d(np.asarray(gpme_value, dtype=float))
    y = np.atleast_1d(np.asarray(engine_value, dtype=float))
    if x.shape != y.shape:
        raise ValueError(f"{engine}/{model}/{quantity}/{case}: shape {x.shape} (gpme) != "
                         f"{y.shape} ({engine})")
    diff = np.abs(x - y)
    finite = np.all(np.isfinite(x)) and np.all(np.isfinite(y))
    idx = np.unravel_index(int(np.nanargmax(diff)) if diff.size and finite else 0, x.shape)
    abs_err = float(diff.max()) if finite and diff.size else float("inf")
    scale = float(np.abs(y).max()) if y.size else 0.0
    rel_err = abs_err / scale if scale > 0 else float("nan")
    if labels is not None and x.ndim == 1:
        labels = (list(labels),)
    passed = bool(finite and abs_err <= tol.abs + tol.rel * scale)
    return {"engine": engine, "model": model, "quantity": quantity, "case": case,
            "entry": _entry_label(idx, labels), "gpme_value": float(x[idx]),
            "engine_value": float(y[idx]), "abs_error": abs_err, "rel_error": rel_err,
            "scale": scale, "tol_abs": tol.abs, "tol_rel": tol.rel, "passed": passed,
            "reason": tol.reason}
