"""What the MuJoCo crosscheck runs for a scenario, and the gates that are not run gates.

Run gates (free and exact programmed runs) come from gpme's own integration error:
crosscheck.run_gates.  This module holds the plan (run lengths, sampling), the crane's
free-motion variant, which scenarios MuJoCo's soft-equality mechanism can express, and
the mechanism's convergence gate.  SI units throughout.
"""
from dataclasses import dataclass, replace

import numpy as np

from gpme_core.errors import ModelError
from gpme_core.gpme import ProgrammedMotion
from gpme_examples.crane import initial_state

from ..compare import Tolerance
from ..run_gates import FULL_RUN_T_END
from . import mechanism as mech

OUTPUT_DT = 1e-2           # s, spacing of the compared samples
QUICK_T_END = 0.2          # s, longest run of the quick (CI) plan
TERM_SEED = 20261122
# free-motion variant of the crane: the unconstrained arm falls and its slider leaves the
# arm; springs on psi3 and z4 (same in both engines) keep the motion bounded
HOLDING_SPRINGS = {"psi3": dict(stiffness=200.0, spring_reference=np.pi / 4, damping=0.1),
                   "z4": dict(stiffness=2000.0, spring_reference=0.2, damping=0.5)}

# ---- soft-equality mechanism, gated by convergence
# MuJoCo's equality rows impose Phi_ddot = -(2/tc) Phi_dot - Phi/tc^2 (dampratio 1) on an
# acceleration that lacks the Jdot q_dot term and leaks (1 - impedance) of the free one,
# so the constraint value obeys Phi_ddot + (2/tc) Phi_dot + Phi/tc^2 = e(t) with e of the
# size of those missing terms.  Its quasi-static response is Phi ~ tc^2 e: halving tc
# (and dt with it) divides the difference to gpme by 4 (ratio 0.25; measured 0.23-0.26 on
# the rigid and n = 1 crane, docs/crosscheck-mujoco.md).  The gate 0.35 leaves room for
# the start transient (decays as exp(-t/tc)) and the change of dt; first-order
# convergence (0.5) or none fails: the difference would then not be the soft constraint.
MECHANISM_RATIO = Tolerance(0.35, 0.0, "soft equality Phi'' + 2/tc Phi' + Phi/tc^2 = e "
                            "(missing Jdot q_dot, 1 - impedance leak): difference ~ tc^2, so "
                            "halving tc and dt must give a ratio ~0.25 (measured 0.23-0.26); "
                            "gate 0.35, a first-order lag (0.5) fails")
MECHANISM_RESOLVED = 100.0  # a coordinate is gated when its coarse difference exceeds this
                            # many round-off floors 2 eps N (|q|max + h |q_dot|max)
MECHANISM_STEPS = 2         # timeconst = dt, then tc/2 with dt/2


@dataclass(frozen=True)
class Plan:
    """How much one run does.

    quick       : the CI version (runs of at most QUICK_T_END s)
    term_states : seeded states per scenario in the terms section
    """

    quick: bool
    term_states: int

    def t_end(self, scenario) -> float:
        """s, run length for ``scenario``: min(t_end, run_gates.FULL_RUN_T_END), or
        min(quick_t_end, QUICK_T_END)."""
        return min(scenario.quick_t_end, QUICK_T_END) if self.quick else \
            min(scenario.t_end, FULL_RUN_T_END)


def plan(quick: bool) -> Plan:
    """The full plan or the quick CI plan."""
    return Plan(True, 2) if quick else Plan(False, 5)


def free_variant(scenario):
    """The scenario without constraints (drives on).  A crane (a model named crane_* with
    the coordinates psi3 and z4) gets HOLDING_SPRINGS, since its free arm falls out of
    the slider's stroke; any other model runs as it is."""
    model = scenario.model
    if model.name.startswith("crane") and set(HOLDING_SPRINGS) <= set(model.coordinate_names):
        model = model.with_changes(joint_changes=HOLDING_SPRINGS, name=f"{model.name}_held")
    return replace(scenario, name=model.name, model=model, constraints=(),
                   system=ProgrammedMotion(model, ()))


def programme(scenario):
    """crosscheck.mujoco.mechanism.EllipticProgramme of the scenario when its constraints
    are exactly one EllipseConstraint and one CoordinateProgramme (Cosine, world z) on one
    frame, which the auxiliary mechanism can express; else None."""
    try:
        return mech.read_programme(scenario.model, scenario.constraints)
    except ModelError:
        return None


def on_manifold(scenario):
    """(q0, q_dot0) (n,) of the scenario placed on its constraints at t = 0."""
    if scenario.on_constraints:
        return np.array(scenario.q0), np.array(scenario.q_dot0)
    return scenario.system.consistent_state(0.0, scenario.q0, scenario.q_dot0)


def off_manifold_start(scenario):
    """(q0, q_dot0) off the constraints for the information section, or None: the
    scenario's own start when it is off them, for the rigid crane the paper's start."""
    if not scenario.on_constraints:
        return np.array(scenario.q0), np.array(scenario.q_dot0)
    if scenario.model.name == "crane_rigid":
        return initial_state(scenario.model)
    return None
