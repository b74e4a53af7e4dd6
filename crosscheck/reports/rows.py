"""The comparison rows of a report on disk, and the names every page links by.

A *check* is one (engine, section, model, quantity) group of comparison rows; its name is
``engine/section/model/quantity`` (summary.csv's ``check`` column).  This module owns how
rows are stored (:func:`write_rows`), read back (:func:`read_rows`), and the relative paths
the HTML pages link to (:func:`check_id`, :func:`slice_path`).

CONTRACT (the HTML pages depend on it; the storage layout behind it may change):
- ``normalise(df)``: rows with ``section`` filled ("terms" where an engine gave none) and
  ``status`` filled from ``passed``; the form verify summarises.
- ``check_name(engine, section, model, quantity)`` -> "engine/section/model/quantity".
- ``check_id(name)`` -> a short, file- and URL-safe, unique id of a check (HTML anchors,
  file names).
- ``slice_path(name)`` -> the path, relative to the run directory, of the file holding
  exactly that check's rows.
- ``write_rows(df, out_dir, engine)`` writes an engine's rows; returns the paths written.
- ``read_rows(run_dir, engine=None)`` -> the rows as one DataFrame with the columns of
  crosscheck.compare (engine, model, quantity, case, entry, gpme_value, engine_value,
  abs_error, rel_error, scale, tol_abs, tol_rel, status, passed, reason, section).
"""
import hashlib
import re
from pathlib import Path

import pandas as pd

from .tables import write_csv

TERMS_SECTION = "terms"     # the section of rows an engine gave none (Pinocchio's terms)
CHECKS_DIR = "checks"
_UNSAFE = re.compile(r"[^A-Za-z0-9._-]+")
MAX_SLUG = 60               # characters of readable name in an id (the hash keeps it unique)


def normalise(df):
    """``df`` with ``section`` ("terms" where missing) and ``status`` (from ``passed``
    where missing) filled; a copy."""
    df = df.copy()
    if "section" not in df.columns:
        df["section"] = None
    df["section"] = df["section"].fillna(TERMS_SECTION)
    if "status" not in df.columns:
        df["status"] = None
    if "passed" in df.columns:
        df["status"] = df["status"].fillna(df["passed"].map({True: "pass", False: "fail"}))
    return df


def check_name(engine, section, model, quantity):
    """The name of a check: "engine/section/model/quantity"."""
    return f"{engine}/{section}/{model}/{quantity}"


def check_id(name):
    """A file- and URL-safe id of the check ``name``: its readable part (at most MAX_SLUG
    characters of [A-Za-z0-9._-]) and 8 hex digits of its SHA-1, so two names never share
    an id even when their readable parts do."""
    readable = _UNSAFE.sub("-", name).strip("-.")[:MAX_SLUG].rstrip("-.")
    digest = hashlib.sha1(name.encode("utf-8")).hexdigest()[:8]
    return f"{readable}-{digest}"


def slice_path(name):
    """Path (relative to the run directory) of the file with check ``name``'s rows."""
    engine = name.split("/", 1)[0]
    return Path(CHECKS_DIR) / _UNSAFE.sub("-", engine) / f"{check_id(name)}.csv"


def write_rows(df, out_dir, engine):
    """Write ``engine``'s rows into ``out_dir`` (atomically, file by file); returns the
    paths written.  (Storage: <engine>.csv for now; see the module contract.)"""
    path = Path(out_dir) / f"{engine}.csv"
    write_csv(df, path)
    return [path]


def read_rows(run_dir, engine=None):
    """The rows of one engine (or of all engines found) of a report directory, as written
    by :func:`write_rows`."""
    run_dir = Path(run_dir)
    names = [engine] if engine else sorted(p.stem for p in run_dir.glob("*.csv")
                                           if p.stem not in ("summary",))
    frames = [pd.read_csv(run_dir / f"{n}.csv") for n in names]
    return pd.concat(frames, ignore_index=True) if frames else pd.DataFrame()
