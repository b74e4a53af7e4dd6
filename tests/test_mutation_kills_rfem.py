"""Kill tests for gpme_core.rfem (docs/mutation.md): cross-section constants, the rigid
finite elements' mass properties and the spring-damping element coefficients, each
against a closed form written out here (I_y and I_z deliberately different)."""
import numpy as np
import pytest

from gpme_core import transforms as tf
from gpme_core.errors import ModelError
from gpme_core.inertia import cuboid
from gpme_core.kinematics import chain_kinematics
from gpme_core.model import REVOLUTE, ChainBuilder
from gpme_core.rfem import BeamProperties, BeamSection, beam_frame_problems

pytestmark = pytest.mark.both_computation_paths

# closed forms evaluated in floating point: agreement to a few ulp
RT = 1e-12


def test_circle_and_tube_sections_are_the_textbook_values():
    """Solid circle d: A = pi d^2/4, I = pi d^4/64, J = pi d^4/32; tube = outer circle minus
    inner circle (d_i = d - 2 t)."""
    d = 0.04
    s = BeamSection.solid_circle(d)
    assert s.area == pytest.approx(np.pi * d ** 2 / 4, rel=RT)
    assert s.second_moment_y == pytest.approx(np.pi * d ** 4 / 64, rel=RT)
    assert s.second_moment_z == pytest.approx(np.pi * d ** 4 / 64, rel=RT)
    assert s.torsion_constant == pytest.approx(np.pi * d ** 4 / 32, rel=RT)
    t = BeamSection.tube(d, 0.005)
    di = d - 2 * 0.005
    assert t.area == pytest.approx(np.pi * (d ** 2 - di ** 2) / 4, rel=RT)
    assert t.second_moment_y == pytest.approx(np.pi * (d ** 4 - di ** 4) / 64, rel=RT)
    assert t.second_moment_z == pytest.approx(np.pi * (d ** 4 - di ** 4) / 64, rel=RT)
    assert t.torsion_constant == pytest.approx(np.pi * (d ** 4 - di ** 4) / 32, rel=RT)
    b = BeamProperties.solid_circular(1.5, d, 2e11, 8e10, 7800.0, bending_viscosity=3.0)
    assert (b.area, b.second_moment_y, b.torsion_constant) == pytest.approx(
        (s.area, s.second_moment_y, s.torsion_constant), rel=RT)
    assert b.mass == pytest.approx(7800.0 * np.pi * d ** 2 / 4 * 1.5, rel=RT)


def test_tube_and_circle_reject_bad_dimensions():
    """A wall as thick as the radius is no tube; sizes must be positive."""
    with pytest.raises(ModelError, match="smaller than the outer radius"):
        BeamSection.tube(0.04, 0.02)
    BeamSection.tube(0.04, 0.0199)                 # just inside: a valid thick tube
    for bad in (lambda: BeamSection.tube(-0.04, 0.001), lambda: BeamSection.solid_circle(0.0),
                lambda: BeamSection.rectangle(0.01, -1.0), lambda: BeamSection.solid_circle("x")):
        with pytest.raises(ModelError):
            bad()


def _saint_venant_torsion(a, b, terms=200):
    """Exact torsion constant of an a x b rectangle (a >= b), Timoshenko and Goodier
    sec. 109: J = a b^3 / 3 [1 - 192/pi^5 (b/a) sum_{n odd} tanh(n pi a / 2b) / n^5]."""
    n = np.arange(1, 2 * terms, 2)
    return a * b ** 3 / 3 * (1 - 192 / np.pi ** 5 * (b / a)
                             * np.sum(np.tanh(n * np.pi * a / (2 * b)) / n ** 5))


def test_rectangle_section_moments_and_torsion_constant():
    """A = w h, I_y = w h^3/12 (about y, the z-extent h counts), I_z = h w^3/12; J within
    Roark's stated 0.5 % of the exact Saint-Venant series, for a square and 3:2 and 4:1
    aspects in both orientations (J does not depend on which side is along y)."""
    w, h = 0.03, 0.01
    s = BeamSection.rectangle(w, h)
    assert s.area == pytest.approx(w * h, rel=RT)
    assert s.second_moment_y == pytest.approx(w * h ** 3 / 12, rel=RT)
    assert s.second_moment_z == pytest.approx(h * w ** 3 / 12, rel=RT)
    for a, b in ((0.01, 0.01), (0.015, 0.01), (0.04, 0.01), (0.03, 0.01)):
        exact = _saint_venant_torsion(a, b)
        for sec in (BeamSection.rectangle(a, b), BeamSection.rectangle(b, a)):
            assert sec.torsion_constant == pytest.approx(exact, rel=5e-3)
    # thin strip limit a >> b: J -> a b^3 / 3 (1 - 0.63 b/a); Roark's leading terms
    thin = BeamSection.rectangle(1.0, 0.001)
    assert thin.torsion_constant == pytest.approx(1.0 * 1e-9 / 3 * (1 - 0.63e-3), rel=1e-6)


def _rect_beam(eta=0.0, eta_g=None):
    sec = BeamSection.rectangle(0.03, 0.01)       # I_z = 9 I_y: a swap shows at once
    return BeamProperties.from_section(1.2, sec, 2.0e11, 8.0e10, 2700.0,
                                       bending_viscosity=eta, torsion_viscosity=eta_g)


def test_from_section_copies_every_constant_and_checks_the_type():
    """from_section: the section's A, I_y, I_z, J in that order."""
    b = _rect_beam()
    assert (b.area, b.second_moment_y, b.second_moment_z, b.torsion_constant) == pytest.approx(
        (3e-4, 0.03 * 1e-6 / 12, 0.01 * 2.7e-5 / 12, BeamSection.rectangle(0.03, 0.01).torsion_constant),
        rel=RT)
    with pytest.raises(ModelError, match="BeamSection"):
        BeamProperties.from_section(1.0, (1, 2, 3, 4), 1.0, 1.0, 1.0)


def test_torsion_viscosity_defaults_to_eta_e_g_over_e():
    """Kelvin-Voigt in shear with the same retardation time: eta_G = eta_E G / E."""
    assert _rect_beam(eta=5.0).eta_g == pytest.approx(5.0 * 8e10 / 2e11, rel=RT)
    assert _rect_beam(eta=5.0, eta_g=7.0).eta_g == 7.0
    assert _rect_beam(eta=5.0, eta_g=0.0).eta_g == 0.0


def test_element_inertia_is_that_of_a_solid_box():
    """A rectangular-section piece of length l is a box l x w x h of mass rho w h l: its
    inertia about its centre is m/12 diag(w^2 + h^2, l^2 + h^2, l^2 + w^2), centre at l/2."""
    b = _rect_beam()
    l = 0.3
    e = b.element_inertia(l)
    m = 2700.0 * 3e-4 * l
    box = cuboid(m, (l, 0.03, 0.01))
    assert e.mass == pytest.approx(m, rel=RT)
    np.testing.assert_allclose(e.com_array, [l / 2, 0, 0], rtol=RT, atol=0)
    np.testing.assert_allclose(e.inertia_array, box.inertia_array, rtol=1e-12, atol=0)


def test_sde_coefficients_bend_about_z_with_i_z_and_about_y_with_i_y():
    """s_psi = E I_z/dl (psi about z bends in the section's y, I_z = int y^2 dA),
    s_theta = E I_y/dl, s_phi = G J/dl; dampers likewise with eta_E, eta_G; dl = L/n."""
    b = _rect_beam(eta=4.0, eta_g=1.5)
    dl = 1.2 / 3
    iy, iz, j = b.second_moment_y, b.second_moment_z, b.torsion_constant
    stiff, damp = b.sde_coefficients(3)
    np.testing.assert_allclose(stiff, [2e11 * iz / dl, 2e11 * iy / dl, 8e10 * j / dl], rtol=RT)
    np.testing.assert_allclose(damp, [4.0 * iz / dl, 4.0 * iy / dl, 1.5 * j / dl], rtol=RT)


def _beam_model(n, frame=None, eta=4.0):
    b = ChainBuilder("beam", gravity=(0, 0, -9.81))
    b.add_joint("base", REVOLUTE, (0, 0, 1))
    b.add_beam("L", _rect_beam(eta=eta), n, frame=frame)
    b.add_frame("tip")
    return b.build(), b


def test_discretised_beam_joints_springs_geometry_and_mass():
    """n = 2: sdes at dl/2 and 3 dl/2 along the beam (dl = L/2), each psi (z), theta (y),
    phi (x) with s = E I_z/dl, E I_y/dl, G J/dl; rfes of length dl/2, dl, dl/2 (total mass
    rho A L, centre of mass L/2 at q = 0); the tip frame at L along the beam frame's x."""
    frame = tf.translation(0.1, 0.2, 0.0) @ tf.rot_z(0.5)
    model, _ = _beam_model(2, frame)
    dl = 0.6
    b = _rect_beam(eta=4.0)
    names = ["base"] + [f"{r}_L_{k}" for k in (1, 2) for r in ("psi", "theta", "phi")]
    assert list(model.coordinate_names) == names
    for k in (1, 2):
        assert model.stiffness[model.index(f"psi_L_{k}")] == pytest.approx(2e11 * b.second_moment_z / dl, rel=RT)
        assert model.stiffness[model.index(f"theta_L_{k}")] == pytest.approx(2e11 * b.second_moment_y / dl, rel=RT)
        assert model.stiffness[model.index(f"phi_L_{k}")] == pytest.approx(8e10 * b.torsion_constant / dl, rel=RT)
        assert model.damping[model.index(f"psi_L_{k}")] == pytest.approx(4.0 * b.second_moment_z / dl, rel=RT)
        np.testing.assert_allclose(model.axes[model.index(f"psi_L_{k}")], [0, 0, 1])
        np.testing.assert_allclose(model.axes[model.index(f"theta_L_{k}")], [0, 1, 0])
        np.testing.assert_allclose(model.axes[model.index(f"phi_L_{k}")], [1, 0, 0])
    kin = chain_kinematics(model, np.zeros(model.n_coordinates))
    u = frame[:3, :3] @ [1, 0, 0]
    root = frame[:3, 3]
    np.testing.assert_allclose(kin.T[model.index("psi_L_1"), :3, 3], root + 0.5 * dl * u, atol=1e-12)
    np.testing.assert_allclose(kin.T[model.index("psi_L_2"), :3, 3], root + 1.5 * dl * u, atol=1e-12)
    np.testing.assert_allclose(kin.T[model.index("phi_L_2"), :3, :3], frame[:3, :3], atol=1e-12)
    tip = model.frame("tip")
    np.testing.assert_allclose((kin.T[tip.link_index] @ tip.transform)[:3, 3], root + 1.2 * u, atol=1e-12)
    h = kin.T @ model.pseudo_inertias @ np.swapaxes(kin.T, 1, 2)
    mass = h[:, 3, 3].sum()
    assert mass == pytest.approx(2700.0 * 3e-4 * 1.2, rel=1e-12)
    np.testing.assert_allclose(h[:, :3, 3].sum(axis=0) / mass, root + 0.6 * u, atol=1e-12)
    # the first rfe (length dl/2) sits on the carrying link, the last one (dl/2) on phi_L_2
    assert model.pseudo_inertias[0, 3, 3] == pytest.approx(2700.0 * 3e-4 * 0.3, rel=1e-12)
    assert model.pseudo_inertias[model.index("phi_L_1"), 3, 3] == pytest.approx(2700.0 * 3e-4 * 0.6, rel=1e-12)
    assert model.pseudo_inertias[model.index("phi_L_2"), 3, 3] == pytest.approx(2700.0 * 3e-4 * 0.3, rel=1e-12)
    info = model.flexible_links[0]
    assert info.n_segments == 2 and len(info.joint_indices) == 6


def test_rigid_beam_n0_puts_the_tip_at_length():
    """n = 0: one rigid body of mass rho A L centred at L/2 and the tip at L."""
    model, _ = _beam_model(0, tf.rot_y(0.3))
    kin = chain_kinematics(model, np.zeros(1))
    tip = model.frame("tip")
    u = tf.rot_y(0.3)[:3, :3] @ [1, 0, 0]
    np.testing.assert_allclose((kin.T[tip.link_index] @ tip.transform)[:3, 3], 1.2 * u, atol=1e-12)
    assert model.pseudo_inertias[0, 3, 3] == pytest.approx(2700.0 * 3e-4 * 1.2, rel=1e-12)
    np.testing.assert_allclose(model.pseudo_inertias[0, :3, 3] / model.pseudo_inertias[0, 3, 3],
                               0.6 * u, atol=1e-12)


def test_static_tip_deflections_use_the_right_second_moment():
    """A tip force F on an n-segment RFEM cantilever: sde r at x_r = (r - 1/2) dl carries the
    moment F (L - x_r) and turns by F (L - x_r) dl / (E I); small tip deflection
    F dl / (E I) sum_r (L - x_r)^2 (the midpoint rule of F L^3 / (3 E I)).  Checked from the
    springs alone: the potential energy gradient K q equals the moment of F at each sde,
    with I = I_z for a force along the section's y (psi rotations) and I_y along z."""
    model, _ = _beam_model(3)
    L, n, dl = 1.2, 3, 0.4
    b = _rect_beam()
    x = (np.arange(1, n + 1) - 0.5) * dl
    for rot, i_sec in (("psi", b.second_moment_z), ("theta", b.second_moment_y)):
        idx = [model.index(f"{rot}_L_{r}") for r in range(1, n + 1)]
        k = model.stiffness[idx]
        turn = 1.0 * (L - x) / k                        # F = 1 N
        assert np.sum(turn * (L - x)) == pytest.approx(dl / (2e11 * i_sec) * np.sum((L - x) ** 2), rel=1e-12)


def test_beam_problems_list_every_bad_value():
    """Negative viscosities, non-finite or non-numeric constants, bad segment counts and a
    beam frame that is not a proper rigid transform are all reported; zero viscosity is fine."""
    assert _rect_beam(eta=0.0, eta_g=0.0).problems("b") == []
    bad = BeamProperties(1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, "x", bending_viscosity=-1.0,
                         torsion_viscosity=float("nan"))
    p = bad.problems("b")
    assert any("torsion_constant" in s for s in p)
    assert any("bending_viscosity" in s for s in p) and any("torsion_viscosity" in s for s in p)
    bad2 = BeamProperties(1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, bending_viscosity="x")
    assert any("bending_viscosity" in s for s in bad2.problems("b"))
    b = ChainBuilder("x")
    with pytest.raises(ModelError, match="carries the beam first"):
        b.add_beam("L", _rect_beam(), 1)
    b.add_joint("j", REVOLUTE, (0, 0, 1))
    for n in (-1, True, 1.5):
        with pytest.raises(ModelError, match="integer from 0 to 1000"):
            b.add_beam("L", _rect_beam(), n)
    assert beam_frame_problems("f", np.eye(4)) == []
    assert "shape" in beam_frame_problems("f", np.eye(3))[0]
    assert "non-finite" in beam_frame_problems("f", np.full((4, 4), np.nan))[0]
    mirror = np.diag([1.0, 1.0, -1.0, 1.0])
    assert "proper rotation" in beam_frame_problems("f", mirror)[0]
    sheared = np.eye(4)
    sheared[0, 1] = 0.1
    assert "proper rotation" in beam_frame_problems("f", sheared)[0]
    last = np.eye(4)
    last[3, 0] = 1.0
    msg = beam_frame_problems("f", last)
    assert len(msg) == 1 and "last row" in msg[0] and "[1.0, 0.0, 0.0, 1.0]" in msg[0]
