"""JUnit XML of a `gpme verify` run (``--junit-xml``), for the test-report views of CI systems.

Built from the run's summary.json document alone, through ElementTree (every name and
reason escaped), in the dialect of Jenkins' xunit plugin schema junit-10.xsd
(tests/data/junit/, validated in tests/test_junit.py), which GitLab's and the GitHub
test-report actions' parsers read too:

- root ``<testsuites name="gpme verify" tests failures errors time>`` (time: the run's
  wall time in s);
- one ``<testsuite>`` per engine and model (``name="engine: model"``, tests, failures,
  errors, skipped, timestamp, hostname, ``time`` = the engine step's wall time when the
  engine checked this one model only, else absent: per-model times are not measured),
  with ``<properties>`` (engine and library versions, commit, mode, the step's time);
- one ``<testcase>`` per check (a row of summary.csv): ``classname="gpme.<engine>.<model>"``
  (model reduced to letters, digits and _), ``name="<section>: <quantity>"``; a failed
  check holds ``<failure>`` whose message carries the worst row's error, the tolerance
  (tol_abs + tol_rel x scale = its value), error/tolerance and where (case, entry), and
  whose text the tolerance's reason; an information check (no finite tolerance) is
  ``<skipped>`` with its reason, never a pass; a crashed step is ``<error>`` naming the
  exception and the traceback file; a passed check carries its numbers in
  ``<system-out>``.
"""
from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any, Iterable, Mapping, Optional

from gpme_io.atomic import atomic_write_bytes
from gpme_io.xml_text import make_tree_safe, xml_safe_text

_NOT_NAME = re.compile(r"[^A-Za-z0-9_]+")
ROOT_NAME = "gpme verify"


def _text(value: Any) -> str:
    """``value`` as text XML can hold (a control character from a traceback, say, shown as
    its escape ``\\x1b``; gpme_io.xml_text)."""
    return xml_safe_text(str(value))


def _line(value: Any) -> str:
    """One line of text for an attribute."""
    return " ".join(_text(value).split())


def _num(x: Optional[float]) -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "n/a"
    return "inf" if math.isinf(x) else f"{x:.3g}"


def _count(n: Any, noun: str) -> str:
    return f"{n} {noun}" + ("" if n == 1 else "s") if n is not None else f"? {noun}s"


def _seconds(t: Optional[float]) -> Optional[str]:
    """s with 3 decimals (the SUREFIRE_TIME pattern of junit-10.xsd allows no more)."""
    if t is None or not math.isfinite(t) or t < 0:
        return None
    return f"{t:.3f}"


def classname(engine: str, model: str) -> str:
    """``gpme.<engine>.<model>`` with each name reduced to letters, digits and _ (a dot would
    split Jenkins' package/class tree)."""
    return ".".join(["gpme"] + [_NOT_NAME.sub("_", part).strip("_") or "_"
                                for part in (engine, model)])


def _where(check: Mapping[str, Any]) -> str:
    parts = [f"{k} {check[key]}" for k, key in (("case", "worst_case"), ("entry", "worst_entry"))
             if check.get(key) not in (None, "", "-")]
    return ", ".join(parts) if parts else "where not recorded"


def _tolerance(check: Mapping[str, Any]) -> str:
    text = f"tol_abs {_num(check.get('tol_abs'))} + tol_rel {_num(check.get('tol_rel'))} x scale"
    if check.get("tolerance") is not None:
        text += f" = {_num(check.get('tolerance'))}"
    return text


def failure_message(check: Mapping[str, Any]) -> str:
    """One line: the worst discrepancy, the tolerance, error/tolerance and where."""
    return (f"abs error {_num(check.get('worst_abs_error'))} (rel "
            f"{_num(check.get('worst_rel_error'))}) > tolerance {_tolerance(check)}; "
            f"error/tolerance {_num(check.get('error_over_tolerance'))}; at {_where(check)}; "
            f"{check.get('n_fail', '?')} of {_count(check.get('n_compared'), 'comparison')} "
            "failed")


def _testcase(parent: ET.Element, check: Mapping[str, Any], report_dir: str) -> str:
    """Append the check's <testcase>; returns its outcome (pass, fail, error, info)."""
    case = ET.SubElement(parent, "testcase", {
        "name": _line(f"{check.get('section') or 'terms'}: {check['quantity']}"),
        "classname": classname(check["engine"], check["model"])})
    reason = _text(check.get("reason") or "")
    if check.get("crashed"):
        trace = f"{report_dir}/{check['engine']}_crash.txt" if report_dir else \
            f"{check['engine']}_crash.txt"
        el = ET.SubElement(case, "error", {"type": _line(check.get("worst_entry") or "Error"),
                                           "message": _line(reason)[:500]})
        el.text = (f"the {check['engine']} step crashed: {reason}\nIf it was not a gpme input "
                   f"or run error, its traceback is in {trace}.")
        return "error"
    status = check.get("status")
    if status == "fail":
        abs_err = check.get("worst_abs_error")
        kind = "NonFiniteValue" if abs_err is None or not math.isfinite(abs_err) \
            else "ToleranceExceeded"
        el = ET.SubElement(case, "failure",
                           {"type": kind, "message": _line(failure_message(check))})
        el.text = f"{failure_message(check)}\nreason for the tolerance: {reason}"
        return "fail"
    if status == "info":
        ET.SubElement(case, "skipped", {"message": _line(
            f"information only (no finite tolerance, not gated): {reason}")}).text = (
            f"value {_num(check.get('worst_abs_error'))} at {_where(check)}; {reason}")
        return "info"
    out = ET.SubElement(case, "system-out")
    out.text = (f"abs error {_num(check.get('worst_abs_error'))} (rel "
                f"{_num(check.get('worst_rel_error'))}) <= tolerance {_tolerance(check)}; "
                f"error/tolerance {_num(check.get('error_over_tolerance'))}; "
                f"{_count(check.get('n_compared'), 'comparison')}; reason: {reason}")
    return "pass"


def _timestamp(run: Mapping[str, Any]) -> Optional[str]:
    """ISO 8601 without time zone (as JUnit readers expect), from run.date_utc."""
    m = re.match(r"(\d{4}-\d{2}-\d{2})[ T](\d{2}:\d{2}:\d{2})", str(run.get("date_utc", "")))
    return f"{m.group(1)}T{m.group(2)}" if m else None


def _properties(parent: ET.Element, items: Iterable[tuple[str, Any]]) -> None:
    props = ET.SubElement(parent, "properties")
    for name, value in items:
        if value is not None:
            ET.SubElement(props, "property", {"name": _line(name), "value": _line(value)})


def junit_tree(summary: Mapping[str, Any], report_dir: str = "") -> ET.Element:
    """The <testsuites> element of a summary.json document (see the module docstring);
    ``report_dir`` is the run directory as the reader should see it (for the crash files)."""
    run = summary.get("run") or {}
    step_times = run.get("step_times_s") or {}
    versions = run.get("versions") or {}
    checks = summary["checks"]
    groups: dict[tuple[str, str], list] = {}
    for check in checks:
        groups.setdefault((check["engine"], check["model"]), []).append(check)
    models_per_engine: dict[str, int] = {}
    for engine, _ in groups:
        models_per_engine[engine] = models_per_engine.get(engine, 0) + 1
    root = ET.Element("testsuites", {"name": ROOT_NAME})
    totals = {"tests": 0, "fail": 0, "error": 0}
    for k, ((engine, model), group) in enumerate(groups.items()):
        suite = ET.SubElement(root, "testsuite", {"name": _line(f"{engine}: {model}")})
        _properties(suite, [("engine", engine), ("model", model),
                            ("mode", "quick" if run.get("quick") else "full"),
                            ("git_commit", run.get("git_commit")),
                            ("step_time_s", _seconds(step_times.get(engine))),
                            *((f"version {name}", v) for name, v in versions.items())])
        outcomes = [_testcase(suite, check, report_dir) for check in group]
        counts = {o: outcomes.count(o) for o in ("fail", "error", "info")}
        attrs = {"tests": len(outcomes), "failures": counts["fail"], "errors": counts["error"],
                 "skipped": counts["info"], "id": k, "package": classname(engine, model),
                 "timestamp": _timestamp(run),
                 "hostname": (run.get("machine") or {}).get("node") or "localhost"}
        if models_per_engine[engine] == 1:
            attrs["time"] = _seconds(step_times.get(engine))
        suite.attrib.update({key: _line(v) for key, v in attrs.items() if v is not None})
        totals["tests"] += len(outcomes)
        totals["fail"] += counts["fail"]
        totals["error"] += counts["error"]
    root.attrib.update({"tests": str(totals["tests"]), "failures": str(totals["fail"]),
                        "errors": str(totals["error"])})
    total_time = _seconds(run.get("wall_time_s"))
    if total_time is not None:
        root.set("time", total_time)
    return make_tree_safe(root)       # names of engines, models, cases and entries included


def junit_xml(summary: Mapping[str, Any], report_dir: str = "") -> bytes:
    """The JUnit document (UTF-8 bytes with its XML declaration)."""
    root = junit_tree(summary, report_dir)
    ET.indent(root)
    return ET.tostring(root, encoding="utf-8", xml_declaration=True) + b"\n"


def write_junit_xml(path: Path | str, summary: Mapping[str, Any], report_dir: str = "") -> Path:
    """Write the JUnit XML of ``summary`` to ``path`` atomically; returns the path."""
    atomic_write_bytes(path, junit_xml(summary, report_dir))
    return Path(path)
