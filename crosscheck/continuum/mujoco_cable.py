"""MuJoCo's elastic cable as a second continuum model of a single flexible beam.

**Which MuJoCo element.**  The task named the ``cable`` composite with the
``mujoco.elasticity.cable`` plugin.  MuJoCo 4.0.0 (the version installed here) removed both
(changelog 4.0.0, "Deformables", item 9, commit 1d6cc8ff5) in favour of the 1D
``flexcomp`` with ``<elasticity young shear>``, its documented successor: a discrete elastic
rod (Bergou et al. 2008) with bending and torsion and no stretching, edges kept at their
length by ``<edge equality="true"/>``, the root clamped by ``<pin id="0 1"/>`` (the first
edge and its material frame fixed to the parent body), one point mass per free vertex and
one twist hinge per free edge.  This module builds that rod; "the cable" below means it.

**Stiffness mapping** (XMLreference, flex/elasticity, "1D flexes"; checked on MuJoCo's side
alone by ``tests/test_mujoco_cable.py`` against F L^3/(3 E I) and T L/(G J)): every
interior vertex between edges of lengths l0, l1 stores k |kappa b|^2 with
k = E I/(l0 + l1), and k_t (d theta)^2 with k_t = G J/(l0 + l1); the section is a circle of
the flex radius r, I = pi r^4/4, J = pi r^4/2.  A beam with I_y = I_z = I is mapped by
r = (4 I/pi)^(1/4), young = E and shear = G J/(pi r^4/2), so that young x I = E I and
shear x J_circle = G J exactly; the radius is used for nothing else (contacts are off, the
twist inertia is overwritten below).  A section with I_y != I_z would need the ``box``
section, whose J is MuJoCo's own approximation: not mapped (:class:`CableModelError`).

**The clamp.**  The clamped first edge lies inside the hub, from x = -c l to the root x = 0
(c = ``clamp_fraction``).  Its length enters the root vertex's stiffness E I/(c l + l): with
c = 1 (the migration guide's uniform grid) the root vertex weighs a whole element, the clamp
sits in effect at x = -l/2 and a cantilever's tip deflection errs by +3/(2 N) (first order;
measured 1.406, 1.195, 1.096, 1.047 x F L^3/(3 E I) at N = 4, 8, 16, 32).  With c -> 0 the
root vertex weighs l/2, its share of the beam, and the rod converges at second order.
Default c = 1e-6: its effect, a relative 1e-6 on one vertex's stiffness, is below every
error measured here.

**Mass** (set on the spec after the flexcomp is expanded; the flexcomp's ``mass`` spreads
equally over all points, pinned ones included, which is first order at the tip): vertex
masses rho A l in the interior and rho A l/2 at the tip (the root vertex's half lies on the
hub); twist hinges rho (I_y + I_z) l per edge (the section's polar inertia).  The rotary
inertia of bending, rho I per length, has no place in a rod of point masses and is left out
(on the spin-up beam it moves the first bending frequency by 2.3e-5 relative).

**Inextensibility** is a soft equality (MuJoCo's constraint model): solref (tau_c, 1) and
solimp (d, d, ...); the residual stretch scales as (1 - d) tau_c^2 and, at a given tau_c,
as N^2 (the constraint's stiffness is an acceleration per metre, times a vertex mass ~ 1/N;
measured on the spin-up beam spinning at 6 rad/s, d = 0.9999: tip x 5.9e-4 m at 16
elements and tau_c = 0.01 s, 5.9e-6 m at 1e-3 s, 2.4e-5 m at 32 elements and 1e-3 s).
Default tau_c = 2 x the step (MuJoCo's advised least; RK4 resolves it: h/tau_c = 0.5) and
d = 0.9999 (MuJoCo's largest impedance); with the step ~ 1/N the stretch then stays ~6e-6 m,
1 % of the physical rod's centrifugal stretch, and vanishes as the step is halved; the
largest edge strain is reported per run.

**The hub programme.**  The rod's vertices are children of a hub body on a hinge about the
world z axis, so their coordinates are relative to the turning hub and MuJoCo's own
kinematics carries the Coriolis and centrifugal terms.  The programme theta(t) is imposed
exactly in the sense of a joint programme: at every Runge-Kutta stage the hub torque tau is
the one that gives the hub the programme's acceleration, found from the linearity of the
accelerations in tau (two solves, tau = 0 and tau = 1 N m: equality constraints only, so
MuJoCo's constrained accelerations are affine in the applied force); tau is then the
programme's multiplier (gpme's lambda).  The integration is classical RK4 written here over
``mj_forward`` (MuJoCo's continuous-time accelerations; every coordinate is a hinge or a
slide, so q and v integrate as plain vectors); the hub angle is then RK4's quadrature of
theta_ddot, and its residual against theta(t) is reported (measured 1.4e-10 rad at most
over the 20 s spin-up).
Alternatives measured or rejected: a mocap hub moves its children rigidly with no velocity
(no centrifugal or Coriolis forces on the rod); a position actuator or resetting qpos each
step gives the hub the wrong acceleration inside the step; MuJoCo's own RK4 cannot take a
stage-wise torque that depends on the constraint forces.  The DER reference frames in
``mjData.plastic`` are not advanced by ``mj_forward``; in the planar runs here they stay 0
(checked per run: a run whose plastic state changes raises).

Frames: world z up; the hub frame H turns about z; the undeformed beam lies along H's x
axis from x = 0 to x = L.  Columns of the runs use the names of
:mod:`crosscheck.continuum.runs` for a beam named ``beam`` (``defl_x_beam``, ...).
"""
from __future__ import annotations

import time
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from typing import Callable, Optional, Tuple

import mujoco
import numpy as np
import pandas as pd

from gpme_core.rfem import BeamProperties

ENGINE = "mujoco-cable"
ROD = "rod"                      # the flexcomp's name: bodies rod_<k>, joints rod_twist_<k>
HUB = "hub"
BEAM = "beam"                    # the beam's name in the output columns
FIRST_FREE_POINT = 2             # points 0, 1 are pinned (the clamped edge)
CLAMP_FRACTION = 1e-6
EDGE_TIMECONST_STEPS = 2.0       # the edges' solref time constant in steps (MuJoCo's least)
EDGE_IMPEDANCE = 0.9999          # MuJoCo's largest (mjMAXIMP)
# the cantilever is relaxed until max |qvel| < STATIC_SETTLE x omega_1 x (closed-form tip
# deflection or twist): the motion left is then ~this fraction of the answer (a decaying
# mode of rate omega_1 and speed v has amplitude v/omega_1); the round-off floor of
# max |qvel| was measured at 3e-12 m/s on the spin-up beam, 1e-9 of its answer x omega_1
STATIC_SETTLE = 1e-8


class CableModelError(ValueError):
    """A beam that the cable cannot represent; the message lists every problem."""


@dataclass(frozen=True)
class CableSection:
    """The cable's section parameters for one beam: radius m, young Pa, shear Pa."""

    radius: float
    young: float
    shear: float


def cable_section(beam: BeamProperties) -> CableSection:
    """Map E I and G J of ``beam`` onto MuJoCo's circular rod section (module docstring).
    Raises CableModelError for a beam the circle cannot represent."""
    problems = []
    iy, iz = float(beam.second_moment_y), float(beam.second_moment_z)
    if not abs(iy - iz) <= 1e-12 * max(iy, iz):
        problems.append(f"I_y = {iy!r} m^4 and I_z = {iz!r} m^4 differ: the cable's circle "
                        "section has one bending stiffness (the box section's J is MuJoCo's "
                        "approximation and is not mapped)")
    for name, value in (("E", beam.youngs_modulus), ("G", beam.shear_modulus), ("I", iy),
                        ("J", beam.torsion_constant), ("rho", beam.density),
                        ("A", beam.area), ("L", beam.length)):
        if not float(value) > 0.0:
            problems.append(f"{name} = {value!r} must be positive")
    if beam.bending_viscosity:
        problems.append("material damping is not mapped (the cable's Rayleigh damping is "
                        "not Kelvin-Voigt): bending_viscosity must be 0")
    if problems:
        raise CableModelError("beam not representable by MuJoCo's cable: " + "; ".join(problems))
    radius = (4.0 * iy / np.pi) ** 0.25
    j_circle = np.pi * radius ** 4 / 2.0
    return CableSection(radius, float(beam.youngs_modulus),
                        float(beam.shear_modulus) * float(beam.torsion_constant) / j_circle)


@dataclass(frozen=True)
class Cable:
    """A compiled cable: model (mujoco.MjModel), the beam, elements N, and the ids used
    to read it: hub_dof (-1 without a hub joint), the free vertex bodies (root to tip, the
    last is the tip point x = L), the twist joints' dofs (edge 1 to N)."""

    model: mujoco.MjModel
    beam: BeamProperties
    elements: int
    hub_dof: int
    vertex_bodies: Tuple[int, ...]
    twist_dofs: Tuple[int, ...]
    edge_length: float

    @property
    def tip_body(self) -> int:
        return self.vertex_bodies[-1]


def cable_model(beam: BeamProperties, elements: int, *, hub_joint: bool = True,
                hub_mass: float = 1.0, hub_inertia=(0.25, 0.25, 0.5),
                timestep: float = 1e-4, integrator: str = "RK4",
                rayleigh_damping: float = 0.0, clamp_fraction: float = CLAMP_FRACTION,
                edge_timeconst: Optional[float] = None,
                edge_impedance: float = EDGE_IMPEDANCE) -> Cable:
    """The beam as a cable of ``elements`` edges clamped at a hub (module docstring).

    hub_joint: a hinge about world z through the root (else the hub is welded to the
    world); hub_mass kg and hub_inertia (3,) kg m^2, principal, in the hub frame;
    timestep s; integrator a MuJoCo integrator name; rayleigh_damping s (flex elasticity
    damping, for static relaxation; 0 in dynamic runs); edge_timeconst s, the edge
    equality's solref time constant (None: EDGE_TIMECONST_STEPS x timestep).

    XML text, generated by ElementTree, because ``flexcomp`` is a macro of MuJoCo's XML
    parser (MjSpec has only the raw flex, whose twist bodies and joints would have to be
    written by hand); the expanded model is then edited through MjSpec (masses, twist
    inertias) before compiling."""
    if int(elements) < 2:
        raise CableModelError(f"elements = {elements!r}: the cable needs at least 2 (MuJoCo "
                              "creates its twist joints from 2 edges on)")
    n = int(elements)
    if edge_timeconst is None:
        edge_timeconst = EDGE_TIMECONST_STEPS * float(timestep)
    section = cable_section(beam)
    length = float(beam.length)
    le = length / n
    rho_a = float(beam.density) * float(beam.area)
    rho_ip = float(beam.density) * (float(beam.second_moment_y) + float(beam.second_moment_z))

    root = ET.Element("mujoco", model=f"cable_{n}")
    ET.SubElement(root, "option", timestep=repr(float(timestep)), integrator=integrator,
                  gravity="0 0 0")
    world = ET.SubElement(root, "worldbody")
    hub = ET.SubElement(world, "body", name=HUB)
    if hub_joint:
        ET.SubElement(hub, "joint", name=HUB, type="hinge", axis="0 0 1")
    ET.SubElement(hub, "inertial", pos="0 0 0", mass=repr(float(hub_mass)),
                  diaginertia=" ".join(repr(float(v)) for v in hub_inertia))
    xs = [-clamp_fraction * le] + [k * le for k in range(n + 1)]
    points = " ".join(f"{x!r} 0 0" for x in xs)
    edges = " ".join(f"{k} {k + 1}" for k in range(n + 1))
    flex = ET.SubElement(hub, "flexcomp", name=ROD, type="direct", dim="1", point=points,
                         element=edges, mass="1", radius=repr(section.radius))
    ET.SubElement(flex, "contact", contype="0", conaffinity="0")
    ET.SubElement(flex, "edge", equality="true",
                  solref=f"{float(edge_timeconst)!r} 1",
                  solimp=f"{float(edge_impedance)!r} {float(edge_impedance)!r} 0.001")
    ET.SubElement(flex, "elasticity", young=repr(section.young), shear=repr(section.shear),
                  damping=repr(float(rayleigh_damping)))
    ET.SubElement(flex, "pin", id="0 1")
    spec = mujoco.MjSpec.from_string(ET.tostring(root, encoding="unicode"))
    for k in range(FIRST_FREE_POINT, n + 2):
        spec.body(f"{ROD}_{k}").mass = rho_a * le * (0.5 if k == n + 1 else 1.0)
    twist_names = [f"{ROD}_twist_{k}" for k in range(1, n)] + [f"{ROD}_twist"]
    for name in twist_names:
        body = spec.body(name)
        body.inertia = [rho_ip * le] * 3
    model = spec.compile()
    bid = lambda name: mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name)
    jdof = lambda name: int(model.jnt_dofadr[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT,
                                                               name)])
    if model.nq != model.nv:
        raise CableModelError(f"expected only hinges and slides (nq == nv), got nq = {model.nq}, "
                              f"nv = {model.nv}")
    return Cable(model, beam, n, jdof(HUB) if hub_joint else -1,
                 tuple(bid(f"{ROD}_{k}") for k in range(FIRST_FREE_POINT, n + 2)),
                 tuple(jdof(name) for name in twist_names), le)


def tip_columns(cable: Cable, data: mujoco.MjData) -> dict:
    """Tip quantities in the hub frame H after mj_kinematics: defl_x|y|z_beam m (tip point
    minus (L, 0, 0)), rot_z_beam rad (the last edge's direction about H's z),
    rot_x_beam rad (the last edge's twist angle), edge_strain (largest |l/l0 - 1|)."""
    hub = mujoco.mj_name2id(cable.model, mujoco.mjtObj.mjOBJ_BODY, HUB)
    r_h = data.xmat[hub].reshape(3, 3)
    p = np.array([r_h.T @ (data.xpos[b] - data.xpos[hub]) for b in cable.vertex_bodies])
    last = p[-1] - p[-2]
    chain = np.vstack([np.zeros(3), p])
    strain = np.abs(np.linalg.norm(np.diff(chain, axis=0), axis=1) / cable.edge_length - 1.0)
    return {f"defl_x_{BEAM}": float(p[-1, 0] - cable.beam.length),
            f"defl_y_{BEAM}": float(p[-1, 1]), f"defl_z_{BEAM}": float(p[-1, 2]),
            f"rot_z_{BEAM}": float(np.arctan2(last[1], last[0])),
            f"rot_x_{BEAM}": float(data.qpos[cable.twist_dofs[-1]]),
            "edge_strain": float(strain.max())}


@dataclass(frozen=True)
class StaticResult:
    """A static cantilever: tip deflection m along the force (H's y), tip twist rad of the
    last edge (its material angle lives at the edge's midpoint x = L - l/2), the station m
    of that twist, and the relaxation's last max |qvel| (m/s or rad/s)."""

    deflection: float
    twist: float
    twist_station: float
    residual_speed: float


def static_cantilever(beam: BeamProperties, elements: int, tip_force: float = 0.0,
                      tip_torque: float = 0.0, timestep: float = 1e-3,
                      max_steps: int = 200000) -> StaticResult:
    """The clamped cable under a tip force (N, along H's y, on the tip point) and a tip
    torque (N m, about the beam axis, on the last edge's twist hinge), relaxed to rest by
    MuJoCo's ``discrete`` integrator (implicit in position) with Rayleigh damping set to
    2/omega_1 (the first bending mode near critical damping).  Rest: max |qvel| below
    STATIC_SETTLE x (1/s) x the closed-form deflection and twist scale."""
    ei = beam.youngs_modulus * beam.second_moment_z
    rho_a = beam.density * beam.area
    omega_1 = 1.875 ** 2 * np.sqrt(ei / (rho_a * beam.length ** 4))
    cable = cable_model(beam, elements, hub_joint=False, timestep=timestep,
                        integrator="discrete", rayleigh_damping=2.0 / omega_1)
    m = cable.model
    d = mujoco.MjData(m)
    d.xfrc_applied[cable.tip_body, 1] = float(tip_force)
    d.qfrc_applied[cable.twist_dofs[-1]] = float(tip_torque)
    scale = (abs(tip_force) * beam.length ** 3 / (3 * ei)
             + abs(tip_torque) * beam.length / (beam.shear_modulus * beam.torsion_constant))
    speed = np.inf
    for step in range(max_steps):
        mujoco.mj_step(m, d)
        speed = float(np.abs(d.qvel).max())
        if step > 10 and speed < STATIC_SETTLE * omega_1 * scale:
            break
    else:
        raise RuntimeError(f"cantilever not at rest after {max_steps} steps "
                           f"(max |qvel| {speed:.3g})")
    mujoco.mj_kinematics(m, d)
    cols = tip_columns(cable, d)
    return StaticResult(cols[f"defl_y_{BEAM}"], cols[f"rot_x_{BEAM}"],
                        beam.length - 0.5 * cable.edge_length, speed)


Programme = Callable[[float], Tuple[float, float, float]]


def programmed_run(cable: Cable, programme: Programme, t_end: float,
                   output_dt: float, constraint: str = "hub_angle") -> pd.DataFrame:
    """The cable with its hub angle programmed: programme(t) -> (theta rad, theta_dot
    rad/s, theta_ddot rad/s^2), from rest, straight.  RK4 with the model's timestep dt (s,
    the one its edge constraints were built for) to t_end (s), recorded every output_dt
    (s, whole numbers of steps).

    Returns columns t, the tip columns of :func:`tip_columns`, lambda_<constraint> N m
    (the hub torque of the programme, gpme's sign: the torque on the hub joint),
    hub_residual rad (hub angle minus theta(t)); attrs engine, dt, elements, wall_time_s,
    max_hub_residual, max_edge_strain."""
    if cable.hub_dof < 0:
        raise ValueError("programmed_run needs a cable built with hub_joint=True")
    if cable.model.opt.integrator != mujoco.mjtIntegrator.mjINT_RK4:
        raise ValueError("programmed_run needs a cable built with integrator='RK4': under "
                         "'discrete' mj_forward's qacc is a step map, not an acceleration")
    dt = float(cable.model.opt.timestep)
    steps, every = int(round(t_end / dt)), int(round(output_dt / dt))
    if steps < 1 or every < 1 or abs(steps * dt - t_end) > 1e-9 * max(t_end, 1.0) or \
            abs(every * dt - output_dt) > 1e-9 * max(output_dt, 1.0):
        raise ValueError(f"t_end = {t_end!r} s and output_dt = {output_dt!r} s must be whole "
                         f"numbers of steps dt = {dt!r} s")
    m = cable.model
    d = mujoco.MjData(m)
    h = cable.hub_dof
    plastic0 = np.array(d.plastic, copy=True)

    def accel(t, q, v):
        d.time, d.qpos[:], d.qvel[:] = t, q, v
        d.qfrc_applied[h] = 0.0
        mujoco.mj_forward(m, d)
        a0 = np.array(d.qacc, copy=True)
        d.qfrc_applied[h] = 1.0
        mujoco.mj_forwardSkip(m, d, mujoco.mjtStage.mjSTAGE_VEL, 0)
        a1 = np.array(d.qacc, copy=True)
        tau = (programme(t)[2] - a0[h]) / (a1[h] - a0[h])
        return a0 + tau * (a1 - a0), tau

    q = np.zeros(m.nq)
    v = np.zeros(m.nv)
    rows = []

    def record(t, tau):
        d.qpos[:] = q
        mujoco.mj_kinematics(m, d)
        row = {"t": t, **tip_columns(cable, d)}
        row[f"lambda_{constraint}"] = tau
        row["hub_residual"] = float(q[h] - programme(t)[0])
        rows.append(row)

    start = time.perf_counter()
    for k in range(steps):
        t = k * dt
        a1_, tau = accel(t, q, v)
        if k % every == 0:
            record(t, tau)
        a2_, _ = accel(t + dt / 2, q + dt / 2 * v, v + dt / 2 * a1_)
        v2 = v + dt / 2 * a1_
        a3_, _ = accel(t + dt / 2, q + dt / 2 * v2, v + dt / 2 * a2_)
        v3 = v + dt / 2 * a2_
        a4_, _ = accel(t + dt, q + dt * v3, v + dt * a3_)
        v4 = v + dt * a3_
        q = q + dt / 6 * (v + 2 * v2 + 2 * v3 + v4)
        v = v + dt / 6 * (a1_ + 2 * a2_ + 2 * a3_ + a4_)
        if not np.all(np.isfinite(v)):
            raise RuntimeError(f"cable run diverged at t = {t:g} s (dt = {dt:g} s, "
                               f"{cable.elements} elements): the step is above RK4's limit")
    _, tau = accel(steps * dt, q, v)
    record(steps * dt, tau)
    if np.abs(np.asarray(d.plastic) - plastic0).max(initial=0.0) > 0.0:
        raise RuntimeError("the rod's DER reference frames (mjData.plastic) changed: this "
                           "RK4 loop does not advance them and holds only for planar runs")
    df = pd.DataFrame(rows)
    df["t"] = np.round(df["t"] / output_dt) * output_dt
    df.attrs.update(engine=ENGINE, dt=dt, elements=cable.elements,
                    wall_time_s=time.perf_counter() - start,
                    max_hub_residual=float(df["hub_residual"].abs().max()),
                    max_edge_strain=float(df["edge_strain"].max()))
    return df
