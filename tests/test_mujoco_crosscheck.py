"""The MuJoCo crosscheck of any scenario, quick CI version: the crane (rigid and RFEM
n = 1, on the constraints) passes with every section present and its report written;
information rows are never passes; a scenario MuJoCo's mechanism cannot express runs
the exact sections only; and a stiffness changed in the MuJoCo model only fails."""
import numpy as np
import pandas as pd
import pytest

from crosscheck.mujoco import cases
from crosscheck.mujoco import check as mujoco_check
from crosscheck.mujoco import runs as mj_runs
from crosscheck.mujoco.mjcf import mjcf_text
from crosscheck.reports.rows import read_rows
from gpme_io.scenario import crane_scenario
from test_exact_runs import arm_scenario

CRANES = (0, 1)


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("mujoco")
    scenarios = [crane_scenario(n, on_constraints=True) for n in CRANES]
    return out, mujoco_check.run(out, scenarios, quick=True)


def test_quick_run_passes_and_writes_the_report(quick_run):
    out, df = quick_run
    failing = df.loc[df["status"] == "fail", ["section", "model", "coordinate", "abs_error",
                                              "tol_abs"]]
    assert failing.empty, failing.to_string()
    assert set(df["section"]) == {"terms", "free", "exact", "mechanism", "off-manifold",
                                  "wall time"}
    csv = read_rows(out, "mujoco")
    # MuJoCo's own rows; gpme's observed-order rows of the runs it made are gpme's checks
    assert len(csv) == (df["engine"] == "mujoco").sum()
    assert set(df["engine"]) == {"mujoco", "gpme"}
    assert {"section", "case", "coordinate", "metric", "abs_error", "status", "reason"} <= set(csv)
    page = (out / "mujoco.html").read_text()
    assert "Soft-equality mechanism" in page and "data:image" not in page
    # each plot stored once, as a PNG beside the page, and linked from it
    pngs = sorted(p.name for p in out.glob("mujoco_*.png"))
    assert pngs and all(f'src="{name}"' in page for name in pngs)


def test_exact_rows_are_gated_by_the_integrator_error(quick_run):
    _, df = quick_run
    exact = df[(df["section"] == "exact") & (df["coordinate"] != "all")]
    for model in ("crane_rigid", "crane_flexible_n1"):
        assert (exact["model"] == model).sum() > 0
    assert (exact["status"] == "pass").all()
    assert exact["reason"].str.contains("Richardson").all()
    # the gates of coordinates sit far below their signal (1e-6 relative)
    coords = exact[exact["coordinate"].isin(["psi3", "z4", "z1"])]
    assert (coords["tol_abs"] < 1e-6 * coords["scale"]).all()


def test_information_rows_are_never_passes(quick_run):
    _, df = quick_run
    assert df["reason"].str.len().min() > 10
    ungated = ~np.isfinite(df["tol_abs"])
    assert (df.loc[ungated, "status"] == "info").all()
    assert (df.loc[df["status"] == "info", "reason"].str.startswith("information")).all()
    assert (df.loc[df["section"] == "off-manifold", "status"] == "info").all()
    mech = df[df["section"] == "mechanism"]
    ratios = mech[mech["metric"] == "difference ratio (fine / coarse)"]
    # a coordinate whose coarse difference is within MECHANISM_RESOLVED round-off floors
    # has no measurable convergence: information; every resolved one must pass, and each
    # model has some
    resolved = ratios[ratios["status"] != "info"]
    assert (resolved["status"] == "pass").all()
    assert set(resolved["model"]) == set(ratios["model"])
    assert ratios.loc[ratios["status"] == "info", "reason"].str.contains("floor").all()
    assert (resolved["tol_abs"] == cases.MECHANISM_RATIO.abs).all()
    assert (mech.loc[mech["metric"] != "difference ratio (fine / coarse)", "status"] == "info").all()


def test_a_scenario_without_mechanism_runs_the_exact_sections(tmp_path, monkeypatch):
    monkeypatch.setattr(cases, "QUICK_T_END", 0.1)
    df = mujoco_check.run(tmp_path, [arm_scenario()], quick=True)
    assert set(df["section"]) == {"terms", "free", "exact", "wall time"}
    assert (df["status"] != "fail").all(), df.loc[df["status"] == "fail", "quantity"].tolist()


def test_a_stiffness_changed_in_mujoco_only_fails_the_run(tmp_path, monkeypatch):
    """The support stiffness s_z of MuJoCo's model is 0.1 % higher: terms, free and exact
    comparisons must report it, and the page must say so."""
    monkeypatch.setattr(cases, "QUICK_T_END", 0.05)

    def perturbed_load(model, dt):
        import mujoco
        changed = model.with_changes(joint_changes={"z1": {"stiffness": model.stiffness[0] * 1.001}})
        return mujoco.MjModel.from_xml_string(mjcf_text(changed, dt))

    monkeypatch.setattr(mj_runs, "load", perturbed_load)
    df = mujoco_check.run(tmp_path, [crane_scenario(0, on_constraints=True)], quick=True)
    failed = df[df["status"] == "fail"]
    assert {"terms", "free", "exact"} <= set(failed["section"])
    assert {"z1", "lambda_Phi_1"} <= set(failed["coordinate"])
    assert "passive -(f + d) vs qfrc_passive [N, N m]" in set(failed["quantity"])
    assert "FAIL" in (tmp_path / "mujoco.html").read_text()
