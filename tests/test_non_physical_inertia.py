"""Inertias that break the triangle inequality I1 + I2 >= I3 (CAD round-off in robot
descriptions; issue 28): accepted as Pinocchio accepts them, said in a warning, a note and
an information row with the excess, and the engines that would compute with another body
(MuJoCo, Drake) give one information row instead of failed checks."""
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from crosscheck import inertia_gate
from crosscheck.run_checks import inertia_rows, run_rows
from gpme.verify_command import terminal_table
from gpme_core.errors import InertiaWarning
from gpme_io.modelfile import load_model_file
from gpme_io.runs import simulate_scenario

REPO = Path(__file__).resolve().parent.parent
CAD_ARM = REPO / "tests" / "data" / "non_physical" / "cad_arm.toml"
MY_ARM = REPO / "examples" / "my_arm" / "my_arm.toml"


@pytest.fixture(scope="module")
def cad_arm():
    with pytest.warns(InertiaWarning, match=r"body on link 'upper_arm': principal moments "
                                            r"\[0\.001, 0\.02, 0\.03\] kg m\^2 break"):
        return load_model_file(CAD_ARM)


def test_the_model_is_accepted_with_a_note_naming_the_link(cad_arm):
    assert any(n.startswith("non-physical inertias of moving links accepted: link "
                            "'upper_arm' <inertial>") for n in cad_arm.notes), cad_arm.notes
    assert len(cad_arm.model.non_physical_inertias()) == 1
    assert not load_model_file(MY_ARM).model.non_physical_inertias()   # the physical original


def test_the_run_reports_the_excess_as_information(cad_arm):
    """Excess I3 - (I1 + I2) = 0.03 - (0.001 + 0.02) = 0.009 kg m^2 (the file's moments)."""
    df = simulate_scenario(cad_arm, t_end=0.05)
    rows = [r for r in run_rows(cad_arm, df) if r["quantity"].startswith("non-physical")]
    assert len(rows) == 1
    row = rows[0]
    assert row["quantity"] == "non-physical inertia (upper_arm)"
    assert row["status"] == "info" and row["gpme_value"] == pytest.approx(0.009, rel=1e-12)
    assert "[0.001, 0.02, 0.03]" in row["reason"]
    assert inertia_rows(load_model_file(MY_ARM), "-") == []


def test_mujoco_and_drake_give_one_information_row_pinocchio_and_exudyn_compare(cad_arm):
    for engine in ("mujoco", "drake"):
        reason = inertia_gate.refusal(engine, cad_arm)
        assert reason and "link 'upper_arm' of this model breaks I1 + I2 >= I3" in reason
        row = inertia_gate.refusal_row(engine, cad_arm, reason)
        assert row["status"] == "info" and row["quantity"] == inertia_gate.QUANTITY
    for engine in ("pinocchio", "exudyn", "gpme"):
        assert inertia_gate.refusal(engine, cad_arm) is None
    assert inertia_gate.refusal("mujoco", load_model_file(MY_ARM)) is None


def test_the_mujoco_step_does_not_compile_the_model(cad_arm, tmp_path):
    """MuJoCo's compiler refuses such an inertia; the step says why in one row and goes on
    (before the gate it crashed the whole step)."""
    from crosscheck.mujoco import check
    df = check.run(tmp_path, [cad_arm], quick=True)
    assert list(df["quantity"]) == [inertia_gate.QUANTITY]
    assert list(df["status"]) == ["info"]


def test_the_terminal_table_shows_an_information_value_not_an_error_of_zero():
    summary = pd.DataFrame({
        "engine": ["gpme", "gpme"], "section": ["run", "run"], "model": ["m", "m"],
        "quantity": ["smallest singular value of the constraint Jacobian", "energy balance"],
        "n_compared": [1, 1], "worst_abs_error": [0.0, 1e-10], "worst_rel_error": [0.0, 2e-10],
        "tolerance": [np.inf, 8e-7], "value": [0.247, 1e-10]})
    table = terminal_table(summary, pd.Series(["info", "pass"]))
    assert list(table["worst |error|"]) == ["value 2.470e-01", "1.000e-10"]
    assert list(table["tolerance"]) == ["-", "8.000e-07"]
    assert list(table["rel error"]) == ["-", "2.000e-10"]
