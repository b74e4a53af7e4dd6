"""What changed since the previous `gpme verify` run: the diff of two summary.json files.

The measure of a check is its **error over tolerance** (:func:`check_ratios`)::

    error / tolerance = abs_error / (tol_abs + tol_rel * scale)

of the check's worst row: the largest value over the check's gated rows (1 is the pass
limit: above it the row fails).  A row with zero tolerance counts 0 when its error is 0 and
infinity otherwise; a row whose value is NaN or infinite (abs_error = inf) counts infinity;
an information row (infinite tolerance) has no ratio, and a check of information rows only
has none (``None`` in summary.json).

:func:`diff_summaries` compares two summary.json documents (matched by check name,
``engine/section/model/quantity``) and lists

- ``grown``: checks whose error/tolerance grew more than GROWTH_FACTOR (10x), ratios below
  RATIO_FLOOR counting as RATIO_FLOOR (round-off noise: a previous ratio of 0 is
  compared as RATIO_FLOOR, so 0 -> 2e-5 is listed, 0 -> 1e-7 is not); a check with no
  ratio on either side (information, or a previous report without ratios) is not compared
  for growth;
- ``status_changed``: pass/fail/info changed (a check that was information and is now
  gated is listed here, not under ``grown``);
- ``new`` and ``vanished`` checks; ``versions_changed`` (engines and libraries of
  summary.json's ``run.versions``) and the commit;
- ``mode_changed``: --quick, --only or the models differ, so the runs are not like for
  like.

The diff is information for a reader; it never changes the exit status.  A missing or
unreadable previous report gives a diff with ``previous`` None and a one-line ``note``.
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Mapping, Optional

import numpy as np
import pandas as pd

from . import strict_json

GROWTH_FACTOR = 10.0
RATIO_FLOOR = 1e-6
DEFINITION = ("error/tolerance = abs_error / (tol_abs + tol_rel * scale) of the check's worst "
              f"row; listed when it grew more than {GROWTH_FACTOR:g}x, ratios below "
              f"{RATIO_FLOOR:g} counting as {RATIO_FLOOR:g} (round-off noise; a previous 0 "
              "is compared as that floor); information checks (no finite tolerance) are not "
              "compared for growth")
SUMMARY_FILE = "summary.json"


def row_tolerances(rows: pd.DataFrame) -> pd.Series:
    """(len(rows),) tol_abs + tol_rel * scale of each comparison row (the quantity's unit;
    inf for an information row).  tol_rel = 0 needs no scale: 0 * NaN would hide an
    absolute-only tolerance."""
    tol_abs, tol_rel = rows["tol_abs"].astype(float), rows["tol_rel"].astype(float)
    scale = rows["scale"].astype(float) if "scale" in rows else np.nan
    return tol_abs + pd.Series(np.where(tol_rel == 0, 0.0, tol_rel * scale), index=rows.index)


def row_ratios(rows: pd.DataFrame) -> pd.Series:
    """(len(rows),) error over tolerance of each comparison row (NaN for an information row
    or a row whose tolerance cannot be evaluated); see the module docstring."""
    err = rows["abs_error"].astype(float).to_numpy()
    budget = row_tolerances(rows).to_numpy()
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = err / budget
    ratio = np.where(budget == 0, np.where(err == 0, 0.0, np.inf), ratio)
    ratio = np.where(np.isnan(err) | (err == np.inf), np.inf, ratio)   # a NaN/inf value fails
    ratio = np.where(np.isinf(budget) | np.isnan(budget), np.nan, ratio)  # information
    return pd.Series(ratio, index=rows.index, dtype=float)


def check_ratios(rows: pd.DataFrame, keys=("engine", "section", "model", "quantity")
                 ) -> pd.DataFrame:
    """One row per check (``keys``): ``error_over_tolerance`` (the largest row ratio, NaN for
    an information-only check) and ``tolerance`` (tol_abs + tol_rel * scale of that row, in
    the quantity's unit)."""
    frame = rows[list(keys)].assign(error_over_tolerance=row_ratios(rows),
                                    tolerance=row_tolerances(rows))
    out = []
    for key, g in frame.groupby(list(keys), sort=False, dropna=False):
        gated = g["error_over_tolerance"].dropna()
        if len(gated):
            worst = g.loc[gated.idxmax()]
            out.append((*key, float(worst["error_over_tolerance"]), float(worst["tolerance"])))
        else:
            out.append((*key, math.nan, math.nan))
    return pd.DataFrame(out, columns=[*keys, "error_over_tolerance", "tolerance"])


def load_previous(path: Path | str) -> tuple[Optional[dict], Optional[str]]:
    """(summary.json document, None), or (None, one-line reason) when ``path`` (a report
    directory or its summary.json) holds no readable gpme summary."""
    path = Path(path)
    file = path / SUMMARY_FILE if path.is_dir() else path
    try:
        data = strict_json.loads(file.read_text(encoding="utf-8"))
    except FileNotFoundError:
        return None, f"previous report {path} has no {SUMMARY_FILE}: nothing to compare with"
    except (OSError, UnicodeDecodeError) as exc:
        return None, f"previous report {file} unreadable ({exc}): nothing compared"
    except ValueError as exc:
        return None, f"previous report {file} is not valid JSON ({exc}): nothing compared"
    if not (isinstance(data, dict) and isinstance(data.get("checks"), list)
            and all(isinstance(c, dict) and isinstance(c.get("name"), str)
                    for c in data["checks"])):
        return None, (f"previous report {file} is not a gpme verify summary (no list of "
                      "named checks): nothing compared")
    return data, None


def _ratio(check: Mapping[str, Any]) -> Optional[float]:
    value = check.get("error_over_tolerance")
    if isinstance(value, (int, float)) and not isinstance(value, bool) and value == value:
        return float(value)
    return None


def _floored(r: float) -> float:
    return max(r, RATIO_FLOOR)


def _run(doc: Mapping[str, Any]) -> Mapping[str, Any]:
    run = doc.get("run")
    return run if isinstance(run, dict) else {}


def diff_summaries(previous: Optional[Mapping[str, Any]], current: Mapping[str, Any],
                   source: str = "", note: Optional[str] = None) -> dict:
    """The diff (a JSON-ready dict, see the module docstring) of ``current`` against
    ``previous`` (summary.json documents; None: nothing to compare, ``note`` says why).
    ``source`` names where the previous report was found."""
    out: dict[str, Any] = {"definition": DEFINITION, "growth_factor": GROWTH_FACTOR,
                           "ratio_floor": RATIO_FLOOR, "previous": None, "note": note,
                           "compared": 0, "grown": [], "status_changed": [], "new": [],
                           "vanished": [], "versions_changed": {}, "commit_changed": None,
                           "mode_changed": []}
    if previous is None:
        return out
    prun, crun = _run(previous), _run(current)
    out["previous"] = {"source": source, "run_id": prun.get("run_id"),
                       "date_utc": prun.get("date_utc"), "git_commit": prun.get("git_commit"),
                       "passed": previous.get("passed")}
    before = {c["name"]: c for c in previous["checks"]}
    now = {c["name"]: c for c in current["checks"]}
    out["new"] = [n for n in now if n not in before]
    out["vanished"] = [n for n in before if n not in now]
    common = [n for n in now if n in before]
    out["compared"] = len(common)
    without_ratio = 0
    for name in common:
        b, c = before[name], now[name]
        if b.get("status") != c.get("status"):
            out["status_changed"].append({"check": name, "previous": b.get("status"),
                                          "current": c.get("status")})
        rb, rc = _ratio(b), _ratio(c)
        if rb is None or rc is None:
            without_ratio += int(b.get("status") != "info" and c.get("status") != "info")
            continue
        if _floored(rc) > GROWTH_FACTOR * _floored(rb):
            factor = _floored(rc) / _floored(rb)
            out["grown"].append({"check": name, "previous": rb, "current": rc,
                                 "factor": factor, "status": c.get("status")})
    out["grown"].sort(key=lambda g: -g["factor"])
    if without_ratio:
        out["note"] = (f"{without_ratio} gated check(s) of the previous report carry no "
                       "error/tolerance (a report from an older gpme): not compared for growth")
    pv, cv = prun.get("versions") or {}, crun.get("versions") or {}
    out["versions_changed"] = {k: [pv.get(k), cv.get(k)] for k in sorted(set(pv) | set(cv))
                               if pv.get(k) != cv.get(k)}
    if prun.get("git_commit") != crun.get("git_commit"):
        out["commit_changed"] = [prun.get("git_commit"), crun.get("git_commit")]
    for key, label in (("quick", "--quick"), ("only", "--only")):
        if prun.get(key) != crun.get(key):
            out["mode_changed"].append(f"{label}: {_mode(key, prun.get(key))} before, "
                                       f"{_mode(key, crun.get(key))} now")
    models = [_model_names(doc) for doc in (previous, current)]
    if None not in models and models[0] != models[1]:
        out["mode_changed"].append(f"models: {', '.join(models[0]) or 'none'} before, "
                                   f"{', '.join(models[1]) or 'none'} now")
    return out


def _model_names(doc: Mapping[str, Any]) -> Optional[list[str]]:
    """Names of the models a summary.json records (None when it records none)."""
    models = doc.get("models")
    if not isinstance(models, list):
        return None
    return [str(m.get("name")) if isinstance(m, dict) else str(m) for m in models]


def _mode(key: str, value: Any) -> str:
    if key == "quick":
        return "quick" if value else "full"
    return value if value else "all steps"


def _fmt(x: Optional[float]) -> str:
    if x is None:
        return "-"
    if math.isinf(x):
        return "inf"
    return f"{x:.3g}"


def headline(diff: Mapping[str, Any]) -> str:
    """One line: against which run, and how many changes of each kind."""
    prev = diff.get("previous")
    if prev is None:
        return f"diff against the previous run: {diff.get('note') or 'no previous run'}"
    parts = [f"{len(diff['grown'])} check(s) with error/tolerance grown >"
             f"{diff['growth_factor']:g}x",
             f"{len(diff['status_changed'])} status change(s)",
             f"{len(diff['new'])} new", f"{len(diff['vanished'])} vanished",
             f"{len(diff['versions_changed'])} version change(s)"]
    when = f"{prev['date_utc']}, " if prev.get("date_utc") else ""
    return (f"against {prev.get('run_id') or prev.get('source')} ({when}{diff['compared']} "
            f"checks compared): " + ", ".join(parts))


def diff_lines(diff: Mapping[str, Any], limit: int = 20) -> list[str]:
    """Plain-text lines for the console: the headline, then each change (at most ``limit``
    per list)."""
    lines = [headline(diff)]
    if diff.get("previous") is None:
        return lines
    if diff.get("note"):
        lines.append(f"  note: {diff['note']}")
    for m in diff["mode_changed"]:
        lines.append(f"  not like for like: {m}")
    for g in diff["grown"][:limit]:
        lines.append(f"  grew {_fmt(g['factor'])}x: {g['check']} (error/tolerance "
                     f"{_fmt(g['previous'])} -> {_fmt(g['current'])}, {g['status']})")
    for s in diff["status_changed"][:limit]:
        lines.append(f"  {s['previous']} -> {s['current']}: {s['check']}")
    for key in ("new", "vanished"):
        names = diff[key]
        for n in names[:limit]:
            lines.append(f"  {key}: {n}")
        if len(names) > limit:
            lines.append(f"  ... and {len(names) - limit} more {key} (summary.json: diff)")
    for k, (a, b) in diff["versions_changed"].items():
        lines.append(f"  version of {k}: {a} -> {b}")
    if diff.get("commit_changed"):
        a, b = diff["commit_changed"]
        lines.append(f"  commit: {a} -> {b}")
    return lines
