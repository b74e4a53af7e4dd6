"""`gpme verify`: the command around crosscheck.verify (its flags' problems, the model files,
the cost estimate, the run, what is printed and the exit status: docs/ci.md)."""
import sys
from pathlib import Path

import pandas as pd

from crosscheck import verify, verify_steps
from crosscheck.engines import missing_message
from crosscheck.mujoco.names import scenario_name_problems   # MuJoCo itself not loaded
from crosscheck.reports import run_diff, strict_json
from gpme_core.errors import GpmeError
from gpme_io.budget import wall_limit
from gpme_io.modelfile import load_model_files
from gpme_io.out_lock import output_file_problem


def compare_to_problem(path):
    """Why ``--compare-to path`` names no report (None when it does; a report whose
    summary.json turns out unreadable is said in one line of the diff, not refused)."""
    text = str(path)
    valid = ("give a gpme verify report directory (e.g. reports/<run-id>, holding "
             "summary.json) or its summary.json")
    if not text.strip():
        return f"--compare-to is empty; {valid}"
    target = Path(text)
    if not target.exists():
        return f"--compare-to {text!r} does not exist; {valid}"
    if target.is_dir() and not (target / run_diff.SUMMARY_FILE).is_file():
        return f"--compare-to {text!r} holds no {run_diff.SUMMARY_FILE}; {valid}"
    return None


def flag_problems(args):
    """Every problem of verify's report flags (--junit-xml, --summary-md, --compare-to)."""
    problems = []
    outputs = {flag: getattr(args, attr, None) for flag, attr in
               (("--junit-xml", "junit_xml"), ("--summary-md", "summary_md"))}
    for (flag, value), example in zip(outputs.items(), ("gpme-junit.xml", "gpme-summary.md")):
        if value is not None:
            problem = output_file_problem(value, flag, example)
            if problem:
                problems.append(problem)
    values = [v for v in outputs.values() if v is not None and str(v).strip()]
    if len(values) == 2 and Path(values[0]).resolve() == Path(values[1]).resolve():
        problems.append(f"--junit-xml and --summary-md both name {values[0]!r}; give each "
                        "its own file")
    if getattr(args, "compare_to", None) is not None:
        problem = compare_to_problem(args.compare_to)
        if problem:
            problems.append(problem)
    return problems


def _print_problems(problems):
    if len(problems) == 1:
        print(f"error: {problems[0]}", file=sys.stderr)
    else:
        print(f"error: {len(problems)} problems on the command line:\n" +
              "\n".join(f"  - {p}" for p in problems), file=sys.stderr)


def _number(v):
    return "-" if v is None or v != v else f"{v:.3e}"


def terminal_table(summary, status):
    """The check table `gpme verify` prints: per check its status, the worst absolute and
    relative error and the tolerance they are judged by; an information check shows its
    value instead (its error is 0 by construction) and no tolerance."""
    info = status == "info"
    return pd.DataFrame({
        "engine": summary["engine"], "section": summary["section"], "model": summary["model"],
        "quantity": summary["quantity"], "n": summary["n_compared"],
        "worst |error|": [f"value {_number(v)}" if i else _number(e) for i, e, v in
                          zip(info, summary["worst_abs_error"], summary["value"])],
        "rel error": ["-" if i else _number(e) for i, e in zip(info, summary["worst_rel_error"])],
        "tolerance": ["-" if i else _number(t) for i, t in zip(info, summary["tolerance"])],
        "status": status})


def main(args, problems=()):
    """`gpme verify`: ``problems`` found by the caller (--out, --keep) are listed with the
    report flags' and the model files' in one message (exit 2)."""
    scenarios = None
    problems = list(problems) + flag_problems(args)
    if getattr(args, "model", None):
        try:
            scenarios = load_model_files(args.model)
            if getattr(args, "only", None) in (None, "mujoco"):
                scenario_name_problems(scenarios)     # names MuJoCo's MJCF cannot take
        except GpmeError as exc:
            problems.append(str(exc))
    only = verify.STEP_ALIASES.get(getattr(args, "only", None), getattr(args, "only", None))
    if only in verify_steps.OPTIONAL_STEPS and missing_message(only):
        problems.append(f"--only {only}: {missing_message(only)}")
    if problems:
        _print_problems(problems)
        return 2
    try:
        verify.estimate_runs(scenarios, args.quick, getattr(args, "force", False))
    except GpmeError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    run_dir, summary, _ = verify.run_verify(args.out, quick=args.quick, only=args.only,
                                     progress=not args.no_progress, scenarios=scenarios,
                                     keep=getattr(args, "keep", None),
                                     max_wall_s=wall_limit(getattr(args, "force", False)),
                                     compare_to=getattr(args, "compare_to", None),
                                     workers=getattr(args, "workers", None) or 1,
                                     scheduler=getattr(args, "scheduler", None))
    status = summary.apply(verify.check_status, axis=1)
    with pd.option_context("display.width", 250, "display.max_rows", 500):
        print(terminal_table(summary, status).to_string(index=False))
    n_fail = int(verify.failed_checks(summary).sum())
    n_pass, n_info = int((status == "pass").sum()), int((status == "info").sum())
    document = strict_json.loads((run_dir / "summary.json").read_text(encoding="utf-8"))
    for path in verify.write_ci_outputs(run_dir, document, getattr(args, "junit_xml", None),
                                 getattr(args, "summary_md", None)):
        print(f"wrote {path}")
    print("\n".join(run_diff.diff_lines(document["diff"])))
    print(f"{len(summary)} checks: {n_pass} passed, {n_fail} failed, {n_info} information "
          f"only (not gated); report: {run_dir / 'index.html'}")
    return 1 if n_fail else 0
