"""`gpme verify --junit-xml`: the JUnit XML of a summary.json document
(crosscheck.reports.junit) validated against the Jenkins xunit plugin's junit-10.xsd
(tests/data/junit/, source and licence in its README) with xmlschema, and read the way
GitLab's parser reads it.  The XML of a real run is validated in tests/test_verify.py."""
import math
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
import xmlschema          # the `test` extra

from crosscheck.reports import junit

SCHEMA_FILE = Path(__file__).parent / "data" / "junit" / "junit-10.xsd"
SUREFIRE_TIME = re.compile(r"^[0-9]+(\.[0-9]{1,3})?$")


@pytest.fixture(scope="module")
def schema():
    return xmlschema.XMLSchema(SCHEMA_FILE)


def _check(engine, model, quantity, status, section="terms", **kw):
    base = {"name": f"{engine}/{section}/{model}/{quantity}", "engine": engine,
            "section": section, "model": model, "quantity": quantity, "n_compared": 5,
            "n_fail": 0, "worst_abs_error": 1e-12, "worst_rel_error": 1e-13,
            "worst_case": "state 3", "worst_entry": "[psi3, z4]", "tol_abs": 1e-10,
            "tol_rel": 1e-9, "tolerance": 1.1e-10, "error_over_tolerance": 0.009,
            "status": status, "reason": "round-off with cond(M)", "crashed": False}
    base.update(kw)
    return base


DOCUMENT = {
    "run": {"run_id": "20260101-000000-quick", "date_utc": "2026-01-01 12:34:56 UTC",
            "git_commit": "abc", "quick": True, "only": None, "wall_time_s": 12.3456,
            "step_times_s": {"gpme": 1.5, "pinocchio": 4.25, "mujoco": 2.0},
            "versions": {"gpme": "0.1.0", "pinocchio (pin)": "3.2.0", "mujoco": "3.3.0"},
            "machine": {"node": "ci-runner"}},
    "passed": False,
    "checks": [
        _check("gpme", "my_arm", "|circle| after transient", "pass", section="run"),
        _check("gpme", "my_arm", "smallest singular value", "info", section="run",
               tol_abs=None, tolerance=None, error_over_tolerance=None,
               reason="information: distance from a singular pose"),
        _check("pinocchio", "my_arm", "M", "fail", n_fail=2, worst_abs_error=3.2e-6,
               worst_rel_error=1.6e-6, error_over_tolerance=29090.9,
               reason="round-off with cond(M) < 1e4 & \"quoted\" <tags> \x1b[31mred"),
        _check("pinocchio", "my_arm (original URDF)", "g", "fail", n_fail=1,
               worst_abs_error=math.inf, worst_rel_error=None,
               error_over_tolerance=math.inf),
        _check("pinocchio", "my_arm (original URDF)", "h", "pass"),
        _check("mujoco", "-", "step crashed", "fail", section="terms", n_compared=1,
               n_fail=1, worst_abs_error=math.inf, worst_entry="RuntimeError",
               worst_case="-", tol_abs=0.0, tol_rel=0.0, tolerance=0.0,
               error_over_tolerance=math.inf, reason="mujoco engine unavailable",
               crashed=True),
    ]}


@pytest.fixture(scope="module")
def tree():
    return ET.fromstring(junit.junit_xml(DOCUMENT, report_dir="reports/run"))


def test_validates_against_junit_10(schema):
    schema.validate(junit.junit_xml(DOCUMENT, report_dir="reports/run").decode("utf-8"))


def test_schema_rejects_a_broken_document(schema):
    """The validation can fail: a testsuite without its counts is refused."""
    root = junit.junit_tree(DOCUMENT)
    del root.find("testsuite").attrib["tests"]
    with pytest.raises(xmlschema.XMLSchemaValidationError):
        schema.validate(ET.tostring(root, encoding="unicode"))


def test_suites_by_engine_and_model_with_their_counts(tree):
    suites = {s.get("name"): s for s in tree.findall("testsuite")}
    assert list(suites) == ["gpme: my_arm", "pinocchio: my_arm",
                            "pinocchio: my_arm (original URDF)", "mujoco: -"]
    counts = {n: tuple(int(s.get(k)) for k in ("tests", "failures", "errors", "skipped"))
              for n, s in suites.items()}
    assert counts == {"gpme: my_arm": (2, 0, 0, 1), "pinocchio: my_arm": (1, 1, 0, 0),
                      "pinocchio: my_arm (original URDF)": (2, 1, 0, 0),
                      "mujoco: -": (1, 0, 1, 0)}
    assert (tree.tag, tree.get("tests"), tree.get("failures"), tree.get("errors")) == \
        ("testsuites", "6", "2", "1")
    for s in suites.values():      # the attributes every JUnit reader looks for
        assert s.get("timestamp") == "2026-01-01T12:34:56" and s.get("hostname") == "ci-runner"
        assert len(s.findall("testcase")) == int(s.get("tests"))


def test_times(tree):
    """The run's wall time on the root; a suite carries its engine step's time only when
    that step checked this one model (per-model times are not measured)."""
    assert tree.get("time") == "12.346"
    times = {s.get("name"): s.get("time") for s in tree.findall("testsuite")}
    assert times == {"gpme: my_arm": "1.500", "pinocchio: my_arm": None,
                     "pinocchio: my_arm (original URDF)": None, "mujoco: -": "2.000"}
    assert all(SUREFIRE_TIME.match(t) for t in times.values() if t)
    steps = {s.get("name"): s.find("properties/property[@name='step_time_s']").get("value")
             for s in tree.findall("testsuite")}
    assert steps["pinocchio: my_arm"] == "4.250"


def _case(tree, name, suite=None):
    path = f"testsuite[@name='{suite}']/testcase" if suite else "testsuite/testcase"
    found = [c for c in tree.findall(path) if c.get("name") == name]
    assert len(found) == 1, name
    return found[0]


def test_failure_carries_discrepancy_tolerance_reason_and_where(tree):
    case = _case(tree, "terms: M")
    assert case.get("classname") == "gpme.pinocchio.my_arm"
    failure = case.find("failure")
    msg = failure.get("message")
    for part in ("abs error 3.2e-06", "rel 1.6e-06", "tol_abs 1e-10", "tol_rel 1e-09",
                 "= 1.1e-10", "error/tolerance 2.91e+04", "case state 3", "entry [psi3, z4]",
                 "2 of 5 comparisons failed"):
        assert part in msg, part
    assert failure.get("type") == "ToleranceExceeded"
    # the reason, escaped by ElementTree, the terminal escape replaced (not XML 1.0)
    assert "round-off with cond(M) < 1e4 & \"quoted\" <tags> \\x1b[31mred" in failure.text


def test_non_finite_failure_says_so(tree):
    failure = _case(tree, "terms: g").find("failure")
    assert failure.get("type") == "NonFiniteValue" and "abs error inf" in failure.get("message")
    assert _case(tree, "terms: g").get("classname") == "gpme.pinocchio.my_arm_original_URDF"


def test_information_is_skipped_with_its_reason_never_a_pass(tree):
    case = _case(tree, "run: smallest singular value")
    skipped = case.find("skipped")
    assert skipped is not None and case.find("failure") is None
    assert "not gated" in skipped.get("message")
    assert "distance from a singular pose" in skipped.get("message")


def test_crashed_step_is_an_error(tree):
    error = _case(tree, "terms: step crashed").find("error")
    assert error.get("type") == "RuntimeError"
    assert error.get("message") == "mujoco engine unavailable"
    assert "reports/run/mujoco_crash.txt" in error.text


def test_pass_carries_its_numbers(tree):
    out = _case(tree, "run: |circle| after transient").find("system-out").text
    assert "abs error 1e-12" in out and "error/tolerance 0.009" in out and "5 comparisons" in out


def _gitlab_cases(root):
    """The test cases as GitLab's JUnit parser (lib/gitlab/ci/parsers/test/junit.rb) finds
    them: one top-level testsuites, testcases of each testsuite below it; the status from
    the first of failure, error, skipped present, else success."""
    assert root.tag == "testsuites"
    out = []
    for suite in root.iter("testsuite"):
        for tc in suite.findall("testcase"):
            status = next((s for s in ("failure", "error", "skipped")
                           if tc.find(s) is not None), "success")
            out.append((suite.get("name"), tc.get("classname"), tc.get("name"), status))
    return out


def test_what_gitlab_reads(tree):
    cases = _gitlab_cases(tree)
    assert all(suite and cls and name for suite, cls, name, _ in cases)
    statuses = [c[3] for c in cases]
    assert statuses.count("failure") == int(tree.get("failures"))
    assert statuses.count("error") == int(tree.get("errors"))
    assert statuses.count("skipped") == 1 and statuses.count("success") == 2
    assert len({(c[1], c[2]) for c in cases}) == len(cases), "classname + name identify a case"


@pytest.mark.parametrize("model, expected", [
    ("my_arm", "gpme.mujoco.my_arm"), ("ur5.v2 (flex)", "gpme.mujoco.ur5_v2_flex"),
    ("-", "gpme.mujoco._")], ids=["plain", "dots-and-spaces", "no-model"])
def test_classname_has_no_stray_dots(model, expected):
    assert junit.classname("mujoco", model) == expected


def test_written_atomically(tmp_path, schema):
    path = junit.write_junit_xml(tmp_path / "out" / "r.xml", DOCUMENT)
    assert [p.name for p in (tmp_path / "out").iterdir()] == ["r.xml"]
    schema.validate(str(path))
