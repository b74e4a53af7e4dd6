"""Two beams added one after the other on one link (ChainBuilder.add_beam, no joint in
between) make one bar of length L1 + L2: the tip frame at L1 + L2 along the beam axis, and
the mass, centre of mass and inertia of two bars placed end to end.

Expected values by hand.  A solid round bar of length l, diameter d, density rho (area
A = pi d^2/4, I_y = I_z = pi d^4/64 = int y^2 dA) along +x from its root has mass
m = rho A l, centre at l/2 and, about its centre,
    I_xx = rho (I_y + I_z) l,   I_yy = I_zz = rho I_z l + m l^2 / 12.
Bar 1 from 0 to L1, bar 2 from L1 to L1 + L2: the centre of mass is
x_c = (m1 L1/2 + m2 (L1 + L2/2)) / (m1 + m2), and by the parallel-axis theorem
    I_yy = I_zz = sum_i (rho I_z,i L_i + m_i L_i^2/12 + m_i (x_i - x_c)^2),
    I_xx = sum_i rho (I_y,i + I_z,i) L_i   (both centres on the x axis).
The same holds for the RFEM discretisation in its undeflected configuration q = 0: its rigid
elements are pieces of the same bars, which add up to the bars exactly.

The model's numbers are read back through the definition of the pseudo-inertia
(gpme_core.inertia: H = int r r^T dm, r = (x, y, z, 1)): the world pseudo-inertia of the
chain at q = 0 is sum_l T_l H_l T_l^T, its [3, 3] entry the mass, [:3, 3] the first moment,
[:3, :3] the second moments.
"""
import numpy as np
import pytest

from gpme_core import transforms as tf
from gpme_core.kinematics import chain_kinematics
from gpme_core.model import REVOLUTE, ChainBuilder
from gpme_core.rfem import BeamProperties

RHO = 7800.0                    # kg/m^3
E, G = 2.1e11, 8.1e10           # Pa
L1, D1 = 1.0, 0.04              # m, bar 1
L2, D2 = 0.6, 0.03              # m, bar 2: another length and section


def _bar(length, diameter):
    return BeamProperties.solid_circular(length, diameter, E, G, RHO)


def _by_hand():
    """(mass kg, centre of mass (3,) m, inertia about it (3, 3) kg m^2), beam along +x."""
    bars = []
    x0 = 0.0
    for length, d in ((L1, D1), (L2, D2)):
        area, i_z = np.pi * d ** 2 / 4, np.pi * d ** 4 / 64
        m = RHO * area * length
        bars.append((m, x0 + length / 2, length, i_z))
        x0 += length
    mass = sum(b[0] for b in bars)
    x_c = sum(m * x for m, x, _, _ in bars) / mass
    i_yy = sum(RHO * i_z * l + m * l ** 2 / 12 + m * (x - x_c) ** 2 for m, x, l, i_z in bars)
    i_xx = sum(RHO * 2 * i_z * l for _, _, l, i_z in bars)
    return mass, np.array([x_c, 0.0, 0.0]), np.diag([i_xx, i_yy, i_yy])


def _two_beams(n1, n2, frame=None):
    b = ChainBuilder("two_beams", gravity=(0.0, 0.0, -9.81))
    b.add_joint("swing", REVOLUTE, (0, 0, 1))
    b.add_beam("first", _bar(L1, D1), n1, frame=frame)
    b.add_beam("second", _bar(L2, D2), n2, frame=None if frame is None else np.eye(4))
    b.add_frame("tip")
    return b.build()


def _chain_mass_properties(model):
    """(mass, centre (3,), inertia about it (3, 3)) of the whole chain at q = 0, world frame."""
    kin = chain_kinematics(model, np.zeros(model.n_coordinates))
    h = sum(t @ hl @ t.T for t, hl in zip(kin.T, model.pseudo_inertias))
    mass = h[3, 3]
    c = h[:3, 3] / mass
    j = h[:3, :3] - mass * np.outer(c, c)       # second moments about the centre
    return mass, c, np.trace(j) * np.eye(3) - j


def _tip(model):
    kin = chain_kinematics(model, np.zeros(model.n_coordinates))
    fr = model.frames["tip"]
    return (kin.T[fr.link_index] @ fr.transform)[:3, 3]


SEGMENTS = [(0, 0), (1, 1), (3, 2), (0, 2), (2, 0)]


@pytest.mark.parametrize("n1, n2", SEGMENTS, ids=[f"n{a}-n{b}" for a, b in SEGMENTS])
def test_tip_frame_is_at_the_sum_of_the_lengths(n1, n2):
    # products of a few transforms of lengths ~1 m: round-off ~1e-15 m
    np.testing.assert_allclose(_tip(_two_beams(n1, n2)), [L1 + L2, 0.0, 0.0], rtol=0,
                               atol=1e-14)


@pytest.mark.parametrize("n1, n2", SEGMENTS, ids=[f"n{a}-n{b}" for a, b in SEGMENTS])
def test_tip_follows_the_beam_frame(n1, n2):
    # the first beam along +y of the link (B = rotation of +90 deg about z, 0.1 m up);
    # the second, with the identity frame, continues from the first one's tip
    frame = tf.homogeneous(np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]),
                           (0.0, 0.0, 0.1))
    model = _two_beams(n1, n2, frame=frame)
    np.testing.assert_allclose(_tip(model), [0.0, L1 + L2, 0.1], rtol=0, atol=1e-14)


@pytest.mark.parametrize("n1, n2", SEGMENTS, ids=[f"n{a}-n{b}" for a, b in SEGMENTS])
def test_mass_centre_and_inertia_are_two_bars_end_to_end(n1, n2):
    mass, com, inertia = _chain_mass_properties(_two_beams(n1, n2))
    m_ref, c_ref, i_ref = _by_hand()
    # sums of a few dozen terms of size <= m_ref (L1 + L2)^2: relative round-off ~1e-14
    assert mass == pytest.approx(m_ref, rel=1e-13)
    np.testing.assert_allclose(com, c_ref, rtol=0, atol=1e-13)
    np.testing.assert_allclose(inertia, i_ref, rtol=0, atol=1e-12 * np.abs(i_ref).max())


def test_two_rigid_beams_make_one_link():
    model = _two_beams(0, 0)
    assert model.n_coordinates == 1            # no joint between them
    link = model.links[0].inertia
    m_ref, c_ref, i_ref = _by_hand()
    assert link.mass == pytest.approx(m_ref, rel=1e-13)
    np.testing.assert_allclose(link.com, c_ref, rtol=0, atol=1e-13)
    np.testing.assert_allclose(link.inertia, i_ref, rtol=0, atol=1e-12 * np.abs(i_ref).max())
