"""Atomic writing of CSV/HTML/PNG report files, and the tables' ordering and summaries.

Every file is written to a temporary file in the same directory and moved into place
with os.replace, so an interrupted run never leaves a half-written file where a good
one was.  The HTML itself, a table's too (html_table), comes from templates
(crosscheck.reports.html, which builds its pages on the summaries here).
"""
import numpy as np
import pandas as pd

from gpme_io.atomic import atomic_write_csv

from ..compare import FAIL, INFO, PASS, STATUSES, row_status


def write_csv(df, path):
    """Write a DataFrame as CSV atomically (no index column)."""
    atomic_write_csv(df, path)


def worst_first(df):
    """Failures first, then gated rows by decreasing error over tolerance
    (abs_error / (tol_abs + tol_rel scale), column error_over_tolerance), info rows last."""
    budget = df["tol_abs"] + df["tol_rel"] * df["scale"]
    ratio = df["abs_error"] / budget.where(budget > 0, other=float("nan"))
    order = pd.Series(row_status(df), index=df.index).map({s: k for k, s in enumerate(STATUSES)})
    return df.assign(error_over_tolerance=ratio.where(np.isfinite(budget)), _order=order) \
        .sort_values(["_order", "error_over_tolerance"], ascending=[True, False],
                     kind="stable", na_position="last").drop(columns="_order")


def checks_worst_first(summary):
    """The checks of a summary (one row per check: status, error_over_tolerance) failures
    first, then by decreasing error over tolerance, information checks last; stable."""
    order = {s: k for k, s in enumerate(STATUSES)}
    return summary.assign(_o=summary["status"].map(order),
                          _r=summary["error_over_tolerance"].fillna(-1.0)) \
        .sort_values(["_o", "_r"], ascending=[True, False], kind="stable") \
        .drop(columns=["_o", "_r"])


def worst_status(statuses):
    """The status of a group of rows: "fail" if any row fails, else "pass" if any row is
    gated, else "info" (a group of information rows only is never a pass)."""
    statuses = set(statuses)
    if FAIL in statuses:
        return FAIL
    return PASS if PASS in statuses else INFO


def summarise(df, keys=("engine", "model", "quantity")):
    """One row per group of ``keys``: worst errors, the worst row's tolerance and reason,
    the group's status (:func:`worst_status`; ``passed`` = status != "fail") and the
    counts n_compared, n_pass, n_fail, n_info; ``value``: gpme's value in the worst row
    (what an information check reports: its error is 0 by construction)."""
    rows = []
    df = df.assign(status=row_status(df))
    for key, g in df.groupby(list(keys), sort=False, dropna=False):
        key = key if isinstance(key, tuple) else (key,)
        w = worst_first(g).iloc[0]
        st = worst_status(g["status"])
        counts = g["status"].value_counts()
        rows.append({**dict(zip(keys, key)), "n_compared": len(g),
                     "n_pass": int(counts.get(PASS, 0)), "n_fail": int(counts.get(FAIL, 0)),
                     "n_info": int(counts.get(INFO, 0)),
                     "worst_abs_error": g["abs_error"].max(),
                     "worst_rel_error": g["rel_error"].max(),
                     "value": w["gpme_value"] if "gpme_value" in w else np.nan,
                     "worst_case": w["case"], "worst_entry": w["entry"],
                     "tol_abs": w["tol_abs"], "tol_rel": w["tol_rel"],
                     "status": st, "passed": st != FAIL, "reason": w["reason"]})
    return pd.DataFrame(rows)
