"""The one comparison helper of the harness: every check goes through :func:`compare`.

A comparison of a gpme quantity x with an engine's y (same shape) has one of three
outcomes, in the ``status`` column of its row:

    "fail"  when x or y holds a NaN or an infinity, or
            max |x - y| > tol_abs + tol_rel * scale      (normwise, infinity norm);
    "info"  when the tolerance is not finite (Tolerance(np.inf, ...)): the row is
            information (a difference we report but do not gate), never a pass;
    "pass"  otherwise.

scale = max(|y|) unless the caller gives another reference magnitude.  The row reports
abs_error = max |x - y|, rel_error = abs_error / scale (NaN when scale is 0), the entry
where the largest difference sits, both values there, the tolerances and their stated
reason.  The boolean ``passed`` column (= status != "fail") is kept for older readers.

A tolerance table is a mapping {quantity: Tolerance}; :func:`tolerance_for` looks one up
and raises KeyError when it is missing: a comparison without a stated tolerance is a bug
in the harness, never a silent "no gate".
"""
import math
from dataclasses import dataclass
from typing import Mapping, Optional, Sequence

import numpy as np
import pandas as pd

COLUMNS = ("engine", "model", "quantity", "case", "entry", "gpme_value", "engine_value",
           "abs_error", "rel_error", "scale", "tol_abs", "tol_rel", "status", "passed", "reason")
FAIL, PASS, INFO = "fail", "pass", "info"
STATUSES = (FAIL, PASS, INFO)          # worst first
CRASH_QUANTITY = "step crashed"        # the quantity of the one row of a step that crashed


@dataclass(frozen=True)
class Tolerance:
    """Absolute (in the quantity's unit) and relative tolerance with its reason.

    abs, rel : >= 0, not NaN; an infinite one makes every row it gates "info".
    reason   : why the tolerance holds (physics: round-off with cond(M), integrator
               order, ...), shown in every row it gates; must not be empty.
    """

    abs: float
    rel: float
    reason: str

    def __post_init__(self):
        problems = [f"{k} = {v!r} must be >= 0 (inf for an ungated row), not NaN"
                    for k, v in (("abs", self.abs), ("rel", self.rel))
                    if not (isinstance(v, (int, float, np.floating)) and v >= 0)]
        if not str(self.reason).strip():
            problems.append("reason must state why the tolerance holds")
        if problems:
            raise ValueError("Tolerance: " + "; ".join(problems))

    @property
    def gated(self) -> bool:
        """True when both parts are finite (the row can pass or fail)."""
        return math.isfinite(self.abs) and math.isfinite(self.rel)


def tolerance_for(table: Mapping[str, Tolerance], quantity: str, where: str = "") -> Tolerance:
    """table[quantity], or KeyError naming the quantity and the known ones (a harness bug)."""
    try:
        return table[quantity]
    except KeyError:
        raise KeyError(f"no tolerance stated for {quantity!r}{' in ' + where if where else ''}; "
                       f"the table has {sorted(table)}: every compared quantity needs a "
                       "Tolerance with its reason (harness bug)") from None


def status(finite: bool, abs_error: float, tol: Tolerance, scale: float) -> str:
    """"fail", "info" or "pass" of one comparison (see the module docstring)."""
    if not finite:
        return FAIL
    if not tol.gated:
        return INFO
    return PASS if abs_error <= tol.abs + tol.rel * scale else FAIL


def _entry_label(index, labels):
    if labels is None:
        return str(tuple(int(i) for i in index)) if len(index) > 1 else str(int(index[0])) \
            if len(index) == 1 else ""
    if len(index) == 1:
        return str(labels[0][index[0]]) if isinstance(labels[0], (list, tuple)) else str(labels[index[0]])
    return "[" + ", ".join(str(lab[i]) for lab, i in zip(labels, index)) + "]"


def compare(engine: str, model: str, quantity: str, case: str, gpme_value, engine_value,
            tol: Tolerance, labels: Optional[Sequence] = None,
            scale: Optional[float] = None) -> dict:
    """One tidy row (dict with :data:`COLUMNS`) comparing gpme_value with engine_value.

    labels: for a vector, a sequence of entry names; for a matrix, a pair of sequences
    (row names, column names).  scale: the reference magnitude of the relative tolerance
    (default max|engine_value|), for a quantity whose reference value is 0 but whose size
    is known (an energy balance relative to the work done).  Raises ValueError on a shape
    mismatch, which is a harness bug, not a discrepancy.
    """
    if not isinstance(tol, Tolerance):
        raise TypeError(f"{engine}/{model}/{quantity}/{case}: tol must be a Tolerance, got "
                        f"{type(tol).__name__}")
    x = np.atleast_1d(np.asarray(gpme_value, dtype=float))
    y = np.atleast_1d(np.asarray(engine_value, dtype=float))
    if x.shape != y.shape:
        raise ValueError(f"{engine}/{model}/{quantity}/{case}: shape {x.shape} (gpme) != "
                         f"{y.shape} ({engine})")
    diff = np.abs(x - y)
    finite = bool(np.all(np.isfinite(x)) and np.all(np.isfinite(y)))
    idx = None
    if x.size and finite:
        idx = np.unravel_index(int(np.argmax(diff)), x.shape)
    elif x.size:                    # point at the first non-finite entry
        bad = np.flatnonzero(~(np.isfinite(x) & np.isfinite(y)))
        idx = np.unravel_index(int(bad[0]), x.shape)
    abs_err = (float(diff.max()) if x.size else 0.0) if finite else float("inf")
    if scale is None:
        finite_y = np.abs(y[np.isfinite(y)])
        scale = float(finite_y.max()) if finite_y.size else 0.0
    scale = float(scale)
    rel_err = abs_err / scale if scale > 0 else float("nan")
    if labels is not None and x.ndim == 1:
        labels = (list(labels),)
    st = status(finite, abs_err, tol, scale)
    return {"engine": engine, "model": model, "quantity": quantity, "case": case,
            "entry": "" if idx is None else _entry_label(idx, labels),
            "gpme_value": float("nan") if idx is None else float(x[idx]),
            "engine_value": float("nan") if idx is None else float(y[idx]),
            "abs_error": abs_err, "rel_error": rel_err, "scale": scale, "tol_abs": tol.abs,
            "tol_rel": tol.rel, "status": st, "passed": st != FAIL, "reason": tol.reason}


NOT_JUDGED = "not judged, because "


def not_judged(row: dict, because: str) -> dict:
    """``row`` (a :func:`compare` dict) turned into information: its comparison cannot be
    judged because a prerequisite failed (``because`` says which check, and that check
    fails in its own engine, once).  The numbers stay for reading; the gate it would have
    had is kept in the reason.  A row with a NaN or an infinity stays a failure."""
    if not math.isfinite(row["abs_error"]):
        return row
    gate = f"{row['tol_abs']:.3g}" + (f" + {row['tol_rel']:.3g} x scale" if row["tol_rel"]
                                       else "")
    return {**row, "status": INFO, "passed": True, "tol_abs": float("inf"), "tol_rel": 0.0,
            "reason": f"information: {NOT_JUDGED}{because} (gate otherwise: {gate}; "
                      f"{row['reason']})"}


def row_status(df) -> "np.ndarray":
    """(len(df),) status of each row of a comparison table: its ``status`` column, but
    "fail" wherever ``passed`` is False (a caller that overrode ``passed``, or a table
    from before the status column)."""
    n = len(df)
    st = df["status"] if "status" in df.columns else pd.Series([None] * n, index=df.index)
    passed = df["passed"].astype(bool) if "passed" in df.columns else \
        pd.Series([True] * n, index=df.index)
    derived = np.where(passed, PASS, FAIL)
    out = np.where(st.isna(), derived, st.astype(object))
    return np.where(~passed.to_numpy(), FAIL, out).astype(object)
