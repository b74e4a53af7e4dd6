"""Natural frequencies of RFEM and of the continuum (crosscheck.continuum.frequencies).

Each side is checked on its own against the closed form of a clamped-free Euler-Bernoulli
beam (with the first-order rotary-inertia term, both models carry the section's rho I),
the eigen-solution against Exudyn's own ComputeODE2Eigenvalues, RFEM against the continuum
on the paper's crane at order 2, and a planted stiffness fault against the frequency gate.
"""
import numpy as np
import pytest
from scipy.integrate import quad

exu = pytest.importorskip("exudyn")

from crosscheck.continuum import frequencies as fq  # noqa: E402
from crosscheck.continuum.layout import continuum_layout  # noqa: E402
from crosscheck.continuum.system import build_system  # noqa: E402
from gpme_core.constraints import JointProgramme  # noqa: E402
from gpme_core.errors import ModelError  # noqa: E402
from gpme_core.gpme import ProgrammedMotion  # noqa: E402
from gpme_core.inertia import RigidBodyInertia  # noqa: E402
from gpme_core.joint_kinds import REVOLUTE  # noqa: E402
from gpme_core.model import ChainBuilder  # noqa: E402
from gpme_core.time_functions import Constant  # noqa: E402
from gpme_examples.spin_up import beam_properties  # noqa: E402
from gpme_io.scenario import crane_scenario  # noqa: E402

FIRST = 0                    # index of the first bending frequency in Modes.frequencies_hz


def _cantilever(n):
    """The spin-up beam (L = 10 m, E I = 1.4e4 N m^2 in both planes, rho A = 1.2 kg/m,
    rho I = 6e-4 kg m) on a hub whose angle is held at 0 by a programme: a clamped-free
    beam.  Gravity is given and must not matter (the frequencies are of the unloaded
    machine)."""
    b = ChainBuilder("held_cantilever", gravity=(0.0, 0.0, -9.81))
    b.add_joint("hub", REVOLUTE, (0, 0, 1), link="hub")
    b.add_body(RigidBodyInertia(1.0, (0.0, 0.0, 0.0), np.diag([0.25, 0.25, 0.5])))
    b.add_beam("beam", beam_properties(), n)
    return ProgrammedMotion(b.build(), [JointProgramme("hub", Constant(0.0), name="held")])


def _closed_form_hz():
    """First bending frequency (Hz) of the clamped-free beam: Euler-Bernoulli,
    (beta_1 L)^2 / (2 pi) sqrt(E I / (rho A L^4)), beta_1 L = 1.8751 the first root of
    cos(beta L) cosh(beta L) = -1 (any vibration text), with the rotary inertia to first
    order: omega^2 = int E I phi''^2 / (int rho A phi^2 + int rho I phi'^2) on the
    Euler-Bernoulli mode phi (the shape's own change is second order, ~5e-10 here)."""
    bp = beam_properties()
    length = bp.length
    ei, rho_a = bp.youngs_modulus * bp.second_moment_z, bp.density * bp.area
    rho_i = bp.density * bp.second_moment_z
    beta = fq.CANTILEVER_ROOT / length
    s = (np.cosh(beta * length) + np.cos(beta * length)) / (np.sinh(beta * length)
                                                          + np.sin(beta * length))

    def phi(x):
        return np.cosh(beta * x) - np.cos(beta * x) - s * (np.sinh(beta * x) - np.sin(beta * x))

    def dphi(x):
        return beta * (np.sinh(beta * x) + np.sin(beta * x) - s * (np.cosh(beta * x)
                                                                   - np.cos(beta * x)))
    ratio = quad(lambda x: dphi(x) ** 2, 0, length)[0] / quad(lambda x: phi(x) ** 2, 0, length)[0]
    f_eb = fq.CANTILEVER_ROOT ** 2 / (2 * np.pi) * np.sqrt(ei / (rho_a * length ** 4))
    return f_eb / np.sqrt(1.0 + rho_i / rho_a * ratio), rho_i / rho_a * ratio


def _richardson(coarse, fine):
    """Order-2 extrapolation from a mesh and its halving."""
    return fine + (fine - coarse) / 3.0


def test_rfem_cantilever_converges_to_the_closed_form_at_order_2():
    """RFEM alone: the first bending frequency of the held cantilever at n = 10, 20, 40
    against the closed form.  Measured: errors 2.3e-3, 5.7e-4, 1.4e-4; observed orders
    2.002 (10 to 20) and 2.0005 (20 to 40); Richardson from (20, 40) within 7e-8."""
    f_closed, rotary = _closed_form_hz()
    f = {}
    for n in (10, 20, 40):
        system = _cantilever(n)
        modes = fq.rfem_frequencies(system, 0.0, np.zeros(system.model.n_coordinates), 2)
        assert modes.zero_modes == 0                # the hub is held: nothing is free
        f[n] = modes.frequencies_hz[FIRST]
        # both bending planes have E I = 1.4e4 N m^2: the first two are one double frequency
        assert modes.frequencies_hz[1] == pytest.approx(f[n], rel=1e-12)
    errors = {n: (v - f_closed) / f_closed for n, v in f.items()}
    order = np.log(errors[10] / errors[20]) / np.log(2.0)
    # order 2 with an n^-4 remainder: it moves the observed order by ~ 3 (c4/c2) / n^2,
    # measured 0.009 at (5, 10) and 0.002 at (10, 20); 0.05 leaves 25x
    assert abs(order - 2.0) < 0.05, errors
    extrapolated = _richardson(f[20], f[40])
    remainder = abs(_richardson(f[10], f[20]) - extrapolated)      # ~ 15 x its own remainder
    # the extrapolation's n^-4 remainder at (20, 40), estimated as remainder / 15 = 7e-8 of
    # f; the rotary-inertia term (2.3e-5) is 20x above this gate, so the closed form without
    # it would fail; 1e-6 leaves 14x over the estimated remainder
    assert rotary > 20 * 1e-6
    assert abs(extrapolated - f_closed) / f_closed < 1e-6, (extrapolated, f_closed, remainder)


def test_continuum_cantilever_converges_to_the_closed_form():
    """The continuum alone (Exudyn's matrices, 16, 32, 64 elements): order 2 in the mesh
    (measured 2.00 and 2.02) and Richardson from (32, 64) at the closed form (measured
    -5.2e-7: the Euler-Bernoulli limit keeps 1e-6 of the shear and axial compliance)."""
    f_closed, _ = _closed_form_hz()
    system = _cantilever(3)
    q = np.zeros(system.model.n_coordinates)
    f = {ne: fq.continuum_frequencies(system.model, 0.0, q, system.constraint_specs, 2,
                                      ne).frequencies_hz[FIRST] for ne in (16, 32, 64)}
    errors = {ne: (v - f_closed) / f_closed for ne, v in f.items()}
    order = np.log(errors[32] / errors[64]) / np.log(2.0)
    # the residual compliance (5e-7 of f) is 1.7 % of e(64) = 2.9e-5: the observed order
    # moves by ~0.025; 0.1 leaves 4x
    assert abs(order - 2.0) < 0.1, errors
    # residual shear and axial compliance of the Euler-Bernoulli limit (1e-6 of the bending
    # compliance: up to ~1e-6 in omega^2, 5e-7 in f) plus the extrapolation's remainder
    # (|R(16, 32) - R(32, 64)| = 3.5e-7): 2e-6 leaves 2x over their sum
    assert abs(_richardson(f[32], f[64]) - f_closed) / f_closed < 2e-6, errors


def test_shifted_solution_equals_exudyns_own_eigenvalues():
    """The continuum's eigen-solution (null space by pivoted QR, shifted and inverted
    generalized problem) against mbs.ComputeODE2Eigenvalues on the same Exudyn system (SVD
    null space, plain eigh on the unshifted problem): the same first four frequencies.
    The physical rod (no stiffening), 16 elements: Exudyn's plain eigh errs by about
    eps x omega_max^2 (the element's axial mode, (2 / l_e)^2 E A / (rho A) = 2.4e8 (rad/s)^2),
    i.e. 2e-9 of the first frequency; measured 7e-9 (with the Euler-Bernoulli limit's 35x
    stiffer rod 6e-7: that is Exudyn's round-off, its double frequency splits by as much)."""
    system = _cantilever(3)
    q = np.zeros(system.model.n_coordinates)
    mine = fq.continuum_frequencies(system.model, 0.0, q, system.constraint_specs, 4, 16,
                                    euler_bernoulli=False)
    model = fq.unloaded_model(system.model)
    built = build_system(model, continuum_layout(model), q, q, system.constraint_specs, 16,
                         np.zeros(3), False)
    built.mbs.Assemble()
    hz, _ = built.mbs.ComputeODE2Eigenvalues(convert2Frequencies=True)
    theirs = np.sort(hz)[:4]
    # 1e-7: 50x the round-off estimate above, 13x the measured difference
    np.testing.assert_allclose(mine.frequencies_hz, theirs, rtol=1e-7)


@pytest.fixture(scope="module")
def crane_reference():
    """The paper's crane at t = 0 (arm at 0.93 rad, slider 0.125 m): its stress-free
    configuration and the continuum's first three frequencies refined to 64 elements."""
    scenario = crane_scenario(3, on_constraints=True)
    (cfg,) = fq.configurations_along_run(scenario, [0.0])
    q = fq.state_of(cfg, scenario.system)
    ref = fq.continuum_reference(scenario.model, cfg.t, q, scenario.constraints, 3,
                                 max_elements=64)
    return scenario, cfg, ref


def test_rfem_converges_to_the_continuum_at_order_2_on_the_crane(crane_reference):
    """The crane's first bending frequency (27.3 Hz, out of the arm's plane, the second
    non-zero mode after the support's 2.4 Hz): RFEM at n = 5, 10, 20 against the
    continuum extrapolated from 32 and 64 elements.  Measured errors 6.3e-3, 1.6e-3,
    4.0e-4; orders 2.004 and 1.998."""
    scenario, cfg, ref = crane_reference
    (_, f32, _), (_, f64, _) = ref.history[-2], ref.history[-1]
    assert ref.elements == 64
    mode = 1                                    # after the support mode (index 0)
    f_ref = _richardson(f32[mode], f64[mode])
    errors = {}
    for n in (5, 10, 20):
        system = crane_scenario(n, on_constraints=True).system
        modes = fq.rfem_frequencies(system, cfg.t, fq.state_of(cfg, system), 3)
        assert modes.labels[mode].startswith("theta_arm")
        errors[n] = (modes.frequencies_hz[mode] - f_ref) / f_ref
    orders = [np.log(errors[a] / errors[b]) / np.log(b / a) for a, b in ((5, 10), (10, 20))]
    # 2 +- 0.1: the n^-4 remainder moves the observed order by ~0.01 at (5, 10) (0.009 on
    # the cantilever, above), the reference's error after extrapolation (~1e-6 of f, as on
    # the cantilever) is 0.25 % of e(20), 0.004 in the order: 10x margin
    assert all(abs(p - 2.0) < 0.1 for p in orders), (orders, errors)
    assert errors[20] > 0                       # RFEM is stiffer than the continuum


@pytest.mark.parametrize("fault", [1.0, 1.1])
def test_frequency_gate_passes_rfem_and_catches_a_stiffness_fault(fault, crane_reference,
                                                                 monkeypatch):
    """The frequency gate (RFEM at n = 3 against the continuum, tolerance RFEM's own error
    predicted from n and 2 n plus 3 x the continuum's last mesh change) on the crane's
    first three frequencies: passes; with the RFEM sde bending springs 10 % too stiff (a
    fault in gpme_core.rfem, so at n and 2 n) the bending frequencies fail."""
    import gpme_core.rfem as rfem
    scenario, cfg, ref = crane_reference
    if fault != 1.0:
        original = rfem.BeamProperties.sde_coefficients

        def faulty(self, n):
            (s_psi, s_theta, s_phi), damp = original(self, n)
            return (s_psi * fault, s_theta * fault, s_phi), damp
        monkeypatch.setattr(rfem.BeamProperties, "sde_coefficients", faulty)
    modes = {}
    for n in (3, 6):
        system = crane_scenario(n, on_constraints=True).system
        modes[n] = fq.rfem_frequencies(system, cfg.t, fq.state_of(cfg, system), 3)
    checks = fq.frequency_checks(modes[3], modes[6], ref)
    assert len(checks) == 3
    if fault == 1.0:
        assert all(c.passed for c in checks), checks
    else:
        # the bending modes (2 and 3) are sqrt(1.1) - 1 = 4.9 % higher: measured 1.8x and
        # 2.8x their tolerances (0.49 of them without the fault); the support's 2.4 Hz mode
        # carries hardly any arm bending and passes either way
        assert not checks[1].passed and not checks[2].passed, checks


def test_bad_input_is_refused_with_the_value():
    system = _cantilever(2)
    n = system.model.n_coordinates
    with pytest.raises(ModelError, match="count must be a whole number >= 1.*got 0"):
        fq.rfem_frequencies(system, 0.0, np.zeros(n), 0)
    with pytest.raises(ModelError, match="t must be a finite time.*nan"):
        fq.rfem_frequencies(system, float("nan"), np.zeros(n), 2)
    with pytest.raises(ModelError, match="q must be 7 finite values"):
        fq.rfem_frequencies(system, 0.0, np.zeros(n + 1), 2)
    bent = np.zeros(n)
    bent[system.model.index("psi_beam_1")] = 0.01
    with pytest.raises(ModelError, match="not stress-free.*psi_beam_1 = 0.01"):
        fq.rfem_frequencies(system, 0.0, bent, 2)
    held = np.zeros(n)
    held[system.model.index("hub")] = 0.1
    with pytest.raises(ModelError, match="not on the constraints"):
        fq.rfem_frequencies(system, 0.0, held, 2)
