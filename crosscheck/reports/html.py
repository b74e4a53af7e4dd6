"""HTML of the reports through Jinja2 templates (crosscheck/reports/templates/), with
autoescaping on: every name, value and reason from a model or an engine is escaped by the
template engine, never by hand.

Tables are passed to the templates as :class:`Table` (column names, which are left-aligned,
and formatted cells with each row's status), so number formatting lives in one place
(:func:`number`) and the markup in one macro (templates/macros.html.j2).
"""
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

import jinja2
import numpy as np
import pandas as pd

from gpme_io.xml_text import xml_safe_text

from ..compare import FAIL, row_status
from . import tables as report

TEMPLATES = Path(__file__).with_name("templates")
WIDE_COLUMNS = ("reason", "Pinocchio side")   # long text: given room instead of wrapped


def number(v):
    """A cell value as text: floats in 6 significant digits, scientific below 1e-3 and from
    1e5 on; NaN as "-"; anything else as str."""
    if isinstance(v, (float, np.floating)):
        v = float(v)
        if v != v:
            return "-"
        if v != 0 and (abs(v) < 1e-3 or abs(v) >= 1e5) and np.isfinite(v):
            return f"{v:.3e}"
        return f"{v:.6g}"
    if isinstance(v, (np.integer,)):
        return str(int(v))
    return "" if v is None else str(v)


@dataclass
class Table:
    """A table for the ``table`` macro: ``columns`` (names), ``left`` (names of the
    left-aligned text columns), ``rows`` (each: {"status": "pass"|"fail"|"info"|None,
    "cells": [text, ...]}), ``wide`` (left columns of long text, given a wide minimum);
    the status column's cell shows FAIL in capitals."""
    columns: list
    left: set = field(default_factory=set)
    rows: list = field(default_factory=list)
    status_column: str = None
    wide: set = field(default_factory=lambda: set(WIDE_COLUMNS))


def table(df, status_column=None, max_rows=None, left_columns=()):
    """:class:`Table` of a DataFrame.  status_column: "status" (pass/fail/info strings) or
    "passed" (booleans); default "status" when present, else "passed"; a name the table
    lacks (e.g. "-") colours nothing."""
    if max_rows is not None:
        df = df.head(max_rows)
    if status_column is None:
        status_column = "status" if "status" in df.columns else "passed"
    statuses = list(row_status(df)) if status_column in df.columns else [None] * len(df)
    rows = []
    for values, st in zip(df.itertuples(index=False, name=None), statuses):
        cells = [("FAIL" if st == FAIL else st) if c == status_column else number(v)
                 for c, v in zip(df.columns, values)]
        rows.append({"status": st, "cells": cells})
    return Table([str(c) for c in df.columns], {str(c) for c in left_columns}, rows,
                 status_column if status_column in df.columns else None)


def printable(value):
    """Every value a template prints, before autoescaping: a str with characters XML and
    HTML cannot hold (controls from a name or a traceback) shown as their escapes
    (gpme_io.xml_text.xml_safe_text); markup (already escaped) keeps its type."""
    if isinstance(value, str):
        safe = xml_safe_text(value)
        return type(value)(safe) if hasattr(value, "__html__") else safe
    if value is None or isinstance(value, (bool, int, float)) or hasattr(value, "__html__"):
        return value
    return xml_safe_text(str(value))        # a Path, a numpy scalar, any object's text


@lru_cache(maxsize=1)
def environment():
    """The Jinja2 environment of the report templates (autoescape, undefined names are
    errors, the ``number`` filter)."""
    env = jinja2.Environment(loader=jinja2.FileSystemLoader(str(TEMPLATES)),
                             autoescape=True, undefined=jinja2.StrictUndefined,
                             trim_blocks=True, lstrip_blocks=True, finalize=printable)
    env.filters["number"] = number
    return env


def render(template, **context):
    """The text of ``template`` (a file name in templates/) rendered with ``context``."""
    return environment().get_template(template).render(**context)


def render_table(tab, table_id=None):
    """The HTML of one :class:`Table` (the ``table`` macro alone)."""
    macro = environment().get_template("macros.html.j2").module.table
    return str(macro(tab, table_id))


def html_table(df, status_column=None, max_rows=None, left_columns=()):
    """The HTML of a table of ``df`` (:func:`table`, rendered by the templates' ``table``
    macro); each row gets the class of its status ('pass', 'fail', 'info')."""
    return render_table(table(df, status_column, max_rows, left_columns))


def section(title, text=(), table=None, figures=(), items=(), id=None):
    """One section of an engine page: paragraphs ``text`` (plain text), an optional
    :class:`Table`, figures [(src, caption)] (paths relative to the page) and list
    ``items``."""
    return {"title": title, "text": list(text), "table": table, "id": id,
            "figures": [{"src": str(src), "caption": caption} for src, caption in figures],
            "items": list(items)}


def engine_page(title, heading, ok, intro, sections):
    """The HTML of an engine's own page (templates/engine.html.j2): a verdict header with
    paragraphs ``intro`` and the ``sections`` (:func:`section`)."""
    return render("engine.html.j2", title=title, heading=heading, ok=ok, intro=list(intro),
                  sections=list(sections))


def reason_refs(*frames):
    """The reasons of ``frames`` numbered once: ({reason: "R<k>"}, a :class:`Table` of
    them); replace each frame's reason column with :func:`cite_reasons` so that a long
    reason is printed once per page, not once per row."""
    ids = {}
    for df in frames:
        for reason in df.get("reason", pd.Series(dtype=object)).dropna():
            ids.setdefault(reason, f"R{len(ids) + 1}")
    side = pd.DataFrame({"id": list(ids.values()), "reason": list(ids.keys())})
    return ids, table(side, status_column="-", left_columns=("id", "reason"))


def cite_reasons(df, ids):
    """``df`` with its reason column holding the reason's id ("R<k>") of :func:`reason_refs`."""
    if "reason" not in df.columns:
        return df
    return df.assign(reason=df["reason"].map(ids).fillna("-"))


WORST_ROWS = 40      # rows of an engine page's worst-cases table


def comparison_page(engine, title, version, df, intro, lead_sections, conventions):
    """The HTML of an engine's comparison page (pinocchio.html, drake.html, exudyn.html):
    verdict, ``intro`` paragraphs, the engine's own ``lead_sections`` (model cases, ...),
    its ``conventions`` text, the WORST_ROWS worst rows, the summary per model and quantity
    and the numbered tolerance reasons.  df: the engine's comparison rows (columns of
    crosscheck.compare.COLUMNS plus ``section``); engine: its checks/ directory name."""
    if df.empty:
        return engine_page(title, f"{title} {version}: nothing compared", False, [], [])
    summary = report.summarise(df, keys=("section", "model", "quantity"))
    worst = report.worst_first(df).head(WORST_ROWS)
    reasons, reason_table = reason_refs(worst, summary)
    n_fail = int((summary["status"] == "fail").sum())
    status = "all comparisons pass" if n_fail == 0 else f"{n_fail} checks FAIL"
    sections = list(lead_sections) + [
        section("Conventions", [conventions]),
        section(f"Worst cases ({min(WORST_ROWS, len(df))} of {len(df)} rows)", [
            f"Every row: the checks/{engine}/ files of this report (one gzip CSV per check), "
            f"or all at once with python -m crosscheck.reports.rows <report dir> {engine}."],
            table=table(cite_reasons(worst, reasons), left_columns=(
                "section", "model", "quantity", "case", "entry"))),
        section("Summary per model and quantity", table=table(
            cite_reasons(summary, reasons), left_columns=("section", "model", "quantity",
                                                          "worst_case", "worst_entry"))),
        section("Why each tolerance is what it is (the reason column's ids)",
                table=reason_table)]
    return engine_page(title, f"{title} {version}: {status}", n_fail == 0, intro, sections)
