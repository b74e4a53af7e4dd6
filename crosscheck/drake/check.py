"""Term-by-term crosscheck of the gpme engine against Drake, and free-motion runs with
Drake's own integrator, for any Scenario (docs/crosscheck-drake.md).

For each scenario (gpme_io.scenario.Scenario) the gpme model is written by
gpme_io.urdf.write_urdf to out_dir/urdf/drake/<name>.urdf and read by Drake's own parser
into a continuous MultibodyPlant (crosscheck.drake.model.from_urdf: springs as force elements and
gravity from the side file, dampers as Drake's joint damping from <dynamics damping>).  At
each state (crosscheck.states.scenario_states: seeded random states within the joint limits
and states along a short run, the plan and states of the Pinocchio check) every term of
gpme's ``ProgrammedMotion.solve(t, q, q_dot).terms`` is compared through
crosscheck.compare.compare, with the tolerances shared with the Pinocchio check
(crosscheck.tolerances) and Drake's own (here):

    quantity             gpme (M q_ddot = h + Q, Q = -(g + d + f) + t)   Drake
    pose position/rot.   chain_kinematics T of links, frames           Frame.CalcPoseInWorld
    M                    terms.M                                       CalcMassMatrix
    bias term C(q,v) v   -terms.h                                      CalcBiasTerm
    gravity tau_g        -terms.g                                      CalcGravityGeneralizedForces
    spring forces        -terms.f                                      force elements at v = 0,
                                                                       minus tau_g
    damper forces        -terms.d                                      force elements at v minus
                                                                       those at v = 0
    frame position, velocity, jacobian, drift (every model frame):
                         kinematics.point_kinematics                   CalcPointsPositions,
                         CalcSpatialVelocityInWorld, CalcJacobianTranslationalVelocity (kV),
                         CalcBiasTranslationalAcceleration (kV), all in the world frame
    free q_ddot          M^-1 (h + Q) (ProgrammedMotion(model).solve)  generalized acceleration
                                                                       output port, drives on
                                                                       the applied generalized
                                                                       force input port
    inverse dynamics tau terms.t (the drives)                          CalcInverseDynamics at
                                                                       gpme's free q_ddot, force
                                                                       elements as external forces

"Force elements" is ``CalcForceElementsContribution`` turned into generalized forces by
``CalcGeneralizedForces``: it holds gravity (as body forces of the UniformGravityFieldElement),
the springs and Drake's joint damping (measured: docs/crosscheck-drake.md), hence the
subtractions above.

Sign conventions: Drake M v_dot + C(q, v) v = tau_g(q) + tau_app + sum J^T F; so Drake's
bias C v is gpme's -h (left-hand side), tau_g is -g, the force elements give -(f + d), and
the drives t enter as tau_app.

The free runs (section "runs") are in crosscheck.drake.runs.
"""
import logging
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping, Optional, Sequence

import numpy as np
import pandas as pd
from pydrake.multibody.tree import JacobianWrtVariable, MultibodyForces
from tqdm import tqdm

from gpme_core.errors import GpmeError, SimulationError
from gpme_core.gpme import ProgrammedMotion
from gpme_core.kinematics import chain_kinematics, point_kinematics
from gpme_io.atomic import atomic_write_text

from .. import inertia_gate
from ..crane_cases import crane_cases
from ..compare import Tolerance, compare, tolerance_for
from ..reports.html import comparison_page, section, table
from ..reports.rows import own_rows, write_rows
from ..states import FULL, QUICK, scenario_states
from ..tolerances import TOLERANCES as TERM_TOLERANCES, solve_tolerances
from .model import DrakeSystem, drake_version, for_model
from .runs import run_section

ENGINE = "drake"
SECTIONS = ("terms", "runs")
URDF_SUBDIR = "urdf/drake"     # under out_dir: the URDFs (and side files) Drake reads
log = logging.getLogger("gpme.crosscheck.drake")

_SPLIT = ("; Drake gives the force elements' sum (gravity, springs, joint damping), so the "
          "part is a difference of sums as large as the largest part: the relative "
          "tolerance is taken of scale = max(|spring|, |damper|, |tau_g|) (the row's scale)")
# Each tolerance: abs (in the quantity's unit, a floor for exact zeros) and rel (normwise, to
# the row's scale), with its reason.  Where the reason is the one the Pinocchio check gives
# too (the same closed-form quantity in double precision), crosscheck.tolerances' entry is
# used.
TOLERANCES = {
    "pose position": TERM_TOLERANCES["pose position"],
    "pose rotation": TERM_TOLERANCES["pose rotation"],
    "M": TERM_TOLERANCES["M"],
    "bias term C(q,v) v": TERM_TOLERANCES["h"],
    "gravity tau_g": TERM_TOLERANCES["g"],
    "spring forces": Tolerance(1e-12, 1e-12, "the same K (q - q_ref) from two sources (gpme "
                               "model vs Drake's RevoluteSpring/PrismaticSpring with the side "
                               "file's stiffness and reference): exact up to a few roundings"
                               + _SPLIT + " (N, N m)"),
    "damper forces": Tolerance(1e-12, 1e-12, "the same D q_dot from two sources (gpme model "
                               "vs the <dynamics damping> Drake's parser read, applied as its "
                               "joint damping): exact up to a few roundings" + _SPLIT +
                               " (N, N m)"),
    "frame position": TERM_TOLERANCES["frame position"],
    "frame velocity": TERM_TOLERANCES["frame velocity"],
    "frame jacobian": TERM_TOLERANCES["frame jacobian"],
    "frame drift": TERM_TOLERANCES["frame drift"],
}
# quantities whose tolerance is set per state: free q_ddot by solve_tolerances (cond(M)),
# the inverse dynamics residual by :func:`residual_tolerance` (n)
SOLVED = ("free q_ddot", "inverse dynamics tau")
EPS = float(np.finfo(float).eps)
# Cholesky's backward error: gpme's q_ddot solves (M + dM) q_ddot = h + Q with ||dM|| <= c n
# eps ||M|| (Higham, Accuracy and Stability of Numerical Algorithms, 2nd ed., Thm 10.3-10.4),
# so the residual M q_ddot - (h + Q) is ~n eps ||M|| ||q_ddot||, whatever cond(M); Drake's
# Newton-Euler pass adds round-off of the same order.  x2 two evaluations, x2 for c.
RESIDUAL_FACTOR = 4.0
QUANTITIES = tuple(TOLERANCES) + SOLVED


def overrides(scenario) -> dict:
    """{quantity: Tolerance} the scenario's model file sets for "drake/<quantity>", each
    with the file's reason.  The free-run columns ("free run <column>") are overridden in
    crosscheck.halving_gates through scenario.tolerance; an override naming neither is a
    KeyError (harness or model-file bug)."""
    out = {}
    for check, o in getattr(scenario, "tolerances", {}).items():
        engine, _, quantity = check.partition("/")
        if engine != ENGINE or quantity.startswith("free run"):
            continue
        if quantity not in QUANTITIES:
            raise KeyError(f"scenario {scenario.name!r}: tolerance override {check!r} names "
                           f"no compared quantity; have {list(QUANTITIES)} and 'free run "
                           "<column>'")
        out[quantity] = Tolerance(o.abs, o.rel, f"model file: {o.reason}")
    return out


@dataclass(frozen=True)
class DrakeCase:
    """One gpme system and its Drake counterpart.

    label    : model column of the report (the scenario's name)
    scenario : the scenario's name
    system   : gpme_core.gpme.ProgrammedMotion without constraints (terms and free q_ddot)
    drake    : crosscheck.drake.model.DrakeSystem
    context  : a Drake context of drake.plant (tests perturb its parameters)
    overrides: {quantity: Tolerance} from the model file
    """

    label: str
    scenario: str
    system: ProgrammedMotion
    drake: DrakeSystem
    context: object
    overrides: Mapping[str, Tolerance] = field(default_factory=dict)


def make_case(scenario, urdf_dir: Path, drake_system: Optional[DrakeSystem] = None) -> DrakeCase:
    """The scenario's gpme model against Drake's plant of the URDF it writes to urdf_dir
    (or ``drake_system``, e.g. a perturbed one in the tests)."""
    model = scenario.model
    ds = drake_system or for_model(model, urdf_dir, scenario.name)
    return DrakeCase(scenario.name, scenario.name, ProgrammedMotion(model), ds,
                     ds.plant.CreateDefaultContext(), overrides(scenario))


# --------------------------------------------------------------------------- one state
def drake_terms(ds: DrakeSystem, context, t: float, q, q_dot, drives) -> dict:
    """Drake's terms at one state, gpme coordinate order (n,) or (n, n), SI units.

    q (n,) rad or m, q_dot (n,), drives (n,) N or N m (the applied generalized forces).
    Keys: M, bias (C v, left-hand side), tau_g, springs, dampers (generalized forces on the
    right-hand side), q_ddot (forward dynamics with the drives), scale (max |tau_g|, |springs|,
    |dampers|: the size of the force elements' sum the two parts are taken from).
    """
    plant = ds.plant
    plant.SetPositions(context, ds.q_drake(q))
    plant.get_applied_generalized_force_input_port().FixValue(context, ds.to_drake(drives))
    forces = MultibodyForces(plant)
    out = {}
    # at v = 0: gravity + springs (+ damping, which vanishes)
    plant.SetVelocities(context, np.zeros(plant.num_velocities()))
    tau_g = np.array(plant.CalcGravityGeneralizedForces(context))
    plant.CalcForceElementsContribution(context, forces)
    at_rest = np.array(plant.CalcGeneralizedForces(context, forces))
    plant.SetVelocities(context, ds.to_drake(q_dot))
    forces.SetZero()
    plant.CalcForceElementsContribution(context, forces)
    moving = np.array(plant.CalcGeneralizedForces(context, forces))
    out["M"] = ds.matrix_to_gpme(plant.CalcMassMatrix(context))
    out["bias"] = ds.to_gpme(plant.CalcBiasTerm(context))
    out["tau_g"] = ds.to_gpme(tau_g)
    out["springs"] = ds.to_gpme(at_rest - tau_g)
    out["dampers"] = ds.to_gpme(moving - at_rest)
    out["scale"] = float(max(np.abs(tau_g).max(initial=0.0), np.abs(at_rest - tau_g).max(
        initial=0.0), np.abs(moving - at_rest).max(initial=0.0)))
    out["q_ddot"] = ds.to_gpme(plant.get_generalized_acceleration_output_port().Eval(context))
    return out


def drake_frame(ds: DrakeSystem, context, name: str) -> tuple:
    """(T (4, 4) pose in the world, p (3,) m, v (3,) m/s, J (3, n) gpme columns, drift (3,)
    m/s^2) of the origin of body ``name``'s frame, world frame; context at (q, v)."""
    plant = ds.plant
    frame = ds.bodies[name].body_frame()
    world = plant.world_frame()
    origin = np.zeros((3, 1))
    pose = frame.CalcPoseInWorld(context).GetAsMatrix4()
    p = np.array(plant.CalcPointsPositions(context, frame, origin, world))[:, 0]
    v = np.array(frame.CalcSpatialVelocityInWorld(context).translational())
    jac = plant.CalcJacobianTranslationalVelocity(context, JacobianWrtVariable.kV, frame,
                                                  origin, world, world)
    drift = np.array(plant.CalcBiasTranslationalAcceleration(
        context, JacobianWrtVariable.kV, frame, origin, world, world))[:, 0]
    return pose, p, v, ds.columns_to_gpme(jac), drift


def compare_state(case: DrakeCase, state) -> list:
    """Tidy rows (list of dict) comparing every term of ``case`` at ``state`` (a
    crosscheck.states.State: case name, t s, q (n,), q_dot (n,))."""
    system, ds, ctx = case.system, case.drake, case.context
    model = system.model
    t, q, qd = state.t, np.asarray(state.q, float), np.asarray(state.q_dot, float)
    coords = list(model.coordinate_names)
    rows = []
    tolerances = {**TOLERANCES, **case.overrides}

    def add(quantity, gpme_value, engine_value, labels=None, scale=None):
        rows.append(compare(ENGINE, case.label, quantity, state.case, gpme_value, engine_value,
                            tolerance_for(tolerances, quantity, case.label), labels, scale))

    # ---- gpme
    sol = system.solve(t, q, qd)
    terms = sol.terms
    kin = terms.kin if getattr(terms, "kin", None) is not None else chain_kinematics(model, q)

    # ---- Drake
    d = drake_terms(ds, ctx, t, q, qd, model.drive_forces(t))
    names = [lk.name for lk in model.links] + list(model.frames)
    frame_data = {n: drake_frame(ds, ctx, n) for n in names}
    gpme_poses = np.concatenate([kin.T] + [(kin.T[f.link_index] @ f.transform)[None]
                                           for f in model.frames.values()])
    drake_poses = np.array([frame_data[n][0] for n in names])
    xyz = ["x", "y", "z"]
    add("pose position", gpme_poses[:, :3, 3], drake_poses[:, :3, 3], (names, xyz))
    add("pose rotation", gpme_poses[:, :3, :3].reshape(-1, 9),
        drake_poses[:, :3, :3].reshape(-1, 9),
        (names, [f"R{i}{j}" for i in range(3) for j in range(3)]))
    if model.frames:
        frames = list(model.frames)
        pks = [point_kinematics(model, kin, qd, model.frames[f].link_index,
                                model.frames[f].transform[:3, 3]) for f in frames]
        add("frame position", [pk.position for pk in pks], [frame_data[f][1] for f in frames],
            (frames, xyz))
        add("frame velocity", [pk.velocity for pk in pks], [frame_data[f][2] for f in frames],
            (frames, xyz))
        add("frame jacobian", np.concatenate([pk.jacobian for pk in pks]),
            np.concatenate([frame_data[f][3] for f in frames]),
            ([f"{f}.{c}" for f in frames for c in xyz], coords))
        add("frame drift", [pk.drift for pk in pks], [frame_data[f][4] for f in frames],
            (frames, xyz))

    add("M", terms.M, d["M"], (coords, coords))
    add("bias term C(q,v) v", -terms.h, d["bias"], coords)
    add("gravity tau_g", -terms.g, d["tau_g"], coords)
    add("spring forces", -terms.f, d["springs"], coords, d["scale"])
    add("damper forces", -terms.d, d["dampers"], coords, d["scale"])
    tolerances.update({**solve_tolerances(d["M"], np.zeros(len(q)), np.zeros((0, len(q))),
                                          np.arange(len(q)), np.zeros(0, dtype=int)),
                       **case.overrides})
    add("free q_ddot", sol.q_ddot, d["q_ddot"], coords)
    tau, scale = inverse_dynamics(ds, ctx, q, qd, sol.q_ddot, d)
    tolerances.update({"inverse dynamics tau": residual_tolerance(len(q)), **case.overrides})
    add("inverse dynamics tau", terms.t, tau, coords, scale)
    return rows


def residual_tolerance(n: int) -> Tolerance:
    """Tolerance of the inverse dynamics residual for n coordinates: rel = 4 n eps of the
    row's scale (||M||_inf ||q_ddot||_inf or the largest force term), abs 1e-12 N."""
    rel = RESIDUAL_FACTOR * n * EPS
    return Tolerance(1e-12, rel, (
        "residual check, round-off only: gpme's q_ddot comes from a backward-stable Cholesky "
        "solve, (M + dM) q_ddot = h + Q with ||dM|| ~ n eps ||M||, so M q_ddot - (h + Q) is "
        "~n eps ||M|| ||q_ddot|| whatever cond(M); Drake's Newton-Euler pass forming M a + C v "
        "- tau_g - force elements adds round-off of that order; rel = 4 n eps (x2 two "
        f"evaluations, x2 for the constant) = {rel:.1e} of scale = max(||M||_inf "
        "||q_ddot||_inf, |C v|, |tau_g|, |springs|, |dampers|) (N, N m)"))


def inverse_dynamics(ds: DrakeSystem, context, q, q_dot, q_ddot, terms: dict) -> tuple:
    """(tau (n,) N or N m, scale N or N m): the applied generalized forces Drake's
    ``CalcInverseDynamics`` needs for the accelerations q_ddot (n,) (gpme's) at (q, q_dot),
    with the force elements (gravity, springs, joint damping) as external forces: tau = M
    q_ddot + C v - tau_g - springs - dampers, which must be the drives t.  scale: the size its
    round-off is relative to, max(||M||_inf ||q_ddot||_inf (Drake's M in ``terms``), |C v|,
    |tau_g|, |springs|, |dampers|)."""
    plant = ds.plant
    plant.SetPositions(context, ds.q_drake(q))
    plant.SetVelocities(context, ds.to_drake(q_dot))
    forces = MultibodyForces(plant)
    plant.CalcForceElementsContribution(context, forces)
    tau = ds.to_gpme(plant.CalcInverseDynamics(context, ds.to_drake(q_ddot), forces))
    m_a = np.linalg.norm(terms["M"], np.inf) * float(np.abs(q_ddot).max(initial=0.0))
    parts = [terms["bias"], terms["tau_g"], terms["springs"], terms["dampers"]]
    return tau, float(max([m_a] + [np.abs(p).max(initial=0.0) for p in parts]))


def compare_case(case: DrakeCase, states: Sequence) -> pd.DataFrame:
    """Tidy DataFrame of every comparison of ``case`` over ``states``."""
    return pd.DataFrame([row for s in states for row in compare_state(case, s)])


# --------------------------------------------------------------------------- the run
def default_scenarios(quick: bool = False) -> list:
    """The paper's crane cases (crosscheck.crane_cases: rigid and 1, 3, 10 RFEM segments;
    quick: rigid and 3, the CI budget)."""
    return crane_cases("drake", quick)


@dataclass(frozen=True)
class CaseRecord:
    """What the report says about one model case besides its rows."""

    label: str
    n: int
    n_states: int
    notes: tuple


def _progress(enabled, total):
    if not enabled:
        return None
    return tqdm(total=total, desc="drake crosscheck", unit="scenario")


def _failed_row(scenario, section, what, exc):
    row = compare(ENGINE, scenario.name, f"{what}: failed", section, [np.nan], [0.0],
                  Tolerance(0.0, 0.0, f"{what} failed: {exc}"[:500]), ["-"])
    return {**row, "section": section}


def terms_section(scenario, out_dir: Path, plan) -> tuple:
    """(rows DataFrame, CaseRecord) of the terms of ``scenario``."""
    case = make_case(scenario, out_dir / URDF_SUBDIR)
    states = scenario_states(scenario, plan)
    try:
        df = compare_case(case, states).assign(section="terms")
    except RuntimeError as exc:     # Drake refuses to evaluate the model (e.g. a link whose
        raise SimulationError(      # articulated inertia is singular): a failed row
            f"Drake cannot evaluate {scenario.name}: {exc}") from None
    log.info("%s: %d states, %d rows, %d failing", case.label, len(states), len(df),
             int((df["status"] == "fail").sum()))
    return df, CaseRecord(case.label, scenario.model.n_coordinates, len(states),
                          case.drake.notes)


def run(out_dir: Path, scenarios: Optional[Sequence] = None, quick: bool = False,
        progress: bool = False, sections: Sequence[str] = SECTIONS) -> pd.DataFrame:
    """Compare gpme with Drake for every scenario; write the rows
    (crosscheck.reports.rows: out_dir/checks/drake/) and out_dir/drake.html (atomically) and
    return the tidy table (columns of crosscheck.compare.COLUMNS plus ``section``, "terms" or
    "runs"; one row per quantity, scenario and state, or per run column).

    scenarios: gpme_io.scenario.Scenario objects; None: default_scenarios(quick).
    quick    : crosscheck.states.QUICK plan (3 random + 2 run states) and runs of at most
               0.2 s, instead of FULL (300 + 100 states) and runs of up to 2 s.
    sections : "terms" and/or "runs" (crosscheck.drake.runs.run_section).
    A scenario Drake cannot express (its URDF, joints) or whose states cannot be drawn gives
    one failed row with the error instead of its rows; the other scenarios go on.
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
    {"frames": row tables, "records": term records}, picklable, for :func:`finish`
    (crosscheck.step_pool runs scenarios in separate processes)."""
    out_dir = Path(out_dir)
    plan = QUICK if quick else FULL
    frames, records = [], []
    refused = inertia_gate.refusal(ENGINE, scenario)
    if refused:
        log.info("%s: %s", scenario.name, refused)
        frames.append(pd.DataFrame([{**inertia_gate.refusal_row(ENGINE, scenario, refused),
                                     "section": "terms"}]))
        return {"frames": frames, "records": records}
    if "terms" in sections:
        try:
            df, record = terms_section(scenario, out_dir, plan)
            frames.append(df)
            records.append(record)
        except GpmeError as exc:     # a model Drake cannot express is a failed check
            frames.append(pd.DataFrame([_failed_row(scenario, "terms", "terms", exc)]))
    if "runs" in sections:
        try:
            rows = run_section(scenario, quick, log.info, urdf_dir=out_dir / URDF_SUBDIR)
        except GpmeError as exc:
            rows = [_failed_row(scenario, "runs", "free run", exc)]
        frames.append(pd.DataFrame(rows).assign(section="runs"))
    return {"frames": frames, "records": records}


def finish(out_dir: Path, parts: Sequence[dict], quick: bool, wall: float) -> pd.DataFrame:
    """The scenarios' parts (:func:`scenario_part`, in scenario order) as one table: its rows
    (crosscheck.reports.rows) and out_dir/drake.html written (atomically), the table
    returned.  wall: s, the time the parts took."""
    out_dir = Path(out_dir)
    frames = [f for part in parts for f in part["frames"]]
    records = [r for part in parts for r in part["records"]]
    df = pd.concat(frames, ignore_index=True) if frames else pd.DataFrame()
    out_dir.mkdir(parents=True, exist_ok=True)
    write_rows(own_rows(df, ENGINE), out_dir, ENGINE)
    atomic_write_text(out_dir / "drake.html", _html(df, records, wall, quick))
    return df


CONVENTIONS = (
    "Conventions: gpme M q̈ = h + Q, Q = -(g + d + f) + t; Drake M v̇ + C(q, v) v = τ_g + "
    "τ_app + Σ Jᵀ F. Compared: CalcBiasTerm (C v) with -h, CalcGravityGeneralizedForces (τ_g) "
    "with -g, the force elements (CalcForceElementsContribution + CalcGeneralizedForces, less "
    "τ_g) with -(f + d), split into springs (at v = 0) and dampers; drives t on the applied "
    "generalized force port; free q̈ from the plant's generalized acceleration output. Errors "
    "are normwise: abs = max|x - y|, rel = abs / scale (max|y|; springs and dampers: the "
    "largest force element part); pass when abs ≤ tol_abs + tol_rel scale; info rows have "
    "no finite tolerance and are never counted as passes.")


def _html(df, records, wall, quick):
    """drake.html (crosscheck.reports.html.comparison_page)."""
    version = drake_version()
    cases = pd.DataFrame([{"model": r.label, "n": r.n, "states": r.n_states,
                           "Drake side": "; ".join(r.notes)} for r in records])
    intro = [f"{len(df)} comparisons over {len(records)} models; "
             f"{'quick' if quick else 'full'} run, {wall:.1f} s. Drake {version}, "
             "MultibodyPlant(time_step=0) from the URDF gpme wrote."]
    models = section("Models", table=table(cases, status_column="-",
                                           left_columns=("model", "Drake side"))
                     if not cases.empty else None)
    return comparison_page(ENGINE, "gpme vs Drake", version, df, intro, [models], CONVENTIONS)
