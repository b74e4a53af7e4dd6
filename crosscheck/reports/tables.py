"""Atomic writing of CSV/HTML/PNG report files and small HTML building blocks.

Every file is written to a temporary file in the same directory and moved into place
with os.replace, so an interrupted run never leaves a half-written file where a good
one was.  HTML pages are self-contained (inline CSS, images as data URIs).
"""
import base64
import html
import io

import numpy as np
import pandas as pd

from gpme_core.atomic import atomic_write_bytes, atomic_write_csv, atomic_write_text  # noqa: F401

from ..compare import FAIL, INFO, PASS, STATUSES, row_status

CSS = """
body{font-family:system-ui,-apple-system,Segoe UI,Roboto,sans-serif;margin:1rem auto;
max-width:72rem;padding:0 1rem;color:#222;line-height:1.4}
table{border-collapse:collapse;font-size:.85rem;display:block;overflow-x:auto;max-width:100%}
th,td{border:1px solid #ccc;padding:.2rem .4rem;text-align:right;white-space:nowrap}
th{background:#f0f0f0;position:sticky;top:0}td.l,th.l{text-align:left}
tr.fail td{background:#fdd}tr.pass td.st{color:#060}tr.fail td.st{color:#a00;font-weight:bold}
tr.info td.st{color:#555;font-style:italic}
img{max-width:100%;height:auto}code{background:#f4f4f4;padding:0 .2rem}
"""


def write_csv(df, path):
    """Write a DataFrame as CSV atomically (no index column)."""
    atomic_write_csv(df, path)


def figure_data_uri(fig, dpi=110):
    """A matplotlib figure as a PNG data URI (for self-contained HTML)."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi, bbox_inches="tight")
    return "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode("ascii")


def _fmt(v):
    if isinstance(v, float):
        return f"{v:.3e}" if (v != 0 and (abs(v) < 1e-3 or abs(v) >= 1e5)) else f"{v:.6g}"
    return html.escape(str(v))


def html_table(df, status_column=None, max_rows=None, left_columns=()):
    """An HTML table of ``df``; each row gets the class of its status ('pass', 'fail',
    'info').  status_column: "status" (pass/fail/info strings) or "passed" (booleans);
    default: "status" when the table has it, else "passed"; a name the table lacks
    (e.g. "-") colours nothing."""
    if max_rows is not None:
        df = df.head(max_rows)
    if status_column is None:
        status_column = "status" if "status" in df.columns else "passed"
    head = "".join(f"<th class='l'>{html.escape(str(c))}</th>" if c in left_columns
                   else f"<th>{html.escape(str(c))}</th>" for c in df.columns)
    statuses = row_status(df) if status_column in df.columns else [None] * len(df)
    rows = []
    for (_, r), st in zip(df.iterrows(), statuses):
        cls = f" class='{st}'" if st else ""
        cells = []
        for c in df.columns:
            v = r[c]
            if c == status_column:
                cells.append(f"<td class='st'>{'FAIL' if st == FAIL else st}</td>")
            else:
                cl = " class='l'" if c in left_columns else ""
                cells.append(f"<td{cl}>{_fmt(v)}</td>")
        rows.append(f"<tr{cls}>{''.join(cells)}</tr>")
    return f"<table><thead><tr>{head}</tr></thead><tbody>{''.join(rows)}</tbody></table>"


def html_page(title, body_html):
    """A complete self-contained HTML document."""
    return (f"<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>"
            f"<meta name='viewport' content='width=device-width,initial-scale=1'>"
            f"<title>{html.escape(title)}</title><style>{CSS}</style></head>"
            f"<body>{body_html}</body></html>")


def worst_first(df):
    """Failures first, then gated rows by decreasing error over tolerance
    (abs_error / (tol_abs + tol_rel scale), column error_over_tolerance), info rows last."""
    budget = df["tol_abs"] + df["tol_rel"] * df["scale"]
    ratio = df["abs_error"] / budget.where(budget > 0, other=float("nan"))
    order = pd.Series(row_status(df), index=df.index).map({s: k for k, s in enumerate(STATUSES)})
    return df.assign(error_over_tolerance=ratio.where(np.isfinite(budget)), _order=order) \
        .sort_values(["_order", "error_over_tolerance"], ascending=[True, False],
                     kind="stable", na_position="last").drop(columns="_order")


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
    counts n_compared, n_pass, n_fail, n_info."""
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
                     "worst_case": w["case"], "worst_entry": w["entry"],
                     "tol_abs": w["tol_abs"], "tol_rel": w["tol_rel"],
                     "status": st, "passed": st != FAIL, "reason": w["reason"]})
    return pd.DataFrame(rows)
