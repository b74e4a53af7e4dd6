"""crosscheck.compare: the three outcomes of a comparison (pass, fail, info), and the
per-group status of crosscheck.reports.tables.summarise."""
import numpy as np
import pandas as pd
import pytest

from crosscheck.compare import COLUMNS, Tolerance, compare, row_status, tolerance_for
from crosscheck.reports.html import html_table
from crosscheck.reports.tables import summarise, worst_first, worst_status

TOL = Tolerance(1e-12, 1e-9, "test tolerance: exact numbers up to a few roundings")
UNGATED = Tolerance(np.inf, 0.0, "information only: the engines differ by design")


def _row(x, y, tol=TOL, **kw):
    return compare("engine", "model", "q", "case", x, y, tol, **kw)


def test_row_has_every_column_and_passed_matches_status():
    r = _row([1.0, 2.0], [1.0, 2.0])
    assert tuple(r) == COLUMNS
    assert r["status"] == "pass" and r["passed"] is True


def test_error_above_budget_fails_and_below_passes():
    # budget = 1e-12 + 1e-9 * 2 = 2.001e-9
    assert _row([1.0, 2.0 + 2.0e-9], [1.0, 2.0])["status"] == "pass"
    r = _row([1.0, 2.0 + 2.01e-9], [1.0, 2.0], labels=["a", "b"])
    assert r["status"] == "fail" and r["passed"] is False and r["entry"] == "b"


@pytest.mark.parametrize("x, y", [([np.nan, 1.0], [0.0, 1.0]), ([0.0, 1.0], [0.0, np.inf]),
                                  ([np.nan], [np.nan])])
def test_nan_or_inf_in_either_value_fails(x, y):
    r = _row(x, y, labels=["a", "b"][:len(x)])
    assert r["status"] == "fail" and not r["passed"]
    assert r["abs_error"] == np.inf


def test_nan_fails_even_under_an_infinite_tolerance():
    assert _row([np.nan], [1.0], UNGATED)["status"] == "fail"


def test_infinite_tolerance_is_info_not_pass():
    r = _row([1.0], [5.0], UNGATED)
    assert r["status"] == "info" and r["passed"] is True and r["abs_error"] == 4.0
    assert _row([1.0], [1.0], Tolerance(0.0, np.inf, "rel ungated"))["status"] == "info"


def test_tolerance_must_be_stated():
    with pytest.raises(ValueError, match="reason must state"):
        Tolerance(1e-12, 1e-12, " ")
    with pytest.raises(ValueError, match="abs = nan"):
        Tolerance(float("nan"), 0.0, "x")
    with pytest.raises(ValueError, match="rel = -1"):
        Tolerance(0.0, -1.0, "x")
    with pytest.raises(TypeError, match="must be a Tolerance"):
        compare("e", "m", "q", "c", [1.0], [1.0], None)


def test_missing_tolerance_is_a_harness_error():
    with pytest.raises(KeyError, match="no tolerance stated for 'M' in crane.*harness bug"):
        tolerance_for({"g": TOL}, "M", "crane")
    assert tolerance_for({"g": TOL}, "g") is TOL


def test_scale_override_and_empty_values():
    r = _row([1e-6], [0.0], scale=1e3)          # budget 1e-12 + 1e-9 * 1e3 = 1e-6
    assert r["status"] == "pass" and r["scale"] == 1e3 and r["rel_error"] == pytest.approx(1e-9)
    r = _row(np.zeros(0), np.zeros(0))
    assert r["status"] == "pass" and r["abs_error"] == 0.0
    with pytest.raises(ValueError, match="shape"):
        _row([1.0, 2.0], [1.0])


def _table():
    rows = [_row([1.0], [1.0]) | {"quantity": "a"},                       # pass
            _row([1.0], [2.0], UNGATED) | {"quantity": "a"},              # info
            _row([1.0], [2.0], UNGATED) | {"quantity": "b"},              # info only
            _row([1.0], [1.0]) | {"quantity": "c"},
            _row([np.nan], [1.0]) | {"quantity": "c"},                    # fail
            _row([1.0], [1.0]) | {"quantity": "d", "passed": False}]      # overridden
    return pd.DataFrame(rows)


def test_summarise_reports_worst_status_and_counts():
    s = summarise(_table()).set_index("quantity")
    assert s.loc["a", "status"] == "pass" and s.loc["a", "passed"]
    assert (s.loc["a", "n_pass"], s.loc["a", "n_info"], s.loc["a", "n_fail"]) == (1, 1, 0)
    assert s.loc["b", "status"] == "info" and s.loc["b", "passed"]
    assert s.loc["c", "status"] == "fail" and not s.loc["c", "passed"]
    assert s.loc["c", "n_fail"] == 1 and s.loc["c", "n_compared"] == 2
    # a row whose caller set passed = False fails whatever its status column says
    assert s.loc["d", "status"] == "fail"


def test_worst_status_order():
    assert worst_status(["info", "pass", "fail"]) == "fail"
    assert worst_status(["info", "pass"]) == "pass"
    assert worst_status(["info", "info"]) == "info"


def test_worst_first_puts_failures_first_and_info_last():
    df = _table()
    order = list(row_status(worst_first(df)))
    assert order[:2] == ["fail", "fail"] and order[-2:] == ["info", "info"]


def test_html_table_marks_each_status():
    page = html_table(_table())
    assert page.count('<tr class="info">') == 2 and page.count('<tr class="fail">') == 2
    assert page.count('<tr class="pass">') == 2 and '<td class="st">FAIL</td>' in page


def test_html_table_escapes_every_cell():
    """Names and reasons from a model reach the page escaped (Jinja2 autoescape)."""
    df = _table().assign(reason="<script>alert(1)</script> & 'x'")
    page = html_table(df.assign(model="a<b"), left_columns=("model", "reason"))
    assert "<script>" not in page and "&lt;script&gt;" in page and "a&lt;b" in page
