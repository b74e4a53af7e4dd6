"""The MuJoCo crosscheck, short CI version (about 1 s of motion per case), and proof that
the harness can fail: a stiffness changed in the MuJoCo model only is reported."""
import pandas as pd
import pytest

from crosscheck.mujoco import cases as cases
from crosscheck.mujoco import check as mujoco_check
from crosscheck.mujoco.mjcf import mjcf_text


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("mujoco")
    return out, mujoco_check.run(out, quick=True)


def test_quick_run_passes_and_writes_the_report(quick_run):
    out, df = quick_run
    failing = df.loc[~df["passed"], ["section", "model", "coordinate", "abs_error", "tol_abs"]]
    assert failing.empty, failing.to_string()
    assert set(df["section"]) == {"terms", "free", "programmed", "convergence", "off-manifold",
                                  "wall time"}
    csv = pd.read_csv(out / "mujoco.csv")
    assert len(csv) == len(df)
    assert {"section", "case", "coordinate", "metric", "abs_error", "passed", "reason"} <= set(csv)
    page = (out / "mujoco.html").read_text()
    assert "data:image/png;base64," in page and "Convergence" in page


def test_every_row_states_a_reason_and_off_manifold_is_not_gated(quick_run):
    _, df = quick_run
    assert df["reason"].str.len().min() > 10
    off = df[df["section"] == "off-manifold"]
    assert len(off) > 0 and off["reason"].str.startswith("not gated").all()
    # the gated programmed rows really are gated (finite tolerances)
    prog = df[(df["section"] == "programmed") & (df["metric"] == "max |gpme - mujoco|")]
    assert (prog["tol_abs"] < 1e-3).all()


def test_a_stiffness_changed_in_mujoco_only_fails_the_run(tmp_path, monkeypatch):
    """The support stiffness s_z of MuJoCo's models is 0.1 % higher: terms, free and
    programmed comparisons must report it, and the run must say so."""
    tiny = cases.Plan(True, 0.2, (0,), 1, (0,), (0,), ((1e-4, 4e-4), (1e-4, 1e-4)), False)
    monkeypatch.setattr(cases, "plan", lambda quick: tiny)

    def perturbed_load(model, dt, constraints=None, settings=None):
        import mujoco
        changed = model.with_changes(joint_changes={"z1": {"stiffness": model.stiffness[0] * 1.001}})
        return mujoco.MjModel.from_xml_string(mjcf_text(changed, dt, constraints, settings))

    monkeypatch.setattr(mujoco_check, "_load", perturbed_load)
    df = mujoco_check.run(tmp_path, quick=True)
    failed = df[~df["passed"]]
    assert {"terms", "free", "programmed"} <= set(failed["section"])
    assert "z1" in set(failed["coordinate"])
    assert "passive -(f + d) vs qfrc_passive [N, N m]" in set(failed["quantity"])
    assert "FAIL" in (tmp_path / "mujoco.html").read_text()
