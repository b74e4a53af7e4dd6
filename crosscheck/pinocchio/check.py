"""Term-by-term crosscheck of the gpme engine against Pinocchio, for any Scenario
(docs/crosscheck-pinocchio.md).

For each scenario (gpme_io.scenario.Scenario) up to three model cases:

    "direct"        the scenario's gpme model against a pin.Model built from it joint by
                    joint (model.from_gpme);
    "URDF"          the gpme model written by gpme_io.urdf.write_urdf to out_dir/urdf/, read
                    back by gpme's reader and by Pinocchio's own parser (model.from_urdf);
    "original URDF" when the scenario comes from a user's URDF and has no flexible link:
                    Pinocchio reads that URDF itself and locks every joint off the chain with
                    buildReducedModel at the frozen values (model.from_original_urdf).

and for each state (crosscheck.states: seeded random states within the joint limits, states
along a short run) every term is compared through crosscheck.compare.compare, with the
tolerances shared with the Drake check (crosscheck.tolerances) and Pinocchio's own (here):

    quantity            gpme                                 Pinocchio
    pose position/rot.  chain_kinematics T of links, frames  forwardKinematics + updateFramePlacements (oMf)
    M                   dynamics.mass_matrix                 crba (lower triangle checked, see _crba)
    g                   dynamics.gravity_forces (dE_p/dq)    computeGeneralizedGravity  (same sign)
    h                   dynamics.velocity_product_terms      -(rnea(q, v, 0) - computeGeneralizedGravity)
    applied tau         -(f + d) + t                         -K (q - q_ref) - D v + t from this side's data
    frame position/velocity/jacobian/drift of every model frame (the constraint frames among them):
                        kinematics.point_kinematics          oMf, getFrameVelocity, getFrameJacobian,
                                                             getFrameClassicalAcceleration (LOCAL_WORLD_ALIGNED, a = 0)
    Phi, Phi_dot, A, kappa   ProgrammedMotion.solve          crosscheck.constraint_reference (SymPy derivatives
                                                             of the task expressions) at Pinocchio's frame states
    free q_ddot         M^-1 (h + Q)  (no constraints)       aba(q, v, tau)
    constrained q_ddot  reduced GPME (ProgrammedMotion.solve)  forwardDynamics(q, v, tau, A, gamma),
                                                             gamma = kappa + 2 alpha Phi_dot + beta^2 Phi
    lambda, A^T lambda  gpme multipliers / reactions         data.lambda_c, A^T lambda_c

Sign conventions: gpme M q_ddot = h + Q + A^T lambda with Q = -(g + d + f) + t; Pinocchio
M a + b(q, v) = tau + J^T lambda_c with b = rnea(q, v, 0) = C v + g_pin and J a + gamma = 0.
Hence g_pin = g, h = -(b - g_pin), tau = Q + g, and the multipliers agree with the same sign.
"""
import logging
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping, Optional, Sequence

import numpy as np
import pandas as pd
import pinocchio as pin
from tqdm import tqdm

from gpme_core.errors import GpmeError, OutputWriteError
from gpme_core.gpme import ProgrammedMotion
from gpme_core import transforms as tf
from gpme_core.kinematics import chain_kinematics, point_kinematics
from gpme_io.atomic import atomic_write_text
from gpme_io.file_names import named_path
from gpme_io.urdf import read_urdf, write_urdf
from gpme_io.urdf_reader import with_link_frames
from gpme_io.urdf_writer import link_own_frame

from ..crane_cases import crane_cases
from ..compare import Tolerance, compare, tolerance_for
from ..constraint_reference import evaluate_reference, reference_constraints, reference_frames
from ..reports.html import comparison_page, section, table
from ..reports.rows import own_rows, write_rows
from ..states import FULL, QUICK, State, scenario_states
from ..tolerances import TOLERANCES as TERM_TOLERANCES, solve_tolerances
from .model import PinocchioSystem, from_gpme, from_original_urdf, from_urdf
from .runs import run_section

ENGINE = "pinocchio"
LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
SECTIONS = ("terms", "runs")
CASE_KINDS = ("direct", "URDF", "original URDF")
log = logging.getLogger("gpme.crosscheck.pinocchio")

# Each tolerance: abs (in the quantity's unit, a floor for exact zeros) and rel (normwise, to
# the largest entry of the Pinocchio value), with its reason.  The closed-form quantities the
# Drake check compares too take crosscheck.tolerances' entry; the rest are Pinocchio's own.
TOLERANCES = {
    "pose position": TERM_TOLERANCES["pose position"],
    "pose rotation": TERM_TOLERANCES["pose rotation"],
    "M": TERM_TOLERANCES["M"],
    "g": TERM_TOLERANCES["g"],
    "h": TERM_TOLERANCES["h"],
    "applied tau": Tolerance(1e-12, 1e-12, "same springs/dampers from two sources (gpme model "
                             "vs Pinocchio's URDF damping + side-file or model-file springs): "
                             "exact up to one rounding"),
    "frame position": TERM_TOLERANCES["frame position"],
    "frame velocity": TERM_TOLERANCES["frame velocity"],
    "frame jacobian": TERM_TOLERANCES["frame jacobian"],
    "frame drift": TERM_TOLERANCES["frame drift"],
    "Phi": Tolerance(1e-14, 1e-12, "constraint value at the two frame positions; round-off"),
    "Phi_dot": Tolerance(1e-13, 1e-12, "constraint rate from the two frame velocities; "
                         "round-off. Phi_dot -> 0 on the constraint manifold, so along runs "
                         "the abs floor (the constraint's unit per s) decides"),
    "constraint jacobian A": Tolerance(1e-14, 1e-12, "dPhi_dot/dv J at the two frame states; "
                                       "round-off"),
    "constraint kappa": Tolerance(1e-12, 1e-11, "Phi_ddot at a = drift (SymPy derivative of "
                                  "the task expression); inherits the drift tolerance"),
}
# quantities from a linear solve with M: tolerances set per state by
# crosscheck.tolerances.solve_tolerances
SOLVED = ("free q_ddot", "constrained q_ddot", "multipliers lambda", "reactions A^T lambda")
CONSTRAINT_QUANTITIES = ("Phi", "Phi_dot", "constraint jacobian A", "constraint kappa",
                         "constrained q_ddot", "multipliers lambda", "reactions A^T lambda")
FRAME_QUANTITIES = ("frame position", "frame velocity", "frame jacobian", "frame drift")


def overrides(scenario) -> dict:
    """{quantity: Tolerance} the scenario's model file sets for "pinocchio/<quantity>",
    each with the file's reason."""
    out = {}
    for check, o in getattr(scenario, "tolerances", {}).items():
        engine, _, quantity = check.partition("/")
        if engine == ENGINE:
            if quantity not in TOLERANCES and quantity not in SOLVED:
                raise KeyError(f"scenario {scenario.name!r}: tolerance override {check!r} names "
                               f"no compared quantity; have {sorted(TOLERANCES) + list(SOLVED)}")
            out[quantity] = Tolerance(o.abs, o.rel, f"model file: {o.reason}")
    return out


@dataclass(frozen=True)
class ModelCase:
    """One gpme system and its Pinocchio counterpart.

    label     : model column of the report, e.g. "crane_flexible_n3 (URDF)"
    kind      : one of CASE_KINDS
    scenario  : the scenario's name
    system    : gpme_core.gpme.ProgrammedMotion (dependent coordinates fixed)
    pin       : crosscheck.pinocchio.model.PinocchioSystem
    references: the constraints derived independently (crosscheck.constraint_reference)
    overrides : {quantity: Tolerance} from the model file
    """

    label: str
    kind: str
    scenario: str
    system: ProgrammedMotion
    pin: PinocchioSystem
    references: tuple
    overrides: Mapping[str, Tolerance] = field(default_factory=dict)


# --------------------------------------------------------------------------- cases
def _case(label, kind, scenario, system, pin_system):
    refs = tuple(reference_constraints(system.constraint_specs, system.model.coordinate_names))
    return ModelCase(label, kind, scenario.name, system, pin_system, refs, overrides(scenario))


def direct_case(scenario) -> ModelCase:
    """The scenario's gpme system against a pin.Model built from it (model.from_gpme)."""
    return _case(scenario.name, "direct", scenario, scenario.system,
                 from_gpme(scenario.system.model))


def urdf_case(scenario, urdf_dir: Path) -> ModelCase:
    """The scenario's model written to urdf_dir/<name>.urdf, read back by gpme_io.urdf
    (gpme) and by Pinocchio's parser."""
    original = scenario.system
    path = named_path(urdf_dir, scenario.name, ".urdf")
    try:
        write_urdf(original.model, path)
        # frames that are a link's own frame are the URDF link itself (gpme_io.urdf_writer)
        model = with_link_frames(read_urdf(path), [f for f in original.model.frames
                                                   if link_own_frame(original.model, f)])
    except OutputWriteError:
        raise
    except Exception as exc:
        raise type(exc)(f"scenario {scenario.name!r}: URDF round trip: {exc}") from exc
    system = ProgrammedMotion(model, original.constraint_specs, dependent=original.dependent,
                              baumgarte=(original.alpha, original.beta),
                              damping_form=original.damping_form)
    pin_sys = from_urdf(path, model.coordinate_names, [lk.name for lk in model.links],
                        list(model.frames))
    return _case(f"{scenario.name} (URDF)", "URDF", scenario, system, pin_sys)


def original_urdf_case(scenario) -> Optional[ModelCase]:
    """Pinocchio's reduction of the user's URDF against the scenario's gpme system, or
    None when the scenario has no URDF or has flexible links (Pinocchio cannot read an
    RFEM link from the user's URDF)."""
    if scenario.urdf is None or scenario.model.flexible_links:
        return None
    model = scenario.system.model
    pin_sys = from_original_urdf(scenario.urdf, model.coordinate_names,
                                 [lk.name for lk in model.links], list(model.frames),
                                 scenario.frozen, model.gravity, model.stiffness,
                                 model.spring_reference, model.damping,
                                 point_springs=model.point_springs,
                                 auxiliary_frames={
                                     name: (frame, tf.translation(*np.eye(3)[axis]))
                                     for name, (frame, axis) in
                                     reference_frames(scenario.constraints).items()})
    return _case(f"{scenario.name} (original URDF)", "original URDF", scenario,
                 scenario.system, pin_sys)


def model_cases(scenario, urdf_dir: Path) -> list:
    """The model cases of ``scenario`` (direct, URDF, original URDF when it applies)."""
    cases = [direct_case(scenario), urdf_case(scenario, urdf_dir)]
    original = original_urdf_case(scenario)
    return cases + ([original] if original is not None else [])


# --------------------------------------------------------------------------- one state
def _crba(pm, data, q):
    """(M (nv, nv), whole) from pin.crba; older Pinocchio filled only the upper triangle, so
    an empty strict lower triangle is mirrored from the upper one (whole = False)."""
    m = np.array(pin.crba(pm, data, q))
    n = m.shape[0]
    if n > 1 and not np.any(np.tril(m, -1)) and np.any(np.triu(m, 1)):
        return np.triu(m) + np.triu(m, 1).T, False
    return m, True


def compare_state(case: ModelCase, state: State) -> list:
    """Tidy rows (list of dict) comparing every term of ``case`` at ``state``."""
    system, ps = case.system, case.pin
    model, pm = system.model, ps.model
    data = pm.createData()
    t, q, qd = state.t, state.q, state.q_dot
    coords = list(model.coordinate_names)
    rows = []
    tolerances = {**TOLERANCES, **case.overrides}

    def add(quantity, gpme_value, engine_value, labels=None):
        rows.append(compare(ENGINE, case.label, quantity, state.case, gpme_value, engine_value,
                            tolerance_for(tolerances, quantity, case.label), labels))

    # ---- gpme
    kin = chain_kinematics(model, q)
    sol = system.solve(t, q, qd)
    terms = sol.terms
    free = ProgrammedMotion(model).solve(t, q, qd).q_ddot

    # ---- Pinocchio: Jacobians, then kinematics with a = 0 (classical acceleration = drift)
    q_p, v_p = ps.q_pin(q), ps.to_pin(qd)
    m_pin, _ = _crba(pm, data, q_p)
    m_pin = m_pin[np.ix_(ps.v_index, ps.v_index)]
    pin.computeJointJacobians(pm, data, q_p)
    pin.forwardKinematics(pm, data, q_p, v_p, np.zeros(pm.nv))
    pin.updateFramePlacements(pm, data)
    names = [lk.name for lk in model.links] + list(model.frames)
    fids = list(ps.link_frames) + [ps.frames[f] for f in model.frames]
    frame_poses = [kin.T[f.link_index] @ f.transform for f in model.frames.values()]
    gpme_poses = np.concatenate([kin.T, np.reshape(frame_poses, (-1, 4, 4))])
    pin_poses = np.array([data.oMf[i].homogeneous for i in fids])
    xyz = ["x", "y", "z"]
    add("pose position", gpme_poses[:, :3, 3], pin_poses[:, :3, 3], (names, xyz))
    rot_labels = [f"R{i}{j}" for i in range(3) for j in range(3)]
    add("pose rotation", gpme_poses[:, :3, :3].reshape(-1, 9), pin_poses[:, :3, :3].reshape(-1, 9),
        (names, rot_labels))

    point = {}
    for name in model.frames:
        fid = ps.frames[name]
        point[name] = (data.oMf[fid].translation.copy(),
                       pin.getFrameVelocity(pm, data, fid, LWA).linear.copy(),
                       ps.columns_to_gpme(pin.getFrameJacobian(pm, data, fid, LWA)[:3]),
                       pin.getFrameClassicalAcceleration(pm, data, fid, LWA).linear.copy())
    if model.frames:
        frames = list(model.frames)
        pks = [point_kinematics(model, kin, qd, model.frames[f].link_index,
                                model.frames[f].transform[:3, 3]) for f in frames]
        rows_xyz = [f"{f}.{c}" for f in frames for c in xyz]
        add("frame position", [pk.position for pk in pks], [point[f][0] for f in frames],
            (frames, xyz))
        add("frame velocity", [pk.velocity for pk in pks], [point[f][1] for f in frames],
            (frames, xyz))
        add("frame jacobian", np.concatenate([pk.jacobian for pk in pks]),
            np.concatenate([point[f][2] for f in frames]), (rows_xyz, coords))
        add("frame drift", [pk.drift for pk in pks], [point[f][3] for f in frames],
            (frames, xyz))

    # ---- Pinocchio: dynamics terms
    g_pin = ps.to_gpme(pin.computeGeneralizedGravity(pm, data, q_p))
    h_pin = -(ps.to_gpme(pin.rnea(pm, data, q_p, v_p, np.zeros(pm.nv))) - g_pin)
    add("M", terms.M, m_pin, (coords, coords))
    add("g", terms.g, g_pin, coords)
    add("h", terms.h, h_pin, coords)
    tau_gpme = -(terms.f + terms.d) + terms.t
    tau_pin = ps.applied_forces(q, qd, model.drive_forces(t))
    add("applied tau", tau_gpme, tau_pin, coords)

    # ---- constraints from the independent reference at Pinocchio's frame states
    m_c = system.n_constraints
    a_free = ps.to_gpme(pin.aba(pm, data, q_p, v_p, ps.to_pin(tau_pin)))
    if m_c == 0:
        tolerances.update({**solve_tolerances(m_pin, np.zeros(len(q)), np.zeros((0, len(q))),
                                              system.ic, system.dc), **case.overrides})
        add("free q_ddot", free, a_free, coords)
        return rows
    phi, phi_dot, a_pin, kappa = evaluate_reference(case.references, t, q, qd, point.__getitem__)
    cons = list(system.constraint_names)
    add("Phi", sol.phi, phi, cons)
    add("Phi_dot", sol.phi_dot, phi_dot, cons)
    add("constraint jacobian A", sol.jacobian, a_pin, (cons, coords))
    add("constraint kappa", sol.kappa, kappa, cons)
    gamma = kappa + 2.0 * system.alpha * phi_dot + system.beta ** 2 * phi
    a_con = ps.to_gpme(pin.forwardDynamics(pm, data, q_p, v_p, ps.to_pin(tau_pin),
                                           ps.to_pin(a_pin.T).T, gamma))
    lam = np.array(data.lambda_c).copy()
    tolerances.update({**solve_tolerances(m_pin, a_pin.T @ lam, a_pin, system.ic, system.dc),
                       **case.overrides})
    add("free q_ddot", free, a_free, coords)
    add("constrained q_ddot", sol.q_ddot, a_con, coords)
    add("multipliers lambda", sol.multipliers, lam, cons)
    add("reactions A^T lambda", sol.reaction_forces, a_pin.T @ lam, coords)
    return rows


def compare_case(case: ModelCase, states: Sequence[State]) -> pd.DataFrame:
    """Tidy DataFrame of every comparison of ``case`` over ``states``."""
    return pd.DataFrame([row for s in states for row in compare_state(case, s)])


# --------------------------------------------------------------------------- the run
def default_scenarios(quick: bool = False) -> list:
    """The paper's crane cases `gpme verify` checks here when no model file is given
    (crosscheck.crane_cases: rigid and 1, 3, 10 RFEM segments; quick: rigid and 3)."""
    return crane_cases("pinocchio", quick)


def _progress(enabled, total):
    if not enabled:
        return None
    return tqdm(total=total, desc="pinocchio crosscheck", unit="scenario")


@dataclass(frozen=True)
class CaseRecord:
    """What the report says about one model case besides its rows."""

    label: str
    kind: str
    scenario: str
    n: int
    nq_pin: int
    n_states: int
    crba_whole: bool
    notes: tuple


def run(out_dir: Path, scenarios: Optional[Sequence] = None, quick: bool = False,
        progress: bool = False, sections: Sequence[str] = SECTIONS) -> pd.DataFrame:
    """Compare gpme with Pinocchio for every scenario; write the rows
    (crosscheck.reports.rows: out_dir/checks/pinocchio/) and out_dir/pinocchio.html
    (atomically) and return the tidy table (columns of
    crosscheck.compare.COLUMNS plus ``section``; one row per quantity, model case and state).

    scenarios: gpme_io.scenario.Scenario objects; None: default_scenarios(quick) (the crane).
    quick    : crosscheck.states.QUICK plan (3 random + 2 run states per model) instead of
               FULL.
    sections : "terms" (this module) and/or "runs" (crosscheck.pinocchio.runs.run_section).
    """
    unknown = sorted(set(sections) - set(SECTIONS))
    if unknown:
        raise ValueError(f"unknown sections {unknown}; choose from {SECTIONS}")
    scenarios = default_scenarios(quick) if scenarios is None else list(scenarios)
    start = time.perf_counter()
    parts = []
    bar = _progress(progress, len(scenarios))
    for scenario in scenarios:
        parts.append(scenario_part(out_dir, scenario, quick, sections))
        if bar:
            bar.update()
    if bar:
        bar.close()
    return finish(out_dir, parts, quick, time.perf_counter() - start)


def scenario_part(out_dir: Path, scenario, quick: bool = False,
                  sections: Sequence[str] = SECTIONS) -> dict:
    """What :func:`run` computes for one scenario (files it writes go under ``out_dir``):
    {"frames": row tables, "records": CaseRecord list, "skipped": notes}, picklable, for
    :func:`finish` (crosscheck.step_pool runs scenarios in separate processes)."""
    out_dir = Path(out_dir)
    plan = QUICK if quick else FULL
    frames, records, skipped = [], [], []
    if "terms" in sections:
        cases = model_cases(scenario, out_dir / "urdf")
        if scenario.urdf is not None and len(cases) < 3:
            skipped.append(f"{scenario.name}: no original-URDF case (the model has "
                           "flexible links, which the user's URDF does not describe)")
        states = scenario_states(scenario, plan)
        for case in cases:
            if case.system.model.coordinate_names != scenario.model.coordinate_names:
                raise ValueError(f"{case.label}: coordinates "
                                 f"{case.system.model.coordinate_names} differ from the "
                                 f"scenario's {scenario.model.coordinate_names}")
            df = compare_case(case, states)
            frames.append(df.assign(section="terms"))
            data = case.pin.model.createData()
            records.append(CaseRecord(
                case.label, case.kind, scenario.name, case.system.model.n_coordinates,
                case.pin.model.nq, len(states),
                _crba(case.pin.model, data, case.pin.q_pin(states[0].q))[1],
                case.pin.notes))
            log.info("%s: %d states, %d rows, %d failing", case.label, len(states), len(df),
                     int((~df["passed"]).sum()))
    if "runs" in sections:
        try:
            rows = run_section(scenario, quick, log.info)
        except GpmeError as exc:     # a run that cannot be made is a failed check
            rows = [compare(ENGINE, scenario.name, "exact programmed run: failed",
                            "run", [np.nan], [0.0], Tolerance(0.0, 0.0, f"the run failed: "
                            f"{exc}"[:500]), ["-"])]
        frames.append(pd.DataFrame(rows).assign(
            section=[r.get("section", "runs") for r in rows]))
    return {"frames": frames, "records": records, "skipped": skipped}


def finish(out_dir: Path, parts: Sequence[dict], quick: bool, wall: float) -> pd.DataFrame:
    """The scenarios' parts (:func:`scenario_part`, in scenario order) as one table: its rows
    (crosscheck.reports.rows) and out_dir/pinocchio.html written (atomically), the table
    returned.  wall: s, the time the parts took."""
    out_dir = Path(out_dir)
    frames = [f for part in parts for f in part["frames"]]
    records = [r for part in parts for r in part["records"]]
    skipped = [s for part in parts for s in part["skipped"]]
    df = pd.concat(frames, ignore_index=True) if frames else pd.DataFrame()
    out_dir.mkdir(parents=True, exist_ok=True)
    write_rows(own_rows(df, ENGINE), out_dir, ENGINE)
    atomic_write_text(out_dir / "pinocchio.html",
                             _html(df, records, skipped, wall, quick))
    return df


CONVENTIONS = (
    "Conventions: gpme M q̈ = h + Q + Aᵀλ, Q = -(g + d + f) + t; Pinocchio M a + b = τ + "
    "Jᵀλ_c, J a + γ = 0. Compared: g with computeGeneralizedGravity, h with -(rnea(q, v, 0) "
    "- g), τ = -K(q - q_ref) - D v + t, γ = κ + 2αΦ̇ + β²Φ; the constraint terms on the "
    "Pinocchio side come from SymPy derivatives of the task expressions at Pinocchio's frame "
    "states. Errors are normwise: abs = max|x - y|, rel = abs / max|y|; pass when abs ≤ "
    "tol_abs + tol_rel max|y|; info rows have no finite tolerance and are never counted as "
    "passes.")


def _html(df, records, skipped, wall, quick):
    """pinocchio.html (crosscheck.reports.html.comparison_page)."""
    crba = ("pin.crba returned the whole symmetric matrix" if all(r.crba_whole for r in records)
            else "pin.crba filled only the upper triangle for some models; it was mirrored "
                 "before comparing")
    cases = pd.DataFrame([{"model case": r.label, "kind": r.kind, "n (gpme)": r.n,
                           "nq (Pinocchio)": r.nq_pin, "states": r.n_states,
                           "Pinocchio side": "; ".join(r.notes)} for r in records])
    intro = [f"{len(df)} comparisons over {len(records)} model cases; "
             f"{'quick' if quick else 'full'} run, {wall:.1f} s. {crba}."]
    model_cases = section("Model cases", items=skipped, table=table(
        cases, status_column="-", left_columns=("model case", "kind", "Pinocchio side")))
    return comparison_page(ENGINE, "gpme vs Pinocchio", pin.__version__, df, intro,
                           [model_cases], CONVENTIONS)
