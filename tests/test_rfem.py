"""RFEM: discretisation bookkeeping and convergence of a cantilever's bending frequencies
to the Euler-Bernoulli values (beta_k L = 1.87510, 4.69409, 7.85476; e.g. Meirovitch,
Fundamentals of Vibrations, 2001, table 8.1)."""
import numpy as np
import pytest
import scipy.linalg as sla

from gpme_core.dynamics import mass_matrix
from gpme_core.errors import ModelError
from gpme_core.inertia import cuboid
from gpme_core.model import PRISMATIC, ChainBuilder
from gpme_core.rfem import BeamProperties

pytestmark = pytest.mark.both_computation_paths

BETA_L = np.array([1.87510407, 4.69409113, 7.85475744])
# slender (L/d = 500) so that rotary inertia, which RFEM includes and Euler-Bernoulli
# neglects, shifts the frequencies by < 1e-5 and the discretisation error dominates
BEAM = BeamProperties.solid_circular(length=1.0, diameter=0.002, youngs_modulus=210e9,
                                     shear_modulus=81e9, density=7850.0)


def cantilever(n, beam=BEAM):
    """Beam on a carrier joint; clamping = removing the carrier coordinate."""
    b = ChainBuilder("cantilever", gravity=(0, 0, 0))
    b.add_joint("carrier", PRISMATIC, (0, 0, 1))
    b.add_body(cuboid(1.0, (0.1, 0.1, 0.1)))
    b.add_beam("beam", beam, n)
    return b.build()


def bending_frequencies(n, count=3):
    model = cantilever(n)
    psi = [k for k, nm in enumerate(model.coordinate_names) if nm.startswith("psi_")]
    m = mass_matrix(model, np.zeros(model.n_coordinates))[np.ix_(psi, psi)]
    k = model.stiffness_matrix()[np.ix_(psi, psi)]
    return np.sqrt(sla.eigvalsh(k, m))[:count]


def euler_bernoulli():
    ei = BEAM.youngs_modulus * BEAM.second_moment_z
    rho_a = BEAM.density * BEAM.area
    return BETA_L ** 2 * np.sqrt(ei / (rho_a * BEAM.length ** 4))


def test_coordinates_and_mass_of_discretisation():
    model = cantilever(4)
    names = model.coordinate_names
    assert names[1:4] == ("psi_beam_1", "theta_beam_1", "phi_beam_1")
    assert len(names) == 1 + 3 * 4
    assert np.isclose(model.total_mass - 1.0, BEAM.mass, rtol=1e-14)
    # rfe 0 and n half length, others full: sde r sits at (r - 1/2) dl
    dl = BEAM.length / 4
    sde_x = np.cumsum([model.joints[k].origin[0, 3] for k in range(1, 13, 3)])
    np.testing.assert_allclose(sde_x, (np.arange(1, 5) - 0.5) * dl)
    s_psi = model.joints[1].stiffness
    assert np.isclose(s_psi, BEAM.youngs_modulus * BEAM.second_moment_z / dl)
    assert np.isclose(model.joints[3].stiffness, BEAM.shear_modulus * BEAM.torsion_constant / dl)


def test_rigid_link_when_n_is_zero():
    model = cantilever(0)
    assert model.coordinate_names == ("carrier",)
    assert np.isclose(model.total_mass - 1.0, BEAM.mass)


def test_cantilever_frequencies_converge_to_euler_bernoulli():
    exact = euler_bernoulli()
    errs = {n: np.abs(bending_frequencies(n) / exact - 1) for n in (5, 10, 20, 40)}
    assert np.all(errs[40] < 2e-3), errs[40]
    # second-order convergence: doubling n divides the error by about 4
    for n in (10, 20):
        ratio = errs[n] / errs[2 * n]
        assert np.all((ratio > 3.0) & (ratio < 5.0)), (n, ratio)


def test_bad_beam_is_reported_with_every_problem():
    bad = BeamProperties(1.0, -1.0, 81e9, 7850.0, 0.0, 1e-9, 1e-9, 2e-9)
    with pytest.raises(ModelError, match="youngs_modulus must be positive") as exc:
        cantilever(3, bad)
    assert "area must be positive" in str(exc.value)
    with pytest.raises(ModelError, match="number of segments must be an integer from 0 to 1000"):
        cantilever(-1)
