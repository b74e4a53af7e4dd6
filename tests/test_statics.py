"""Static sag of the flexible arm: equilibrium of gravity and the sde springs, and the
cantilever deflection it implies against beam theory."""
import numpy as np
import pytest

from gpme_examples.crane import CraneParameters, build_crane, initial_state
from gpme_core.dynamics import gravity_forces, spring_forces
from gpme_core.errors import ConstraintError
from gpme_core.kinematics import link_transforms
from gpme_core.statics import static_equilibrium

pytestmark = pytest.mark.both_computation_paths


def test_static_arm_balances_gravity_with_the_sde_springs():
    model = build_crane(5)
    q, _ = initial_state(model, static_arm=True)
    flex = [k for k, nm in enumerate(model.coordinate_names) if "_arm_" in nm]
    resid = (gravity_forces(model, q) + spring_forces(model, q))[flex]
    assert np.abs(resid).max() < 1e-10
    assert np.abs(q[flex]).max() > 1e-4          # it really sags


def test_tip_sag_of_horizontal_arm_matches_beam_theory():
    """Arm horizontal (psi3 = 0), slider tip at the arm tip (z4 = 0): Euler-Bernoulli
    cantilever under its own weight w and the slider's weight P carried at the tip as a
    force P and a moment -P Ls/2 (the slider's centre lies Ls/2 back along the arm):
    w L^4/(8EI) + P L^3/(3EI) + M L^2/(2EI).  RFEM with n = 40 matches it to 2e-3."""
    p = CraneParameters()
    model = build_crane(40, p)
    q = np.zeros(model.n_coordinates)
    q = static_equilibrium(model, q, [nm for nm in model.coordinate_names if "_arm_" in nm])
    straight = link_transforms(model, np.zeros(model.n_coordinates))
    tip = model.frame("E")
    sag = straight[tip.link_index][2, 3] - link_transforms(model, q)[tip.link_index][2, 3]
    beam = p.beam()
    ei = beam.youngs_modulus * beam.second_moment_z
    length, w = beam.length, beam.density * beam.area * 9.81
    load = p.slider_mass * 9.81
    # slider: a rigid rod of length Ls fixed at the tip, centre Ls/2 back along the arm; its
    # weight acts at the tip as a force P and a moment M = -P Ls/2 (towards the pivot)
    moment = -load * p.slider_length / 2
    deflection = w * length ** 4 / (8 * ei) + load * length ** 3 / (3 * ei) + moment * length ** 2 / (2 * ei)
    # E sits at the slider tip = the arm tip (z4 = 0): its drop is the tip deflection
    assert sag == pytest.approx(deflection, rel=2e-3), (sag, deflection)


def test_no_equilibrium_without_a_spring():
    model = build_crane(0)
    with pytest.raises(ConstraintError, match=r"no static equilibrium of \['psi3'\]"):
        static_equilibrium(model, np.zeros(model.n_coordinates), ["psi3"])
