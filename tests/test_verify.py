"""`gpme verify`: atomic run directories, summary.json, and the page checked in a real
headless browser (Debian's chromium + chromedriver through selenium)."""
import json
import os
import shutil
from pathlib import Path

import pandas as pd
import pytest

from crosscheck import verify

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
    for name in ("index.html", "summary.json", "summary.csv", "gpme.csv", "models.json",
                 "paper/rigid.csv", "paper/flexible.csv", "paper/fig2_joint_coordinates.png"):
        assert (run_dir / name).is_file(), name
    data = json.loads((run_dir / "summary.json").read_text())
    assert len(data["checks"]) == len(summary)
    assert {"name", "engine", "model", "quantity", "worst_abs_error", "tol_abs", "tol_rel",
            "status"} <= set(data["checks"][0])
    assert data["run"]["versions"]["mujoco"] and data["run"]["git_commit"]
    back = pd.read_csv(run_dir / "gpme.csv")
    assert set(back["quantity"]) == {"|Phi_1| after transient", "|Phi_2| after transient",
                                     "energy balance",
                                     "smallest singular value of the constraint Jacobian",
                                     "peak bending angle (arm)", "peak torsion angle (arm)",
                                     "peak bending stress (arm)"}


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
    monkeypatch.setattr(verify, "_paper_step", lambda run_dir, quick, progress: (rows, None))
    first, _, _ = verify.run_verify(root, quick=True, only="paper", progress=False, run_id="same")
    second, _, _ = verify.run_verify(root, quick=True, only="paper", progress=False, run_id="same")
    assert first != second and first.name == "same" and second.name == "same-2"
    assert (first / "index.html").is_file() and (second / "index.html").is_file()
    assert (root / "latest").resolve() == second.resolve()


def test_failing_check_gives_nonzero_exit(report, monkeypatch, capsys):
    root = report[0]

    def broken_step(name, run_dir, scenarios, quick, progress):
        raise RuntimeError(f"{name} engine unavailable")
    monkeypatch.setattr(verify, "_engine_step", broken_step)

    class Args:
        out, quick, only, no_progress, model = str(root), True, "pinocchio", True, []
    assert verify.main(Args) == 1
    assert "1 failed" in capsys.readouterr().out


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
        rows = browser.execute_script("return document.querySelectorAll('#summary tbody tr').length")
        assert rows == len(summary)
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
