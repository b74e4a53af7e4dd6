"""Bad input gets one clear error naming the value and what would be valid."""
import numpy as np
import pytest

from gpme_core import transforms as tf
from gpme_examples.crane import CraneParameters, crane_system, initial_state
from gpme_core.errors import ModelError, SimulationError, UnstableStepError
from gpme_core.gpme import ProgrammedMotion
from gpme_core.inertia import RigidBodyInertia, check_pseudo_inertia, cuboid
from gpme_core.integrate import simulate
from gpme_core.model import PRISMATIC, REVOLUTE, ChainBuilder

pytestmark = pytest.mark.both_computation_paths


def test_negative_mass():
    b = ChainBuilder()
    b.add_joint("q", REVOLUTE, (0, 0, 1))
    with pytest.raises(ModelError, match=r"mass must be positive and finite, got -1\.0 kg"):
        b.add_body(RigidBodyInertia(-1.0, (0, 0, 0), np.eye(3)))


def test_non_positive_definite_inertia():
    with pytest.raises(ModelError, match="inertia tensor must be positive definite"):
        check_pseudo_inertia(RigidBodyInertia(1.0, (0, 0, 0), np.diag([1.0, 1.0, -0.1]))
                             .pseudo_inertia())
    # the triangle inequality is not a problem (accepted, as Pinocchio accepts it), a
    # negative principal moment is
    cad = RigidBodyInertia(1.0, (0, 0, 0), np.diag([1.0, 0.1, 0.1]))
    assert not cad.problems("link a") and "triangle inequality" in cad.non_physical("a")[0]
    asym = RigidBodyInertia(1.0, (0, 0, 0), [[1, 0.1, 0], [0, 1, 0], [0, 0, 1]])
    assert "symmetric" in asym.problems("link a")[0]
    with pytest.raises(ModelError, match=r"expected shape \(4, 4\), got \(3, 4\)"):
        check_pseudo_inertia(np.zeros((3, 4)))


def test_every_problem_is_listed_at_once():
    b = ChainBuilder(gravity=(0, 0, np.nan))
    b.add_joint("a", REVOLUTE, (0, 0, 2), stiffness=-5.0)
    b.add_body(cuboid(1.0, (0.1, 0.1, 0.1)))
    b.add_joint("a", "screw", (1, 0, 0), origin=np.diag([1.0, 1.0, -1.0, 1.0]), damping=-1)
    b.add_drive("nowhere", lambda t: 0.0)
    with pytest.raises(ModelError) as exc:
        b.build()
    msg = str(exc.value)
    for part in ("axis must be a unit 3-vector, got [0.0, 0.0, 2.0]",
                 "stiffness must be finite and >= 0", "duplicate coordinate name",
                 "kind must be one of ('revolute', 'prismatic'), got 'screw'",
                 "not a proper rotation", "damping must be finite and >= 0",
                 "gravity must be a finite (3,) vector", "drive on 'nowhere': no such coordinate"):
        assert part in msg, part
    assert "duplicate link name" in msg
    assert msg.startswith("9 problems in the model")


def test_massless_chain_is_rejected_with_the_coordinate_named():
    b = ChainBuilder()
    b.add_joint("loose", PRISMATIC, (1, 0, 0))
    with pytest.raises(ModelError, match=r"coordinates moving no mass: \['loose'\]"):
        b.build()


def test_model_is_immutable():
    model = crane_system(0).model
    with pytest.raises(ValueError):
        model.stiffness[0] = 1.0
    with pytest.raises(AttributeError):
        model.joints[0].stiffness = 1.0


def test_wrong_state_shape_and_method():
    system = crane_system(0)
    with pytest.raises(ModelError) as exc:
        simulate(system, -1.0, np.zeros(3), np.full(4, np.nan), method="Euler")
    msg = str(exc.value)
    assert "q0 must have shape (4,) ordered as ['z1', 'psi2', 'psi3', 'z4'], got (3,)" in msg
    assert "q_dot0 must be finite" in msg
    assert "method must be one of ('RK4', 'RadauIIA', 'RK45', 'DOP853', 'Radau'), got 'Euler'" in msg
    assert "t_end must be positive" in msg


def test_diverging_run_stops_at_the_first_bad_step():
    """RK4 far beyond its stability limit on the stiff RFEM torsion modes (no joint limits,
    so that the blow-up itself, not a limit, stops the run)."""
    free = CraneParameters(slider_stroke=(-np.inf, np.inf), arm_pitch_range=(-np.inf, np.inf))
    model = crane_system(3, free).model
    system = ProgrammedMotion(model, ())
    q, qd = initial_state(model)
    # refused before the first step, as a step problem
    with pytest.raises(UnstableStepError, match=r"dt = 0\.005 s is unstable at the start "
                                                r"\(t = 0\).*stiffest mode .* Hz.*mostly phi_arm"):
        simulate(system, 2.0, q, qd, dt=5e-3)
    # let through (check_step=False): it blows up, and the blow-up is still reported as the
    # step's instability at the last recorded state, with the divergence it caused
    with pytest.raises(UnstableStepError, match=r"dt = 0\.005 s is unstable at t = .* s, the "
                                                r"last recorded state.*use dt <= .*The failure "
                                                r"it caused: the run diverged at t = .* s with "
                                                r"dt = 0\.005 s"):
        simulate(system, 2.0, q, qd, dt=5e-3, check_step=False)


def test_unknown_names():
    model = crane_system(0).model
    with pytest.raises(ModelError, match=r"no coordinate named 'psi9'; the model has \['z1'"):
        model.index("psi9")
    with pytest.raises(ModelError, match="no frame named 'tool'"):
        model.frame("tool")
    with pytest.raises(ModelError, match=r"dependent coordinates.*got \['z1'\]"):
        ProgrammedMotion(model, crane_system(0).constraint_specs, dependent=["z1"])
