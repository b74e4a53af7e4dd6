"""Checks of a scenario's own gpme run (no other engine): the programmed constraints are met
once the Baumgarte transient has decayed, and the energy balance closes.

Tidy rows through crosscheck.compare (engine "gpme", section "run").

Transient: with Phi_ddot + 2 alpha Phi_dot + beta^2 Phi = 0 the slowest decay rate is
r = alpha - sqrt(alpha^2 - beta^2) (alpha >= beta) or alpha (alpha < beta); for the
critically damped case alpha = beta the decay is (1 + r t) exp(-r t).  A run started off
the constraints is checked from the time at which that envelope, times the initial
violation, has fallen below PHI_TOL.abs / 1000; a run started on them from t = 0.
"""
import numpy as np
import pandas as pd

from gpme_core.elastic_loads import SMALL_ANGLE_LIMIT, STRESS_SAFETY_FACTOR, elastic_peaks
from gpme_core.smoothness import KINK_TOL, check_run

from .compare import Tolerance, compare

WARNING = "WARNING: "   # prefix of the reason of an information row whose limit is exceeded

# After the transient the constraints hold to the RK4 truncation error of the dependent
# coordinates (Baumgarte pulls back any drift at rate r); on the paper's crane that was
# measured at 2.2e-10 (rigid, dt 1e-4 s) and 4.5e-11 (flexible, dt 5e-5 s) over 10 s.
# 1e-8 (m for position programmes, dimensionless for normalised shapes) asks for the task
# to be met to 10 nm, well inside any manipulator's accuracy, and still leaves the RK4
# error room for faster tasks.  A scenario may override it with its reason.
PHI_TOL = Tolerance(1e-8, 0.0, "programmed constraints met after the Baumgarte transient: "
                    "RK4 truncation of the dependent coordinates (m, or 1 for normalised "
                    "shapes); 10 nm task accuracy")
# energy balance: E - E(0) = W_drive + W_reaction - W_dissipated holds to the integrator's
# accuracy (the work integrals are integrated with the same scheme, gpme_core.integrate);
# relative to the largest work term.
ENERGY_TOL = Tolerance(0.0, 1e-6, "energy E - E(0) = W_drive + W_reaction - W_dissipated to "
                       "RK4 accuracy, relative to the largest work term")


def transient_time(alpha, beta, phi0, tol=PHI_TOL.abs * 1e-3):
    """s, time after which the Baumgarte envelope (1 + r t) e^{-r t} |phi0| < tol."""
    phi0 = float(np.max(np.abs(phi0))) if np.size(phi0) else 0.0
    if phi0 <= tol:
        return 0.0
    rate = alpha - np.sqrt(alpha * alpha - beta * beta) if alpha >= beta else alpha
    if rate <= 0:
        return np.inf
    t = 0.0
    while (1.0 + rate * t) * np.exp(-rate * t) * phi0 > tol:
        t += 0.01 / rate
    return t


def run_rows(scenario, df, tolerances=None):
    """Rows for one gpme run ``df`` (gpme_core.integrate.simulate) of ``scenario``."""
    system = scenario.system
    names = list(system.constraint_names)
    rows = []
    label = scenario.name
    case = f"{df['t'].iloc[-1]:g} s, {df.attrs.get('method', 'RK4')}"
    if names:
        t_tr = transient_time(system.alpha, system.beta, df[names].iloc[0].to_numpy())
        late = df[df["t"] >= t_tr]
        override = scenario.tolerance("gpme", "constraints after transient")
        tol = PHI_TOL if override is None else Tolerance(
            override.abs, override.rel, f"override from the model file: {override.reason}")
        for name in names:
            if late.empty:
                # information, not a failure: no sample lies after the transient
                rows.append(compare("gpme", label, f"|{name}| after transient", case,
                                    [0.0], [0.0], Tolerance(np.inf, 0.0, f"information: not "
                                    f"checked: the run ends inside the {t_tr:.3g} s Baumgarte "
                                    "transient")) | {"entry": "no sample after the transient"})
                continue
            worst = late[name].abs().idxmax()
            rows.append(compare("gpme", label, f"|{name}| after transient", case,
                                late[name].loc[worst], 0.0, tol)
                        | {"entry": f"t = {df['t'].loc[worst]:.4f} s (transient {t_tr:.3g} s)"})
    if names:
        rows.append(_jacobian_row(scenario, df, case))
    # the largest work term, or the largest energy change when no work is done
    energy = df["E_kin"] + df["E_pot"]
    scale = max(float(df[["W_drive", "W_reaction", "W_dissipated"]].abs().max().max()),
                float((energy - energy.iloc[0]).abs().max()))
    k = df["E_balance_error"].abs().idxmax()
    err = float(df["E_balance_error"].loc[k])
    energy_tol = Tolerance(ENERGY_TOL.rel * scale, 0.0, ENERGY_TOL.reason +
                           f" ({ENERGY_TOL.rel:g} x {scale:.3g} J)")
    row = compare("gpme", label, "energy balance", case, err, 0.0, energy_tol)
    row.update(entry=f"t = {df['t'].loc[k]:.4f} s", scale=scale,
               rel_error=abs(err) / scale if scale > 0 else np.nan)
    rows.append(row)
    rows += smoothness_rows(scenario, df, case)
    rows += elastic_rows(scenario, df, case)
    rows += inertia_rows(scenario, case)
    return rows


def inertia_rows(scenario, case):
    """Information rows of the links whose inertia breaks the triangle inequality of a
    physical body (accepted, as Pinocchio accepts it; gpme_core.inertia): the excess
    I3 - (I1 + I2) in kg m^2, the moments in the reason.  The run finishing is the check
    that matters: its reduced solve stops the run where the mass matrix is not positive
    definite."""
    rows = []
    for link in scenario.model.links:
        if link.inertia is None or not link.inertia.triangle_excess():
            continue
        excess = link.inertia.triangle_excess()
        moments = np.linalg.eigvalsh(link.inertia.inertia_array)
        row = compare("gpme", scenario.name, f"non-physical inertia ({link.name})", case,
                      excess, excess, Tolerance(np.inf, 0.0, (
                          f"information: kg m^2, I3 - (I1 + I2) of the principal moments "
                          f"{[float(f'{m:.4g}') for m in moments]} kg m^2 (a physical body has "
                          "I1 + I2 >= I3); accepted as Pinocchio accepts it, the mass matrix "
                          "stayed positive definite along the run")))
        row.update(entry=f"link {link.name}")
        rows.append(row)
    return rows


# kink measure of a constraint's or programme's expression along the run
# (gpme_core.smoothness); a failure is reported as inf: it is not an error of the step
SMOOTH_TOL = Tolerance(KINK_TOL, 0.0, "expression smooth along the run: the change of its "
                       "gradient between samples matches its Hessian's to 4th order in the "
                       "sample step (gpme_core.smoothness); inf: a kink or a singular set "
                       "(sqrt, log, division at 0) met, which no step removes")


def smoothness_rows(scenario, df, case):
    """One row per SymPy expression of the scenario's constraints and programmes: the
    largest kink measure along the run, or inf with where the expression is not smooth
    (the time and the singular set) when the run meets a kink or a singular set."""
    rows = []
    for check in check_run(scenario.system, df):
        value = check.kink if check.smooth else np.inf
        row = compare("gpme", scenario.name, f"smoothness of {check.who}", case, value, 0.0,
                      SMOOTH_TOL)
        row.update(entry=f"t = {check.t:.4f} s" + ("" if check.smooth else
                                                    f" ({check.finding()})"))
        rows.append(row)
    return rows


def elastic_rows(scenario, df, case):
    """Information rows of the peak element angles and bending stress of every RFEM link
    (gpme_core.elastic_loads): the run's distance from the limits of the model's validity.
    A row whose limit is exceeded has a reason starting with WARNING."""
    rows = []
    for peak in elastic_peaks(scenario.model, df, scenario.yield_strengths):
        allowed = peak.allowed_stress
        items = (
            ("peak bending angle", peak.bending_angle, peak.bending_sde, peak.bending_time,
             SMALL_ANGLE_LIMIT, f"rad; sqrt(psi^2 + theta^2) of an sde; small-angle limit "
             f"{SMALL_ANGLE_LIMIT} rad of the linear RFEM springs on Euler angles"),
            ("peak torsion angle", peak.torsion_angle, peak.torsion_sde, peak.torsion_time,
             SMALL_ANGLE_LIMIT, f"rad; |phi| of an sde; small-angle limit {SMALL_ANGLE_LIMIT} rad"),
            ("peak bending stress", peak.bending_stress, peak.stress_sde, peak.stress_time,
             allowed, "Pa; from the sde spring moments; " + (
                 f"allowed: yield {peak.yield_strength:.4g} Pa / {STRESS_SAFETY_FACTOR}"
                 if allowed is not None else "no yield strength given: no elasticity verdict")),
        )
        for quantity, value, sde, t, limit, what in items:
            exceeded = limit is not None and value > limit
            reason = (WARNING if exceeded else "information: ") + what + \
                (f"; exceeded ({value:.3g} > {limit:.3g})" if exceeded else "")
            row = compare("gpme", scenario.name, f"{quantity} ({peak.link})", case, value,
                          value, Tolerance(np.inf, 0.0, reason))
            row.update(entry=f"sde {sde}, t = {t:.4f} s")
            rows.append(row)
    return rows


def run_warnings(rows):
    """The reasons of the rows whose validity limit was exceeded (WARNING ...), with their
    model and quantity, as sentences."""
    return [f"{r['model']}: {r['quantity']} = {r['gpme_value']:.4g} at {r['entry']}: "
            f"{r['reason']}" for r in rows if str(r.get("reason", "")).startswith(WARNING)]


def smallest_singular_values(scenario, df, samples=200):
    """(t (k,), sigma_min (k,)): smallest singular value of the constraint Jacobian A (m, n)
    at up to ``samples`` recorded states of the run (units of A: 1/rad, m/rad, ...).  Its
    approach to zero means the task drives the mechanism towards a singular pose."""
    names = list(scenario.model.coordinate_names)
    step = max(1, len(df) // samples)
    ts, sig = [], []
    for _, r in df.iloc[::step].iterrows():
        q = r[names].to_numpy(float)
        q_dot = r[[f"{n}_dot" for n in names]].to_numpy(float)
        _, _, a, _ = scenario.system.constraints(float(r["t"]), q, q_dot)
        ts.append(float(r["t"]))
        sig.append(float(np.linalg.svd(a, compute_uv=False).min()))
    return np.array(ts), np.array(sig)


def _jacobian_row(scenario, df, case):
    ts, sig = smallest_singular_values(scenario, df)
    k = int(np.argmin(sig))
    row = compare("gpme", scenario.name, "smallest singular value of the constraint Jacobian",
                  case, sig[k], sig[k], Tolerance(np.inf, 0.0, "information: distance from a "
                  "singular pose along the run (min over the run; 0 = singular)"))
    row.update(entry=f"t = {ts[k]:.4f} s")
    return row


def rows_frame(rows):
    """DataFrame of rows with section "run"."""
    df = pd.DataFrame(rows)
    df["section"] = "run"
    return df
