"""A short markdown summary of a `gpme verify` run (``--summary-md``), for a CI job summary
(GitHub's $GITHUB_STEP_SUMMARY, a merge-request note).

Built from the run's summary.json document alone: the verdict first, the pass/fail/info
counts, the failed checks with their discrepancy, tolerance and reason, the warnings, the
diff against the previous run, the engine versions and the path of index.html.  A passing
run fits one screen; long lists are cut at MAX_ROWS with the count of the rest.  Every
name and reason is escaped (a quantity such as ``|Phi_1|`` would otherwise break a table).
"""
from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any, Mapping, Optional

from gpme_io.atomic import atomic_write_text

from .run_diff import headline

MAX_ROWS = 20
# backslash-escaped: emphasis, code, links, HTML and table pipes (an underscore inside a
# name such as psi3_0 is no emphasis in GitHub's markdown and stays as it is)
_MD_SPECIAL = re.compile(r"([\\`*\[\]<|])")


def md_escape(text: Any) -> str:
    """``text`` on one line with markdown's punctuation backslash-escaped."""
    return _MD_SPECIAL.sub(r"\\\1", " ".join(str(text).split()))


def _code(text: Any, table: bool = False) -> str:
    """A code span (names of checks: no emphasis inside); in a table cell its pipes escaped
    (GitHub reads a backslash-escaped pipe in a table cell as a pipe, but elsewhere shows
    the backslash)."""
    span = " ".join(str(text).replace("`", "'").split())
    return "`" + (span.replace("|", "\\|") if table else span) + "`"


def _num(x: Optional[float]) -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "-"
    return "inf" if math.isinf(x) else f"{x:.3g}"


def _cut(items: list, what: str) -> tuple[list, str]:
    if len(items) <= MAX_ROWS:
        return items, ""
    return items[:MAX_ROWS], f"\n... and {len(items) - MAX_ROWS} more {what} (summary.json)\n"


def _failed_section(failed: list) -> list[str]:
    shown, more = _cut(failed, "failed checks")
    lines = ["", "### Failed checks", "",
             "| check | abs error | tolerance | error/tolerance | where | reason |",
             "|---|---:|---:|---:|---|---|"]
    for c in shown:
        where = ", ".join(str(c[k]) for k in ("worst_case", "worst_entry")
                          if c.get(k) not in (None, "", "-"))
        if c.get("crashed"):
            tol, ratio = "step crashed", "-"
        else:
            tol = (f"{_num(c.get('tol_abs'))} + {_num(c.get('tol_rel'))} × scale"
                   + (f" = {_num(c.get('tolerance'))}" if c.get("tolerance") is not None else ""))
            ratio = _num(c.get("error_over_tolerance"))
        lines.append(f"| {_code(c['name'], table=True)} | {_num(c.get('worst_abs_error'))} | "
                     f"{tol} | {ratio} | {md_escape(where) or '-'} | "
                     f"{md_escape(c.get('reason') or '')} |")
    return lines + ([more] if more else [])


def diff_markdown(diff: Optional[Mapping[str, Any]]) -> list[str]:
    """The "against the run before this one" section (lines)."""
    lines = ["", "### Against the run before this one", ""]
    if not diff:
        return lines + ["No diff recorded in this report."]
    if diff.get("previous") is None:
        return lines + [md_escape(diff.get("note") or "No previous run to compare with.")]
    lines.append(md_escape(headline(diff)))
    lines.append("")
    if diff.get("note"):
        lines.append(f"- note: {md_escape(diff['note'])}")
    for m in diff.get("mode_changed", []):
        lines.append(f"- not like for like: {md_escape(m)}")
    grown, more = _cut(list(diff.get("grown", [])), "grown checks")
    for g in grown:
        lines.append(f"- error/tolerance grew {_num(g['factor'])}x: {_code(g['check'])} "
                     f"({_num(g['previous'])} → {_num(g['current'])}, now {g['status']})")
    if more:
        lines.append(f"- {md_escape(more.strip())}")
    for s in diff.get("status_changed", [])[:MAX_ROWS]:
        lines.append(f"- {s['previous']} → {s['current']}: {_code(s['check'])}")
    for key in ("new", "vanished"):
        names = list(diff.get(key, []))
        if names:
            shown = ", ".join(_code(n) for n in names[:MAX_ROWS])
            rest = f" and {len(names) - MAX_ROWS} more" if len(names) > MAX_ROWS else ""
            lines.append(f"- {key} checks ({len(names)}): {shown}{rest}")
    for k, (a, b) in diff.get("versions_changed", {}).items():
        lines.append(f"- {md_escape(k)}: {md_escape(a)} → {md_escape(b)}")
    if diff.get("commit_changed"):
        a, b = diff["commit_changed"]
        lines.append(f"- commit: `{a}` → `{b}`")
    if lines[-1] == "":
        lines.append("Nothing changed: same checks, no error/tolerance grew "
                     f">{diff.get('growth_factor', 10):g}x, same versions.")
    return lines


def summary_markdown(summary: Mapping[str, Any], index_path: str = "index.html") -> str:
    """The markdown text of a summary.json document; ``index_path`` is the report page as
    the reader should find it (a path in the job's artifact)."""
    checks = summary["checks"]
    run = summary.get("run") or {}
    status = [c.get("status") for c in checks]
    n_fail, n_pass, n_info = status.count("fail"), status.count("pass"), status.count("info")
    verdict = "PASSED: no check failed" if n_fail == 0 else \
        f"FAILED: {n_fail} of {len(checks)} checks failed"
    models = ", ".join(md_escape(m.get("name", "?")) for m in summary.get("models", [])) or "-"
    commit = str(run.get("git_commit", "unknown"))
    lines = [f"## gpme verify {'✅' if n_fail == 0 else '❌'} {verdict}", "",
             f"**{n_pass} passed, {n_fail} failed, {n_info} information only** (not gated, "
             f"never counted as a pass) of {len(checks)} checks; "
             f"{'quick' if run.get('quick') else 'full'} run"
             + (f" (--only {md_escape(run['only'])})" if run.get("only") else "")
             + (f", {run['wall_time_s']:.0f} s" if isinstance(run.get("wall_time_s"), (int, float))
                else "")
             + f", commit `{commit[:12]}{'-dirty' if commit.endswith('-dirty') else ''}`.",
             "", f"Models: {models}."]
    failed = [c for c in checks if c.get("status") == "fail"]
    if failed:
        lines += _failed_section(failed)
    warnings = list(summary.get("warnings") or [])
    if warnings:
        shown, more = _cut(warnings, "warnings")
        lines += ["", "### Warnings", ""] + [f"- {md_escape(w)}" for w in shown] + \
            ([more] if more else [])
    lines += diff_markdown(summary.get("diff"))
    versions = run.get("versions") or {}
    lines += ["", "Versions: " + ", ".join(f"{md_escape(k)} {md_escape(v)}"
                                            for k, v in versions.items()) + ".",
              "", f"Report: `{index_path}` (summary.json, summary.csv and each check's "
                  "comparison rows in checks/ beside it)."]
    return "\n".join(lines) + "\n"


def write_summary_md(path: Path | str, summary: Mapping[str, Any],
                     index_path: str = "index.html") -> Path:
    """Write the markdown summary to ``path`` atomically; returns the path."""
    atomic_write_text(path, summary_markdown(summary, index_path))
    return Path(path)
