"""Why RFEM is first order on the Bathe-Bolourchi bend (benchmarks/rfem_rotation_order.py;
tables and reasoning: docs/rfem-continuum.md, section "Why order 1: the Cardan-angle
springs (confirmed)").

The sde springs act on the Cardan angles (psi, theta, phi) of Rz Ry Rx.  The checks: the
tip of a straight cantilever converges at order 2 in planar bending and at order 1 when
bending and torsion combine (eccentric tip force, rectangle under an oblique force); the
same models with the springs on the rotation vector (same stiffnesses, only the law
changed) converge at order 2, on the bend too; the energy the Cardan law adds to the
converged deformation is first order in dl with the predicted coefficient.

Reference: the inextensible, unshearable Kirchhoff rod by shooting (RFEM's limit), itself
checked against the elastica closed form (Bisshopp & Drucker 1945, Q. Appl. Math. 3:272)
and Exudyn's converged bend.  Orders are observed between 16 and 32 segments against that
reference (its error, ~1e-10 m, is 1e-6 of RFEM's at 32 segments).
"""
import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq

from benchmarks import rfem_rotation_order as ro
from crosscheck.continuum import bend45
from gpme_core.dynamics import spring_forces

MESHES = (16, 32)
CARDAN, ROTVEC = ro.SpringLaw.CARDAN, ro.SpringLaw.ROTATION_VECTOR


@pytest.fixture(scope="module")
def rods():
    """The converged Kirchhoff rods of every case and of the bend at 600 N (about 3 s)."""
    out = {c.name: ro.kirchhoff_case(c) for c in ro.CASES}
    out["bend45"] = ro.kirchhoff_bend()
    return out


def _run(rods, name, law):
    return ro.run_case(name, law, MESHES, rods[name])


# ------------------------------------------------------------------ the harness itself
def test_rotation_vector_jacobian_matches_finite_differences():
    """dv/d(psi, theta, phi) of the rotation vector of Rz Ry Rx against central differences
    (step 1e-6 rad) at random angles up to ~1 rad: truncation h^2 ~ 1e-12 and round-off
    eps / h ~ 2e-10 bound the difference; 1e-8 is well above both and far below any error
    in the formula (order one)."""
    rng = np.random.default_rng(20240611)
    angles = rng.normal(scale=0.5, size=(20, 3))
    _, jac = ro.rotation_vector_jacobian(angles)
    h = 1e-6
    fd = np.stack([(ro.rotation_vector(ro.cardan_matrices(angles + h * e))
                    - ro.rotation_vector(ro.cardan_matrices(angles - h * e))) / (2 * h)
                   for e in np.eye(3)], axis=2)
    assert np.abs(jac - fd).max() < 1e-8


def test_laws_agree_without_a_second_angle():
    """With theta alone non-zero at every sde (planar bending about y) the rotation vector
    is (0, theta, 0) exactly, so both spring laws give the same forces, to round-off
    (1e-12 of the largest)."""
    model = ro.cantilever_model(ro.CASE_BY_NAME["planar"], 8, 1.0)
    triplets = ro.sde_triplets(model)
    q = np.zeros(model.n_coordinates)
    q[triplets[:, 1]] = np.linspace(0.05, 0.4, len(triplets))
    cardan = spring_forces(model, q)
    rotvec = ro.rotation_vector_spring_forces(model, q, triplets)
    assert np.abs(cardan - rotvec).max() <= 1e-12 * np.abs(cardan).max()
    q[triplets[:, 0]] = 0.1                     # a second angle: the laws differ
    assert np.abs(spring_forces(model, q)
                  - ro.rotation_vector_spring_forces(model, q, triplets)).max() \
        > 1e-4 * np.abs(cardan).max()


def test_cardan_excess_is_the_cubic_term():
    """1/2 (q^T S q - v^T S v) of one sde at angles ~1e-3 rad equals
    (s_phi - s_theta + s_psi) psi theta phi / 2 (BCH); the next term is of relative order
    the angles (3e-3), so 2 % is a bound with margin, and a wrong sign or factor in the
    cubic term fails it."""
    angles = np.array([[1e-3, 2e-3, 3e-3]])
    s = np.array([[2.0, 3.0, 5.0]])                 # s_psi, s_theta, s_phi (N m/rad)
    expected = (5.0 - 3.0 + 2.0) * np.prod(angles) / 2.0
    assert ro.cardan_energy_excess(angles, s) == pytest.approx(expected, rel=0.02)


def test_reference_rod_against_the_elastica_and_exudyn(rods):
    """The shooting reference against two others: (1) the planar case against the elastica
    of a cantilever under a normal tip force (Bisshopp & Drucker: sqrt(a) =
    (1/sqrt 2) int_0^t0 dt / sqrt(sin t0 - sin t), x/L = sqrt(2 sin t0 / a), a = P L^2/EI,
    by quadrature): 1e-7 m, 1e-9 of L, above both computations' accuracy (they agree to
    1e-11 m);
    (2) the bend at 600 N against Exudyn's Euler-Bernoulli limit stored in bend45, within
    that limit's tolerance MESH_GOAL (5e-4 m; measured 6e-5 m)."""
    case = ro.CASE_BY_NAME["planar"]
    a = case.force[2] * ro.LENGTH ** 2 / (ro.YOUNGS_MODULUS * ro.SQUARE.second_moment_y)

    def integral(g, t0):
        """int_0^t0 g(t) dt / sqrt(sin t0 - sin t), with t = t0 (1 - w^2) taking out the
        endpoint's inverse square root: sin t0 - sin t = 2 cos(t0 - u) sin u, u = t0 w^2/2,
        and w / sqrt(sin u) = sqrt(2 / (t0 sinc u)), so the integrand is smooth in w."""
        def f(w):
            u = 0.5 * t0 * w * w
            return 2.0 * t0 * g(t0 - 2.0 * u) * np.sqrt(
                1.0 / (t0 * np.cos(t0 - u) * np.sinc(u / np.pi)))
        return quad(f, 0.0, 1.0, limit=200, epsabs=0.0, epsrel=1e-12)[0]

    # tip angle t0 (rad) in a bracket clear of 90 degrees, where cos t0 -> 0 makes the
    # integrand's peak a round-off problem (the solution is at 0.64 rad)
    t0 = brentq(lambda t: integral(lambda _: 1.0, t) / np.sqrt(2.0) - np.sqrt(a), 0.01, 1.5,
                xtol=1e-15)
    x = ro.LENGTH * np.sqrt(2.0 * np.sin(t0) / a)
    z = ro.LENGTH / np.sqrt(2.0 * a) * integral(np.sin, t0)
    assert np.abs(rods["planar"].position - (x, 0.0, z)).max() < 1e-7
    eb = np.asarray(bend45.CONTINUUM_EULER_BERNOULLI[ro.BEND_LOAD])
    assert np.abs(rods["bend45"].position - eb).max() < bend45.MESH_GOAL


# ------------------------------------------------------------------------ the orders
def test_planar_large_deflection_is_second_order(rods):
    """Tip deflection 0.41 L, bending about y only: x and z converge at order 2 within 0.15
    (measured 2.01, 2.00; 0.15 leaves room for the order-3 remainder at 16 segments, and
    an order-1 term of any visible size would show as < 1.85); y stays zero."""
    run = _run(rods, "planar", CARDAN)
    order = run.orders()[-1]
    assert order[[0, 2]] == pytest.approx([2.0, 2.0], abs=0.15)
    assert np.abs(run.position_error[:, 1]).max() < ro.POSITION_FLOOR


def test_bending_with_torsion_is_first_order(rods):
    """Eccentric tip force (a torque about the axis and a transverse force together): the
    tip's x, y and orientation converge at order 1 within 0.2 (measured 1.09, 1.01, 1.02;
    0.2 because the order-2 term is still a few % of the error at 16 segments, which the x
    component shows; an order 2 would be 1.8 or more).  z carries a large order-2 part
    (1.8 measured) and is not asserted."""
    run = _run(rods, "eccentric", CARDAN)
    assert run.orders()[-1][:2] == pytest.approx([1.0, 1.0], abs=0.2)
    assert run.rotation_orders()[-1] == pytest.approx(1.0, abs=0.2)


def test_rotation_vector_springs_restore_second_order(rods):
    """The same eccentric case with the same stiffnesses on the rotation vector instead of
    the Cardan angles: every tip component and the orientation at order 2 within 0.15
    (measured 2.00-2.01): changing only the spring law removes the order-1 error, so the
    law is its cause."""
    run = _run(rods, "eccentric", ROTVEC)
    assert run.orders()[-1] == pytest.approx([2.0, 2.0, 2.0], abs=0.15)
    assert run.rotation_orders()[-1] == pytest.approx(2.0, abs=0.15)


def test_rotation_vector_springs_make_the_bend_second_order(rods):
    """The Bathe-Bolourchi bend at 600 N (one segment per chord; order 1 with the Cardan
    law, tests/test_bend45.py) with the springs on the rotation vector: order 2 within 0.15
    in every component (measured 2.00-2.02)."""
    run = _run(rods, "bend45", ROTVEC)
    assert run.orders()[-1] == pytest.approx([2.0, 2.0, 2.0], abs=0.15)


def test_two_bending_planes_without_torsion(rods):
    """Square section, force at 45 degrees between the principal axes: physically planar
    (I_y = I_z), but psi and theta are both non-zero.  The tip position stays at order 2
    (within 0.15; measured 2.00) while the orientation is order 1 (within 0.15; measured
    1.00): the spurious twist (dl/2)|int k_y k_z ds| left by the unloaded torsion springs,
    which the rotation error at 32 segments matches within 3 % (its order-2 part is 0.4 %
    of it, the prediction's own O(dl) remainder about 1 %)."""
    run = _run(rods, "oblique-square", CARDAN)
    assert run.orders()[-1] == pytest.approx([2.0, 2.0, 2.0], abs=0.15)
    assert run.rotation_orders()[-1] == pytest.approx(1.0, abs=0.15)
    predicted = ro.spurious_twist(rods["oblique-square"], MESHES[-1])
    assert run.rotation_error[-1] == pytest.approx(predicted, rel=0.03)


def test_two_bending_planes_of_a_rectangle_are_first_order(rods):
    """Rectangle (I_z = 4 I_y), force at 45 degrees: bending in two planes with geometric
    torsion; x and y at order 1 within 0.2 (measured 1.02, 1.00), the orientation too
    (1.01); z (1.16, order-2 part still visible) within 0.3 of 1, still far from 2."""
    run = _run(rods, "oblique-rectangle", CARDAN)
    order = run.orders()[-1]
    assert order[:2] == pytest.approx([1.0, 1.0], abs=0.2)
    assert order[2] == pytest.approx(1.0, abs=0.3)
    assert run.rotation_orders()[-1] == pytest.approx(1.0, abs=0.2)


def test_energy_excess_of_the_bend_is_first_order(rods):
    """The converged bend's deformation mapped onto n sdes: the Cardan law's energy minus
    the rotation-vector law's, against its leading term
    dl (G J - E I_y + E I_z)/2 int k_x k_y k_z ds: ratio within 0.1 of 1 at 256 sdes (its
    remainder is O(dl), measured 1.061) and halving from 128 (1.122): first order in dl.
    The planar case's excess is zero to round-off (1e-12 of its elastic energy)."""
    rod = rods["bend45"]
    ratio = [ro.continuum_energy_excess(rod, n)[0] / ro.leading_excess(rod, n)
             for n in (128, 256)]
    assert ratio[1] == pytest.approx(1.0, abs=0.1)
    assert (ratio[0] - 1.0) / (ratio[1] - 1.0) == pytest.approx(2.0, abs=0.3)
    excess, energy = ro.continuum_energy_excess(rods["planar"], 64)
    assert abs(excess) < 1e-12 * energy
