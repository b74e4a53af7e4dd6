"""The diff of a verify run against the previous one (crosscheck.reports.run_diff), on
synthetic summary.json documents; the end-to-end diff of two real runs is in
tests/test_verify.py."""
import copy
import json
import math

import numpy as np
import pandas as pd
import pytest

from crosscheck.reports import run_diff

INF, NAN = math.inf, math.nan


@pytest.mark.parametrize("abs_error, tol_abs, tol_rel, scale, expected", [
    (1e-9, 1e-8, 0.0, NAN, 0.1),              # absolute only: no scale needed
    (2e-9, 1e-8, 1e-6, 0.01, 2e-9 / 2e-8),    # abs + rel * scale
    (0.0, 0.0, 0.0, 1.0, 0.0),                # zero tolerance, exact
    (1e-20, 0.0, 0.0, 1.0, INF),              # zero tolerance, any error
    (INF, 1e-8, 0.0, 1.0, INF),               # a NaN or infinite value (abs_error = inf)
    (NAN, 1e-8, 0.0, 1.0, INF),
    (1.0, INF, 0.0, 1.0, NAN),                # information row: no ratio
], ids=["abs-only", "abs-plus-rel", "zero-tol-exact", "zero-tol-error", "inf-error",
        "nan-error", "information"])
def test_row_ratio(abs_error, tol_abs, tol_rel, scale, expected):
    rows = pd.DataFrame({"abs_error": [abs_error], "tol_abs": [tol_abs], "tol_rel": [tol_rel],
                         "scale": [scale]})
    got = run_diff.row_ratios(rows).iloc[0]
    if math.isnan(expected):
        assert math.isnan(got)
    else:
        assert got == pytest.approx(expected, rel=1e-12)


def test_check_ratio_is_the_worst_row_and_its_tolerance():
    rows = pd.DataFrame({
        "engine": ["e"] * 4, "section": ["s"] * 4, "model": ["m"] * 4,
        "quantity": ["M", "M", "M", "wall time"],
        "abs_error": [1e-9, 5e-9, 1e-3, 0.2], "tol_abs": [1e-8, 1e-8, 1.0, INF],
        "tol_rel": [0.0, 1e-6, 0.0, 0.0], "scale": [2.0, 10.0, 1.0, 1.0]})
    out = run_diff.check_ratios(rows).set_index("quantity")
    # row 2: 5e-9 / (1e-8 + 1e-6 * 10) = 5e-9 / 1.001e-5 is below row 1's 0.1 and row 3's 1e-3
    assert out.loc["M", "error_over_tolerance"] == pytest.approx(0.1)
    assert out.loc["M", "tolerance"] == pytest.approx(1e-8)
    assert math.isnan(out.loc["wall time", "error_over_tolerance"])


def _check(name, ratio, status="pass"):
    return {"name": name, "engine": name.split("/")[0], "status": status,
            "error_over_tolerance": ratio}


def _doc(checks, versions=None, commit="aaa", quick=True, only=None, run_id="run-1"):
    return {"run": {"run_id": run_id, "date_utc": "2026-01-01 00:00:00 UTC",
                    "git_commit": commit, "quick": quick, "only": only,
                    "versions": versions or {"gpme": "0.1.0", "mujoco": "3.2.0"}},
            "passed": True, "checks": checks}


PREVIOUS = _doc([_check("p/terms/arm/M", 1e-3), _check("p/terms/arm/g", 1e-3),
                 _check("p/terms/arm/h", 0.0), _check("p/terms/arm/Phi", 0.0),
                 _check("m/runs/arm/q", 0.5), _check("m/runs/arm/wall", None, "info"),
                 _check("m/runs/arm/order", None, "info"), _check("p/terms/arm/gone", 0.1)])
CURRENT = _doc([_check("p/terms/arm/M", 5e-2),          # 50x: listed
                _check("p/terms/arm/g", 9e-3),          # 9x: not listed
                _check("p/terms/arm/h", 2e-5),          # 0 -> 2e-5: 20x the floor, listed
                _check("p/terms/arm/Phi", 1e-7),        # 0 -> 1e-7: below the floor
                _check("m/runs/arm/q", 7.0, "fail"),    # 14x and now failing
                _check("m/runs/arm/wall", None, "info"),
                _check("m/runs/arm/order", 0.3),        # info -> gated: a status change
                _check("p/terms/arm/new", 0.2)],
               versions={"gpme": "0.1.0", "mujoco": "3.3.0", "sympy": "1.13"},
               commit="bbb", run_id="run-2")


def test_diff_of_two_summaries():
    d = run_diff.diff_summaries(PREVIOUS, CURRENT, source="reports/run-1")
    assert d["previous"]["run_id"] == "run-1" and d["previous"]["source"] == "reports/run-1"
    assert d["compared"] == 7
    assert [g["check"] for g in d["grown"]] == ["p/terms/arm/M", "p/terms/arm/h",
                                                "m/runs/arm/q"]
    assert [g["factor"] for g in d["grown"]] == pytest.approx([50.0, 20.0, 14.0])
    assert d["grown"][2]["status"] == "fail"
    assert {(s["check"], s["previous"], s["current"]) for s in d["status_changed"]} == {
        ("m/runs/arm/q", "pass", "fail"), ("m/runs/arm/order", "info", "pass")}
    assert d["new"] == ["p/terms/arm/new"] and d["vanished"] == ["p/terms/arm/gone"]
    assert d["versions_changed"] == {"mujoco": ["3.2.0", "3.3.0"], "sympy": [None, "1.13"]}
    assert d["commit_changed"] == ["aaa", "bbb"]
    assert d["mode_changed"] == [] and d["note"] is None
    json.dumps(d, allow_nan=False)          # plain JSON: goes into summary.json as it is


def test_a_run_against_itself_lists_nothing():
    d = run_diff.diff_summaries(PREVIOUS, PREVIOUS)
    assert (d["grown"], d["status_changed"], d["new"], d["vanished"], d["versions_changed"],
            d["commit_changed"], d["mode_changed"]) == ([], [], [], [], {}, None, [])
    assert "0 check(s) with error/tolerance grown >10x" in run_diff.headline(d)


def test_a_failure_growing_to_infinity_is_listed():
    cur = copy.deepcopy(PREVIOUS)
    cur["checks"][0]["error_over_tolerance"] = INF       # a NaN appeared
    d = run_diff.diff_summaries(PREVIOUS, cur)
    assert d["grown"][0]["check"] == "p/terms/arm/M" and math.isinf(d["grown"][0]["current"])
    assert "grew infx" in "\n".join(run_diff.diff_lines(d))


def test_modes_that_differ_are_said():
    cur = copy.deepcopy(CURRENT)
    cur["run"].update(quick=False, only="gpme")
    prev = dict(PREVIOUS, models=[{"name": "crane_rigid"}, {"name": "crane_flexible_n3"}])
    cur["models"] = [{"name": "my_arm"}]
    d = run_diff.diff_summaries(prev, cur)
    assert d["mode_changed"] == ["--quick: quick before, full now",
                                 "--only: all steps before, gpme now",
                                 "models: crane_rigid, crane_flexible_n3 before, my_arm now"]
    assert any("not like for like: --quick" in line for line in run_diff.diff_lines(d))


def test_previous_report_without_ratios_is_said_not_compared():
    old = copy.deepcopy(PREVIOUS)
    for c in old["checks"]:
        c.pop("error_over_tolerance")
    d = run_diff.diff_summaries(old, CURRENT)
    assert d["grown"] == []
    # M, g, h, Phi, q (wall and order were information before)
    assert "5 gated check(s) of the previous report carry no error/tolerance" in d["note"]


def test_lists_are_cut_on_the_console_but_whole_in_the_diff():
    prev = _doc([])
    cur = _doc([_check(f"g/run/m/q{k}", 0.1) for k in range(30)])
    d = run_diff.diff_summaries(prev, cur)
    assert len(d["new"]) == 30
    lines = run_diff.diff_lines(d, limit=5)
    assert sum(line.startswith("  new: ") for line in lines) == 5
    assert "  ... and 25 more new (summary.json: diff)" in lines


@pytest.mark.parametrize("content, says", [
    (None, "has no summary.json"),
    ("{not json", "is not valid JSON"),
    ('{"checks": "none"}', "is not a gpme verify summary"),
    ('[1, 2]', "is not a gpme verify summary"),
    (b"\xff\xfe\x00", "unreadable"),
], ids=["missing", "corrupt-json", "checks-not-a-list", "not-an-object", "not-utf8"])
def test_unusable_previous_report_is_one_line(tmp_path, content, says):
    run = tmp_path / "run-1"
    run.mkdir()
    if isinstance(content, bytes):
        (run / "summary.json").write_bytes(content)
    elif content is not None:
        (run / "summary.json").write_text(content)
    data, note = run_diff.load_previous(run)
    assert data is None and says in note and "\n" not in note
    d = run_diff.diff_summaries(data, CURRENT, source=str(run), note=note)
    assert d["previous"] is None and d["note"] == note
    assert run_diff.diff_lines(d) == [f"diff against the previous run: {note}"]


def test_previous_report_read_from_its_directory_or_file(tmp_path):
    (tmp_path / "summary.json").write_text(json.dumps(PREVIOUS))
    for where in (tmp_path, tmp_path / "summary.json"):
        data, note = run_diff.load_previous(where)
        assert note is None and data["run"]["run_id"] == "run-1"


def test_ratios_written_as_json_read_back():
    """summary.json holds an infinite ratio as Infinity (Python's json) and NaN as null."""
    rows = pd.DataFrame({"engine": ["e", "e"], "section": ["s", "s"], "model": ["m", "m"],
                         "quantity": ["a", "b"], "abs_error": [np.inf, 1.0],
                         "tol_abs": [1.0, np.inf], "tol_rel": [0.0, 0.0], "scale": [1.0, 1.0]})
    r = run_diff.check_ratios(rows)
    doc = _doc([_check(f"e/s/m/{q}", None if math.isnan(v) else v)
                for q, v in zip(r["quantity"], r["error_over_tolerance"])])
    back = json.loads(json.dumps(doc))
    assert run_diff._ratio(back["checks"][0]) == INF and run_diff._ratio(back["checks"][1]) is None


def test_summary_json_is_strict_json_and_reads_back():
    """No NaN/Infinity tokens (jq and JSON.parse refuse them); inf comes back as a float."""
    import json
    import math
    from crosscheck.reports import strict_json
    doc = {"checks": [{"name": "inf", "reason": "inf", "error_over_tolerance": math.inf,
                       "worst_abs_error": float("nan"), "tol_abs": -math.inf,
                       "tolerance": 1e-9}]}
    text = strict_json.dumps(doc)
    json.loads(text, parse_constant=lambda c: pytest.fail(f"non-strict token {c}"))
    back = strict_json.loads(text)["checks"][0]
    assert back["error_over_tolerance"] == math.inf and back["tol_abs"] == -math.inf
    assert back["worst_abs_error"] is None and back["tolerance"] == 1e-9
    assert back["name"] == "inf" and back["reason"] == "inf"    # text fields stay text
