"""`gpme verify`: atomic run directories, summary.json, and the page checked in a real
headless browser (Debian's chromium + chromedriver through selenium)."""
import json
import os
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pandas as pd
import pytest

from crosscheck import verify, verify_steps
from gpme import verify_command
from gpme_examples import paper

REPO = Path(__file__).resolve().parent.parent
SCREENSHOTS = REPO / "reports" / "screenshots"


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    """A real quick verify run (paper section only: the engine sections have their own
    tests; the page structure is the same)."""
    root = tmp_path_factory.mktemp("reports")
    run_dir, summary, rows = verify.run_verify(root, quick=True, only="paper", progress=False,
                                               run_id="run-a")
    return root, run_dir, summary, rows


def test_run_directory_and_latest(report):
    root, run_dir, summary, _ = report
    assert (root / "latest").resolve() == run_dir.resolve()
    for name in ("index.html", "summary.json", "summary.csv", "checks/index.csv",
                 "tolerances.csv.gz", "checks/gpme/columns.csv", "models.json",
                 "runs/crane_rigid.csv.gz", "runs/crane_flexible_n3.csv.gz",
                 "runs/crane_rigid_constraints.png", "paper/fig2_joint_coordinates.png",
                 "paper/fig3_end_effector.png", "paper/constraint_violation.png"):
        assert (run_dir / name).is_file(), name
    data = json.loads((run_dir / "summary.json").read_text())
    assert len(data["checks"]) == len(summary)
    # an information check carries its value (issue 28: a smallest singular value of
    # 0.247 is not "an error 0"); a gated one has none
    sigma = [c for c in data["checks"] if c["quantity"].startswith("smallest singular value")]
    assert sigma and all(c["status"] == "info" and c["value"] > 0 for c in sigma)
    assert all(c["value"] is None for c in data["checks"] if c["status"] != "info")
    assert "value " in (run_dir / "index.html").read_text()
    assert {"name", "engine", "model", "quantity", "worst_abs_error", "tol_abs", "tol_rel",
            "status"} <= set(data["checks"][0])
    assert data["run"]["versions"]["mujoco"] and data["run"]["git_commit"]
    from crosscheck.reports.rows import read_rows
    back = read_rows(run_dir, "gpme")
    assert pd.read_csv(run_dir / "runs" / "crane_rigid.csv.gz")["t"].iloc[-1] == paper.QUICK_T_END
    run_rows = back[back["section"] == "run"]
    assert set(run_rows["quantity"]) == {"|Phi_1| after transient", "|Phi_2| after transient",
                                         "energy balance",
                                         "smallest singular value of the constraint Jacobian",
                                         "peak bending angle (arm)", "peak torsion angle (arm)",
                                         "peak bending stress (arm)"}
    # and the crane arm's RFEM discretisation against beam theory (crosscheck.rfem_reference)
    from crosscheck.rfem_reference import QUANTITIES, SECTION
    assert set(back.loc[back["section"] == SECTION, "quantity"]) == set(QUANTITIES)
    assert set(back["section"]) == {"run", SECTION}


def test_interrupted_run_leaves_previous_report_and_latest(report, monkeypatch):
    root, run_dir, _, _ = report
    before = (run_dir / "index.html").read_bytes()

    def crash(*args, **kwargs):
        raise KeyboardInterrupt("simulated interruption while writing the index")
    monkeypatch.setattr(verify, "write_index", crash)
    with pytest.raises(KeyboardInterrupt):
        verify.run_verify(root, quick=True, only="paper", progress=False, run_id="run-b")
    assert (root / "latest").resolve() == run_dir.resolve()
    assert (run_dir / "index.html").read_bytes() == before
    assert not (root / "run-b").exists()
    assert not list(root.glob(".run-b*")), "the staging directory of the interrupted run stays"


def test_two_runs_with_the_same_id_get_two_directories(report, monkeypatch):
    root = report[0]
    rows = report[3]
    # the directory logic is under test, not the runs: a step that returns the first run's rows
    monkeypatch.setattr(verify_steps, "_gpme_part", lambda *args, **kwargs: {})
    monkeypatch.setattr(verify_steps, "_gpme_finish", lambda *args, **kwargs: rows)
    first, _, _ = verify.run_verify(root, quick=True, only="paper", progress=False, run_id="same")
    second, _, _ = verify.run_verify(root, quick=True, only="paper", progress=False, run_id="same")
    assert first != second and first.name == "same" and second.name == "same-2"
    assert (first / "index.html").is_file() and (second / "index.html").is_file()
    assert (root / "latest").resolve() == second.resolve()


def test_failing_check_gives_nonzero_exit(report, monkeypatch, capsys, tmp_path):
    root = report[0]

    class BrokenEngine:
        """An engine check module whose every scenario crashes."""
        @staticmethod
        def scenario_part(*args, **kwargs):
            raise RuntimeError("pinocchio engine unavailable")
    monkeypatch.setattr(verify_steps, "_check_module", lambda step: BrokenEngine)

    class Args:
        out, quick, only, no_progress, model = str(root), True, "pinocchio", True, []
        junit_xml, summary_md = str(tmp_path / "r.xml"), str(tmp_path / "r.md")
    assert verify_command.main(Args) == 1
    out = capsys.readouterr().out
    assert "1 failed" in out
    # the crashed step: an <error> in the JUnit XML, the verdict first in the markdown
    error = ET.parse(tmp_path / "r.xml").getroot().find("testsuite/testcase/error")
    assert error.get("type") == "RuntimeError"
    assert error.get("message") == "pinocchio engine unavailable"
    md = (tmp_path / "r.md").read_text()
    assert md.startswith("## gpme verify ❌ FAILED: 1 of 1 checks failed")
    assert "| `pinocchio/terms/-/step crashed` |" in md and "step crashed |" in md
    # the crashed step's row is stored and linked from the index like any check's
    from crosscheck.reports.rows import read_rows, slice_path
    crash = slice_path("pinocchio/terms/-/step crashed")
    assert (root / "latest" / crash).is_file()
    assert read_rows(root / "latest", "pinocchio")["reason"].tolist() == \
        ["pinocchio engine unavailable"]
    assert f'href="{crash}"' in (root / "latest" / "index.html").read_text()
    # the previous run (`latest`) ran the paper step only: its checks vanished, not failed
    data = json.loads((root / "latest" / "summary.json").read_text())
    assert data["diff"]["mode_changed"] == ["--only: gpme before, pinocchio now"]
    assert data["diff"]["new"] == ["pinocchio/terms/-/step crashed"]
    assert "not like for like: --only" in out


def test_first_run_says_there_is_nothing_to_compare(report):
    _, run_dir, _, _ = report
    diff = json.loads((run_dir / "summary.json").read_text())["diff"]
    assert diff["previous"] is None and "no previous run in" in diff["note"]
    assert "Against the run before this one" in (run_dir / "index.html").read_text()


def test_unreadable_previous_report_is_one_line_not_a_crash(report, monkeypatch, tmp_path):
    rows = report[3]
    monkeypatch.setattr(verify_steps, "_gpme_part", lambda *args, **kwargs: {})
    monkeypatch.setattr(verify_steps, "_gpme_finish", lambda *args, **kwargs: rows)
    bad = tmp_path / "old-run"
    bad.mkdir()
    (bad / "summary.json").write_text('{"run": {"run_id": "old"}, "checks": [')
    root = tmp_path / "reports"
    run_dir, _, _ = verify.run_verify(root, quick=True, only="paper", progress=False,
                                      compare_to=bad)
    diff = json.loads((run_dir / "summary.json").read_text())["diff"]
    assert diff["previous"] is None and "is not valid JSON" in diff["note"]
    # `latest` pointing at a report that was removed since
    shutil.rmtree(run_dir)
    run_dir, _, _ = verify.run_verify(root, quick=True, only="paper", progress=False)
    diff = json.loads((run_dir / "summary.json").read_text())["diff"]
    assert diff["previous"] is None and "has no summary.json" in diff["note"]


# ---- the CI outputs and the diff of two real runs (the CLI as a user runs it) ----------

MY_ARM = REPO / "examples" / "my_arm" / "my_arm.toml"
JUNIT_SCHEMA = REPO / "tests" / "data" / "junit" / "junit-10.xsd"


def _cli_verify(root, tag):
    out = root.parent / tag
    proc = subprocess.run(
        [sys.executable, "-m", "gpme.cli", "verify", "--quick", "--only", "gpme", "--model",
         str(MY_ARM), "--out", str(root), "--no-progress", "--junit-xml", str(out / "r.xml"),
         "--summary-md", str(out / "r.md")], cwd=REPO, capture_output=True, text=True,
        timeout=600)
    return proc, out


@pytest.fixture(scope="module")
def two_runs(tmp_path_factory):
    """`gpme verify --quick --only gpme --model examples/my_arm/my_arm.toml` twice in one
    --out root, with --junit-xml and --summary-md."""
    root = tmp_path_factory.mktemp("ci") / "reports"
    first = _cli_verify(root, "first")
    second = _cli_verify(root, "second")
    return root, first, second


def test_ci_outputs_written_and_junit_valid(two_runs):
    import xmlschema
    schema = xmlschema.XMLSchema(JUNIT_SCHEMA)
    for proc, out in two_runs[1:]:
        assert proc.returncode == 0, proc.stderr
        assert f"wrote {out / 'r.xml'}" in proc.stdout and f"wrote {out / 'r.md'}" in proc.stdout
        schema.validate(str(out / "r.xml"))
    root_el = ET.parse(two_runs[2][1] / "r.xml").getroot()
    data = json.loads((two_runs[0] / "latest" / "summary.json").read_text())
    assert int(root_el.get("tests")) == len(data["checks"])
    assert len(root_el.findall("testsuite/testcase/skipped")) == \
        sum(c["status"] == "info" for c in data["checks"])


def test_markdown_summary_of_a_passing_run_fits_one_screen(two_runs):
    root, _, (_, out) = two_runs
    md = (out / "r.md").read_text()
    lines = md.splitlines()
    assert lines[0] == "## gpme verify ✅ PASSED: no check failed"
    assert "passed, 0 failed, 1 information only** (not gated" in md
    assert "Versions: gpme" in md and "mujoco" in md
    run_dir = (root / "latest").resolve()
    assert f"Report: `{root / run_dir.name / 'index.html'}`" in md
    assert len(lines) <= 25 and max(map(len, lines)) <= 400


def test_diff_of_two_consecutive_runs(two_runs):
    root, (first, _), (second, out) = two_runs
    assert "no previous run in" in first.stdout
    runs = sorted(d.name for d in root.iterdir() if not d.name.startswith(".")
                  and d.name != "latest")
    assert len(runs) == 2
    data = json.loads((root / runs[1] / "summary.json").read_text())
    diff = data["diff"]
    assert diff["previous"]["run_id"] == runs[0]
    assert diff["compared"] == len(data["checks"]) and diff["compared"] >= 5
    # the same model, code and machine: the run is deterministic, nothing grew or changed
    assert (diff["grown"], diff["status_changed"], diff["new"], diff["vanished"],
            diff["versions_changed"], diff["mode_changed"]) == ([], [], [], [], {}, [])
    # the run compared with is named with its date (the page is read later, when other
    # runs have come since: "the previous run" would then be another one)
    assert f"against {runs[0]} ({diff['previous']['date_utc']}, {diff['compared']} checks " \
           "compared): 0 check(s) with error/tolerance grown >10x" in second.stdout
    assert "Against the run before this one" in (out / "r.md").read_text()
    page = (root / runs[1] / "index.html").read_text()
    assert '<section id="diff">' in page and runs[0] in page
    for check in data["checks"]:            # every gated check has its ratio, information none
        ratio = check["error_over_tolerance"]
        assert (ratio is None) == (check["status"] == "info"), check["name"]
        assert ratio is None or 0 <= ratio <= 1


def _md_check(k, status="fail", quantity="|Phi_1| after transient"):
    return {"name": f"gpme/run/crane {k}/{quantity}", "engine": "gpme", "section": "run",
            "model": f"crane {k}", "quantity": quantity, "status": status, "n_compared": 1,
            "n_fail": 1, "worst_abs_error": 3e-6, "worst_rel_error": None,
            "worst_case": "2 s, RK4", "worst_entry": "t = 1.2 s", "tol_abs": 1e-8,
            "tol_rel": 0.0, "tolerance": 1e-8, "error_over_tolerance": 300.0,
            "reason": "task accuracy <10 nm | *Baumgarte*", "crashed": False}


def test_markdown_summary_of_a_failing_run():
    from crosscheck.reports.summary_md import MAX_ROWS, summary_markdown
    doc = {"run": {"quick": False, "git_commit": "abc", "versions": {"gpme": "0.1.0"}},
           "models": [{"name": "crane"}], "warnings": ["arm: peak angle 0.07 rad > 0.05 rad"],
           "checks": [_md_check(k) for k in range(MAX_ROWS + 3)] +
                     [_md_check(99, "pass"), _md_check(98, "info")]}
    md = summary_markdown(doc, "reports/x/index.html")
    lines = md.splitlines()
    assert lines[0] == f"## gpme verify ❌ FAILED: {MAX_ROWS + 3} of {MAX_ROWS + 5} checks failed"
    assert f"**1 passed, {MAX_ROWS + 3} failed, 1 information only**" in md
    row = next(line for line in lines if "`gpme/run/crane 0/" in line)
    # the pipes of |Phi_1| and of the reason escaped: the row keeps its six cells
    assert row == ("| `gpme/run/crane 0/\\|Phi_1\\| after transient` | 3e-06 | 1e-08 + 0 × "
                   "scale = 1e-08 | 300 | 2 s, RK4, t = 1.2 s | task accuracy \\<10 nm \\| "
                   "\\*Baumgarte\\* |")
    assert sum(line.startswith("| `gpme/") for line in lines) == MAX_ROWS
    assert "... and 3 more failed checks (summary.json)" in md
    assert "### Warnings" in md and "peak angle 0.07 rad" in md
    assert "No diff recorded in this report." in md


# ---- bad report flags: one error listing every problem, before any work ----------------

@pytest.mark.parametrize("flags, words", [
    (["--junit-xml", "{tmp}"], ["--junit-xml", "is a directory; give a file name"]),
    (["--junit-xml", "{tmp}/a_file/r.xml"], ["--junit-xml", "a_file", "on its way is a file"]),
    (["--summary-md", ""], ["--summary-md is empty; give a file name"]),
    (["--junit-xml", "{tmp}/r.out", "--summary-md", "{tmp}/r.out"],
     ["--junit-xml and --summary-md both name", "give each its own file"]),
    (["--compare-to", "{tmp}/nowhere"], ["--compare-to", "nowhere", "does not exist",
                                         "report directory", "summary.json"]),
    (["--compare-to", "{tmp}/empty"], ["--compare-to", "holds no summary.json"]),
    (["--junit-xml", "{tmp}", "--compare-to", "{tmp}/nowhere", "--model", "/nonexistent.toml"],
     ["3 problems on the command line", "is a directory", "does not exist",
      "/nonexistent.toml"]),
], ids=["junit-is-a-directory", "junit-under-a-file", "summary-md-empty", "same-file-twice",
        "compare-to-missing", "compare-to-without-summary", "three-at-once"])
def test_bad_report_flags(flags, words, tmp_path, capsys):
    from gpme.cli import main
    (tmp_path / "a_file").write_text("x")
    (tmp_path / "empty").mkdir()
    root = tmp_path / "reports"
    argv = ["verify", "--quick", "--out", str(root), "--no-progress",
            *[f.replace("{tmp}", str(tmp_path)) for f in flags]]
    code = main(argv)
    err = capsys.readouterr().err
    assert code == 2 and "Traceback" not in err and err.startswith("error: ")
    for word in words:
        assert word in err, word
    assert not root.exists() or not any(root.iterdir()), "no work for a refused command"


def _browser():
    chromium, driver = shutil.which("chromium"), shutil.which("chromedriver")
    if not (chromium and driver):
        if os.environ.get("CI"):
            pytest.fail("chromium/chromedriver missing: .ci/run installs Debian's chromium "
                        "and chromium-driver")
        pytest.skip("Debian chromium/chromium-driver not installed (apt-get install chromium "
                    "chromium-driver)")
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service
    opts = webdriver.ChromeOptions()
    opts.binary_location = chromium
    for flag in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-quic",
                 "--no-first-run", "--disable-background-networking",
                 "--disable-component-update", "--disable-sync", "--disable-dev-shm-usage"):
        opts.add_argument(flag)
    opts.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    return webdriver.Chrome(service=Service(driver), options=opts)


def test_page_in_headless_chromium(report):
    _, run_dir, summary, _ = report
    browser = _browser()
    try:
        SCREENSHOTS.mkdir(parents=True, exist_ok=True)
        browser.set_window_size(1280, 900)
        browser.get((run_dir / "index.html").as_uri())
        errors = [e for e in browser.get_log("browser") if e["level"] in ("SEVERE", "ERROR")]
        assert errors == []
        images = browser.execute_script(
            "return Array.from(document.images).map(i => [i.complete, i.naturalWidth, i.alt])")
        assert len(images) >= 3 and all(ok and w > 0 for ok, w, _ in images), images
        rows = browser.execute_script(
            "return document.querySelectorAll('table.checks tbody tr').length")
        assert rows == len(summary)
        assert browser.execute_script("return document.querySelectorAll('table.matrix td.c a')"
                                      ".length") >= 1
        assert browser.execute_script(
            "return document.documentElement.scrollWidth - window.innerWidth") <= 0
        browser.save_screenshot(str(SCREENSHOTS / "index-laptop.png"))
        # readable on a phone: the page itself does not scroll sideways (wide tables scroll
        # inside their own box)
        browser.set_window_size(390, 844)
        browser.get((run_dir / "index.html").as_uri())
        overflow = browser.execute_script(
            "return document.documentElement.scrollWidth - window.innerWidth")
        assert overflow <= 1
        browser.save_screenshot(str(SCREENSHOTS / "index-phone.png"))
    finally:
        browser.quit()


# ---- the CI examples: docs/ci/github-actions-verify.yml and the GitLab job of docs/ci.md --

def _verify_argv(command):
    """The arguments of a `gpme verify ...` command line, parsed by gpme's own parser."""
    import shlex
    from gpme.cli import build_parser
    words = shlex.split(command)
    assert words[:2] == ["gpme", "verify"], command
    return build_parser().parse_args(words[1:])


def test_github_actions_example():
    import yaml           # a dependency of gpme (YAML sweep files)
    workflow = yaml.safe_load((REPO / "docs" / "ci" / "github-actions-verify.yml").read_text())
    steps = workflow["jobs"]["verify"]["steps"]
    runs = [s for s in steps if s.get("run", "").startswith("gpme verify")]
    assert len(runs) == 1
    args = _verify_argv(runs[0]["run"])
    assert (args.quick, args.junit_xml, args.summary_md, args.model) == \
        (True, "gpme-junit.xml", "gpme-summary.md", ["$MODEL"])
    after = steps[steps.index(runs[0]) + 1:]
    assert after and all(s.get("if") == "always()" for s in after), \
        "the summary and the report must be kept when a check fails"
    assert any("$GITHUB_STEP_SUMMARY" in s.get("run", "") and "gpme-summary.md" in s["run"]
               for s in after)
    assert any(s.get("uses", "").startswith("actions/upload-artifact@") for s in after)
    install = [s for s in steps if "pip install" in s.get("run", "")]
    assert install and "git+" in workflow["env"]["GPME_SOURCE"]


def test_gitlab_example_in_docs():
    import yaml           # a dependency of gpme (YAML sweep files)
    text = (REPO / "docs" / "ci.md").read_text()
    block = text.split("```yaml\n", 1)[1].split("```", 1)[0]
    job = yaml.safe_load(block)["gpme-verify"]
    args = _verify_argv(next(line for line in job["script"] if line.startswith("gpme verify")))
    assert job["artifacts"]["reports"]["junit"] == args.junit_xml
    assert job["artifacts"]["when"] == "always" and args.summary_md in job["artifacts"]["paths"]
