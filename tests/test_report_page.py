"""index.html on a made-up report with every status (pass, fail, info, a crashed step),
three engines, odd names and many quantities: the matrix, the verdict, the links, the
escaping, and in headless Chromium the filters, folding, cell links and phone width.

The report is synthetic so that a failure and a crash are on the page (a real run has
none); tests/test_verify.py checks the page of a real run.
"""
import json
import math

import numpy as np
import pandas as pd
import pytest

from crosscheck import verify
from crosscheck.reports import index_page
from crosscheck.reports.matrix import quantity_family, ratio_colour
from crosscheck.reports.rows import check_id, normalise
from crosscheck.verify_meta import environment

from test_verify import _browser

COORDINATES = ("z1", "psi2", "phi_arm_1")
CONSTRAINTS = ("Phi_1", "Phi_<edge>")
ODD_MODEL = "arm <b>&'\"x\"</b>"


def _row(engine, section, model, quantity, error, tol=1e-6, case="s0", reason=None):
    gated = math.isfinite(tol)
    status = "info" if not gated else ("pass" if error <= tol else "fail")
    return {"engine": engine, "section": section, "model": model, "quantity": quantity,
            "case": case, "entry": "[0]", "gpme_value": 1.0, "engine_value": 1.0 + error,
            "abs_error": error, "rel_error": error, "scale": 1.0, "tol_abs": tol,
            "tol_rel": 0.0, "status": status, "passed": status != "fail",
            "reason": reason or f"round-off of {engine} {section}"}


def _rows():
    rows = []
    for model in ("crane", ODD_MODEL):
        for k, q in enumerate(("M", "h", "g")):
            for case in ("s0", "s1"):
                rows.append(_row("pinocchio", "terms", model, q, 10.0 ** (-14 + k), 1e-9,
                                 case))
        for c in COORDINATES:
            rows.append(_row("mujoco", "exact", model, f"exact programmed run {c}", 1e-8))
            rows.append(_row("mujoco", "exact", model, f"exact programmed run {c}_dot", 1e-9))
        for c in CONSTRAINTS:
            rows.append(_row("mujoco", "exact", model, f"exact programmed run lambda_{c}",
                             1e-7))
    rows.append(_row("mujoco", "exact", "crane", "exact programmed run psi2", 3e-5,
                     case="t=1.5 s", reason="RK4 error bound <script>alert(1)</script>"))
    rows.append(_row("mujoco", "wall time", "crane", "wall time per simulated second [s/s]",
                     2.0, tol=math.inf, reason="information: timing"))
    rows.append(_row("gpme", "run", "crane", "|Phi_1| after transient", 1e-9))
    crash = _row("exudyn", "terms", "-", "step crashed", math.inf, tol=0.0,
                 reason="ValueError: boom")
    rows.append(crash)
    return normalise(pd.DataFrame(rows))


@pytest.fixture(scope="module")
def page(tmp_path_factory):
    run_dir = tmp_path_factory.mktemp("run")
    rows = _rows()
    summary = verify.summary_of(rows)
    meta = environment(quick=True, only=None, run_id="run-x", wall_time_s=1.0,
                       step_times_s={"gpme": 1.0})
    diff = {"previous": {"run_id": "run-w"}, "compared": len(summary), "growth_factor": 10.0,
            "grown": [{"check": summary["check"].iloc[0], "factor": 100.0, "previous": 1e-6,
                       "current": 1e-4, "status": "pass"}],
            "status_changed": [], "new": [], "vanished": [], "versions_changed": {},
            "mode_changed": [], "definition": "error / tolerance of each check"}
    index_page.write_index(run_dir, summary, rows, meta, [], diff=diff,
                           names={"coordinates": set(COORDINATES),
                                  "constraints": set(CONSTRAINTS)})
    return run_dir, summary, (run_dir / "index.html").read_text(encoding="utf-8")


def test_quantities_are_grouped_by_the_kind_of_name_they_compare():
    fam = [quantity_family(q, COORDINATES, CONSTRAINTS) for q in (
        "exact programmed run psi2", "exact programmed run z1", "exact programmed run z1_dot",
        "exact programmed run lambda_Phi_1", "mechanism viol_aux_yoke max over time [m]",
        "M", "frame position", "mechanism psi2 difference ratio, tc/2 over tc")]
    assert fam == ["exact programmed run q", "exact programmed run q", "exact programmed run "
                   "q_dot", "exact programmed run lambda", "mechanism viol max over time [m]",
                   "M", "frame position", "mechanism q difference ratio, tc/2 over tc"]


def test_colour_runs_from_green_to_amber_on_a_log_scale_and_fails_red():
    hues = [float(ratio_colour(r, "pass")[4:].split(",")[0]) for r in
            (0.0, 1e-10, 1e-8, 1e-4, 1e-1, 1.0)]
    assert hues[0] == hues[1] == hues[2] == 120 and hues[-1] == 40
    assert all(a > b for a, b in zip(hues[2:], hues[3:]))       # strictly towards amber
    assert ratio_colour(2.0, "fail") != ratio_colour(0.99, "pass")
    assert ratio_colour(float("nan"), "info") == ratio_colour(None, "info")


def test_verdict_names_failures_changes_and_engines_first(page):
    _, summary, html = page
    head = html[:html.index('id="matrix"')]
    n_fail = int((summary["status"] == "fail").sum())
    assert n_fail == 2           # the psi2 run check and the crashed step
    assert f"{n_fail} of " in head and "FAILED" in head
    assert "exact programmed run psi2" in head and "step crashed" in head
    assert "1 check(s) with error/tolerance grown" in head and "run-w" in head
    for engine in ("pinocchio", "mujoco", "gpme", "exudyn"):
        assert f'href="#engine-{engine}"' in head


def test_every_link_in_the_page_resolves(page):
    import re
    run_dir, summary, html = page
    ids = set(re.findall(r'id="([^"]+)"', html))
    anchors = set(re.findall(r'href="#([^"]+)"', html))
    assert anchors <= ids, anchors - ids
    for check in summary["check"]:
        assert check_id(check) in ids
    files = set(re.findall(r'(?:href|src)="([^"#:]+)"', html)) - {"../benchmarks/"}
    assert files and all((run_dir / f).exists() for f in files), \
        [f for f in files if not (run_dir / f).exists()]


def test_names_and_reasons_are_escaped(page):
    _, _, html = page
    assert "<script>alert(1)" not in html and "&lt;script&gt;alert(1)" in html
    assert "<b>&" not in html and "arm &lt;b&gt;&amp;" in html


def test_each_reason_is_stored_once(page):
    _, summary, html = page
    for reason in summary["reason"].unique():
        escaped = reason.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")
        # below the verdict (which quotes a crash's message): once, in the side table;
        # each check links to it
        assert html[html.index('id="checks"'):].count(escaped) == 1, reason


def test_page_in_headless_chromium(page):
    run_dir, summary, _ = page
    browser = _browser()
    try:
        browser.set_window_size(1280, 900)
        browser.get((run_dir / "index.html").as_uri())
        errors = [e for e in browser.get_log("browser") if e["level"] in ("SEVERE", "ERROR")]
        assert errors == []
        js = browser.execute_script
        assert js("return document.documentElement.scrollWidth - window.innerWidth") <= 0
        # the matrix: one block per engine, one coloured cell per (quantity group, model)
        blocks = js("return document.querySelectorAll('table.matrix').length")
        assert blocks == summary["engine"].nunique()
        cells = js("return Array.from(document.querySelectorAll('table.matrix td.c a'))"
                   ".map(a => [a.textContent, getComputedStyle(a.parentElement)"
                   ".backgroundColor, a.getAttribute('href')])")
        assert len(cells) >= 10 and all(bg not in ("", "rgba(0, 0, 0, 0)") for _, bg, _ in cells)
        assert any(text == "FAIL" for text, _, _ in cells)
        visible = "return Array.from(document.querySelectorAll('table.checks tbody tr'))" \
                  ".filter(r => r.checkVisibility()).map(r => r.className)"
        rows = "return document.querySelectorAll('table.checks tbody tr').length"
        assert js(rows) == len(summary)
        # filter: failures only
        for status in ("pass", "info"):
            browser.find_element("css selector", f".status-filter[value={status}]").click()
        assert sorted(js(visible)) == ["fail", "fail"]
        assert "2 of" in browser.find_element("id", "shown").text
        # text filter on top of it: nothing of the crash matches "psi2"
        box = browser.find_element("id", "text-filter")
        box.send_keys("psi2")
        assert js(visible) == ["fail"]
        box.clear()
        box.send_keys(" ")
        for status in ("pass", "info"):
            browser.find_element("css selector", f".status-filter[value={status}]").click()
        # fold all: no check row visible; a matrix cell's link unfolds and marks its check
        browser.find_element("id", "fold").click()
        assert js(visible) == []
        href = cells[0][2]
        browser.find_element("css selector", f"table.matrix a[href='{href}']").click()
        target = js(f"return document.getElementById('{href[1:]}')")
        assert target.is_displayed() and target.get_attribute("data-target") is not None
        # a phone: nothing scrolls sideways, the verdict and the matrix are there
        browser.set_window_size(390, 844)
        browser.get((run_dir / "index.html").as_uri())
        assert js("return document.documentElement.scrollWidth - window.innerWidth") <= 0
        assert browser.find_element("id", "verdict").is_displayed()
        assert js("return document.querySelector('table.matrix').getBoundingClientRect()"
                  ".width") <= 390
    finally:
        browser.quit()


def test_page_stays_small(page):
    run_dir, summary, html = page
    # ~1 kB per check row and no embedded image: a 400-check run stays far below 500 kB
    assert "data:image" not in html
    assert len(html.encode()) < 40_000 + 1_500 * len(summary)
