"""First bending modes in both planes and the first torsion mode of an RFEM cantilever
(gpme_core.rfem via ChainBuilder.add_beam) against beam theory, with convergence in n.

The beam: L = 0.4 m, solid rectangle 40 x 10 mm (width_y 4x height_z), steel.  The two
bending planes differ: psi (about z, deflection along y) uses I_z = h w^3/12, theta
(about y, deflection along z) I_y = w h^3/12 = I_z/16, so the first frequencies differ
by 4x.  A swap of I_y and I_z in rfem.py's sde stiffness moves each by 4x, and a swap in
the rigid elements' rotary inertia (I_yy <-> I_zz) moves the psi frequency by ~+0.2 %
(the Rayleigh correction below), which the extrapolated comparison resolves to ~1e-5:
both are caught (tried by hand: each swap fails all five bending tests, the inertia swap
through the ~1e-5-resolved Rayleigh comparison and the 5 % agreement of c2 = err n^2).

References
* Euler-Bernoulli clamped-free: omega_1 = (beta_1 L)^2 / L^2 sqrt(E I / (rho A)),
  beta_1 L = 1.87510407 (Meirovitch, Fundamentals of Vibrations, 2001, table 8.1).
* Rayleigh beam (Euler-Bernoulli plus rotary inertia rho I w_xt^2/2 in the kinetic energy;
  Rayleigh, Theory of Sound, 1877, sec. 186), which RFEM converges to: each rigid element
  carries rho I l of rotary inertia and the sdes have no shear flexibility.  Its frequency is
  computed here independently by a Ritz method (x^2 P_k(2x/L - 1), Legendre P_k, exact
  Gauss quadrature), checked against beta_1 L when the rotary term is off.  For this beam
  the rotary inertia lowers omega_1 by 0.19 % in the psi plane (slenderness L/r_z = 35)
  and 0.012 % in the theta plane (L/r_y = 139); to first order (Rayleigh quotient)
  omega_R/omega_EB = 1 - (r/L)^2 int phi'^2 ds / (2 int phi^2 ds) with phi the EB mode,
  s = x/L, r^2 = I/A; the Ritz value includes all orders.
* Shaft (clamped-free torsion): omega_1 = (pi / 2L) sqrt(G J / (rho I_p)), i.e.
  f = (1/4L) sqrt(G J / (rho I_p)), I_p = I_y + I_z the polar mass moment per unit rho.  The
  RFEM torsion chain (springs G J/dl between elements of torsional inertia rho I_p dl, the
  last dl/2) has the exact discrete frequency omega_1 = (2 n c / L) sin(pi / (4n)),
  c = sqrt(G J/(rho I_p)) (derived in test_torsion_...), so its relative error is
  1 - sin(x)/x < x^2/6 = pi^2 / (96 n^2), x = pi/(4n): the O(1/n^2) rate with its constant.

Convergence in bending: the RFEM frequency error behaves as c2/n^2 + c4/n^4; the ratio of
errors at n and 2n is 4 + O(1/n^2) and Richardson's (4 f(2n) - f(n))/3 removes c2.  The
gate on the extrapolated value is the difference of two successive extrapolations (which
estimates 15x the remaining error when c4 dominates).
"""
import numpy as np
import pytest
import scipy.linalg as sla
from scipy.optimize import brentq
from numpy.polynomial import Polynomial
from numpy.polynomial import legendre as npleg

from gpme_core.dynamics import mass_matrix
from gpme_core.inertia import cuboid
from gpme_core.model import PRISMATIC, ChainBuilder
from gpme_core.rfem import BeamProperties, BeamSection

E, G, RHO = 210e9, 81e9, 7850.0
LENGTH, WIDTH_Y, HEIGHT_Z = 0.4, 0.04, 0.01
BEAM = BeamProperties.from_section(LENGTH, BeamSection.rectangle(WIDTH_Y, HEIGHT_Z), E, G, RHO)
# first root of 1 + cos(x) cosh(x) = 0 (clamped-free frequency equation), 1.87510407
BETA1_L = brentq(lambda x: 1 + np.cos(x) * np.cosh(x), 1.5, 2.5, xtol=1e-15)
NS = (10, 20, 40, 80)
PLANES = {"psi": WIDTH_Y * HEIGHT_Z ** 3 / 12 * 16,    # I_z = h w^3/12 (w = 4h)
          "theta": WIDTH_Y * HEIGHT_Z ** 3 / 12}       # I_y = w h^3/12


def cantilever(n):
    """The beam on a prismatic carrier; clamping = dropping the carrier coordinate."""
    b = ChainBuilder("cantilever", gravity=(0, 0, 0))
    b.add_joint("carrier", PRISMATIC, (0, 0, 1))
    b.add_body(cuboid(1.0, (0.1, 0.1, 0.1)))
    b.add_beam("beam", BEAM, n)
    return b.build()


@pytest.fixture(scope="module")
def first_frequencies():
    """{n: {"psi": omega_1, "theta": omega_1, "phi": omega_1}} rad/s, from the clamped
    model's M and K at q = 0 (psi, theta and phi decouple there: the elements' centres lie
    on the beam axis and their inertia is diagonal in the beam frame)."""
    out = {}
    for n in NS:
        model = cantilever(n)
        m = mass_matrix(model, np.zeros(model.n_coordinates))
        k = model.stiffness_matrix()
        out[n] = {}
        for rot in ("psi", "theta", "phi"):
            idx = [i for i, nm in enumerate(model.coordinate_names) if nm.startswith(rot + "_")]
            lam = sla.eigvalsh(k[np.ix_(idx, idx)], m[np.ix_(idx, idx)], subset_by_index=[0, 0])
            out[n][rot] = float(np.sqrt(lam[0]))
    return out


def euler_bernoulli(i):
    """rad/s, first clamped-free frequency for second moment ``i`` m^4."""
    return BETA1_L ** 2 / LENGTH ** 2 * np.sqrt(E * i / (RHO * BEAM.area))


def rayleigh_beam(i, rotary=True, n_basis=10):
    """rad/s, first clamped-free frequency of the Rayleigh beam (Ritz, independent of
    gpme): K a = lambda M a with K_ij = int phi_i'' phi_j'', M_ij = int phi_i phi_j +
    (r/L)^2 int phi_i' phi_j' on s = x/L in [0, 1], phi_k = s^2 P_k(2s - 1) (clamped at
    s = 0, free end natural), omega^2 = lambda E I / (rho A L^4)."""
    r2 = i / BEAM.area / LENGTH ** 2 if rotary else 0.0
    s, wq = npleg.leggauss(2 * n_basis + 6)
    s, wq = 0.5 * (s + 1), 0.5 * wq                        # Gauss on [0, 1]
    basis = [Polynomial([0, 0, 1]) * Polynomial(npleg.leg2poly(np.eye(n_basis)[k]))(
        Polynomial([-1, 2])) for k in range(n_basis)]
    v0, v1, v2 = (np.array([p.deriv(d)(s) for p in basis]) for d in (0, 1, 2))
    k = (v2 * wq) @ v2.T
    m = (v0 * wq) @ v0.T + r2 * (v1 * wq) @ v1.T
    lam = sla.eigvalsh(k, m, subset_by_index=[0, 0])[0]
    return np.sqrt(lam * E * i / (RHO * BEAM.area * LENGTH ** 4))


def test_ritz_reference_reproduces_euler_bernoulli_without_rotary_inertia():
    """Ritz with 10 polynomials is converged for the first mode to ~1e-10 (its error is
    spectral); the rotary correction is the size stated in the module docstring."""
    for i in PLANES.values():
        assert rayleigh_beam(i, rotary=False) == pytest.approx(euler_bernoulli(i), rel=1e-10)
        assert rayleigh_beam(i, n_basis=12) == pytest.approx(rayleigh_beam(i), rel=1e-9)
    drop = {p: 1 - rayleigh_beam(i) / euler_bernoulli(i) for p, i in PLANES.items()}
    # first-order estimate (r/L)^2 int phi'^2/(2 int phi^2) ~ 2.3 (r/L)^2 for mode 1: 1.9e-3, 1.2e-4
    assert 1.5e-3 < drop["psi"] < 2.5e-3 and 0.9e-4 < drop["theta"] < 1.6e-4, drop


@pytest.mark.parametrize("plane", ["psi", "theta"])
def test_bending_error_falls_as_one_over_n_squared(first_frequencies, plane):
    """Error against the Rayleigh beam at n and 2n: ratio 4 (O(1/n^2)) to within the
    next term (ratio 4 (1 + O(1/n^2)): accepted [3.5, 4.5] from n = 20 on), and the
    coefficient c2 = err n^2 agrees between n = 40 and 80 to 5 %."""
    ref = rayleigh_beam(PLANES[plane])
    err = {n: first_frequencies[n][plane] / ref - 1 for n in NS}
    for n in NS[1:-1]:
        assert 3.5 < err[n] / err[2 * n] < 4.5, (plane, n, err)
    c40, c80 = err[40] * 40 ** 2, err[80] * 80 ** 2
    assert abs(c40 / c80 - 1) < 0.05, (c40, c80)
    # and the Euler-Bernoulli value is approached as well, up to the rotary offset
    eb = euler_bernoulli(PLANES[plane])
    offset = 1 - ref / eb
    assert abs(first_frequencies[80][plane] / eb - 1) < abs(c80) / 80 ** 2 + offset * 1.01


@pytest.mark.parametrize("plane", ["psi", "theta"])
def test_bending_extrapolates_to_the_rayleigh_beam(first_frequencies, plane):
    """Richardson extrapolation of n = 40, 80 against the Ritz Rayleigh value, with the
    gate |f_ext(40, 80) - f_ext(20, 40)| (the remaining error is about 1/15 of it; the
    gate keeps that factor as margin) plus 1e-9 for the eigen-solves' round-off.  The
    psi-plane rotary correction (0.2 %) is far above this gate, so dropping or swapping
    the element rotary inertia fails here, and the EB value is excluded."""
    f = {n: first_frequencies[n][plane] for n in NS}
    ext = {n: (4 * f[2 * n] - f[n]) / 3 for n in (20, 40)}
    ref = rayleigh_beam(PLANES[plane])
    gate = abs(ext[40] - ext[20]) / ref + 1e-9
    assert abs(ext[40] / ref - 1) <= gate, (ext, ref, gate)
    if plane == "psi":
        eb = euler_bernoulli(PLANES[plane])
        assert abs(ext[40] / eb - 1) > 10 * gate     # rotary inertia resolved


def test_the_two_planes_differ_by_the_section_ratio(first_frequencies):
    """omega_psi / omega_theta = sqrt(I_z / I_y) = w/h = 4 for Euler-Bernoulli; the
    Rayleigh values differ by the planes' rotary corrections."""
    ratio = first_frequencies[80]["psi"] / first_frequencies[80]["theta"]
    expected = rayleigh_beam(PLANES["psi"]) / rayleigh_beam(PLANES["theta"])
    assert ratio == pytest.approx(expected, rel=2e-3)   # O(1/n^2) errors, c2/80^2 < 1e-3 each
    assert 3.9 < ratio < 4.0


def test_torsion_against_the_shaft_formula(first_frequencies):
    """Exact discrete value and convergence to f = (1/4L) sqrt(G J/(rho I_p)).

    Discrete chain: theta_r = rotation of element r (theta_0 = 0 clamped), inertias
    m = rho I_p dl (the last m/2), springs k = G J/dl.  theta_r = sin(alpha r) solves the
    interior equations with omega^2 = (4k/m) sin^2(alpha/2); the free end
    (m/2) theta_n'' = k (theta_{n-1} - theta_n) then needs cos(alpha n) = 0, alpha = pi/(2n).
    Hence omega_1 = (2 n c/L) sin(pi/(4n)), c = sqrt(G J/(rho I_p)), error < pi^2/(96 n^2)."""
    j, i_p = BEAM.torsion_constant, BEAM.second_moment_y + BEAM.second_moment_z
    c = np.sqrt(G * j / (RHO * i_p))
    shaft = np.pi * c / (2 * LENGTH)                      # = 2 pi f, f = c / (4L)
    for n in NS:
        omega = first_frequencies[n]["phi"]
        exact_discrete = 2 * n * c / LENGTH * np.sin(np.pi / (4 * n))
        assert omega == pytest.approx(exact_discrete, rel=1e-10)   # eigen-solve round-off
        err = 1 - omega / shaft
        assert 0 < err <= np.pi ** 2 / (96 * n ** 2) * (1 + 1e-8), (n, err)
    errs = [1 - first_frequencies[n]["phi"] / shaft for n in NS]
    ratios = np.array(errs[:-1]) / np.array(errs[1:])
    assert np.all(np.abs(ratios - 4) < 0.01), ratios      # 4 (1 + O(1/n^2)), n >= 10
