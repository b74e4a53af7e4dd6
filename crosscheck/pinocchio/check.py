"""Term-by-term crosscheck of the gpme engine against Pinocchio (docs/crosscheck-pinocchio.md).

For each model case (the crane rigid and RFEM-flexible, built directly and round-tripped
through URDF) and each state (seeded random states over the working range, and states
along simulated runs), every term is compared through crosscheck.compare.compare:

    quantity           gpme                                Pinocchio
    pose position/rot. kinematics.chain_kinematics T, frames   forwardKinematics + updateFramePlacements (oMf)
    M                  dynamics.mass_matrix                crba (lower triangle checked, see _crba)
    g                  dynamics.gravity_forces (dE_p/dq)   computeGeneralizedGravity  (same sign)
    h                  dynamics.velocity_product_terms     -(rnea(q, v, 0) - computeGeneralizedGravity)
    applied tau        -(f + d) + t                        -K (q - q_ref) - D v + t from Pinocchio's
                                                           URDF damping and the side file's springs
    E position/velocity/Jacobian/drift  kinematics.point_kinematics   frame placement, getFrameVelocity,
                       getFrameJacobian, getFrameClassicalAcceleration (LOCAL_WORLD_ALIGNED, a = 0)
    Phi, Phi_dot, A, kappa   gpme constraints           the same constraint functions at Pinocchio's
                                                           E position, velocity, Jacobian and drift
    free q_ddot        M^-1 (h + Q)  (no constraints)      aba(q, v, tau)
    constrained q_ddot reduced GPME (ProgrammedMotion.solve)   forwardDynamics(q, v, tau, A, gamma),
                                                           gamma = kappa + 2 alpha Phi_dot + beta^2 Phi
    lambda, A^T lambda gpme multipliers / reactions        data.lambda_c, A^T lambda_c

Sign conventions: gpme M q_ddot = h + Q + A^T lambda with Q = -(g + d + f) + t; Pinocchio
M a + b(q, v) = tau + J^T lambda_c with b = rnea(q, v, 0) = C v + g_pin and J a + gamma = 0.
Hence g_pin = g, h = -(b - g_pin), tau = Q + g, and the multipliers agree with the same sign.
"""
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
import pinocchio as pin

from gpme_core.constraints import PointConstraint
from gpme_examples.crane import CraneParameters, crane_constraints, crane_system, initial_state
from gpme_core.errors import ConstraintError
from gpme_core.gpme import ProgrammedMotion
from gpme_core.integrate import simulate
from gpme_core.kinematics import chain_kinematics, point_kinematics

from ..reports import tables as report
from ..compare import Tolerance, compare
from .model import from_gpme, from_urdf
from gpme_io.urdf import read_urdf, write_urdf

ENGINE = "pinocchio"
SEED = 20240611
CRANE_SEGMENTS = (0, 1, 3, 10)        # n_rfe of the crane cases; 0 = rigid arm
LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED

_ROUND_OFF = ("round-off only: both engines evaluate the same closed-form quantity in double "
              "precision through ~n products of 4x4 transforms or spatial recursions")
_FORCE = ("round-off only: sums of products of inertia, transforms and velocities; normwise "
          "relative to the largest entry")
EPS = np.finfo(float).eps
# eps cond(M) is the first-order forward error of one backward-stable solve, an estimate
# rather than a bound; two engines' errors add (x2) and the estimate gets a margin of 4
# (the full run measured errors up to 1.5 eps cond(M) for the reactions): SOLVE_FACTOR = 8.
SOLVE_FACTOR = 8.0
_SOLVE = ("linear solve with M (aba / KKT in Pinocchio, Cholesky / reduced GPME in gpme): "
          "forward error ~eps cond(M) relative, and the RFEM arm makes M ill-conditioned "
          "(element torsion inertias ~1e-9 kg m^2 next to ~10 kg of crane: cond(M) up to ~3e7 "
          "for n = 10); tol_rel = max(1e-12, 8 eps cond_2(M)) (x2 two engines, x4 margin), "
          "here cond(M) = {cond:.1e}")
_MULTIPLIER = ("; lambda = A_dc^-T F_dc inherits the reaction error: tol_abs = 8 eps cond(M) "
               "max|A^T lambda| ||A_dc^-T||_inf = {tol:.1e}")
# Each tolerance: abs (in the quantity's unit, a floor for exact zeros such as h at rest)
# and rel (normwise, to the largest entry of the Pinocchio value), with its reason.
TOLERANCES = {
    "pose position": Tolerance(1e-14, 1e-12, _ROUND_OFF + " (m)"),
    "pose rotation": Tolerance(1e-14, 1e-12, _ROUND_OFF),
    "M": Tolerance(1e-14, 1e-12, _FORCE + " (kg, kg m, kg m^2)"),
    "g": Tolerance(1e-12, 1e-12, _FORCE + " (N, N m)"),
    "h": Tolerance(1e-12, 1e-11, _FORCE + "; h cancels terms of size |M| |q_dot|^2, which "
                   "can be 100x its result (measured up to 5e-13)"),
    "applied tau": Tolerance(1e-12, 1e-12, "same springs/dampers from two sources (gpme model "
                             "vs Pinocchio's URDF damping + side-file springs): exact up to "
                             "one rounding"),
    "E position": Tolerance(1e-14, 1e-12, _ROUND_OFF + " (m)"),
    "E velocity": Tolerance(1e-14, 1e-12, _ROUND_OFF + " (m/s)"),
    "E jacobian": Tolerance(1e-14, 1e-12, _ROUND_OFF + " (m or m/rad)"),
    "E drift": Tolerance(1e-12, 1e-11, _ROUND_OFF + "; the drift sums ~n^2 velocity "
                         "products (m/s^2)"),
    "Phi": Tolerance(1e-14, 1e-12, "constraint value at the two E positions; round-off"),
    "Phi_dot": Tolerance(1e-13, 1e-12, "constraint rate from the two E velocities; round-off. "
                         "Phi_dot -> 0 on the constraint manifold, so along runs the abs "
                         "floor (1/s for Phi_1, m/s for Phi_2) decides; measured <= 1e-14"),
    "constraint jacobian A": Tolerance(1e-14, 1e-12, "grad(phi)^T J at the two E states; "
                                       "round-off"),
    "constraint kappa": Tolerance(1e-12, 1e-11, "grad(phi).drift + p_dot^T Hess p_dot + ...; "
                                  "inherits the drift tolerance"),
}
# quantities from a linear solve with M: tolerances set per state by solve_tolerances
SOLVED = ("free q_ddot", "constrained q_ddot", "multipliers lambda", "reactions A^T lambda")


def solve_tolerances(m, reactions, a_dc):
    """Tolerances of the SOLVED quantities at one state.

    m (n, n) mass matrix, reactions (n,) A^T lambda (N, N m), a_dc (m, m) dependent
    block of the constraint Jacobian.  rel = max(1e-12, 8 eps cond_2(M)) for all four;
    the multipliers get abs = 8 eps cond(M) max|A^T lambda| ||A_dc^-T||_inf as well,
    because lambda = A_dc^-T (A^T lambda)_dc can be small beside the reactions.
    """
    cond = float(np.linalg.cond(m))
    rel = max(1e-12, SOLVE_FACTOR * EPS * cond)
    reason = _SOLVE.format(cond=cond)
    lam_abs = rel * float(np.max(np.abs(reactions))) * float(
        np.linalg.norm(np.linalg.inv(a_dc).T, np.inf))
    return {"free q_ddot": Tolerance(1e-12, rel, reason + " (m/s^2, rad/s^2)"),
            "constrained q_ddot": Tolerance(1e-12, rel, reason + " (m/s^2, rad/s^2)"),
            "reactions A^T lambda": Tolerance(1e-12, rel, reason + " (N, N m)"),
            "multipliers lambda": Tolerance(
                max(1e-12, lam_abs), rel, reason + _MULTIPLIER.format(tol=lam_abs) +
                " (N m for the dimensionless Phi_1, N for Phi_2 in m)")}


@dataclass(frozen=True)
class ModelCase:
    """One gpme system and its Pinocchio counterpart.

    label  : model column of the report, e.g. "crane_flexible_n3 (URDF)"
    system : gpme_core.gpme.ProgrammedMotion (dependent coordinates fixed)
    pin    : crosscheck.pinocchio.model.PinocchioSystem
    """

    label: str
    system: object
    pin: object


@dataclass(frozen=True)
class State:
    """case name (str), t (s), q (n,), q_dot (n,) ordered as the model's coordinates."""

    case: str
    t: float
    q: np.ndarray
    q_dot: np.ndarray


# --------------------------------------------------------------------------- states
def crane_ranges(model, params=CraneParameters()):
    """(q_lo (n,), q_hi (n,), q_dot_max (n,)) of the crane's working range (SI units).

    z1 +-0.02 m (static sag ~0.01 m), psi2 +-pi, psi3 and z4 over their limits, RFEM
    angles +-0.02 rad (static bending ~0.004 rad per element); rates z1 0.05 m/s,
    psi2 1.5 rad/s, psi3 1 rad/s, z4 0.5 m/s, RFEM 2 rad/s (runs reach ~0.3 rad/s).
    """
    fixed = {"z1": (-0.02, 0.02, 0.05), "psi2": (-np.pi, np.pi, 1.5),
             "psi3": (*params.arm_pitch_range, 1.0), "z4": (*params.slider_stroke, 0.5)}
    rows = [fixed.get(name, (-0.02, 0.02, 2.0)) for name in model.coordinate_names]
    lo, hi, rate = (np.array(c, dtype=float) for c in zip(*rows))
    return lo, hi, rate


def random_states(system, count, rng, t_max=10.0):
    """``count`` seeded random states in the working range where the GPME is solvable
    (a draw with a singular dependent block is replaced by the next draw)."""
    lo, hi, rate = crane_ranges(system.model)
    out, draws = [], 0
    while len(out) < count:
        draws += 1
        if draws > 20 * count:
            raise ConstraintError(f"{system.model.name}: fewer than {count} solvable random "
                                  f"states in {draws} draws")
        t = float(rng.uniform(0.0, t_max))
        q = rng.uniform(lo, hi)
        q_dot = rng.uniform(-rate, rate)
        try:
            system.solve(t, q, q_dot)
        except ConstraintError:
            continue
        out.append(State(f"random {len(out):02d}", t, q, q_dot))
    return out


def run_states(system, count, t_end):
    """``count`` states along a Radau run of ``system`` from the paper's initial state.

    Radau with rtol 1e-4: only realistic states are needed here, not an accurate run,
    and the RFEM arm's torsion modes (~1e6 rad/s) make explicit integrators crawl.
    """
    q0, qd0 = initial_state(system.model)
    df = simulate(system, t_end, q0, qd0, method="Radau", output_dt=t_end / count,
                  rtol=1e-4, atol=1e-6)
    names = list(system.model.coordinate_names)
    rows = np.linspace(0, len(df) - 1, count).round().astype(int)
    return [State(f"run t={df['t'].iloc[r]:.3f}", float(df["t"].iloc[r]),
                  df[names].iloc[r].to_numpy(float),
                  df[[f"{n}_dot" for n in names]].iloc[r].to_numpy(float)) for r in rows]


# --------------------------------------------------------------------------- cases
def crane_case(n_rfe, params=CraneParameters()):
    """The crane built directly in gpme and in Pinocchio (pinocchio_model.from_gpme)."""
    system = crane_system(n_rfe, params)
    return ModelCase(system.model.name, system, from_gpme(system.model))


def urdf_case(n_rfe, urdf_dir, params=CraneParameters()):
    """The crane written to URDF, read back by gpme_io.urdf (gpme) and by Pinocchio."""
    original = crane_system(n_rfe, params).model
    path, _ = write_urdf(original, Path(urdf_dir) / f"{original.name}.urdf")
    model = read_urdf(path)
    system = ProgrammedMotion(model, crane_constraints(params), dependent=("psi3", "z4"),
                              baumgarte=(params.baumgarte_alpha, params.baumgarte_beta))
    pin_sys = from_urdf(path, model.coordinate_names, [lk.name for lk in model.links],
                        list(model.frames))
    return ModelCase(f"{model.name} (URDF)", system, pin_sys)


# --------------------------------------------------------------------------- one state
def _crba(pm, data, q):
    """(M (n, n), whole) from pin.crba; older Pinocchio filled only the upper triangle, so
    an empty strict lower triangle is mirrored from the upper one (whole = False)."""
    m = np.array(pin.crba(pm, data, q))
    n = m.shape[0]
    if n > 1 and not np.any(np.tril(m, -1)) and np.any(np.triu(m, 1)):
        return np.triu(m) + np.triu(m, 1).T, False
    return m, True


def _point_constraints(system):
    bad = [type(b.spec).__name__ for b in system.bound if not isinstance(b.spec, PointConstraint)]
    if bad:
        raise TypeError(f"the Pinocchio crosscheck handles point constraints only, got {bad}")
    frames = {b.spec.frame for b in system.bound}
    if len(frames) != 1:
        raise TypeError(f"the Pinocchio crosscheck needs all constraints on one frame, got {frames}")
    return frames.pop()


def compare_state(case, state):
    """Tidy rows (list of dict) comparing every term of ``case`` at ``state``."""
    system, ps = case.system, case.pin
    model, pm = system.model, ps.model
    data = pm.createData()
    t, q, qd = state.t, state.q, state.q_dot
    n = model.n_coordinates
    coords = list(model.coordinate_names)
    rows = []

    tolerances = dict(TOLERANCES)

    def add(quantity, gpme_value, engine_value, labels=None):
        rows.append(compare(ENGINE, case.label, quantity, state.case, gpme_value, engine_value,
                            tolerances[quantity], labels))

    # ---- gpme
    kin = chain_kinematics(model, q)
    sol = system.solve(t, q, qd)
    terms = sol.terms
    free = ProgrammedMotion(model).solve(t, q, qd).q_ddot
    frame_name = _point_constraints(system)
    fr = model.frame(frame_name)
    pk = point_kinematics(model, kin, qd, fr.link_index, fr.transform[:3, 3])

    # ---- Pinocchio: kinematics with a = 0 (classical acceleration = drift)
    m_pin, _ = _crba(pm, data, q)
    pin.forwardKinematics(pm, data, q, qd, np.zeros(n))
    pin.updateFramePlacements(pm, data)
    names = [lk.name for lk in model.links] + list(model.frames)
    fids = list(ps.link_frames) + [ps.frames[f] for f in model.frames]
    gpme_poses = np.concatenate([kin.T, [kin.T[f.link_index] @ f.transform
                                         for f in model.frames.values()]])
    pin_poses = np.array([data.oMf[i].homogeneous for i in fids])
    add("pose position", gpme_poses[:, :3, 3], pin_poses[:, :3, 3], (names, ["x", "y", "z"]))
    rot_labels = [f"R{i}{j}" for i in range(3) for j in range(3)]
    add("pose rotation", gpme_poses[:, :3, :3].reshape(-1, 9), pin_poses[:, :3, :3].reshape(-1, 9),
        (names, rot_labels))
    fid = ps.frames[frame_name]
    p_pin = data.oMf[fid].translation.copy()
    v_pin = pin.getFrameVelocity(pm, data, fid, LWA).linear.copy()
    drift_pin = pin.getFrameClassicalAcceleration(pm, data, fid, LWA).linear.copy()
    jac_pin = pin.computeFrameJacobian(pm, data, q, fid, LWA)[:3].copy()
    xyz = ["x", "y", "z"]
    add("E position", pk.position, p_pin, xyz)
    add("E velocity", pk.velocity, v_pin, xyz)
    add("E jacobian", pk.jacobian, jac_pin, (xyz, coords))
    add("E drift", pk.drift, drift_pin, xyz)

    # ---- Pinocchio: dynamics terms
    g_pin = np.array(pin.computeGeneralizedGravity(pm, data, q))
    h_pin = -(np.array(pin.rnea(pm, data, q, qd, np.zeros(n))) - g_pin)
    add("M", terms.M, m_pin, (coords, coords))
    add("g", terms.g, g_pin, coords)
    add("h", terms.h, h_pin, coords)
    tau_gpme = -(terms.f + terms.d) + terms.t
    tau_pin = ps.applied_forces(q, qd, model.drive_forces(t))
    add("applied tau", tau_gpme, tau_pin, coords)

    # ---- constraints at Pinocchio's E state, and the constrained dynamics
    m_c = system.n_constraints
    phi, phi_dot, kappa = np.empty(m_c), np.empty(m_c), np.empty(m_c)
    a_pin = np.empty((m_c, n))
    for k, b in enumerate(system.bound):
        f, grad, hess, f_t, grad_t, f_tt = b.spec.local_terms(p_pin, t)
        phi[k], a_pin[k] = f, grad @ jac_pin
        phi_dot[k] = float(grad @ v_pin) + f_t
        kappa[k] = float(grad @ drift_pin + v_pin @ hess @ v_pin + 2.0 * grad_t @ v_pin + f_tt)
    cons = list(system.constraint_names)
    add("Phi", sol.phi, phi, cons)
    add("Phi_dot", sol.phi_dot, phi_dot, cons)
    add("constraint jacobian A", sol.jacobian, a_pin, (cons, coords))
    add("constraint kappa", sol.kappa, kappa, cons)
    gamma = kappa + 2.0 * system.alpha * phi_dot + system.beta ** 2 * phi
    a_con = np.array(pin.forwardDynamics(pm, data, q, qd, tau_pin, a_pin, gamma))
    lam = np.array(data.lambda_c).copy()
    tolerances.update(solve_tolerances(m_pin, a_pin.T @ lam, a_pin[:, system.dc]))
    add("free q_ddot", free, np.array(pin.aba(pm, data, q, qd, tau_pin)), coords)
    add("constrained q_ddot", sol.q_ddot, a_con, coords)
    add("multipliers lambda", sol.multipliers, lam, cons)
    add("reactions A^T lambda", sol.reaction_forces, a_pin.T @ lam, coords)
    return rows


def compare_case(case, states):
    """Tidy DataFrame of every comparison of ``case`` over ``states``."""
    return pd.DataFrame([row for s in states for row in compare_state(case, s)])


# --------------------------------------------------------------------------- the run
@dataclass(frozen=True)
class RunPlan:
    """How much to compare: number of random and run states, run length (s), which
    crane cases are also round-tripped through URDF."""

    n_random: int
    n_run: int
    t_run: float
    urdf_segments: tuple


FULL = RunPlan(n_random=300, n_run=100, t_run=1.0, urdf_segments=CRANE_SEGMENTS)
QUICK = RunPlan(n_random=3, n_run=2, t_run=0.05, urdf_segments=(0, 3))


def _progress(enabled, total):
    if not enabled:
        return None
    try:
        from tqdm import tqdm
    except ImportError:
        return None
    return tqdm(total=total, desc="pinocchio crosscheck", unit="model")


def _crba_whole():
    """True when this Pinocchio's crba fills the whole matrix (checked on the crane)."""
    case = crane_case(0)
    data = case.pin.model.createData()
    q = np.array([0.01, 0.3, 0.5, 0.1])
    return _crba(case.pin.model, data, q)[1]


def run(out_dir: Path, quick: bool = False, progress: bool = False) -> pd.DataFrame:
    """Compare gpme with Pinocchio term by term; write out_dir/pinocchio.csv and .html.

    Returns the tidy table (one row per quantity, model and state; column ``passed``).
    quick: a reduced set of states and URDF cases (seconds, for CI).
    """
    out_dir = Path(out_dir)
    plan = QUICK if quick else FULL
    start = time.perf_counter()
    rng = np.random.default_rng(SEED)
    frames = []
    bar = _progress(progress, len(CRANE_SEGMENTS) + len(plan.urdf_segments))
    for n in CRANE_SEGMENTS:
        case = crane_case(n)
        states = random_states(case.system, plan.n_random, rng) + \
            run_states(case.system, plan.n_run, plan.t_run)
        frames.append(compare_case(case, states))
        if bar:
            bar.update()
        if n in plan.urdf_segments:
            frames.append(compare_case(urdf_case(n, out_dir / "urdf"), states))
            if bar:
                bar.update()
    if bar:
        bar.close()
    df = pd.concat(frames, ignore_index=True)
    wall = time.perf_counter() - start
    report.write_csv(df, out_dir / "pinocchio.csv")
    report.atomic_write_text(out_dir / "pinocchio.html", _html(df, wall, quick))
    return df


def _html(df, wall, quick):
    n_fail = int((~df["passed"]).sum())
    summary = report.summarise(df)
    n_states = df.groupby("model")["case"].nunique()
    status = "all comparisons pass" if n_fail == 0 else f"{n_fail} comparisons FAIL"
    crba = ("pin.crba returned the whole symmetric matrix" if _crba_whole() else
            "pin.crba filled only the upper triangle; it was mirrored before comparing")
    body = (
        f"<h1>gpme vs Pinocchio {pin.__version__}: {status}</h1>"
        f"<p>{len(df)} comparisons over {len(n_states)} model cases "
        f"({', '.join(f'{m}: {k} states' for m, k in n_states.items())}); "
        f"{'quick' if quick else 'full'} run, {wall:.1f} s. {crba}.</p>"
        "<p>Conventions: gpme M q&#776; = h + Q + A<sup>T</sup>&lambda;, Q = -(g + d + f) + t; "
        "Pinocchio M a + b = &tau; + J<sup>T</sup>&lambda;<sub>c</sub>, J a + &gamma; = 0. "
        "Compared: g with computeGeneralizedGravity, h with -(rnea(q, v, 0) - g), "
        "&tau; = -K(q - q<sub>ref</sub>) - D v + t (Pinocchio side: URDF damping, side-file "
        "springs), &gamma; = &kappa; + 2&alpha;&Phi;&#775; + &beta;<sup>2</sup>&Phi;. "
        "Errors are normwise: abs = max|x - y|, rel = abs / max|y|; pass when "
        "abs &le; tol_abs + tol_rel max|y|.</p>"
        "<h2>Worst cases</h2>"
        + report.html_table(report.worst_first(df).head(40), left_columns=(
            "model", "quantity", "case", "entry", "reason"))
        + "<h2>Summary per model and quantity</h2>"
        + report.html_table(summary, left_columns=("engine", "model", "quantity", "worst_case",
                                                   "worst_entry", "reason")))
    return report.html_page("gpme vs Pinocchio", body)
