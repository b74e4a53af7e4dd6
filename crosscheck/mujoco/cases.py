"""The cases of the MuJoCo crosscheck and their tolerances, stated once with reasons.

Every gated tolerance of a whole run is ten times the difference measured on
2026-11-22 (MuJoCo 4.0.0, numbers in docs/crosscheck-mujoco.md), as issue 4 asks, or a
round-off bound where both engines do the same arithmetic.  Units: m for z1, z4,
rad for angles, J for energies, dimensionless for Phi_1, m for Phi_2.
"""
from dataclasses import dataclass

import numpy as np

from gpme_examples.crane import CraneParameters, build_crane, crane_constraints, crane_system

from ..compare import Tolerance
from .mechanism import MechanismSettings

DT = 1e-4                  # s, RK4 step of both engines in the gated runs
OUTPUT_DT = 1e-2           # s, spacing of the compared samples
FLEX_N = 1                 # RFEM segments of the flexible case (n = 2 needs dt <= 2.5e-5 for RK4)
# free-motion variant: the unconstrained crane's arm falls and its slider leaves the arm;
# springs on psi3 and z4 (same in both engines) keep the motion bounded for 10 s
HOLDING_SPRINGS = {"psi3": dict(stiffness=200.0, spring_reference=np.pi / 4, damping=0.1),
                   "z4": dict(stiffness=2000.0, spring_reference=0.2, damping=0.5)}


@dataclass(frozen=True)
class Plan:
    """What one run does.  quick = the CI version (about 1 s of motion per case)."""

    quick: bool
    t_end: float
    term_models: tuple          # n_rfe of the models compared term by term
    term_states: int
    free_models: tuple
    programmed_models: tuple
    convergence: tuple          # ((dt s, timeconst s), ...) for the rigid crane
    gpme_reference_check: bool  # also run gpme at 2 DT to bound its own RK4 error


def plan(quick):
    """The full plan (10 s cases) or the quick CI plan."""
    if quick:
        return Plan(True, 1.0, (0, 1), 2, (0,), (0, 1), ((DT, 4 * DT), (DT, DT)), False)
    return Plan(False, 10.0, (0, 1, 2, 3), 5, (0, FLEX_N), (0, FLEX_N),
                ((DT, 4 * DT), (DT, 2 * DT), (DT, DT), (DT / 2, DT / 2), (DT / 4, DT / 4)), True)


def free_model(n_rfe):
    """The crane with holding springs on psi3 and z4 (free-motion comparison)."""
    model = build_crane(n_rfe)
    return model.with_changes(joint_changes=HOLDING_SPRINGS, name=f"{model.name}_held")


def programmed_system(n_rfe, params=CraneParameters()):
    """(ProgrammedMotion, constraint specs) of the paper's case."""
    return crane_system(n_rfe, params), crane_constraints(params)


def mechanism(dt, timeconst=None):
    """MechanismSettings of the gated runs: timeconst = dt unless given."""
    return MechanismSettings(timeconst=timeconst or dt)


# ---------------------------------------------------------------- tolerances
FREE_REASON = ("same RK4 scheme, same step, drive sampled at the same stage times: only "
               "round-off differs (measured {m:.1e} over {t:g} s); gate {f}x that")
# measured largest differences of the full run (10 s, dt = 1e-4), by (section, n, column)
MEASURED = {
    ('free', 0, 'z1'): 1.15e-14,
    ('free', 0, 'psi2'): 1.99e-11,
    ('free', 0, 'psi3'): 1.38e-13,
    ('free', 0, 'z4'): 2.97e-14,
    ('free', 0, 'E_kin'): 2.11e-11,
    ('free', 0, 'E_pot'): 1.06e-11,
    ('free', 1, 'z1'): 1.22e-14,
    ('free', 1, 'psi2'): 1.79e-11,
    ('free', 1, 'psi3'): 1.28e-13,
    ('free', 1, 'psi_arm_1'): 1.65e-14,
    ('free', 1, 'theta_arm_1'): 6.39e-16,
    ('free', 1, 'phi_arm_1'): 1.33e-16,
    ('free', 1, 'z4'): 2.69e-14,
    ('free', 1, 'E_kin'): 1.73e-11,
    ('free', 1, 'E_pot'): 9.55e-12,
    ('programmed', 0, 'z1'): 1.82e-05,
    ('programmed', 0, 'psi2'): 0.00218,
    ('programmed', 0, 'psi3'): 0.000444,
    ('programmed', 0, 'z4'): 0.000348,
    ('programmed', 0, 'E_kin'): 0.0212,
    ('programmed', 0, 'E_pot'): 0.00344,
    ('programmed-rms', 0, 'z1'): 4.23e-06,
    ('programmed-rms', 0, 'psi2'): 0.000345,
    ('programmed-rms', 0, 'psi3'): 7e-05,
    ('programmed-rms', 0, 'z4'): 7.1e-05,
    ('programmed', 0, 'Phi_1'): 4.09e-05,
    ('programmed', 0, 'Phi_2'): 4.33e-08,
    ('programmed', 1, 'z1'): 0.000241,
    ('programmed', 1, 'psi2'): 0.0337,
    ('programmed', 1, 'psi3'): 0.0124,
    ('programmed', 1, 'psi_arm_1'): 0.0143,
    ('programmed', 1, 'theta_arm_1'): 0.017,
    ('programmed', 1, 'phi_arm_1'): 4.36e-05,
    ('programmed', 1, 'z4'): 0.00491,
    ('programmed', 1, 'E_kin'): 1.63,
    ('programmed', 1, 'E_pot'): 1.59,
    ('programmed-rms', 1, 'z1'): 3.69e-05,
    ('programmed-rms', 1, 'psi2'): 0.00454,
    ('programmed-rms', 1, 'psi3'): 0.00131,
    ('programmed-rms', 1, 'psi_arm_1'): 0.00155,
    ('programmed-rms', 1, 'theta_arm_1'): 0.0018,
    ('programmed-rms', 1, 'phi_arm_1'): 3.58e-06,
    ('programmed-rms', 1, 'z4'): 0.000902,
    ('programmed', 1, 'Phi_1'): 4.33e-05,
    ('programmed', 1, 'Phi_2'): 1.38e-07,
}
# measured largest differences of the quick run (1 s), same keys
QUICK_MEASURED = {
    ('free', 0, 'z1'): 3.99e-17,
    ('free', 0, 'psi2'): 5.01e-15,
    ('free', 0, 'psi3'): 7.77e-16,
    ('free', 0, 'z4'): 8.33e-17,
    ('free', 0, 'E_kin'): 2.72e-15,
    ('free', 0, 'E_pot'): 1.07e-14,
    ('programmed', 0, 'z1'): 1.99e-09,
    ('programmed', 0, 'psi2'): 1.74e-09,
    ('programmed', 0, 'psi3'): 5.84e-08,
    ('programmed', 0, 'z4'): 6.04e-08,
    ('programmed', 0, 'E_kin'): 6.49e-06,
    ('programmed', 0, 'E_pot'): 1.3e-07,
    ('programmed-rms', 0, 'z1'): 8.98e-10,
    ('programmed-rms', 0, 'psi2'): 6.28e-10,
    ('programmed-rms', 0, 'psi3'): 2.75e-08,
    ('programmed-rms', 0, 'z4'): 2.7e-08,
    ('programmed', 0, 'Phi_1'): 3.27e-07,
    ('programmed', 0, 'Phi_2'): 7.81e-10,
    ('programmed', 1, 'z1'): 2.12e-09,
    ('programmed', 1, 'psi2'): 1.77e-09,
    ('programmed', 1, 'psi3'): 6.18e-08,
    ('programmed', 1, 'psi_arm_1'): 1.21e-08,
    ('programmed', 1, 'theta_arm_1'): 2.68e-10,
    ('programmed', 1, 'phi_arm_1'): 1.22e-11,
    ('programmed', 1, 'z4'): 6.03e-08,
    ('programmed', 1, 'E_kin'): 5.27e-06,
    ('programmed', 1, 'E_pot'): 1.34e-07,
    ('programmed-rms', 1, 'z1'): 9.48e-10,
    ('programmed-rms', 1, 'psi2'): 6.19e-10,
    ('programmed-rms', 1, 'psi3'): 2.71e-08,
    ('programmed-rms', 1, 'psi_arm_1'): 6.05e-09,
    ('programmed-rms', 1, 'theta_arm_1'): 5.67e-11,
    ('programmed-rms', 1, 'phi_arm_1'): 3.72e-12,
    ('programmed-rms', 1, 'z4'): 2.7e-08,
    ('programmed', 1, 'Phi_1'): 3.26e-07,
    ('programmed', 1, 'Phi_2'): 7.79e-10,
}


def _unit(column):
    return "m" if column in ("z1", "z4", "Phi_2") else "J" if column.startswith("E_") else \
        "1" if column == "Phi_1" else "rad"


def gate(section, n_rfe, column, quick, measured_table=None):
    """Tolerance of one gated (section, model, column) comparison."""
    table = measured_table if measured_table is not None else (QUICK_MEASURED if quick else MEASURED)
    key = (section, n_rfe, column)
    if section == "free":
        m = table.get(key, 1e-12)
        return Tolerance(max(10 * m, 1e-12), 0.0, FREE_REASON.format(m=m, t=1 if quick else 10, f=10)
                         + "; floor 1e-12")
    m = table.get(key)
    if m is None:
        return Tolerance(np.inf, 0.0, "not gated: no measurement recorded for this entry")
    return Tolerance(10 * m, 0.0, f"10 x measured {m:.2e} {_unit(column)} ({'quick' if quick else 'full'} "
                     "run): MuJoCo's soft constraints (tendon lag ~ timeconst^2 v^2 / focus "
                     "distance), see docs/crosscheck-mujoco.md")
