"""The term-by-term Pinocchio crosscheck (crosscheck/pinocchio/check.py): a reduced run,
and proof that the harness fails when one engine is perturbed by 1e-6."""
import dataclasses

import numpy as np
import pandas as pd
import pinocchio as pin
import pytest

from crosscheck.pinocchio import check as pc
from gpme_examples.crane import CraneParameters, crane_constraints
from gpme_core.gpme import ProgrammedMotion
from gpme_core.inertia import RigidBodyInertia

QUANTITIES = set(pc.TOLERANCES) | set(pc.SOLVED)
PERTURBATION = 1e-6      # relative change of one inertia entry or one stiffness


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("report")
    return out, pc.run(out, quick=True)


def test_quick_run_passes_and_writes_reports(quick_run):
    out, df = quick_run
    failed = df[~df["passed"]]
    assert failed.empty, failed[["model", "quantity", "case", "rel_error", "tol_rel"]].to_string()
    assert set(df["quantity"]) == QUANTITIES
    assert set(df["model"]) == {"crane_rigid", "crane_flexible_n1", "crane_flexible_n3",
                                "crane_flexible_n10", "crane_rigid (URDF)",
                                "crane_flexible_n3 (URDF)"}
    per_model = df.groupby("model")["case"].nunique()
    assert (per_model == pc.QUICK.n_random + pc.QUICK.n_run).all()
    csv = pd.read_csv(out / "pinocchio.csv")
    assert len(csv) == len(df) and list(csv.columns) == list(df.columns)
    page = (out / "pinocchio.html").read_text()
    assert "all comparisons pass" in page and "Worst cases" in page


def test_every_tolerance_at_most_1e9_or_explained(quick_run):
    _, df = quick_run
    loose = df[df["tol_rel"] > 1e-9]
    assert set(loose["quantity"]) <= set(pc.SOLVED)
    assert loose["reason"].str.contains("cond").all()
    assert (df["reason"].str.len() > 20).all()


def _states(case, count=3):
    return pc.random_states(case.system, count, np.random.default_rng(7))


def _failed_quantities(case, states):
    df = pc.compare_case(case, states)
    return df, set(df.loc[~df["passed"], "quantity"])


def test_inertia_perturbed_in_gpme_only_is_reported():
    case = pc.crane_case(1)
    states = _states(case)
    _, failed = _failed_quantities(case, states)
    assert not failed
    column = next(lk for lk in case.system.model.links if lk.name == "column").inertia
    i = column.inertia_array.copy()
    i[2, 2] *= 1.0 + PERTURBATION
    model = case.system.model.with_changes(
        link_inertias={"column": RigidBodyInertia(column.mass, column.com, i)})
    p = CraneParameters()
    system = ProgrammedMotion(model, crane_constraints(p), dependent=("psi3", "z4"),
                              baumgarte=(p.baumgarte_alpha, p.baumgarte_beta))
    df, failed = _failed_quantities(dataclasses.replace(case, system=system), states)
    assert "M" in failed
    m_rows = df[df["quantity"] == "M"]
    assert not m_rows["passed"].any()
    assert set(m_rows["entry"]) == {"[psi2, psi2]"}


def test_inertia_perturbed_in_pinocchio_only_is_reported():
    case = pc.crane_case(0)
    states = _states(case)
    pm = case.pin.model.copy()
    k = case.system.model.index("z4") + 1          # Pinocchio joint of the slider
    old = pm.inertias[k]
    i = np.array(old.inertia).copy()
    i[1, 1] *= 1.0 + PERTURBATION
    pm.inertias[k] = pin.Inertia(old.mass, old.lever, i)
    df, failed = _failed_quantities(
        dataclasses.replace(case, pin=dataclasses.replace(case.pin, model=pm)), states)
    assert {"M", "h"} <= failed
    assert not df.loc[df["quantity"] == "M", "passed"].any()


def test_stiffness_perturbed_in_gpme_only_is_reported():
    case = pc.crane_case(3)
    states = _states(case, 2)
    joint = "theta_arm_2"
    k0 = case.system.model.joints[case.system.model.index(joint)].stiffness
    model = case.system.model.with_changes(
        joint_changes={joint: {"stiffness": k0 * (1.0 + PERTURBATION)}})
    p = CraneParameters()
    system = ProgrammedMotion(model, crane_constraints(p), dependent=("psi3", "z4"),
                              baumgarte=(p.baumgarte_alpha, p.baumgarte_beta))
    df, failed = _failed_quantities(dataclasses.replace(case, system=system), states)
    tau = df[df["quantity"] == "applied tau"]
    assert not tau["passed"].any() and set(tau["entry"]) == {joint}
    assert failed <= {"applied tau", "free q_ddot", "constrained q_ddot", "multipliers lambda",
                      "reactions A^T lambda"}


def test_upper_triangle_crba_is_mirrored_not_misreported(monkeypatch):
    """Older Pinocchio filled only the upper triangle of crba; the harness checks which."""
    case = pc.crane_case(1)
    states = _states(case, 1)
    real = pin.crba
    monkeypatch.setattr(pc.pin, "crba", lambda m, d, q: np.triu(real(m, d, q)))
    df = pc.compare_case(case, states)
    assert df.loc[df["quantity"] == "M", "passed"].all()
    m, whole = pc._crba(case.pin.model, case.pin.model.createData(), states[0].q)
    assert not whole and np.array_equal(m, m.T)


def test_this_pinocchio_fills_the_whole_mass_matrix():
    case = pc.crane_case(3)
    data = case.pin.model.createData()
    q = _states(case, 1)[0].q
    raw = np.array(pin.crba(case.pin.model, data, q))
    assert np.array_equal(raw, raw.T), "pin.crba no longer returns the whole matrix"
