"""Flexible links: how a URDF link becomes an RFEM beam on reading (its plan).

:class:`FlexibleLink` is what a caller gives; :func:`_beam_plan` checks it against the
chain's geometry and returns the beam's properties, its segment count and the beam frame
in the link frame.  The rule (axis towards the next chain joint, the section frame) is
:class:`FlexibleLink`'s docstring.
"""
from dataclasses import dataclass
from typing import Optional, Union

import numpy as np
from numpy.typing import NDArray

from gpme_core import transforms as tf
from gpme_core.rfem import MAX_SEGMENTS, BeamProperties, BeamSection

from .attributes import _UNIT_TOL

# Below this norm (of a unit vector's component) the default section y axis is taken as
# parallel to the beam and the link z axis is used instead.
_PARALLEL_TOL = 1e-6


@dataclass(frozen=True)
class FlexibleLink:
    """How to make one URDF link an RFEM beam on reading.

    section           : gpme_core.rfem.BeamSection (area, I_y, I_z, J in the beam frame)
    youngs_modulus    : E, Pa
    shear_modulus     : G, Pa
    density           : rho, kg/m^3
    n_segments        : RFEM segments, int >= 0 (0 = one rigid body with the beam's mass)
    bending_viscosity : eta_E, Pa s (Kelvin-Voigt), default 0
    torsion_viscosity : eta_G, Pa s; None = eta_E G / E
    axis              : (3,) unit vector, link frame; None = towards the next chain joint
    length            : m; None = the next chain joint's distance along ``axis``
    section_y_axis    : (3,) link frame, the direction of the section's y axis (projected
                        orthogonal to the beam); None = the link y axis, or the link z axis
                        when y is parallel to the beam

    The rule: the beam starts at the link frame origin.  Its axis and length are the
    vector p from the link origin to the origin of the next chain joint's frame (in the
    link frame, through any fixed joints in between): axis = p / |p|, length = p . axis,
    unless ``axis`` / ``length`` are given; the chain's tip link has no next joint, so both
    must be given.  The beam frame B has x along the axis, y the normalised component of
    ``section_y_axis`` orthogonal to x, z = x cross y.  The link's <inertial> is replaced
    by the beam's RFEM masses; links fixed to it keep theirs.  Everything hanging on the
    link (the next joint, fixed links, frames) moves to the beam tip with its transform T
    from the link frame replaced by inv(B @ translation(L)) @ T, so that at zero
    deflection the rigid geometry is unchanged.
    """

    section: BeamSection
    youngs_modulus: float
    shear_modulus: float
    density: float
    n_segments: int
    bending_viscosity: float = 0.0
    torsion_viscosity: Optional[float] = None
    axis: Optional[tuple] = None
    length: Optional[float] = None
    section_y_axis: Optional[tuple] = None

    def __post_init__(self):
        for fld in ("axis", "section_y_axis"):
            v = getattr(self, fld)
            if v is not None and not isinstance(v, (str, bytes)) and np.ndim(v) == 1:
                object.__setattr__(self, fld, tuple(np.asarray(v).tolist()))


# what ``flexible={link: spec}`` takes: a FlexibleLink, or the older (BeamProperties,
# n_segments) along the link's +x
FlexibleSpec = Union[FlexibleLink, tuple]


def _vector(v, label, problems) -> Optional[NDArray[np.float64]]:
    """(3,) finite floats of ``v``, or None (the problem appended)."""
    try:
        a = np.asarray(v, dtype=float)
    except (TypeError, ValueError):
        a = None
    if a is None or a.shape != (3,) or not np.all(np.isfinite(a)):
        problems.append(f"{label}: expected 3 finite numbers, got {v!r}")
        return None
    return a


def _segments_problem(label, n) -> Optional[str]:
    """The problem of a segment count ``n`` that is not an integer 0..MAX_SEGMENTS."""
    if not isinstance(n, (int, np.integer)) or isinstance(n, bool) \
            or not 0 <= n <= MAX_SEGMENTS:
        return f"{label}: n_segments must be an integer from 0 to {MAX_SEGMENTS}, got {n!r}"
    return None


def _beam_plan(name, spec, t_next, problems):
    """(BeamProperties, n_segments, (4, 4) beam frame in the link frame) or None.

    t_next: (4, 4) link frame -> next chain joint frame at q = 0, None at the chain tip.
    """
    label = f"flexible link {name!r}"
    if isinstance(spec, tuple) and len(spec) == 2 and isinstance(spec[0], BeamProperties):
        return _plan_along_x(label, spec, problems)
    if not isinstance(spec, FlexibleLink):
        problems.append(f"{label}: expected a FlexibleLink or (BeamProperties, n_segments), "
                        f"got {spec!r}")
        return None
    bad = []
    if not isinstance(spec.section, BeamSection):
        bad.append(f"{label}: section must be a gpme_core.rfem.BeamSection (solid_circle, "
                   f"tube, rectangle), got {type(spec.section).__name__}")
    n = spec.n_segments
    segments = _segments_problem(label, n)
    if segments is not None:
        bad.append(segments)
    p = None if t_next is None else t_next[:3, 3]
    x = _beam_axis(label, spec, p, bad)
    length = _beam_length(label, spec, p, x, bad)
    y = None if x is None else _section_y(label, spec, x, bad)
    if isinstance(spec.section, BeamSection):
        # material constants and the length, whether or not the geometry is complete
        probe = BeamProperties.from_section(1.0 if length is None else length, spec.section,
                                            spec.youngs_modulus, spec.shear_modulus,
                                            spec.density, spec.bending_viscosity,
                                            spec.torsion_viscosity)
        bad += probe.problems(label)
    problems.extend(bad)
    if bad or x is None or y is None or length is None:
        return None
    y = y / np.linalg.norm(y)
    frame = tf.homogeneous(np.column_stack((x, y, np.cross(x, y))), np.zeros(3))
    beam = BeamProperties.from_section(float(length), spec.section, spec.youngs_modulus,
                                       spec.shear_modulus, spec.density,
                                       spec.bending_viscosity, spec.torsion_viscosity)
    return beam, int(n), frame


def _plan_along_x(label, spec, problems):
    """The plan of the older spec (BeamProperties, n_segments): the beam along the link's
    +x, its frame the link frame; None with the problems appended."""
    beam, n = spec
    bad = beam.problems(label)
    segments = _segments_problem(label, n)
    if segments is not None:
        bad.append(segments)
    problems.extend(bad)
    return None if bad else (beam, int(n), np.eye(4))


def _beam_axis(label, spec, p, bad) -> Optional[NDArray[np.float64]]:
    """(3,) unit beam axis in the link frame: ``spec.axis``, else towards ``p`` (the next
    chain joint's origin in the link frame, m; None at the chain tip); None with the
    problem appended to ``bad``."""
    if spec.axis is not None:
        x = _vector(spec.axis, f"{label} axis", bad)
        if x is not None and abs(np.linalg.norm(x) - 1.0) > _UNIT_TOL:
            bad.append(f"{label}: axis must be a unit vector in the link frame, got "
                       f"{x.tolist()} (norm {np.linalg.norm(x)!r})")
            return None
        return x
    if p is None:
        bad.append(f"{label}: it is the chain tip (no next chain joint): give axis= (unit, "
                   "link frame) and length= (m)")
        return None
    if np.linalg.norm(p) == 0.0:
        bad.append(f"{label}: the next chain joint's frame is at the link origin, so the "
                   "beam axis is undefined: give axis= (unit, link frame) and length= (m)")
        return None
    return p / np.linalg.norm(p)


def _beam_length(label, spec, p, x, bad) -> Optional[float]:
    """Beam length, m: ``spec.length``, else the next chain joint's distance ``p @ x``
    along the axis ``x`` (a problem appended to ``bad`` when it is not positive, or at
    the chain tip); None when it cannot be found."""
    length = spec.length
    if length is None and x is not None:
        if p is None:
            if spec.axis is not None:
                bad.append(f"{label}: it is the chain tip (no next chain joint): give length= (m)")
        else:
            length = float(p @ x)
            if not length > 0.0:
                bad.append(f"{label}: the next chain joint lies {length!r} m along the given "
                           "axis; give length= (m) or an axis pointing towards it")
    return length


def _section_y(label, spec, x, bad) -> Optional[NDArray[np.float64]]:
    """(3,) the section's y direction orthogonal to the unit axis ``x`` (not normalised):
    from ``spec.section_y_axis``, else the link y axis (z when y is parallel to x); None
    with the problem appended to ``bad``."""
    if spec.section_y_axis is None:
        y = np.array((0.0, 1.0, 0.0)) - x[1] * x
        if np.linalg.norm(y) <= _PARALLEL_TOL:
            y = np.array((0.0, 0.0, 1.0)) - x[2] * x
        return y
    s = _vector(spec.section_y_axis, f"{label} section_y_axis", bad)
    if s is None:
        return None
    y = s - (s @ x) * x
    if np.linalg.norm(y) <= _PARALLEL_TOL * np.linalg.norm(s):
        bad.append(f"{label}: section_y_axis {s.tolist()} is parallel to the beam "
                   f"axis {x.tolist()} (or zero)")
        return None
    return y


def _beam_plans(flexible, side_flex, chain_links, next_origin, problems) -> dict:
    """{link: plan or None} of every valid entry of ``flexible`` ({link: FlexibleSpec}):
    a link moved by a chain joint (``chain_links``, in order) and not already
    RFEM-discretised in the side file (``side_flex``, {name: record}); the others'
    problems appended.  ``next_origin``: {k: (4, 4) frame of the one joint mounted on chain
    link k, in its frame} (absent for the tip of a chain and a link carrying several
    branches), which gives each beam its default axis and length."""
    plans = {}
    for lk, spec in flexible.items():
        if lk not in chain_links:
            problems.append(f"flexible link {lk!r}: not a link moved by a joint of the chain "
                            f"(moving links: {chain_links})")
            continue
        if lk in side_flex and side_flex[lk]["n_segments"] > 0:
            problems.append(f"flexible link {lk!r}: already RFEM-discretised with "
                            f"{side_flex[lk]['n_segments']} segments in this file; read the "
                            "rigid model to re-discretise it")
            continue
        k = chain_links.index(lk)
        plans[lk] = _beam_plan(lk, spec, next_origin.get(k), problems)
    return plans
