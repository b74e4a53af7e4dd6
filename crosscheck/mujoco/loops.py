"""Loops closed by MuJoCo's own equality constraints: a second, soft realisation of the
constraints between two frames (gpme_core.pair_constraints), as the auxiliary mechanism is
for the crane's programme.

A scenario whose constraints are all loop closures MuJoCo can write itself gets them as
``<connect site1 site2>`` (the frames' origins coincide: gpme's ``coincident`` rows, all
three axes, or fewer when the missing axes' rows are structurally zero, as a planar loop
closed in the plane is) and ``<weld site1 site2>`` (gpme's ``weld``: coincident and
aligned).  MuJoCo then integrates its own constrained dynamics (its soft constraints with
solref = (timeconst, 1), solimp impedance 0.9999, RK4 at dt), which converge to the exact
motion as the time constant falls: crosscheck.mujoco.check.soft_rows gates the differences
to gpme by that law, as for the mechanism.

Anything else (a programme, a point constraint, a distance, an expression, a rotation
alone) has no MuJoCo equality here: :func:`native_loops` says which in words.
"""
from dataclasses import dataclass
import xml.etree.ElementTree as ET

import mujoco
import numpy as np

from gpme_core.gpme import ProgrammedMotion
from gpme_core.pair_constraints import AxisAlignment, RelativeCoordinate
from gpme_core.time_functions import Constant

from .mjcf import _f, _vec, mjcf_element
from .sim import simulate_mujoco

# MuJoCo's largest solimp impedance: the fraction of the reference acceleration imposed
IMPEDANCE = 0.9999
# a missing axis of a coincidence counts as structurally zero (a planar loop) when its row
# is at most this fraction of the present rows' size at every state tried (round-off)
ZERO_ROW = 1e-12
_AXES = "xyz"
# the rotation rows of gpme_core.pair_constraints.aligned: (axis of a, axis of b)
_ALIGNED = {(1, 2), (2, 0), (0, 1)}


@dataclass(frozen=True)
class Loop:
    """One MuJoCo equality: kind "connect" or "weld" between the sites of frames a and b,
    realising the gpme constraint rows ``rows`` (names)."""

    kind: str
    frame_a: str
    frame_b: str
    rows: tuple


def describe(loops) -> str:
    """'connect E-F, weld tool_a-tool_b' of the loops."""
    return ", ".join(f"{lp.kind} {lp.frame_a}-{lp.frame_b}" for lp in loops)


def _zero_level(spec) -> bool:
    return isinstance(spec.function, Constant) and spec.function.level == 0.0


def native_loops(scenario) -> tuple:
    """(loops, "") when every constraint of ``scenario`` is a loop MuJoCo's equalities
    express; ((), why) when some are not ('' when the scenario has no two-frame
    constraint at all)."""
    specs = scenario.constraints
    pairs = [s for s in specs if isinstance(s, (RelativeCoordinate, AxisAlignment))]
    if not any(hasattr(s, "frame_a") for s in specs):
        return (), ""
    others = [s for s in specs if s not in pairs or not _zero_level(s)]
    if others:
        return (), ("MuJoCo's equalities express loops closed at a constant pose "
                    "(coincident, weld); these constraints are not: "
                    + ", ".join(f"{s.name} ({type(s).__name__})" for s in others))
    groups = {}
    for s in pairs:
        groups.setdefault((s.frame_a, s.frame_b), []).append(s)
    loops = []
    for (a, b), rows in groups.items():
        axes = {s.axis for s in rows if isinstance(s, RelativeCoordinate)}
        turns = {(s.axis_a, s.axis_b) for s in rows if isinstance(s, AxisAlignment)}
        names = tuple(s.name for s in rows)
        if turns and (turns != _ALIGNED or axes != {0, 1, 2}):
            return (), (f"the rows {list(names)} between {a!r} and {b!r} are not a whole weld "
                        "(3 coincidence and 3 alignment rows), which MuJoCo's <weld> is")
        if turns:
            loops.append(Loop("weld", a, b, names))
            continue
        missing = sorted({0, 1, 2} - axes)
        if missing and not _rows_vanish(scenario, a, b, missing, sorted(axes)):
            return (), (f"the coincidence of {a!r} and {b!r} on axes "
                        f"{''.join(_AXES[i] for i in sorted(axes))} leaves out rows that are "
                        "not zero here; MuJoCo's <connect> would add them")
        loops.append(Loop("connect", a, b, names))
    return tuple(loops), ""


def _rows_vanish(scenario, a, b, missing, present) -> bool:
    """Whether the rows of the missing axes of a coincidence are structurally zero (value
    and Jacobian) at the start and at seeded states near it, relative to the present rows."""
    model = scenario.model
    probe = ProgrammedMotion(model, [RelativeCoordinate(a, b, i, 0.0, name=f"probe_{i}")
                                     for i in missing + present])
    rng = np.random.default_rng(20261126)
    q0 = np.asarray(scenario.q0, dtype=float)
    for q in [q0] + [q0 + rng.uniform(-0.3, 0.3, q0.size) for _ in range(4)]:
        phi, _, jac, _ = probe.constraints(0.0, q, np.zeros_like(q))
        k = len(missing)
        scale = max(float(np.abs(jac[k:]).max(initial=0.0)), 1e-300)
        if np.abs(jac[:k]).max() > ZERO_ROW * scale or np.abs(phi[:k]).max() > ZERO_ROW:
            return False
    return True


def loop_mjcf(model, dt: float, loops, timeconst: float) -> str:
    """The MJCF of ``model`` (crosscheck.mujoco.mjcf) with the loops as <connect>/<weld>
    equalities between the frames' sites, solref (timeconst, 1), solimp IMPEDANCE."""
    root = mjcf_element(model, dt)
    equality = root.find("equality")
    if equality is None:
        equality = ET.SubElement(root, "equality")
    impedance = _f(IMPEDANCE)
    for k, lp in enumerate(loops):
        ET.SubElement(equality, lp.kind, name=f"loop{k + 1}_{lp.frame_a}_{lp.frame_b}",
                      site1=lp.frame_a, site2=lp.frame_b, solref=_vec((timeconst, 1.0)),
                      solimp=" ".join((impedance, impedance, "0.001", "0.5", "2")))
    ET.indent(root, space="  ")
    return ET.tostring(root, encoding="unicode")


def loop_run(scenario, loops, dt: float, timeconst: float, t_end: float, q0, q_dot0,
             output_dt: float):
    """MuJoCo's own run of the scenario with its loops as equalities (RK4 at dt), from
    (q0, q_dot0) on the constraints: crosscheck.mujoco.sim.simulate_mujoco's table."""
    mj = mujoco.MjModel.from_xml_string(loop_mjcf(scenario.model, dt, loops, timeconst))
    return simulate_mujoco(mj, scenario.model, t_end, q0, q_dot0, output_dt)
