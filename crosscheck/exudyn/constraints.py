"""The programmed constraints as Exudyn algebraic equations with time-dependent user functions.

Every constraint of a scenario (the crane's ellipse and coordinate programme, a model file's
SymPy point constraints, joint programmes q_k = f(t)) becomes one row of a single
ObjectConnectorCoordinateVector between the tree node's coordinates (marker 0, n entries)
and a ground point's (marker 1, 3 entries, all 0), with

    constraintUserFunction(mbs, t, item, q, q_t, velocityLevel) -> Phi(t, q) (m,)
                                                   (Phi_dot(t, q, q_dot) if velocityLevel)
    jacobianUserFunction(mbs, t, item, q, q_t, velocityLevel)   -> dPhi/dq (m, n)

(q holds n + 3 entries, the ground point's 3 last and 0; the Jacobian has the columns of
the connector's ODE2 coordinates only, n: the ground point has none.)

Exudyn's index-3 generalized-alpha solver enforces Phi(t_{k+1}, q_{k+1}) = 0 exactly (to
its Newton tolerance) at every step: no Baumgarte term, no softness.

Nothing here comes from gpme's formulas.  The end-effector kinematics are Pinocchio's (a
PinocchioSystem built from the gpme model's data: frame positions oMf and
LOCAL_WORLD_ALIGNED frame Jacobians, velocities getFrameVelocity), and the task
expressions with their derivatives come from crosscheck.constraint_reference (SymPy
derivatives of the task definitions): Phi = phi(p, t), dPhi/dq = grad_p phi . J,
Phi_dot = grad_p phi . v + phi_t; a joint programme gives Phi = q_k - f(t), row e_k.
Units: Phi in the constraint's own unit (m, m^2, 1, rad), q in rad or m.
"""
from typing import Optional

import numpy as np
import pinocchio as pin
from exudyn.itemInterface import ObjectConnectorCoordinateVector
from numpy.typing import NDArray

from gpme_core.errors import ConstraintError

from ..constraint_reference import evaluate_reference, reference_constraints
from ..pinocchio.model import from_gpme

LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
GROUND_COORDINATES = 3          # the ground point node's coordinates in the connector's q
# rad, m or the constraint's unit: the start must lie on the constraints (Phi, Phi_dot) to
# this level.  An index-3 solver projects an inconsistent start onto Phi = 0 in its first
# step, a jump that gpme's Baumgarte run does not make, so the runs would differ by the
# start's violation and not by the integrators.  gpme's consistent_state reaches ~1e-12.
CONSISTENT_TOL = 1e-9


class ProgrammedConstraints:
    """Phi(t, q), Phi_dot and dPhi/dq of a scenario's constraint specs, on Pinocchio's side.

    specs      : gpme constraint specs (scenario.constraints), names and order kept
    model      : the gpme model (data for Pinocchio's model and the coordinate names)
    pin_system : a crosscheck.pinocchio.model.PinocchioSystem to use instead of
                 from_gpme(model) (tests perturb it)
    """

    def __init__(self, specs, model, pin_system=None):
        self.refs = reference_constraints(specs, model.coordinate_names)
        self.names = tuple(r.name for r in self.refs)
        self.m = len(self.refs)
        self.n = model.n_coordinates
        self.ps = pin_system or from_gpme(model)
        self.data = self.ps.model.createData()
        self._key = None
        self._value = None
        self._position_key = None
        self._position_value = None
        self._no_velocity = np.zeros(self.n)
        self.evaluations = 0

    def _frame_id(self, frame):
        try:
            return self.ps.frames[frame]
        except KeyError:
            raise ConstraintError(f"constraint frame {frame!r} is not a frame of the Pinocchio "
                                  f"model; it has {sorted(self.ps.frames)}") from None

    def _frame_jacobian(self, fid):
        """(3, n) translational LOCAL_WORLD_ALIGNED Jacobian of frame ``fid``, gpme column
        order (reshaped: Pinocchio hands a (6, 1) matrix over as a (6,) vector)."""
        pm = self.ps.model
        jac6 = np.asarray(pin.getFrameJacobian(pm, self.data, fid, LWA)).reshape(6, pm.nv)
        return self.ps.columns_to_gpme(jac6[:3])

    def _point_state(self, frame, drift=False):
        pm, data = self.ps.model, self.data
        fid = self._frame_id(frame)
        p = data.oMf[fid].translation.copy()
        v = pin.getFrameVelocity(pm, data, fid, LWA).linear.copy()
        a = pin.getFrameClassicalAcceleration(pm, data, fid, LWA).linear.copy() if drift \
            else np.zeros(3)
        return p, v, self._frame_jacobian(fid), a

    def _kinematics(self, q, q_dot):
        pm, data = self.ps.model, self.data
        q_pin = self.ps.q_pin(q)
        pin.forwardKinematics(pm, data, q_pin, self.ps.to_pin(q_dot), np.zeros(pm.nv))
        pin.computeJointJacobians(pm, data, q_pin)
        pin.updateFramePlacements(pm, data)

    def evaluate(self, t: float, q: NDArray, q_dot: Optional[NDArray] = None):
        """(Phi (m,), Phi_dot (m,), A = dPhi/dq (m, n)) at time t (s), q (n,), q_dot (n,)
        (zeros when None), gpme coordinate order.  The last evaluation is cached: Exudyn
        asks for the value and the Jacobian at the same state."""
        q = np.asarray(q, dtype=float)
        q_dot = np.zeros(self.n) if q_dot is None else np.asarray(q_dot, dtype=float)
        key = (float(t), q.tobytes(), q_dot.tobytes())
        if key == self._key:
            return self._value
        self.evaluations += 1
        self._kinematics(q, q_dot)
        phi, phi_dot, a, _ = evaluate_reference(self.refs, float(t), q, q_dot, self._point_state)
        self._key, self._value = key, (phi, phi_dot, a)
        return self._value

    def position_terms(self, t: float, q: NDArray):
        """(Phi (m,), A = dPhi/dq (m, n)) at time t (s) and q (n,), gpme coordinate order:
        the position level alone, what Exudyn's index-3 solver asks for (no frame
        velocities: Phi and its gradient do not depend on them).  The same Pinocchio
        kinematics (oMf after computeJointJacobians) and SymPy expressions as
        :meth:`evaluate`, each frame's state formed once; the last evaluation is cached."""
        q = np.asarray(q, dtype=float)
        key = (float(t), q.tobytes())
        if key == self._position_key:
            return self._position_value
        self.evaluations += 1
        pm, data = self.ps.model, self.data
        pin.computeJointJacobians(pm, data, self.ps.q_pin(q))
        pin.updateFramePlacements(pm, data)
        states = {}

        def point_state(frame):
            if frame not in states:
                fid = self._frame_id(frame)
                states[frame] = (data.oMf[fid].translation.copy(), np.zeros(3),
                                 self._frame_jacobian(fid), np.zeros(3))
            return states[frame]

        phi, _, a, _ = evaluate_reference(self.refs, float(t), q, self._no_velocity,
                                          point_state)
        self._position_key, self._position_value = key, (phi, a)
        return self._position_value

    def acceleration_terms(self, t: float, q: NDArray, q_dot: NDArray):
        """(A (m, n), kappa (m,)): Phi_ddot = A q_ddot + kappa at (t, q, q_dot), kappa from
        Pinocchio's classical frame accelerations at q_ddot = 0 (LOCAL_WORLD_ALIGNED) and
        the SymPy second derivatives of the task expressions."""
        q, q_dot = np.asarray(q, dtype=float), np.asarray(q_dot, dtype=float)
        self._kinematics(q, q_dot)
        self._key = None
        _, _, a, kappa = evaluate_reference(self.refs, float(t), q, q_dot,
                                            lambda f: self._point_state(f, drift=True))
        return a, kappa

    # ------------------------------------------------------------------ Exudyn callbacks
    def constraint_function(self, mbs, t, item, q, q_t, velocity_level):
        """Exudyn's constraintUserFunction: Phi (m,), or Phi_dot if velocity_level."""
        if not velocity_level:
            return self.position_terms(t, np.asarray(q)[:self.n])[0].tolist()
        _, phi_dot, _ = self.evaluate(t, np.asarray(q)[:self.n], np.asarray(q_t)[:self.n])
        return phi_dot.tolist()

    def jacobian_function(self, mbs, t, item, q, q_t, velocity_level):
        """Exudyn's jacobianUserFunction: (m, n) dPhi/dq (Exudyn takes the columns of the
        connector's ODE2 coordinates only: the ground point has none); the same matrix is
        dPhi_dot/dq_dot at velocity level."""
        return self.position_terms(t, np.asarray(q)[:self.n])[1]

    def add_to(self, mbs, tree) -> int:
        """Add the constraints to ``mbs`` as one ObjectConnectorCoordinateVector between
        ``tree``'s node coordinates and its ground point (crosscheck.exudyn.model.ExudynTree);
        returns the object index (its AE coordinates are the multipliers, in ``names``
        order)."""
        return mbs.AddObject(ObjectConnectorCoordinateVector(
            markerNumbers=[tree.node_marker, tree.ground_marker],
            scalingMarker0=np.zeros((self.m, self.n)),
            scalingMarker1=np.zeros((self.m, GROUND_COORDINATES)),
            constraintUserFunction=self.constraint_function,
            jacobianUserFunction=self.jacobian_function, visualization={"show": False}))

    def check_start(self, t: float, q: NDArray, q_dot: NDArray, label: str = "") -> tuple:
        """(max|Phi|, max|Phi_dot|) at the start; ConstraintError when either exceeds
        CONSISTENT_TOL (the index-3 run would start with a projection jump)."""
        phi, phi_dot, _ = self.evaluate(t, q, q_dot)
        worst = (float(np.abs(phi).max(initial=0.0)), float(np.abs(phi_dot).max(initial=0.0)))
        if max(worst) > CONSISTENT_TOL:
            bad = [f"{nm}: Phi = {p:.3g}, Phi_dot = {pd:.3g}" for nm, p, pd in
                   zip(self.names, phi, phi_dot) if max(abs(p), abs(pd)) > CONSISTENT_TOL]
            raise ConstraintError(
                f"{label or 'start'}: the initial state is not on the programmed constraints "
                f"at t = {t:g} s ({'; '.join(bad)}; need |Phi|, |Phi_dot| <= "
                f"{CONSISTENT_TOL:g}); an index-3 run would begin by projecting onto them. "
                "Start from a consistent state, e.g. crane_scenario(n, on_constraints=True) or "
                "on_constraints = true in the model file")
        return worst
