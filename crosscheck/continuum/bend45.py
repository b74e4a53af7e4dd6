"""The Bathe-Bolourchi 45-degree bend: a spatial static benchmark with bending in two planes
and torsion, RFEM (gpme) and the continuum (Exudyn) against the published tip positions.

Problem (Bathe & Bolourchi 1979; Simo & Vu-Quoc 1986, Example 7.5; sources, ambiguities and
quotations in docs/flexible-beam-benchmark-sources.md, section 2): a cantilever whose
centreline is a 45-degree arc of radius R = 100 in a horizontal plane, square section
1 x 1, E = 1e7, nu = 0 (G = E/2), loaded at the free end by a dead force P = 300, 450, 600
normal to the arc's plane.  The numbers are run as they stand in the consistent set
R = 100 m, A = 1 m^2, E = 1e7 Pa, P in N (the problem depends only on P R^2/EI and the
stiffness ratios), so positions are in m.

Frame (the one of the published tables): origin at the clamped root, x along the root
tangent, the arc bending towards +y, centre of curvature (0, R, 0), z = x cross y normal
to the arc's plane; the force is P e_z.  Undeformed tip (R sin 45, R (1 - cos 45), 0) =
(70.711, 29.289, 0).  A tip position is (tangent coordinate x, radial coordinate y,
out-of-plane z).

Torsion constant (the ambiguity of the sources): BeamDyn and Kynema use G J = G (I_y + I_z)
= 8.333e5 N m^2 (:data:`TORSION_POLAR`); Saint-Venant's J of a unit square is 0.1406
(G J = 7.03e5, :data:`TORSION_SAINT_VENANT`, Roark's formula as in
gpme_core.rfem.BeamSection.rectangle).  Every function takes the torsion constant.

RFEM side (:func:`gpme_tip`): gpme's links are straight, so the arc is a polygon of
``chords`` straight flexible links inscribed in it (vertices on the arc, chord k along the
angle (k + 1/2) dtheta, dtheta = 45 deg / chords), each discretised into ``segments`` RFEM
segments (ChainBuilder.add_beam), joined rigidly at the kinks (consecutive beams on one
link), on a root revolute joint held at 0.  The dead tip force is gravity on a point mass
at the tip: g = (0, 0, 1) m/s^2 and m = P / g, whose generalized force -d(m g . r_tip)/dq
= J_tip^T P e_z is the dead force's exactly.  The beam's own weight is removed exactly
rather than made small: gpme's model validation needs a mass matrix with
cond(M) < 1e12, which a beam light enough for its weight not to matter (1e-5 of P and
below) fails from 64 segments on (the tip mass dwarfs the segments' rotary inertia), so
the beam carries a physical density (BEAM_DENSITY: its mass of the order of the tip
mass) and the residual is
gravity_forces(beam + tip mass) - gravity_forces(beam alone) + spring_forces, the tip
force alone to round-off (:func:`tip_force_residual`), solved by static_equilibrium's Newton
iteration (gpme_core.statics.newton_equilibrium, central-difference Jacobian) on this
residual, with load steps (:func:`solve_load_path`).

Continuum side (:func:`exudyn_tip`): Exudyn's ObjectBeamGeometricallyExact on nodes on the
arc, each node frame the arc's tangent frame; the element is stress-free in the
reference configuration of its nodes (checked: the unloaded bend does not move, and the
small-load tip deflection converges to the closed form of :func:`linear_tip_deflection`),
section data from crosscheck.continuum.section (k = 5/6 for the square at nu = 0, as the
r-test's k G A = 4.16667e6); ``euler_bernoulli`` raises E A and k G A to RFEM's limit.
"""
from dataclasses import dataclass
from typing import Dict, Mapping, Optional, Sequence, Tuple

import numpy as np
from numpy.typing import NDArray

from gpme_core import transforms as tf
from gpme_core.dynamics import gravity_forces, spring_forces
from gpme_core.errors import ConstraintError, ModelError
from gpme_core.inertia import RigidBodyInertia
from gpme_core.kinematics import link_transforms
from gpme_core.model import ChainBuilder, Model, REVOLUTE
from gpme_core.rfem import BeamProperties, BeamSection
from gpme_core.statics import newton_equilibrium

from .section import continuum_section

try:                                    # the continuum side needs Exudyn (extra "test")
    import exudyn as exu
    from exudyn.itemInterface import (LoadForceVector, MarkerNodeRigid, NodePointGround,
                                      NodeRigidBodyEP, ObjectBeamGeometricallyExact,
                                      ObjectJointGeneric)
    from exudyn.rigidBodyUtilities import RotationMatrix2EulerParameters
except ImportError:                     # pragma: no cover - exercised without Exudyn only
    exu = None

# ----------------------------------------------------------------------------- problem data
RADIUS = 100.0                          # m, R of the centreline
ARC_ANGLE = np.pi / 4.0                 # rad, the bend's opening angle
ARC_LENGTH = RADIUS * ARC_ANGLE         # m
YOUNGS_MODULUS = 1.0e7                  # Pa
SHEAR_MODULUS = 0.5 * YOUNGS_MODULUS    # Pa, nu = 0
SIDE = 1.0                              # m, the square section's side
SECTION = BeamSection.rectangle(SIDE, SIDE)      # A = 1 m^2, I_y = I_z = 1/12 m^4
TORSION_POLAR = SECTION.second_moment_y + SECTION.second_moment_z   # m^4, G J = 8.333e5
TORSION_SAINT_VENANT = SECTION.torsion_constant  # m^4, Roark: 0.1406, G J = 7.03e5
LOADS = (300.0, 450.0, 600.0)           # N, the published load levels
# Simo & Vu-Quoc's load steps to 600 N (300, +150, +150): the Newton start of each level
LOAD_STEPS = (300.0, 150.0, 150.0)
COMPONENTS = ("x", "y", "z")            # tangent, radial, out-of-plane coordinate
TIP_UNDEFORMED = np.array([RADIUS * np.sin(ARC_ANGLE), RADIUS * (1.0 - np.cos(ARC_ANGLE)), 0.0])
TIP_UNDEFORMED.setflags(write=False)

# gravity that turns the tip mass into the dead force P e_z (m/s^2); P = m |g|
LOAD_GRAVITY = (0.0, 0.0, 1.0)
# kg/m^3, the RFEM beam's density: its mass (785 kg) of the order of the tip mass at the
# largest load (600 kg), so that the model's mass matrix passes gpme's validation at every
# load; the beam's weight itself is cancelled (module docstring)
BEAM_DENSITY = 10.0
# Newton on the RFEM residual: goal relative to P R (N m), far above round-off (eps x the
# stiffest sde spring E I / dl x its angle, ~1e-10 of P R at 256 segments) and far below
# what moves the tip (residual x dl / E I ~ 1e-16 m)
RESIDUAL_FRACTION = 1e-10
JACOBIAN_STEP = 1e-7                    # rad, central differences of the residual
MAX_NEWTON = 25
MAX_HALVINGS = 6                        # of a load step whose Newton iteration diverges


# ----------------------------------------------------------------------- published values
@dataclass(frozen=True)
class PublishedTip:
    """A tip position as published (positions in the frame of the module docstring, m).

    source     : who computed it and how (citation in docs/flexible-beam-benchmark-sources.md)
    load       : P, N
    position   : (3,) m, tangent, radial, out-of-plane coordinate
    half_unit  : m, half a unit in the last digit given (the rounding the number carries)
    torsion    : "polar" or "unknown", the G J the source used
    computed   : True for a converged computation quoted to many digits (Kynema)
    """

    source: str
    load: float
    position: Tuple[float, float, float]
    half_unit: float
    torsion: str = "unknown"
    computed: bool = False


def _from_displacement(u_tangent, u_radial, u_out) -> Tuple[float, float, float]:
    """Position (m) from a displacement (tangent, radial towards the root line, out-of-plane)
    quoted by sources that tabulate displacements (radial: their in-plane one, signed so
    that a negative value moves the tip towards y = 0)."""
    return (float(TIP_UNDEFORMED[0] + u_tangent), float(TIP_UNDEFORMED[1] + u_radial),
            float(u_out))


PUBLISHED = (
    PublishedTip("Bathe & Bolourchi 1979", 300.0, (59.2, 22.5, 39.5), 0.05),
    PublishedTip("Simo & Vu-Quoc 1986, 8 linear elements", 300.0, (58.84, 22.33, 40.08), 0.005),
    PublishedTip("Simo & Vu-Quoc 1986, 8 linear elements", 450.0, (52.32, 18.62, 48.39), 0.005),
    PublishedTip("Bathe & Bolourchi 1979", 600.0, (47.2, 15.9, 53.4), 0.05),
    PublishedTip("Simo & Vu-Quoc 1986, 8 linear elements", 600.0, (47.23, 15.79, 53.37), 0.005),
    PublishedTip("Crisfield 1990 (displacement)", 600.0, _from_displacement(-23.5, -13.6, 53.4),
                 0.05),
)
# BeamDyn (Wang et al. 2015) and Kynema: the same three key points, fitted by a polynomial
# (the r-test / Kynema input), not necessarily the arc; quoted, compared as information
BEAMDYN_2015 = PublishedTip("BeamDyn, Wang et al. 2015 (displacement)", 600.0,
                            _from_displacement(-23.7, -13.5, 53.4), 0.05, "polar")
# Kynema regression test (tip displacement in its frame: arc towards -y, force +z; its
# y displacement is our radial one with the sign flipped), asserted to 1e-12 there
KYNEMA = PublishedTip("Kynema LSFE, 15 nodes (converged)", 600.0,
                      _from_displacement(-23.6459716009047, -13.7208006040058,
                                         53.5776450626987), 5e-13, "polar", computed=True)


# --------------------------------------------------------------------------- closed form
def linear_tip_deflection(load: float, torsion_constant: float,
                          shear_coefficient: Optional[float] = None) -> float:
    """Out-of-plane tip deflection, m, of the bend under a small tip force ``load`` N
    (linear theory of a circular cantilever loaded normal to its plane; Castigliano):

        w = P R^3 [(a/2 - sin 2a / 4) / E I + (3a/2 - 2 sin a + sin 2a / 4) / G J]
            + P R a / (k G A)

    a = 45 deg; the bending moment at angle phi from the tip is P R sin phi, the torque
    P R (1 - cos phi).  ``shear_coefficient`` None: no shear term (RFEM's rod).
    """
    a = ARC_ANGLE
    ei = YOUNGS_MODULUS * SECTION.second_moment_y
    gj = SHEAR_MODULUS * torsion_constant
    w = load * RADIUS ** 3 * ((a / 2.0 - np.sin(2.0 * a) / 4.0) / ei
                              + (1.5 * a - 2.0 * np.sin(a) + np.sin(2.0 * a) / 4.0) / gj)
    if shear_coefficient is not None:
        w += load * RADIUS * a / (shear_coefficient * SHEAR_MODULUS * SECTION.area)
    return float(w)


# ------------------------------------------------------------------------------ RFEM side
def chord_beam(chords: int, torsion_constant: float, density: float) -> BeamProperties:
    """The straight flexible link of one chord: length 2 R sin(dtheta / 2) m, the square
    section with J = ``torsion_constant`` m^4, ``density`` kg/m^3."""
    half = 0.5 * ARC_ANGLE / chords
    return BeamProperties(2.0 * RADIUS * np.sin(half), YOUNGS_MODULUS, SHEAR_MODULUS, density,
                          SECTION.area, SECTION.second_moment_y, SECTION.second_moment_z,
                          float(torsion_constant), extreme_fibre_y=SECTION.extreme_fibre_y,
                          extreme_fibre_z=SECTION.extreme_fibre_z)


def gpme_bend_model(segments: int, chords: int, load: float,
                    torsion_constant: float = TORSION_POLAR, tip_mass: bool = True,
                    density: float = BEAM_DENSITY) -> Model:
    """gpme model of the bend (module docstring): ``chords`` straight flexible links of
    ``segments`` RFEM segments each, inscribed in the arc, on a root revolute joint about z
    (coordinate "root", to be held at 0); with ``tip_mass`` a point mass m = load / |g|
    (kg) at the tip frame "tip" (plus a rotary inertia m x 1 m^2 about each axis, which no
    static load sees, for a well-conditioned mass matrix); gravity LOAD_GRAVITY; beam
    ``density`` kg/m^3 (its weight is cancelled by :func:`tip_force_residual`, which needs
    the same density with and without the tip mass)."""
    bad = []
    for label, v in (("segments", segments), ("chords", chords)):
        if not isinstance(v, (int, np.integer)) or isinstance(v, bool) or v < 1:
            bad.append(f"bend45: {label} must be an integer >= 1, got {v!r}")
    if not (np.isfinite(load) and load > 0):
        bad.append(f"bend45: load must be positive and finite (N), got {load!r}")
    if bad:
        raise ModelError(bad)
    mass = float(load) / float(np.linalg.norm(LOAD_GRAVITY))
    beam = chord_beam(int(chords), torsion_constant, density)
    dtheta = ARC_ANGLE / chords
    builder = ChainBuilder("bend45", gravity=LOAD_GRAVITY)
    builder.add_joint("root", REVOLUTE, (0.0, 0.0, 1.0))
    for k in range(int(chords)):
        # chord 0 turned by dtheta/2 from the root tangent, each next one by dtheta more
        builder.add_beam(f"chord{k}", beam, int(segments),
                         frame=tf.rot_z(0.5 * dtheta if k == 0 else dtheta))
    if tip_mass:
        builder.add_body(RigidBodyInertia(mass, (0.0, 0.0, 0.0), mass * np.eye(3)))
    builder.add_frame("tip")
    return builder.build()


def tip_position(model: Model, q: NDArray[np.float64]) -> NDArray[np.float64]:
    """(3,) m, the tip frame's origin in the world (= the module's) frame at q."""
    frame = model.frame("tip")
    return (link_transforms(model, q)[frame.link_index] @ frame.transform)[:3, 3]


def tip_force_residual(loaded: Model, unloaded: Model, free: NDArray[np.int64],
                       q: NDArray[np.float64]) -> NDArray[np.float64]:
    """(len(free),) N m: g_F + f_F of the bend with the beam's weight removed, i.e.
    d(-P e_z . r_tip)/dq + K q on the coordinates ``free``: gravity_forces of the model with
    the tip mass minus that of the same model without it (same beam, same density), plus
    the sde springs (gpme_core.dynamics)."""
    return (gravity_forces(loaded, q) - gravity_forces(unloaded, q)
            + spring_forces(loaded, q))[free]


def _newton(loaded, unloaded, free, q, tol):
    """q at equilibrium from the start q, or None when Newton's iteration does not reach
    ``tol`` (N m) within MAX_NEWTON steps (gpme_core.statics.newton_equilibrium, the loop
    of static_equilibrium, on :func:`tip_force_residual`)."""
    return newton_equilibrium(lambda x: tip_force_residual(loaded, unloaded, free, x), q, free,
                              tol, MAX_NEWTON, JACOBIAN_STEP)


def solve_load_path(segments: int, chords: int, loads: Sequence[float] = LOADS,
                    torsion_constant: float = TORSION_POLAR,
                    torsion_scale: float = 1.0) -> Dict[float, NDArray[np.float64]]:
    """{load N: (3,) m tip position} of the RFEM bend, loads in increasing order, each
    solved from the previous equilibrium (the first from the straight chords); a step
    whose Newton iteration fails is halved (up to MAX_HALVINGS times).

    torsion_scale multiplies every sde torsion spring (phi) after the build: a planted
    fault for tests (1 = the model as built)."""
    loads = sorted(float(p) for p in loads)
    unloaded = gpme_bend_model(segments, chords, loads[-1], torsion_constant, tip_mass=False)
    free = np.array([unloaded.index(c) for c in unloaded.flexible_coordinates], dtype=int)
    if torsion_scale != 1.0:
        phis = [c for c in unloaded.flexible_coordinates if c.startswith("phi_")]
        changes = {c: {"stiffness": unloaded.joints[unloaded.index(c)].stiffness * torsion_scale}
                   for c in phis}
        unloaded = unloaded.with_changes(joint_changes=changes)
    q = np.zeros(unloaded.n_coordinates)
    out, reached = {}, 0.0
    for target in loads:
        step = target - reached
        halvings = 0
        while reached < target:
            p = min(reached + step, target)
            loaded = gpme_bend_model(segments, chords, p, torsion_constant, tip_mass=True)
            if torsion_scale != 1.0:
                loaded = loaded.with_changes(joint_changes=changes)
            q_new = _newton(loaded, unloaded, free, q, RESIDUAL_FRACTION * p * RADIUS)
            if q_new is None:
                halvings += 1
                if halvings > MAX_HALVINGS:
                    raise ConstraintError(
                        f"bend45 RFEM ({segments} segments x {chords} chords): no equilibrium "
                        f"at P = {p:g} N from P = {reached:g} N after {MAX_HALVINGS} halvings "
                        "of the load step")
                step *= 0.5
                continue
            q, reached = q_new, p
        out[target] = tip_position(loaded, q)
    return out


def gpme_tip(segments: int, chords: int, loads: Sequence[float] = LOADS,
             torsion_constant: float = TORSION_POLAR) -> Dict[float, NDArray[np.float64]]:
    """{load N: (3,) m RFEM tip position} (:func:`solve_load_path`)."""
    return solve_load_path(segments, chords, loads, torsion_constant)


# ------------------------------------------------------------------------- continuum side
def continuum_beam(torsion_constant: float) -> BeamProperties:
    """The whole arc as a gpme BeamProperties (length R x 45 deg), for its continuum
    section data (crosscheck.continuum.section: E A, k G A with k = 5/6, G J, E I)."""
    return BeamProperties(ARC_LENGTH, YOUNGS_MODULUS, SHEAR_MODULUS, 1.0, SECTION.area,
                          SECTION.second_moment_y, SECTION.second_moment_z,
                          float(torsion_constant), extreme_fibre_y=SECTION.extreme_fibre_y,
                          extreme_fibre_z=SECTION.extreme_fibre_z)


def _require_exudyn():
    if exu is None:
        raise ModelError("bend45: the continuum side needs Exudyn (pip install exudyn, or the "
                         "'test' extra of gpme)")


def exudyn_tip(elements: int, loads: Sequence[float] = LOADS,
               torsion_constant: float = TORSION_POLAR, euler_bernoulli: bool = False,
               load_steps: int = 10) -> Dict[float, NDArray[np.float64]]:
    """{load N: (3,) m tip position} of the bend as ``elements`` geometrically exact beam
    elements in Exudyn (module docstring), each load solved from the unloaded bend by
    Exudyn's static solver in ``load_steps`` equal steps; ``euler_bernoulli``: E A and
    k G A raised to RFEM's limit (crosscheck.continuum.section)."""
    _require_exudyn()
    from .system import exudyn_section          # needs Exudyn
    if not isinstance(elements, (int, np.integer)) or elements < 1:
        raise ModelError(f"bend45: elements must be an integer >= 1, got {elements!r}")
    cs = continuum_section(continuum_beam(torsion_constant), euler_bernoulli)
    out = {}
    for load in loads:
        sc = exu.SystemContainer()
        mbs = sc.AddSystem()
        section = exudyn_section(cs, damping=False)
        nodes = []
        for i in range(elements + 1):
            phi = ARC_ANGLE * i / elements
            r_0_node = tf.rot_z(phi)[:3, :3]            # tangent frame on the arc
            position = [RADIUS * np.sin(phi), RADIUS * (1.0 - np.cos(phi)), 0.0]
            ep = np.asarray(RotationMatrix2EulerParameters(r_0_node), dtype=float)
            nodes.append(mbs.AddNode(NodeRigidBodyEP(referenceCoordinates=[*position, *ep])))
        for a, b in zip(nodes[:-1], nodes[1:]):
            mbs.AddObject(ObjectBeamGeometricallyExact(nodeNumbers=[a, b],
                                                       length=ARC_LENGTH / elements,
                                                       sectionData=section))
        ground = mbs.AddMarker(MarkerNodeRigid(nodeNumber=mbs.AddNode(NodePointGround())))
        mbs.AddObject(ObjectJointGeneric(markerNumbers=[ground, mbs.AddMarker(
            MarkerNodeRigid(nodeNumber=nodes[0]))], constrainedAxes=[1] * 6))
        mbs.AddLoad(LoadForceVector(markerNumber=mbs.AddMarker(MarkerNodeRigid(
            nodeNumber=nodes[-1])), loadVector=[0.0, 0.0, float(load)]))
        mbs.Assemble()
        settings = exu.SimulationSettings()
        settings.solution.file.write = False
        settings.staticSolver.verboseMode = 0
        settings.staticSolver.numberOfLoadSteps = int(load_steps)
        settings.linearSolver.solverType = exu.LinearSolverType.EigenSparse
        # residual goal N: ROUND_OFF_MARGIN x eps x the stiffest element spring x R (as
        # crosscheck.continuum.runs.newton_absolute_tolerance); Newton converges
        # quadratically, so the last step lands far below it
        stiffest = max(cs.stiffness[:3]) * elements / ARC_LENGTH
        settings.staticSolver.newton.absoluteTolerance = (100.0 * float(np.finfo(float).eps)
                                                          * stiffest * RADIUS)
        settings.staticSolver.newton.relativeTolerance = 1e-12
        exu.SolveStatic(mbs, settings)
        out[float(load)] = np.asarray(mbs.GetNodeOutput(nodes[-1],
                                                        exu.OutputVariableType.Position),
                                      dtype=float)
    return out


# ------------------------------------------------------------------- convergence helpers
def observed_order(coarse: NDArray[np.float64], fine: NDArray[np.float64],
                   finer: NDArray[np.float64], ratio: float = 2.0) -> NDArray[np.float64]:
    """Observed order per component, log(|coarse - fine| / |fine - finer|) / log(ratio),
    from three solutions on meshes refined by ``ratio`` each time (nan where a difference
    is zero)."""
    d1 = np.abs(np.asarray(coarse) - np.asarray(fine))
    d2 = np.abs(np.asarray(fine) - np.asarray(finer))
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.log(d1 / d2) / np.log(ratio)


def extrapolate_order_one_two(f_h, f_h2, f_h4) -> NDArray[np.float64]:
    """Limit of f = f* + a h + b h^2 from f at h, h/2, h/4: (8 f(h/4) - 6 f(h/2) + f(h))/3
    (RFEM on the bend: an order-1 term from the sde springs on Cardan angles at large
    rotation, order-2 terms from the segments and the polygon; docs/rfem-continuum.md)."""
    return (8.0 * np.asarray(f_h4) - 6.0 * np.asarray(f_h2) + np.asarray(f_h)) / 3.0


def extrapolate(f_h, f_h2, order: float) -> NDArray[np.float64]:
    """Richardson's limit of f = f* + a h^order from f at h and h/2."""
    return np.asarray(f_h2) + (np.asarray(f_h2) - np.asarray(f_h)) / (2.0 ** order - 1.0)


@dataclass(frozen=True)
class RfemLimit:
    """RFEM's limit from one chord per segment (segments = 1), chords N, 2N, 4N.

    tips      : {chords: {load: (3,) m}}
    limit     : {load: (3,) m}, :func:`extrapolate_order_one_two` of the three
    error     : {load: (3,) m}, |limit - (order-1 Richardson of the two finest)|: the
                size of the order-2 term at the finest mesh, which bounds the limit's
                remaining error while the sequence is asymptotic (checked in the table of
                docs/rfem-continuum.md: the three-level limit of 16/32/64 chords differs
                from the continuum by <= 2e-4 m, against an error estimate of 1.3e-2 m)
    """

    tips: Mapping[int, Mapping[float, NDArray[np.float64]]]
    limit: Mapping[float, NDArray[np.float64]]
    error: Mapping[float, NDArray[np.float64]]


def rfem_limit(chords: Sequence[int] = (16, 32, 64), loads: Sequence[float] = LOADS,
               torsion_constant: float = TORSION_POLAR, torsion_scale: float = 1.0) -> RfemLimit:
    """:class:`RfemLimit` from RFEM with one segment per chord at the three ``chords``
    counts (each twice the previous)."""
    n1, n2, n3 = (int(c) for c in chords)
    if n2 != 2 * n1 or n3 != 2 * n2:
        raise ModelError(f"bend45: chords must double, e.g. (16, 32, 64), got {tuple(chords)}")
    tips = {n: solve_load_path(1, n, loads, torsion_constant, torsion_scale) for n in (n1, n2, n3)}
    limit, error = {}, {}
    for p in tips[n1]:
        limit[p] = extrapolate_order_one_two(tips[n1][p], tips[n2][p], tips[n3][p])
        error[p] = np.abs(limit[p] - extrapolate(tips[n2][p], tips[n3][p], 1.0))
    return RfemLimit(tips, limit, error)


@dataclass(frozen=True)
class ContinuumReference:
    """Exudyn's bend refined until converged.

    tips        : {elements: {load: (3,) m}}, meshes doubled from the first
    limit       : {load: (3,) m}, order-2 Richardson of the two finest meshes
    mesh_change : {load: (3,) m}, |finest - second finest|
    error       : {load: (3,) m}, |limit - finest|, the finest mesh's estimated error (the
                  limit's own is of higher order)
    """

    tips: Mapping[int, Mapping[float, NDArray[np.float64]]]
    limit: Mapping[float, NDArray[np.float64]]
    mesh_change: Mapping[float, NDArray[np.float64]]
    error: Mapping[float, NDArray[np.float64]]


# m: the continuum is refined until every tip component changes by less than this between
# two meshes: a tenth of the finest published rounding (0.005 m, Simo & Vu-Quoc); its
# Richardson limit is then good to a few 1e-5 m (order 2 observed), below RFEM's
MESH_GOAL = 5e-4


def continuum_reference(loads: Sequence[float] = LOADS, torsion_constant: float = TORSION_POLAR,
                        euler_bernoulli: bool = False, first: int = 8,
                        max_elements: int = 256, goal: float = MESH_GOAL) -> ContinuumReference:
    """:class:`ContinuumReference`: Exudyn's bend with ``first`` elements doubled until the
    tip changes by less than ``goal`` m (every load and component) or ``max_elements``."""
    tips, elements = {}, int(first)
    while True:
        tips[elements] = exudyn_tip(elements, loads, torsion_constant, euler_bernoulli)
        if len(tips) >= 2:
            prev = tips[elements // 2]
            change = max(float(np.abs(tips[elements][p] - prev[p]).max()) for p in prev)
            if change < goal or 2 * elements > max_elements:
                break
        elements *= 2
    fine, coarse = tips[elements], tips[elements // 2]
    limit = {p: extrapolate(coarse[p], fine[p], 2.0) for p in fine}
    return ContinuumReference(tips, limit, {p: np.abs(fine[p] - coarse[p]) for p in fine},
                              {p: np.abs(limit[p] - fine[p]) for p in fine})


# The continuum's limits (m): Exudyn 1.13.6, order-2 Richardson of 128 and 256 elements
# (observed order 2.00 from 16 elements on; the 256-element mesh changes by <= 4.1e-4 m,
# the limit lies <= 1.4e-4 m from it), as benchmarks/bend45.py measures them.  The RFEM
# tests compare with these (they run without Exudyn); tests/test_bend45.py recomputes
# them when Exudyn is installed.
CONTINUUM_EULER_BERNOULLI = {
    300.0: (58.77968, 22.24503, 40.18832),
    450.0: (52.23929, 18.50846, 48.49803),
    600.0: (47.15128, 15.68507, 53.46866),
}
CONTINUUM_PHYSICAL = {
    300.0: (58.77890, 22.24468, 40.19239),
    450.0: (52.23826, 18.50806, 48.50349),
    600.0: (47.15010, 15.68469, 53.47548),
}


# ------------------------------------------------------------ against the published values
@dataclass(frozen=True)
class PublishedBand:
    """What the published tip positions at one load support (m, per component).

    lower, upper : (3,) the range of the published values, each widened by its rounding
                   (half a unit in its last digit)
    width        : (3,) the allowed distance outside [lower, upper]: the published
                   solutions' disagreement upper - lower, the only evidence there is of their
                   own discretisation errors (none states one); at a load with a single
                   source, interpolated linearly in P between the loads that have two
    sources      : the PublishedTip entries used
    """

    lower: NDArray[np.float64]
    upper: NDArray[np.float64]
    width: NDArray[np.float64]
    sources: tuple


def _range(entries):
    lo = np.min([np.asarray(e.position) - e.half_unit for e in entries], axis=0)
    hi = np.max([np.asarray(e.position) + e.half_unit for e in entries], axis=0)
    return lo, hi


def published_band(load: float, published: Sequence[PublishedTip] = PUBLISHED) -> PublishedBand:
    """:class:`PublishedBand` at ``load`` N (one of LOADS)."""
    at = [e for e in published if e.load == float(load)]
    if not at:
        raise ModelError(f"bend45: no published value at P = {load!r} N; have "
                         f"{sorted({e.load for e in published})}")
    lo, hi = _range(at)
    if len({e.source for e in at}) > 1:
        return PublishedBand(lo, hi, hi - lo, tuple(at))
    multi = sorted(p for p in {e.load for e in published}
                   if len({e.source for e in published if e.load == p}) > 1)
    below = max(p for p in multi if p < load)
    above = min(p for p in multi if p > load)
    w_b = np.subtract(*reversed(_range([e for e in published if e.load == below])))
    w_a = np.subtract(*reversed(_range([e for e in published if e.load == above])))
    s = (float(load) - below) / (above - below)
    return PublishedBand(lo, hi, (1.0 - s) * w_b + s * w_a, tuple(at))


def outside_band(position: NDArray[np.float64], band: PublishedBand) -> NDArray[np.float64]:
    """(3,) m, how far each component of ``position`` lies outside [lower, upper] (0 inside)."""
    p = np.asarray(position, dtype=float)
    return np.maximum(band.lower - p, 0.0) + np.maximum(p - band.upper, 0.0)
