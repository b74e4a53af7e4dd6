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

STORAGE (in a run directory; every file written atomically, gpme_io.atomic):
- ``checks/<engine>/<check_id>.csv.gz``: the rows of one check (after :func:`normalise`),
  each row once, gzip-compressed CSV; the wide table's columns in its order except that
  ``tol_abs, tol_rel, reason`` are replaced by ``tol_id`` (at tol_abs's place).
- ``tolerances.csv.gz``: ``tol_id, tol_abs, tol_rel, reason``, one row per distinct
  triple; ids are ``<engine>-<k>`` (k = 1, 2, ...), unique across the engines of a
  directory.  Compressed because the solve tolerances state cond(M) per state: the full
  crane run has 10,772 distinct triples, 5.6 MB as plain CSV, 153 kB gzipped.
- ``checks/index.csv``: one row per check: check, engine, section, model, quantity, file
  (the slice, relative to the run directory), n_rows, status (the check's worst status).
- ``checks/<engine>/columns.csv``: column, kind (float, int, bool, text) and stored_in of
  every column: ``slice`` for the columns the check files have, in their order (``tol_id``
  among them), ``tolerances.csv.gz`` for tol_abs, tol_rel and reason (joined by tol_id);
  in the wide table's order, so that :func:`read_rows` gives back the very table written.
  (Reports written before 2026-11-26 have no stored_in: their schema is the wide table's,
  read as such.)
Several engines write into one directory (verify: gpme, pinocchio, mujoco): tolerances and
checks/index.csv are merged, an engine's earlier entries replaced by its new ones.
``<engine>`` is the engine's name where it is file-safe, else a slug with a hash.

Numbers are written as Python's shortest round-trip repr (pandas' default), so floats read
back bit-exact (inf, -inf, -0.0 and subnormals included; NaN as an empty field).  Text
columns read back as the strings written; an empty or missing text reads back as NaN.
Rows come back grouped by check (checks in the order of their first row), each check's
rows in the order written.

Why gzip CSV and not Parquet: a slice is one link in the report, read by pandas, R, a
spreadsheet or ``zcat | less`` without a Parquet library; text columns (quantity, entry,
case) compress ~10x either way.  Measured on a full ``gpme crosscheck pinocchio`` of the
crane (57,667 rows): pinocchio.csv 23.3 MB; this layout 2.29 MB (211 slices 2.09 MB,
tolerances 153 kB, index 42 kB); the same rows as per-check Parquet slices (pyarrow, zstd)
3.76 MB (a footer and schema per file); one Parquet file of all rows 1.50 MB, but it
cannot be linked check by check, and a 0.8 MB saving does not pay for a binary format.

``python -m crosscheck.reports.rows RUN_DIR [ENGINE]`` prints the wide table as one CSV on
stdout (``... > pinocchio.csv``); a directory without rows is one error line and exit 2.
"""
import argparse
import gzip
import io
import shutil
import sys
from pathlib import Path
from typing import List, Optional

import pandas as pd

from gpme_core.errors import GpmeError
from gpme_io import file_names
from gpme_io.atomic import atomic_write_bytes, atomic_write_text

from ..compare import row_status
from .tables import worst_status

TERMS_SECTION = "terms"     # the section of rows an engine gave none (Pinocchio's terms)
CHECKS_DIR = "checks"
INDEX_FILE = "index.csv"                # in CHECKS_DIR
COLUMNS_FILE = "columns.csv"            # in CHECKS_DIR/<engine>
TOLERANCES_FILE = "tolerances.csv.gz"
SLICE_SUFFIX = ".csv.gz"
KEYS = ("engine", "section", "model", "quantity")
TOLERANCE = ("tol_abs", "tol_rel", "reason")
TOL_ID = "tol_id"
# columns.csv's third column: where a column of the wide table is stored
STORED_IN, IN_SLICE = "stored_in", "slice"
INDEX_COLUMNS = ("check", "engine", "section", "model", "quantity", "file", "n_rows",
                 "status")
KINDS = ("float", "int", "bool", "text")


class RowsError(GpmeError):
    """A report directory holds no comparison rows (of the engine asked for), or its row
    files cannot be read; the message names the directory, the files and what is there."""


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
    """A file- and URL-safe id of the check ``name``: its readable part (at most
    gpme_io.file_names.MAX_READABLE characters of [A-Za-z0-9._-], others replaced by '-',
    not starting with '-' or '.') and 8 hex digits of its SHA-1, so names that share a
    readable part still get different ids (a collision of the 8 digits, about 1 in 4e9 for
    a pair, is refused by :func:`write_rows`)."""
    return file_names.hashed_stem(name, joiner="-")


def _engine_dir(engine):
    """The directory name of an engine under checks/: gpme_io.file_names.file_stem (the
    name itself when plain), check_id(engine) for the index's name."""
    engine = str(engine)
    return check_id(engine) if engine == INDEX_FILE else file_names.file_stem(engine)


def slice_path(name):
    """Path (relative to the run directory) of the gzip CSV with check ``name``'s rows."""
    engine = name.split("/", 1)[0]
    return Path(CHECKS_DIR) / _engine_dir(engine) / f"{check_id(name)}{SLICE_SUFFIX}"


def _kind(series):
    """The kind a column is stored and read back as (one of KINDS)."""
    if pd.api.types.is_bool_dtype(series):
        return "bool"
    if pd.api.types.is_integer_dtype(series):
        return "int"
    if pd.api.types.is_float_dtype(series):
        return "float"
    values = series.dropna()
    if len(values) and values.map(lambda v: isinstance(v, bool)).all():
        return "bool"           # booleans with gaps (object column)
    return "text"


def _csv_text(df):
    return df.to_csv(index=False, lineterminator="\n")


def _gzip(text):
    """gzip bytes of ``text`` (no time stamp: the same rows give the same bytes)."""
    return gzip.compress(text.encode("utf-8"), compresslevel=9, mtime=0)


def _read_text_csv(data):
    """A CSV (bytes or a path; gzip when the name ends in .gz) as a DataFrame of strings
    ("" for an empty field)."""
    if isinstance(data, Path):
        data = data.read_bytes()
        data = gzip.decompress(data) if data[:2] == b"\x1f\x8b" else data
    return pd.read_csv(io.BytesIO(data), dtype=str, keep_default_na=False, na_filter=False)


def _write_table(path, df):
    """``df`` as CSV at ``path`` atomically (gzip when the name ends in .gz)."""
    text = _csv_text(df)
    if path.name.endswith(".gz"):
        atomic_write_bytes(path, _gzip(text))
    else:
        atomic_write_text(path, text)


def _schema(rows):
    """columns.csv of the wide ``rows``: column, kind and stored_in, in the wide order with
    tol_id (a slice column, at tol_abs's place) before the tolerance columns it joins."""
    return _schema_of_wide(pd.DataFrame({"column": [str(c) for c in rows.columns],
                                         "kind": [_kind(rows[c]) for c in rows.columns]}))


def _schema_of_wide(schema):
    """The stored_in schema (column, kind, stored_in) of a wide one (column, kind): what
    :func:`_schema` writes, and how an older columns.csv is read."""
    out = []
    for c, kind in zip(schema["column"], schema["kind"]):
        if c == "tol_abs":
            out.append((TOL_ID, "text", IN_SLICE))
        out.append((c, kind, TOLERANCES_FILE if c in TOLERANCE else IN_SLICE))
    return pd.DataFrame(out, columns=["column", "kind", STORED_IN])


def _owned_by(tol_ids, engine):
    """Boolean Series: tol_ids of ``engine`` ("<engine>-<k>")."""
    return tol_ids.map(lambda t: t.rsplit("-", 1)[0] == engine)


def _tolerance_table(stored, engine):
    """(tolerances, tol_id per row): one row per distinct (tol_abs, tol_rel, reason) of
    ``stored``, in order of first appearance, with ids "<engine>-<k>"."""
    # keys by their text: -0.0 and 0.0 stay apart, NaN equals NaN
    key = list(zip(stored["tol_abs"].map(repr), stored["tol_rel"].map(repr),
                   stored["reason"].map(lambda r: None if pd.isna(r) else str(r))))
    ids, first = {}, []
    for i, k in enumerate(key):
        if k not in ids:
            ids[k] = f"{engine}-{len(ids) + 1}"
            first.append(i)
    table = stored.iloc[first][list(TOLERANCE)].reset_index(drop=True)
    table.insert(0, TOL_ID, [ids[key[i]] for i in first])
    return table, [ids[k] for k in key]


def _merge(path, new, keep):
    """The CSV at ``path`` (strings) without the rows ``keep`` refuses, then ``new``."""
    if path.is_file():
        old = _read_text_csv(path)
        old = old[~keep(old)] if len(old) else old
        if len(old):       # the new rows as their CSV text, the old ones as read
            new = pd.concat([old, _read_text_csv(_csv_text(new).encode("utf-8"))],
                            ignore_index=True)
    return new


def own_rows(df, engine):
    """The rows of ``df`` that judge ``engine``'s own numbers (a step's table may also hold
    rows of a prerequisite it judged on the way, e.g. gpme's observed order in the
    Pinocchio step: those are gpme's checks, written with gpme's rows)."""
    if not len(df) or "engine" not in df.columns:
        return df
    return df[df["engine"] == engine]


def other_rows(df, engine):
    """The rows of ``df`` that belong to other engines than ``engine`` (see own_rows)."""
    if not len(df) or "engine" not in df.columns:
        return df.iloc[0:0]
    return df[df["engine"] != engine]


def write_rows(df, out_dir, engine) -> List[Path]:
    """Write ``engine``'s rows into ``out_dir``; returns the paths written.

    One gzip CSV slice per check (checks/<engine>/<check_id>.csv.gz), the engine's
    tolerances merged into tolerances.csv.gz and its checks into checks/index.csv (replacing
    what ``engine`` wrote there before; other engines' entries kept), its column order and
    kinds in checks/<engine>/columns.csv; slices of the engine's earlier checks that are
    gone are removed.  Each file is written atomically.  An empty ``df`` removes the
    engine's rows.  Raises ValueError (a harness bug) when columns are missing or a row
    belongs to another engine, or the engine's name is empty or holds a '/'."""
    out_dir = Path(out_dir)
    engine = str(engine)
    if not engine or "/" in engine:
        raise ValueError(f"write_rows: engine name {engine!r} must be non-empty and without "
                         "'/' (it is the first part of every check name; harness bug)")
    missing = [c for c in ("engine", "model", "quantity", *TOLERANCE) if c not in df.columns]
    if len(df) and missing:
        raise ValueError(f"write_rows({engine!r}): the rows lack the columns {missing} "
                         "(rows come from crosscheck.compare.compare; harness bug)")
    if len(df):
        others = sorted({str(e) for e in df["engine"] if e != engine})
        if others:
            raise ValueError(f"write_rows({engine!r}): rows of other engines {others} "
                             "(each engine writes its own rows; harness bug)")
    engine_dir = out_dir / CHECKS_DIR / _engine_dir(engine)
    written = []
    if not len(df):
        stored, tolerances, index = None, pd.DataFrame(columns=[TOL_ID, *TOLERANCE]), \
            pd.DataFrame(columns=list(INDEX_COLUMNS))
    else:
        rows = normalise(df)
        schema = _schema(rows)
        tolerances, ids = _tolerance_table(rows, engine)
        stored = rows.drop(columns=["tol_rel", "reason"]).rename(columns={"tol_abs": TOL_ID})
        stored[TOL_ID] = ids
        statuses = pd.Series(row_status(rows), index=rows.index)
        index, paths = [], {}
        for key, group in stored.groupby(list(KEYS), sort=False, dropna=False):
            name = check_name(*key)
            rel = slice_path(name)
            if rel in paths:
                raise ValueError(f"write_rows({engine!r}): checks {paths[rel]!r} and {name!r} "
                                 f"share the file {rel} (harness bug)")
            paths[rel] = name
            _write_table(out_dir / rel, group)
            written.append(out_dir / rel)
            index.append({"check": name, **dict(zip(KEYS, key)), "file": rel.as_posix(),
                          "n_rows": len(group),
                          "status": worst_status(statuses.loc[group.index])})
        index = pd.DataFrame(index, columns=list(INDEX_COLUMNS))
        _write_table(engine_dir / COLUMNS_FILE, schema)
        written.append(engine_dir / COLUMNS_FILE)
    tol_path = out_dir / TOLERANCES_FILE
    _write_table(tol_path, _merge(tol_path, tolerances,
                                  lambda old: _owned_by(old[TOL_ID], engine)))
    index_path = out_dir / CHECKS_DIR / INDEX_FILE
    _write_table(index_path, _merge(index_path, index, lambda old: old["engine"] == engine))
    written += [tol_path, index_path]
    if stored is None:
        shutil.rmtree(engine_dir, ignore_errors=True)
    else:
        keep = {p.name for p in written}
        for old in engine_dir.glob(f"*{SLICE_SUFFIX}"):
            if old.name not in keep:
                old.unlink(missing_ok=True)
    return written


def _typed(values, kind):
    """A column of strings (as read) turned back into its kind."""
    if kind == "float":
        return values.where(values != "", "nan").astype(float)
    if kind == "int":
        return values.astype("int64")
    if kind == "bool":
        mapped = values.map({"True": True, "False": False})
        return mapped.astype(bool) if mapped.notna().all() else mapped.astype(object)
    return values.mask(values == "")


def _legacy(run_dir, engine):
    """Rows of a report written before the checks/ layout (<engine>.csv), or None."""
    names = [engine] if engine else sorted(p.stem for p in run_dir.glob("*.csv")
                                           if p.stem not in ("summary", "tolerances"))
    paths = [run_dir / f"{n}.csv" for n in names if (run_dir / f"{n}.csv").is_file()]
    if not paths:
        return None
    return pd.concat([pd.read_csv(p) for p in paths], ignore_index=True)


def read_rows(run_dir, engine: Optional[str] = None) -> pd.DataFrame:
    """The rows of one engine (or of all engines, in the order they were written) of a
    report directory, as given to :func:`write_rows`: the same columns in the same order
    (tol_abs, tol_rel and reason joined back from tolerances.csv.gz), floats bit-exact;
    grouped by check (see the module docstring).

    A report from before the checks/ layout is read from its <engine>.csv.  Raises
    RowsError when the directory holds no rows (or none of ``engine``, naming those it
    holds) or a row file is missing or unreadable (every such file named at once)."""
    run_dir = Path(run_dir)
    index_path = run_dir / CHECKS_DIR / INDEX_FILE
    if not index_path.is_file():
        legacy = _legacy(run_dir, engine) if run_dir.is_dir() else None
        if legacy is not None:
            return legacy
        what = "is not a directory" if not run_dir.is_dir() else \
            f"holds no comparison rows ({CHECKS_DIR}/{INDEX_FILE} is missing)"
        raise RowsError(f"{str(run_dir)!r} {what}; give a report directory written by "
                        "`gpme verify` (reports/<run-id>) or `gpme crosscheck pinocchio|mujoco`")
    problems = []
    try:
        index = _read_text_csv(index_path)
        tolerances = _read_text_csv(run_dir / TOLERANCES_FILE)
    except (OSError, ValueError, UnicodeDecodeError) as exc:
        raise RowsError(f"{str(run_dir)!r}: cannot read its row index: {exc}") from None
    engines = list(dict.fromkeys(index["engine"]))
    if engine is not None:
        if str(engine) not in engines:
            raise RowsError(f"{str(run_dir)!r} holds no rows of engine {str(engine)!r}; it "
                            f"holds rows of {engines or 'no engine'}")
        engines = [str(engine)]
    tol = tolerances.set_index(TOL_ID)
    frames = []
    for name in engines:
        columns_path = run_dir / CHECKS_DIR / _engine_dir(name) / COLUMNS_FILE
        try:
            schema = _read_text_csv(columns_path)
        except (OSError, ValueError, UnicodeDecodeError) as exc:
            problems.append(f"{columns_path}: {exc}")
            continue
        if STORED_IN not in schema.columns:     # a report written before stored_in
            schema = _schema_of_wide(schema)
        expected = list(schema.loc[schema[STORED_IN] == IN_SLICE, "column"])
        schema = schema[schema["column"] != TOL_ID]      # the wide table has no tol_id
        pieces = []
        for rel in index.loc[index["engine"] == name, "file"]:
            path = run_dir / rel
            try:
                piece = _read_text_csv(path)
            except (OSError, EOFError, ValueError, UnicodeDecodeError) as exc:
                problems.append(f"{path}: {exc}")
                continue
            if list(piece.columns) != expected:
                problems.append(f"{path}: columns {list(piece.columns)}, expected {expected} "
                                f"({columns_path})")
                continue
            pieces.append(piece)
        if not pieces or problems:
            continue
        stored = pd.concat(pieces, ignore_index=True)
        unknown = sorted(set(stored[TOL_ID]) - set(tol.index))
        if unknown:
            problems.append(f"{run_dir / TOLERANCES_FILE}: no tolerance with tol_id "
                            f"{unknown[:5]} (engine {name!r})")
            continue
        joined = tol.loc[stored[TOL_ID], list(TOLERANCE)].reset_index(drop=True)
        wide = {}
        for column, kind in zip(schema["column"], schema["kind"]):
            values = joined[column] if column in TOLERANCE else stored[column]
            wide[column] = _typed(values, kind)
        frames.append(pd.DataFrame(wide))
    if problems:
        raise RowsError(f"{len(problems)} row files of {str(run_dir)!r} cannot be read:\n"
                        + "\n".join(f"  - {p}" for p in problems))
    return pd.concat(frames, ignore_index=True) if frames else pd.DataFrame()


def main(argv=None) -> int:
    """``python -m crosscheck.reports.rows RUN_DIR [ENGINE]``: the wide table as CSV on
    stdout; exit 2 with one error line when there is nothing to print."""
    parser = argparse.ArgumentParser(
        prog="python -m crosscheck.reports.rows",
        description="Print the comparison rows of a gpme report directory as one CSV "
                    "(the columns of crosscheck.compare; tolerances and reasons joined back).")
    parser.add_argument("run_dir", help="a report directory (reports/<run-id>, reports/latest)")
    parser.add_argument("engine", nargs="?", help="only this engine's rows (gpme, pinocchio, "
                        "mujoco); default: every engine's")
    args = parser.parse_args(argv)
    try:
        rows = read_rows(args.run_dir, args.engine)
        if rows.empty:
            raise RowsError(f"{args.run_dir!r} holds no comparison rows (every engine wrote "
                            "none)")
    except RowsError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    try:
        sys.stdout.write(_csv_text(rows))
        sys.stdout.flush()
    except BrokenPipeError:       # `... | head`: the reader has what it wanted
        sys.stderr.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
