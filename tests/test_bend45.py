"""The Bathe-Bolourchi 45-degree bend (crosscheck.continuum.bend45): a spatial static
benchmark with bending in two planes and torsion.

Published reference: K.-J. Bathe, S. Bolourchi, Int. J. Numer. Meth. Engng 14:961-986
(1979); J. C. Simo, L. Vu-Quoc, CMAME 58:79-116 (1986), Example 7.5; M. A. Crisfield (1990),
as quoted in docs/flexible-beam-benchmark-sources.md, section 2.  Tables and the reasons
for every tolerance: docs/rfem-continuum.md, section "Bathe-Bolourchi 45-degree bend".

Checks: RFEM against linear theory (small load); RFEM's extrapolated limit against the
continuum (tolerance: the extrapolation's own error estimate from the same run, plus the
continuum's); the same limit against the published band; a planted fault (the sde torsion
springs 10 % stiffer or softer) fails the continuum check; with Exudyn installed, the
continuum's stored limits recomputed and the continuum against the published band.
"""
import numpy as np
import pytest

from crosscheck.continuum import bend45 as b

CHORDS = (16, 32, 64)          # one segment per chord; the RFEM limit from these three


@pytest.fixture(scope="module")
def rfem():
    """RFEM's limit at the published loads (about 10 s)."""
    return b.rfem_limit(CHORDS)


def _continuum_check(limit: b.RfemLimit) -> dict:
    """{load: (|RFEM limit - continuum|, tolerance)} per component, m.  Tolerance: the RFEM
    limit's error estimate (its order-2 term at 64 chords, from the same three runs) plus the
    stored continuum's (its last mesh change, MESH_GOAL at most)."""
    out = {}
    for p in b.LOADS:
        diff = np.abs(limit.limit[p] - np.asarray(b.CONTINUUM_EULER_BERNOULLI[p]))
        out[p] = (diff, limit.error[p] + b.MESH_GOAL)
    return out


def test_small_load_against_linear_theory():
    """At P = 0.01 N (tip rotation 2e-5 rad, nonlinear terms ~1e-5 relative) RFEM's
    out-of-plane tip deflection converges to the closed form of a circular cantilever
    (bending and torsion, Castigliano) at order 2: the error at 32 chords is within 2 x its
    order-2 Richardson estimate |w(16) - w(32)| / 3 of the closed form (factor 2: covers an
    observed order down to 1.6), and the observed order is 2 within 0.05."""
    load = 0.01
    exact = b.linear_tip_deflection(load, b.TORSION_POLAR)
    w = [b.solve_load_path(1, n, [load])[load][2] for n in (8, 16, 32)]
    order = np.log(abs(w[0] - exact) / abs(w[1] - exact)) / np.log(2.0)
    assert order == pytest.approx(2.0, abs=0.05)
    assert abs(w[2] - exact) <= 2.0 * abs(w[1] - w[2]) / 3.0


def test_rfem_limit_matches_the_continuum(rfem):
    """RFEM (inextensible, shear-rigid) converges to the continuum's Euler-Bernoulli limit:
    every tip component at 300, 450 and 600 N within the extrapolation's own error
    estimate plus the continuum's."""
    for p, (diff, tol) in _continuum_check(rfem).items():
        assert np.all(diff <= tol), (p, diff, tol)


def test_rfem_is_first_order_at_large_rotation(rfem):
    """The radial coordinate at 600 N converges at order 1 (sde springs on Cardan angles:
    an energy error (G J / dl) psi theta phi / 2 per sde when bending in two planes and
    torsion occur together; docs/rfem-continuum.md): observed order within 0.15 of 1."""
    ref = np.asarray(b.CONTINUUM_EULER_BERNOULLI[600.0])
    e = [abs(rfem.tips[n][600.0][1] - ref[1]) for n in CHORDS]
    assert np.log(e[1] / e[2]) / np.log(2.0) == pytest.approx(1.0, abs=0.15)


def test_rfem_limit_within_the_published_band(rfem):
    """RFEM's limit lies within the band the published values support (their range, each
    widened by its rounding, plus the range's width as the allowance for the sources' own
    discretisation errors; crosscheck.continuum.bend45.published_band)."""
    for p in b.LOADS:
        band = b.published_band(p)
        assert np.all(b.outside_band(rfem.limit[p], band) <= band.width), p


@pytest.mark.parametrize("scale", [1.1, 0.9], ids=["torsion+10%", "torsion-10%"])
def test_planted_torsion_fault_fails(scale):
    """The sde torsion springs 10 % off: the tangent (x) or out-of-plane (z) tip component
    leaves the continuum check's tolerance (the benchmark sees torsion)."""
    limit = b.rfem_limit(CHORDS, loads=b.LOADS, torsion_scale=scale)
    checks = _continuum_check(limit)
    diff, tol = checks[600.0]
    assert diff[0] > tol[0] or diff[2] > tol[2], (diff, tol)
    assert any(np.any(d > t) for d, t in checks.values())


def test_stored_continuum_limits_are_exudyns():
    """With Exudyn: the continuum's limits stored in the module (used above) are what
    Exudyn gives, order-2 Richardson of 64 and 128 elements, within its error estimate
    |limit - finest| plus MESH_GOAL (the stored ones' own bound)."""
    pytest.importorskip("exudyn")
    for eb, stored in ((True, b.CONTINUUM_EULER_BERNOULLI), (False, b.CONTINUUM_PHYSICAL)):
        ref = b.continuum_reference(euler_bernoulli=eb, first=64, max_elements=128,
                                    goal=0.0)
        for p in b.LOADS:
            diff = np.abs(ref.limit[p] - np.asarray(stored[p]))
            assert np.all(diff <= ref.error[p] + b.MESH_GOAL), (eb, p, diff)


def test_continuum_within_the_published_band_and_saint_venant_not():
    """With Exudyn: the physical rod with G J = G (I_y + I_z) (BeamDyn's, Kynema's) lies in
    the published band at every load; with Saint-Venant's G J (0.1406, 16 % less) the tip
    at 600 N leaves it: the published solutions used the polar value (or one near it)."""
    pytest.importorskip("exudyn")
    for j, inside in ((b.TORSION_POLAR, True), (b.TORSION_SAINT_VENANT, False)):
        ref = b.continuum_reference(torsion_constant=j, first=32, max_elements=64, goal=0.0)
        for p in (b.LOADS if inside else (600.0,)):
            band = b.published_band(p)
            ok = bool(np.all(b.outside_band(ref.limit[p], band) <= band.width))
            assert ok is inside, (j, p, ref.limit[p])


def test_exudyn_curved_reference_is_stress_free_and_linear():
    """With Exudyn: the unloaded bend stays where it is (the element takes its nodes'
    curved reference as stress-free), and at P = 0.1 N its out-of-plane tip deflection,
    Richardson-extrapolated from 32 and 64 elements, equals the closed form with the
    shear term k = 5/6 to 1e-4 (nonlinear terms ~rotation 2e-4 rad)."""
    pytest.importorskip("exudyn")
    unloaded = b.exudyn_tip(8, loads=[0.0])[0.0]
    assert np.abs(unloaded - b.TIP_UNDEFORMED).max() < 1e-9
    load = 0.1
    w = [b.exudyn_tip(n, loads=[load], load_steps=1)[load][2] for n in (32, 64)]
    exact = b.linear_tip_deflection(load, b.TORSION_POLAR, shear_coefficient=5.0 / 6.0)
    assert b.extrapolate(w[0], w[1], 2.0) == pytest.approx(exact, rel=1e-4)
