"""The continuum reference (crosscheck.continuum): its section, layout and whole runs.

Each check compares with something derived independently: closed-form beam statics,
mass conservation, gpme's rigid runs (the continuum's rigid machinery must converge to
them as the step falls), the closed-form centrifugal stretch of a spinning rod.
"""
import dataclasses
import numpy as np
import pytest

exu = pytest.importorskip("exudyn")

from exudyn.itemInterface import (LoadForceVector, LoadTorqueVector, MarkerNodeRigid,  # noqa: E402
                                  NodePointGround, NodeRigidBodyEP,
                                  ObjectBeamGeometricallyExact, ObjectJointGeneric)

from crosscheck.continuum.layout import continuum_layout  # noqa: E402
from crosscheck.continuum.runs import continuum_run  # noqa: E402
from crosscheck.continuum.section import continuum_section, shear_coefficient  # noqa: E402
from crosscheck.continuum.system import exudyn_section  # noqa: E402
from crosscheck.continuum.study import max_difference, rfem_history  # noqa: E402
from gpme_core.rfem import BeamProperties, BeamSection  # noqa: E402
from gpme_examples.crane import crane_system, initial_state  # noqa: E402
from gpme_examples.spin_up import (AREA, DENSITY, LENGTH, SPIN_RATE,  # noqa: E402
                                   YOUNGS_MODULUS, spin_up_system)


def _rectangle_beam(length=1.0):
    section = BeamSection.rectangle(0.02, 0.01)            # 20 mm (y) x 10 mm (z)
    return BeamProperties.from_section(length, section, 7e10, 2.6e10, 2700.0)


def _cantilever_tip(beam, elements, load, torque=False):
    """Static tip displacement and rotation of a clamped geometrically exact cantilever
    along x with this section, a small tip load (N or N m, world axes)."""
    cs = continuum_section(beam)
    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    section = exudyn_section(cs, damping=False)
    nodes = [mbs.AddNode(NodeRigidBodyEP(referenceCoordinates=[beam.length * i / elements, 0, 0,
                                                                 1, 0, 0, 0]))
             for i in range(elements + 1)]
    for i in range(elements):
        mbs.AddObject(ObjectBeamGeometricallyExact(nodeNumbers=[nodes[i], nodes[i + 1]],
                                                   length=beam.length / elements,
                                                   sectionData=section))
    ground = mbs.AddMarker(MarkerNodeRigid(nodeNumber=mbs.AddNode(NodePointGround())))
    mbs.AddObject(ObjectJointGeneric(markerNumbers=[ground, mbs.AddMarker(
        MarkerNodeRigid(nodeNumber=nodes[0]))], constrainedAxes=[1] * 6))
    tip = mbs.AddMarker(MarkerNodeRigid(nodeNumber=nodes[-1]))
    mbs.AddLoad((LoadTorqueVector if torque else LoadForceVector)(markerNumber=tip,
                                                                  loadVector=list(load)))
    mbs.Assemble()
    s = exu.SimulationSettings()
    s.solution.file.write = False
    s.staticSolver.verboseMode = 0
    # residual goal (N): above the round-off floor eps x E A N / L x L ~ 5e-8 N of the
    # stiffest (axial) element spring; it moves the tip by < 1e-7 / (3 E I / L^3) ~ 3e-10 m
    s.staticSolver.newton.absoluteTolerance = 1e-7
    exu.SolveStatic(mbs, s)
    u = np.asarray(mbs.GetNodeOutput(nodes[-1], exu.OutputVariableType.Displacement))
    r = np.asarray(mbs.GetNodeOutput(nodes[-1], exu.OutputVariableType.Rotation))
    return u, r


@pytest.mark.parametrize("case", ["force_z", "force_y", "axial", "torsion"])
def test_section_strain_order_against_beam_statics(case):
    """The continuum section's entries act in the directions the docstring says: the
    cantilever's tip displacement under each load, Richardson-extrapolated from 8 and 16
    elements (the element's error falls as 1/N^2), equals Timoshenko statics:
    P L^3/(3 E I) + P L/(k G A) bending, P L/(E A) axial, T L/(G J) torsion."""
    beam = _rectangle_beam()
    e, g, a, length = beam.youngs_modulus, beam.shear_modulus, beam.area, beam.length
    k, _ = shear_coefficient(beam)
    p = 1e-2              # N or N m: tip rotation ~1e-4 rad, linear closed forms to ~1e-8
    load, component, torque, expected = {
        "force_z": ((0, 0, p), 2, False,
                    p * length ** 3 / (3 * e * beam.second_moment_y) + p * length / (k * g * a)),
        "force_y": ((0, p, 0), 1, False,
                    p * length ** 3 / (3 * e * beam.second_moment_z) + p * length / (k * g * a)),
        "axial": ((p, 0, 0), 0, False, p * length / (e * a)),
        "torsion": ((p, 0, 0), 0, True, p * length / (g * beam.torsion_constant)),
    }[case]
    values = []
    for n in (8, 16):
        u, r = _cantilever_tip(beam, n, load, torque)
        values.append((r if torque else u)[component])
    extrapolated = values[1] + (values[1] - values[0]) / 3.0
    # 1e-6: the linear closed forms neglect terms of order the rotation (~1e-4 rad here)
    # squared, the extrapolation leaves O(1/N^4) ~ 1e-7 and Newton's goal ~1e-8 of it
    assert extrapolated == pytest.approx(expected, rel=1e-6)


def test_shear_coefficients_of_cowper():
    """Cowper's solid circle 6(1+nu)/(7+6nu) and thin tube limit 2(1+nu)/(4+3nu)."""
    e, g = 2e11, 2e11 / 2.6                                  # nu = 0.3
    solid = BeamProperties.solid_circular(1.0, 0.02, e, g, 7800.0)
    assert shear_coefficient(solid)[0] == pytest.approx(6 * 1.3 / (7 + 1.8), rel=1e-12)
    thin = BeamProperties.from_section(1.0, BeamSection.tube(0.1, 1e-5), e, g, 7800.0)
    assert shear_coefficient(thin)[0] == pytest.approx(2 * 1.3 / (4 + 0.9), rel=1e-3)


@pytest.mark.parametrize("n", [1, 3, 5])
def test_layout_keeps_the_mass_and_does_not_depend_on_n(n):
    """Rigid residuals + the beam's rho A L = the model's mass, and the rigid parts are the
    same whatever the RFEM segment count (the continuum model of one machine)."""
    model = crane_system(n).model
    layout = continuum_layout(model)
    (beam,) = layout.beams
    total = sum(b.mass for b in layout.bodies.values()) + \
        beam.beam.density * beam.beam.area * beam.beam.length
    assert total == pytest.approx(model.total_mass, rel=1e-12)
    other = continuum_layout(crane_system(2).model)
    by_name = {b.name: b for b in other.bodies.values()}
    for part in layout.bodies.values():
        twin = by_name[part.name] if part.name in by_name else None
        if twin is None:          # the tip link's name carries the segment number
            continue
        assert part.mass == pytest.approx(twin.mass, abs=1e-12)
        np.testing.assert_allclose(part.inertia, twin.inertia, atol=1e-12)


def test_rigid_programmed_crane_converges_to_gpme():
    """The continuum model's rigid machinery (bodies, generic joints, the support spring,
    the drive, gravity, the ellipse and height programmes through a constrained point):
    its difference to gpme's run falls with the step as generalized-alpha's order 2."""
    system = crane_system(0)
    q0, v0 = initial_state(system.model)
    q0, v0 = system.consistent_state(0.0, q0, v0)
    t_end, out = 0.2, 0.01
    gp = rfem_history(system, q0, v0, t_end, out, dt=2.5e-5)
    errors = []
    for dt in (4e-4, 2e-4):
        c = continuum_run(system.model, q0, v0, t_end, dt, out, system.constraint_specs)
        c["t"] = np.round(c["t"] / out) * out
        errors.append({col: max_difference(c, gp, col) for col in
                       ("z1", "psi2", "psi3", "z4", "lambda_Phi_1", "lambda_Phi_2")})
    # psi2 barely moves in 0.2 s (the drive's quintic ramp): its 1e-10 rad difference is
    # the reference's own error (gpme's RK4 and the output), not a step-dependent one
    assert errors[1]["psi2"] < 1e-9
    for col in ("z1", "psi3", "z4", "lambda_Phi_1", "lambda_Phi_2"):
        # order 2 gives a ratio of 4; >= 2.5 leaves room for the pre-asymptotic start
        assert errors[0][col] / errors[1][col] >= 2.5, (col, errors)
    assert errors[1]["psi3"] < 1e-4 and errors[1]["z4"] < 1e-4


def test_spin_up_stretch_is_the_centrifugal_closed_form():
    """After a short spin-up to Omega the continuum tip has stretched by the centrifugal
    load, u(L) = rho A Omega^2 L^3 / (3 E A) (a rod clamped on the axis), which RFEM's
    rigid segments cannot show: what its deflection along the beam converges to differs by
    exactly this."""
    system, q0, v0 = spin_up_system(1)               # Omega_s = 6 rad/s reached at 15 s
    c = continuum_run(system.model, q0, v0, 20.0, 0.01, 0.1, system.constraint_specs,
                      elements=8)
    late = c[c["t"] >= 16.0]
    stretch = DENSITY * AREA * SPIN_RATE ** 2 * LENGTH ** 3 / (3 * YOUNGS_MODULUS * AREA)
    # 3 %: the residual bending oscillation (~3e-3 m) shortens the tip's projection by
    # ~v^2 / L ~ 1e-6 m (0.2 %); 8 linear elements carry the quadratic axial force to
    # well within 1 % at the tip (mesh change to 16 elements measured below 0.1 %)
    assert late["defl_x_beam"].mean() == pytest.approx(stretch, rel=0.03)
    rfem = rfem_history(system, q0, v0, 20.0, 0.1)
    assert abs(rfem["defl_x_beam"][rfem["t"] >= 16.0].mean()) < 0.05 * stretch


def _springy_chain():
    """A rigid three-joint chain: revolute about z, revolute about y with a spring (offset
    reference) and damper, prismatic along a rotated x with a spring; a drive."""
    from gpme_core import transforms as tf
    from gpme_core.gpme import ProgrammedMotion
    from gpme_core.inertia import RigidBodyInertia
    from gpme_core.joint_kinds import PRISMATIC, REVOLUTE
    from gpme_core.model import ChainBuilder
    b = ChainBuilder("springy")
    b.add_joint("a", REVOLUTE, (0, 0, 1), link="l1")
    b.add_body(RigidBodyInertia(2.0, (0.3, 0.05, 0.0), np.diag([0.01, 0.02, 0.03])))
    b.add_joint("b", REVOLUTE, (0, 1, 0), origin=tf.translation(0.5, 0, 0), stiffness=30.0,
                spring_reference=-1.0, damping=0.5, link="l2")
    b.add_body(RigidBodyInertia(1.0, (0.2, 0.0, 0.02), np.diag([0.01, 0.02, 0.01])))
    b.add_joint("c", PRISMATIC, (1, 0, 0), origin=tf.translation(0.4, 0, 0) @ tf.rot_x(0.3),
                stiffness=50.0, spring_reference=0.05, damping=0.2, link="l3")
    b.add_body(RigidBodyInertia(0.5, (0.0, 0.0, 0.0), np.diag([0.001, 0.001, 0.001])))
    b.add_drive("a", lambda t: 0.5 * np.sin(3 * t))
    return ProgrammedMotion(b.build(), [])


def test_springs_dampers_and_drives_converge_to_gpme():
    """Revolute and prismatic joint springs with references away from the start, dampers,
    a drive and gravity, started moving: the continuum's rigid machinery converges to
    gpme's run at generalized-alpha's order 2 (measured ratio 4.0)."""
    system = _springy_chain()
    q0, v0 = np.array([0.3, -1.2, 0.1]), np.array([0.5, 0.2, -0.1])
    gp = rfem_history(system, q0, v0, 0.5, 0.01, dt=1e-4)
    errors = []
    for dt in (2e-4, 1e-4):
        c = continuum_run(system.model, q0, v0, 0.5, dt, 0.01)
        c["t"] = np.round(c["t"] / 0.01) * 0.01
        errors.append({k: max_difference(c, gp, k) for k in "abc"})
    for k in "abc":
        assert errors[0][k] / errors[1][k] >= 3.0, errors
        assert errors[1][k] < 1e-6


def _hanging_beam(viscosity):
    """The spin-up beam held still (hub angle programmed to 0) under gravity across it:
    released straight, it vibrates about its sag (first mode 0.6 Hz)."""
    import dataclasses
    from gpme_core.constraints import JointProgramme
    from gpme_core.gpme import ProgrammedMotion
    from gpme_core.inertia import RigidBodyInertia
    from gpme_core.joint_kinds import REVOLUTE
    from gpme_core.model import ChainBuilder
    from gpme_core.time_functions import Constant
    from gpme_examples.spin_up import beam_properties
    b = ChainBuilder("hanging_beam", gravity=(0.0, -1.0, 0.0))
    b.add_joint("theta", REVOLUTE, (0, 0, 1), link="hub")
    b.add_body(RigidBodyInertia(1.0, (0.0, 0.0, 0.0), np.diag([0.25, 0.25, 0.5])))
    b.add_beam("beam", dataclasses.replace(beam_properties(), bending_viscosity=viscosity), 8)
    return ProgrammedMotion(b.build(), [JointProgramme("theta", Constant(0.0), name="hub")])


def test_beam_material_damping_matches_rfem():
    """Exudyn's beam ignores its section damping matrix; the element dampers put the
    Kelvin-Voigt damping back.  A beam vibrating about its sag, with and without bending
    viscosity (0.8 % of critical in its first mode): what the damping changes in the
    continuum's tip deflection is as large as what it changes in RFEM's (n = 8), to 10 %
    (the two models' own offset cancels in the difference; without the element dampers
    the continuum's change is 0)."""
    effect = {}
    for side in ("continuum", "rfem"):
        runs = {}
        for viscosity in (0.0, 3e8):
            system = _hanging_beam(viscosity)
            n = system.model.n_coordinates
            if side == "continuum":
                df = continuum_run(system.model, np.zeros(n), np.zeros(n), 6.0, 0.01, 0.1,
                                   system.constraint_specs, elements=8)
                df["t"] = np.round(df["t"] / 0.1) * 0.1
            else:
                df = rfem_history(system, np.zeros(n), np.zeros(n), 6.0, 0.1)
            runs[viscosity] = df.set_index("t")["defl_y_beam"]
        effect[side] = (runs[3e8] - runs[0.0]).to_numpy()
    change = np.abs(effect["rfem"]).max()
    assert change > 1e-3                       # the damping does something measurable
    # the size of the effect, not its phase: both oscillate at the first mode, whose
    # frequency differs between the models by their own discretisations (~0.1 %)
    assert abs(np.abs(effect["continuum"]).max() - change) < 0.1 * change, effect


@pytest.mark.parametrize("fault", [1.0, 1.1])
def test_model_validity_gate_passes_the_crane_and_catches_a_stiffness_fault(fault, monkeypatch):
    """The model-validity gate on the paper's flexible crane (n = 3) over 0.2 s: every
    gated row passes; with the RFEM sde bending springs 10 % too stiff (a fault in
    gpme_core.rfem's discretisation, so in both n and 2 n) a gated row fails."""
    import gpme_core.rfem as rfem
    from crosscheck.continuum.validity import check_scenario
    from gpme_io.scenario import crane_scenario
    if fault != 1.0:
        original = rfem.BeamProperties.sde_coefficients

        def faulty(self, n):
            (s_psi, s_theta, s_phi), damp = original(self, n)
            return (s_psi * fault, s_theta * fault, s_phi), damp
        monkeypatch.setattr(rfem.BeamProperties, "sde_coefficients", faulty)
    validity = check_scenario(crane_scenario(3, on_constraints=True), quick=True,
                              log=lambda m: None, horizon=0.2)
    gated = [r for r in validity.rows if r["status"] != "info"]
    assert len(gated) == 3
    failed = [r["quantity"] for r in gated if r["status"] == "fail"]
    assert (failed == []) if fault == 1.0 else failed, [(r["quantity"], r["abs_error"],
                                                          r["tol_abs"]) for r in gated]


def test_a_model_file_tolerance_replaces_the_validity_gate_with_its_reason():
    """[[tolerance]] check = "continuum/<gated row>" replaces that row's physics gate by the
    file's abs/rel and reason (the issue's 'or a tolerance the model file states with a
    reason'); the crane with its sde bending springs 10 % too stiff fails the tip-deflection
    gate (the test above) but passes a stated 1 m, and the row says whose tolerance it is
    and what the physics gate would have been.  A check naming an information row or no
    row is a ModelError before any run."""
    import gpme_core.rfem as rfem
    from crosscheck.continuum.validity import check_scenario
    from gpme_core.errors import ModelError
    from gpme_io.scenario import ToleranceOverride, crane_scenario
    base = crane_scenario(3, on_constraints=True)
    for bad in ("continuum/multipliers vs continuum", "continuum/tip bending"):
        scenario = dataclasses.replace(base, tolerances={bad: ToleranceOverride(bad, 1.0, 0.0,
                                                                                "x")})
        with pytest.raises(ModelError, match="names no gated model-validity row"):
            check_scenario(scenario, quick=True, log=lambda m: None, horizon=0.2)
    check = "continuum/tip deflection vs continuum"
    original = rfem.BeamProperties.sde_coefficients

    def faulty(self, n):
        (s_psi, s_theta, s_phi), damp = original(self, n)
        return (s_psi * 1.1, s_theta * 1.1, s_phi), damp
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(rfem.BeamProperties, "sde_coefficients", faulty)   # before the build
        scenario = dataclasses.replace(crane_scenario(3, on_constraints=True), tolerances={
            check: ToleranceOverride(check, 1.0, 0.0, "stated for the test: 1 m")})
        validity = check_scenario(scenario, quick=True, log=lambda m: None, horizon=0.2)
    row = next(r for r in validity.rows if r["quantity"] == "tip deflection vs continuum")
    assert row["status"] == "pass" and row["tol_abs"] == 1.0
    assert row["reason"].startswith("model file: stated for the test: 1 m (instead of "
                                        "the physics gate"), row["reason"]
    gate = float(row["reason"].split("physics gate ")[1].split(":")[0])
    assert row["abs_error"] > gate          # the fault fails the physics gate it replaced
