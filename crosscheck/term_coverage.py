"""Which terms of the equations do the shipped examples exercise?  (issue 23)

A fault in a term that is identically zero in every example passes every check: the
factor 2 of 2 grad(phi_t) . p_dot in kappa was changed to 1.9 in the compiled path and no
check failed, because no shipped constraint had a gradient changing with time.  This tool
runs every shipped example's quick run with gpme and evaluates, at the recorded samples
(t, q, q_dot), the largest absolute value of every term of

    M(q) q_ddot = h(q, q_dot) - g(q) - f(q) - d(q_dot) + t(t) + A^T lambda,
    Phi(q, t) = 0,  Phi_dot = A q_dot + Phi_t,  Phi_ddot = A q_ddot + kappa,
    kappa = grad(phi) . d + p_dot^T Hess(phi) p_dot + 2 grad(phi_t) . p_dot + phi_tt

separately (:data:`TERMS`): the mass matrix, velocity products, gravity, chain-joint
springs, dampers and drives, RFEM springs and dampers per section kind, whether joints of
each kind move, and for every kind of constraint its value, row, Phi_t and each piece of
kappa.  The pieces come from the engine's public functions
(gpme_core.dynamics.dynamics_terms, gpme_core.kinematics.point_kinematics, each
constraint's ``local_terms``, a joint programme's time function), not from formulas
copied here; at every sample they must add up to the engine's own Phi, A, Phi_dot and kappa
(gpme_core.constraints.evaluate_constraints), else :class:`TermCoverageError`.

A term is *zero* in an example when its largest value along the run is at most
ZERO_RELATIVE of a scale of its own equation (:data:`SCALES`): a round-off residue, not a
term.  It is *weak* when at most WEAK_RELATIVE of that scale: present only through the
run's drift off the constraints or round-off-sized motions, so a wrong factor in it would
hide under the integrators' error; only a term above WEAK_RELATIVE counts as exercised.

    python -m crosscheck.term_coverage [--write docs/coverage.md] [--t-end S] [--model F]

prints the table and the required terms that no example exercises (exit status 1 when
there are any); ``--write`` writes the page (docs/coverage.md).
"""
import argparse
import math
import sys
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Callable, Mapping, Optional, Sequence

import numpy as np
from numpy.typing import NDArray

from gpme_io.atomic import atomic_write_text
from gpme_io.modelfile import load_model_file
from gpme_io.runs import resolved_step
from gpme_core.constraints import (CoordinateProgramme, EllipseConstraint, JointProgramme,
                                   SympyPointConstraint, evaluate_constraints)
from gpme_core.dynamics import dynamics_terms
from gpme_core.errors import ModelError
from gpme_core.integrate import simulate
from gpme_core.kinematics import point_kinematics, vector_kinematics
from gpme_core.model import PRISMATIC, REVOLUTE
from gpme_core.pair_constraints import (AxisAlignment, Distance, RelativeCoordinate,
                                        SympyPairConstraint)
from gpme_core.rfem import BeamSection

from .crane_cases import crane_cases

REPO = Path(__file__).resolve().parent.parent

# A term at most this fraction of its scale is zero.  Every term is computed in double
# precision (eps = 2.2e-16) from numbers of the size of its scale through at most a few
# hundred operations (4x4 products over n <= ~30 links), so a term that is zero in exact
# arithmetic comes out below ~1e-13 of the scale; 1e-12 leaves a factor 10 for
# cancellation.  Measured: the zero terms of the shipped examples are 0 or <= 1e-14.
ZERO_RELATIVE = 1e-12
# A term at most this fraction of its scale is weak: it is zero on the exact motion and
# shows up only through the run's drift off its constraints (the UR5's rotating "angle"
# constraint has 2 grad(phi_t).p_dot ~ 5e-12 of its scale on the run: zero on the circle).
# A factor wrong by 10 % in a term of 1e-6 of its scale changes the acceleration by 1e-7
# of the scale, comparable with the RK4 error the run gates allow over a quick run, so a
# fault there may pass every check.  A term must exceed this in some example to count.
WEAK_RELATIVE = 1e-6

ZERO, WEAK, EXERCISED, ABSENT = "zero", "weak", "exercised", "absent"

# constraint kinds, as gpme_core.constraints offers them (model file: [[constraint]] kind
# "expression", "ellipse", "coordinate"; [[programme]])
EXPRESSION, ELLIPSE, COORDINATE, JOINT_PROGRAMME, TWO_FRAME = (
    "expression", "ellipse", "coordinate", "joint programme", "two-frame")
# Constraints between two frames (gpme_core.pair_constraints: relative, distance, axis
# alignment, expression) share one row assembly from their stacked vectors (kernels
# _pair_row, pair_constraints._BoundPairConstraint), whose pieces are counted together as
# the kind "two-frame"; each kind's local terms are checked on their own against finite
# differences and between the computation paths (tests/test_pair_constraints.py,
# tests/test_compiled.py), whatever the examples exercise.
CONSTRAINT_KINDS = MappingProxyType({
    SympyPointConstraint: EXPRESSION, EllipseConstraint: ELLIPSE,
    CoordinateProgramme: COORDINATE, JointProgramme: JOINT_PROGRAMME,
    RelativeCoordinate: TWO_FRAME, Distance: TWO_FRAME, AxisAlignment: TWO_FRAME,
    SympyPairConstraint: TWO_FRAME})
KINDS = tuple(dict.fromkeys(CONSTRAINT_KINDS.values()))
"""The constraint kinds of the table, each once, in order."""

# the pieces of a constraint: its value, its Jacobian row, Phi_t (Phi_dot = A q_dot +
# Phi_t) and the four pieces of kappa
PHI, ROW, PHI_T, DRIFT, HESS, GRAD_T, PHI_TT = (
    "Phi", "A", "Phi_t", "grad(phi).d", "p_dot^T Hess p_dot", "2 grad(phi_t).p_dot", "phi_tt")
PIECES = (PHI, ROW, PHI_T, DRIFT, HESS, GRAD_T, PHI_TT)
KAPPA_PIECES = (DRIFT, HESS, GRAD_T, PHI_TT)
_A_QDOT = "A q_dot"
_PHI_DOT_BOUND, _KAPPA_BOUND = "phi_dot bound", "kappa bound"
# Pieces a kind cannot have, by its definition in gpme_core.constraints: an ellipse does
# not depend on t; a coordinate programme p[axis] - f(t) is linear in p with a constant
# gradient; a joint programme q_k - f(t) has no point (its kappa is -f'').  They are not
# rows of the table.  tests/test_term_coverage.py checks this against local_terms.
STRUCTURALLY_ZERO = MappingProxyType({
    EXPRESSION: frozenset(),
    ELLIPSE: frozenset({PHI_T, GRAD_T, PHI_TT}),
    COORDINATE: frozenset({HESS, GRAD_T}),
    JOINT_PROGRAMME: frozenset({DRIFT, HESS, GRAD_T}),
    TWO_FRAME: frozenset(),
})
# Phi is not required: a run that starts on its constraints (on_constraints = true, as
# every example but the paper's crane) keeps Phi at round-off by design.  Its value off
# the zero set enters only the Baumgarte term beta^2 Phi (shared by all kinds, exercised
# by the crane's off-manifold start); a Phi with a wrong zero set moves the run off its
# programme, which the reference engines see (crosscheck.constraint_reference derives Phi
# on their side).
NOT_REQUIRED = frozenset({PHI})

# RFEM section kinds: the constructors of gpme_core.rfem.BeamSection (model-file shapes)
SECTION_KINDS = ("circle", "tube", "rectangle", "hollow_rectangle")
OTHER_SECTION = "other"
JOINT_KINDS = (REVOLUTE, PRISMATIC)
# relative agreement of a beam's constants with a BeamSection constructor's (section_kind):
# the same formula in double precision agrees to a few eps; the wall thickness solved
# back from the area loses a few digits more for thin walls
SECTION_MATCH = 1e-9


@dataclass(frozen=True)
class Term:
    """One row of the coverage table.

    key      : unique name, e.g. "constraint expression: 2 grad(phi_t).p_dot"
    label    : what the row shows
    unit     : SI unit of the largest value ([Phi]: the constraint's own unit)
    scale    : key of SCALES, what the value is compared with
    required : whether some shipped example must exercise it (NOT_REQUIRED: Phi)
    """

    key: str
    label: str
    unit: str
    scale: str
    required: bool = True


SCALES = MappingProxyType({
    "itself": "its own largest value (M is positive definite and A has full rank: never "
              "zero)",
    "force": "the example's largest generalized force, max over the run of |h|, |g|, |f|, "
             "|d| and |t| over every coordinate (N and N m alike)",
    "speed": "the example's largest chain-joint speed max |q_dot| (rad/s and m/s alike: "
             "the examples' links are ~0.3-1 m)",
    "distance": "the constraint's largest Jacobian entry max |A| times 1 m or 1 rad, so "
                "that |Phi| / scale is the distance from the constraint",
    "phi_dot": "the constraint's largest |grad(phi)| |p_dot| + |Phi_t| (a joint programme: "
               "|q_dot_k| + |f'|), the sizes of the two parts of Phi_dot",
    "kappa": "the constraint's largest |grad(phi)| |d| + |p_dot|^2 ||Hess(phi)|| + "
             "2 |grad(phi_t)| |p_dot| + |phi_tt| (a joint programme: |f''|): the bounds of "
             "the four pieces by the sizes of their factors (Cauchy-Schwarz), so that a piece "
             "that vanishes by cancellation, a gradient's rate orthogonal to the velocity, "
             "is zero even when every other piece vanishes too",
})


def constraint_term_key(kind: str, piece: str) -> str:
    """Key of the term ``piece`` (one of PIECES) of constraints of ``kind``."""
    return f"constraint {kind}: {piece}"


def _constraint_unit(piece):
    return {PHI: "[Phi]", ROW: "[Phi]/[q]", PHI_T: "[Phi]/s"}.get(piece, "[Phi]/s^2")


def _constraint_scale(piece):
    return {PHI: "distance", ROW: "itself", PHI_T: "phi_dot"}.get(piece, "kappa")


def _piece_label(kind, piece):
    if kind == JOINT_PROGRAMME:
        text = {PHI: "Phi = q_k - f", ROW: "A (unit row)", PHI_T: "Phi_t = -f'",
                PHI_TT: "kappa = -f''"}[piece]
    else:
        text = piece if piece in (PHI, ROW, PHI_T) else f"kappa: {piece}"
    return f"{kind}: {text}"


def _terms():
    out = [Term("M", "M, mass matrix (trace form)", "kg, kg m, kg m^2", "itself"),
           Term("h", "h, velocity products", "N, N m", "force"),
           Term("g", "g, gravity", "N, N m", "force"),
           Term("spring", "f, springs of chain joints", "N, N m", "force"),
           Term("damper", "d, dampers of chain joints", "N, N m", "force"),
           Term("drive", "t, drives", "N, N m", "force")]
    for kind in SECTION_KINDS:
        out.append(Term(f"rfem spring {kind}", f"f, RFEM springs, {kind} section", "N m",
                        "force"))
        out.append(Term(f"rfem damper {kind}", f"d, RFEM dampers, {kind} section", "N m",
                        "force"))
    for kind in JOINT_KINDS:
        out.append(Term(f"joint {kind}", f"{kind} joints: max abs(q_dot)",
                        "rad/s" if kind == REVOLUTE else "m/s", "speed"))
    for kind in KINDS:
        for piece in PIECES:
            if piece not in STRUCTURALLY_ZERO[kind]:
                out.append(Term(constraint_term_key(kind, piece), _piece_label(kind, piece),
                                _constraint_unit(piece), _constraint_scale(piece),
                                piece not in NOT_REQUIRED))
    return tuple(out)


TERMS = _terms()
"""Every row of the table, in order."""


@dataclass(frozen=True)
class TermValue:
    """Largest absolute value of one term along one run and its scale (same unit)."""

    largest: float
    scale: float

    @property
    def relative(self) -> float:
        """largest / scale (0 when both are 0)."""
        if self.scale > 0.0:
            return self.largest / self.scale
        return math.inf if self.largest > 0.0 else 0.0

    @property
    def status(self) -> str:
        """ZERO, WEAK or EXERCISED, by ZERO_RELATIVE and WEAK_RELATIVE."""
        if not self.largest > ZERO_RELATIVE * self.scale:
            return ZERO
        if not self.largest > WEAK_RELATIVE * self.scale:
            return WEAK
        return EXERCISED


@dataclass(frozen=True)
class Example:
    """A shipped example: its name, where it comes from, and how to get its Scenario."""

    name: str
    origin: str
    load: Callable[[], object]


@dataclass(frozen=True)
class ExampleCoverage:
    """The terms of one example's run.

    values       : {Term.key: TermValue}; a term the example does not have (no
                   constraint of that kind, no beam of that section, no drive) is missing
    t_end        : s, run length;  n_samples : samples evaluated
    mismatch     : largest difference between the pieces' Phi, Phi_dot, kappa and the
                   engine's, relative to their scales, over the run (round-off)
    constraints  : {constraint name: kind}
    time_functions: ("drive psi2: QuinticRamp", ...), the time functions of the drives
                   and programmes
    """

    name: str
    origin: str
    t_end: float
    n_samples: int
    values: Mapping[str, TermValue]
    mismatch: float
    constraints: Mapping[str, str]
    time_functions: tuple = ()

    def status(self, key: str) -> str:
        """ABSENT, or the status of the term's TermValue."""
        value = self.values.get(key)
        return ABSENT if value is None else value.status


class TermCoverageError(RuntimeError):
    """The pieces of a constraint do not add up to the engine's Phi, A, Phi_dot or kappa."""


# ----------------------------------------------------------------------------- examples
def shipped_examples(root: Path = REPO) -> list:
    """The shipped examples, in order: the crane cases of `gpme verify`'s gpme step without
    --model (crosscheck.crane_cases, which crosscheck.verify.default_scenarios gives), every
    models/*.toml (models/zoo/ is not shipped here) and every examples/*/*.toml.  A file
    whose scenario has the name of one already listed (models/crane_rigid.toml and
    crane_flexible.toml: the crane cases, tests/test_modelfile.py checks they agree) is named
    in that example's origin instead."""
    out = []
    for scenario in crane_cases("gpme", quick=True):
        n_rfe = len(scenario.model.flexible_coordinates) // 3
        out.append([scenario.name, f"crane_scenario({n_rfe}), gpme verify's default", scenario])
    files = sorted((root / "models").glob("*.toml")) + sorted((root / "examples").glob("*/*.toml"))
    for path in files:
        scenario = load_model_file(path)
        rel = path.relative_to(root).as_posix()
        same = [e for e in out if e[0] == scenario.name]
        if same:
            same[0][1] += f" (= {rel})"
        else:
            out.append([scenario.name, rel, scenario])
    return [Example(name, origin, lambda s=scenario: s) for name, origin, scenario in out]


def example_from_file(path) -> Example:
    """An Example of one model file (for a model that is not shipped, e.g. in a test)."""
    scenario = load_model_file(path)
    return Example(scenario.name, str(path), lambda: scenario)


# ----------------------------------------------------------------------------- kinds
def section_kind(beam) -> str:
    """The BeamSection constructor that gives ``beam``'s (gpme_core.rfem.BeamProperties)
    section constants: one of SECTION_KINDS, or OTHER_SECTION.

    Candidates are built from the extreme fibres c_y, c_z and the area A: a solid circle of
    diameter 2c; a tube of outer diameter 2c and the wall that gives A; a 2c_y x 2c_z
    rectangle; a 2c_y x 2c_z hollow rectangle with the wall that gives A.  The first whose
    A, I_y, I_z and J agree with the beam's to SECTION_MATCH is the kind."""
    c_y, c_z, area = beam.extreme_fibre_y, beam.extreme_fibre_z, beam.area
    if c_y is None or c_z is None:
        return OTHER_SECTION
    candidates = []
    if math.isclose(c_y, c_z, rel_tol=SECTION_MATCH):
        candidates.append(("circle", lambda: BeamSection.solid_circle(2.0 * c_y)))
        inner_sq = c_y ** 2 - area / math.pi
        if inner_sq > 0.0:
            candidates.append(("tube", lambda: BeamSection.tube(
                2.0 * c_y, c_y - math.sqrt(inner_sq))))
    w, h = 2.0 * c_y, 2.0 * c_z
    candidates.append(("rectangle", lambda: BeamSection.rectangle(w, h)))
    disc = (w + h) ** 2 - 4.0 * area          # A = 2 t (w + h) - 4 t^2
    if disc > 0.0:
        candidates.append(("hollow_rectangle", lambda: BeamSection.hollow_rectangle(
            w, h, 0.25 * ((w + h) - math.sqrt(disc)))))
    mine = (area, beam.second_moment_y, beam.second_moment_z, beam.torsion_constant)
    for kind, make in candidates:
        try:
            s = make()
        except ModelError:          # a candidate its constructor refuses is not this section
            continue
        theirs = (s.area, s.second_moment_y, s.second_moment_z, s.torsion_constant)
        if all(math.isclose(a, b, rel_tol=SECTION_MATCH) for a, b in zip(mine, theirs)):
            return kind
    return OTHER_SECTION


def constraint_kind(spec) -> str:
    """The kind of a constraint spec (CONSTRAINT_KINDS), or 'point (<class>)' for a
    PointConstraint subclass of the user's (its pieces are reported under that kind)."""
    kind = CONSTRAINT_KINDS.get(type(spec))
    return kind if kind is not None else f"point ({type(spec).__name__})"


# ----------------------------------------------------------------------------- runs
def run_example(scenario, t_end: Optional[float] = None, compiled: bool = True):
    """History DataFrame of the scenario's quick run (or its first ``t_end`` s) with gpme,
    run as gpme_io.runs.simulate_scenario runs it: the scenario's integrator, step (RK4:
    gpme_io.runs.resolved_step) and output spacing.  compiled=False runs
    RK4 on the Python reference path (no numba compilation; same motion to round-off)."""
    t_run = scenario.quick_t_end if t_end is None else min(float(t_end), scenario.quick_t_end)
    dt = resolved_step(scenario) if scenario.integrator == "RK4" else scenario.dt
    return simulate(scenario.system, t_run, scenario.q0, scenario.q_dot0, dt=dt,
                    method=scenario.integrator, output_dt=min(scenario.output_dt, t_run),
                    compiled=compiled)


def constraint_pieces(model, spec, bound, t: float, kin, q: NDArray[np.float64],
                      q_dot: NDArray[np.float64]) -> dict:
    """{piece: value} of one constraint at (t s, q, q_dot): PIECES (ROW (n,), the others
    scalars in [Phi], [Phi]/s, [Phi]/s^2), "A q_dot", and the bounds of the pieces of
    Phi_dot and kappa by the sizes of their factors (SCALES "phi_dot", "kappa"), from the
    engine's public functions: point_kinematics and ``spec.local_terms`` for a point
    constraint (``bound`` its bound form, with link and r_local), the time function's
    derivatives for a joint programme.  kin: gpme_core.kinematics.ChainKinematics at q."""
    if isinstance(spec, JointProgramme):
        k = model.index(spec.coordinate)
        f, f_t, f_tt = spec.function.derivatives(t)
        row = np.zeros(model.n_coordinates)
        row[k] = 1.0
        return {PHI: q[k] - f, ROW: row, _A_QDOT: float(q_dot[k]), PHI_T: -f_t,
                DRIFT: 0.0, HESS: 0.0, GRAD_T: 0.0, PHI_TT: -f_tt,
                _PHI_DOT_BOUND: abs(q_dot[k]) + abs(f_t), _KAPPA_BOUND: abs(f_tt)}
    if getattr(bound, "vector_keys", None) is not None:      # two frames: stacked (6,)
        position, v, jacobian, drift = bound.stacked(
            [vector_kinematics(model, kin, q_dot, *key) for key in bound.vector_keys])
    else:
        pk = point_kinematics(model, kin, q_dot, bound.link, bound.r_local)
        position, v, jacobian, drift = pk.position, pk.velocity, pk.jacobian, pk.drift
    phi, grad, hess, phi_t, grad_t, phi_tt = spec.local_terms(position, t)
    speed, slope = float(np.linalg.norm(v)), float(np.linalg.norm(grad))
    return {PHI: float(phi), ROW: grad @ jacobian, _A_QDOT: float(grad @ v),
            PHI_T: float(phi_t), DRIFT: float(grad @ drift), HESS: float(v @ hess @ v),
            GRAD_T: 2.0 * float(grad_t @ v), PHI_TT: float(phi_tt),
            _PHI_DOT_BOUND: slope * speed + abs(phi_t),
            _KAPPA_BOUND: (slope * float(np.linalg.norm(drift))
                           + speed ** 2 * float(np.linalg.norm(hess, 2))
                           + 2.0 * float(np.linalg.norm(grad_t)) * speed + abs(phi_tt))}


class _Maxima:
    """Running maxima of |value| per key."""

    def __init__(self):
        self.values = {}

    def put(self, key, value):
        v = float(np.max(np.abs(value))) if np.size(value) else 0.0
        self.values[key] = max(v, self.values.get(key, 0.0))

    def get(self, key):
        return self.values.get(key, 0.0)


# the pieces must reproduce the engine's Phi, Phi_dot, kappa to this fraction of their
# scales (the same numbers summed in another order: a few eps); and A to round-off of |A|
AGREEMENT = 1e-9


def _check_agreement(scenario, name, kind, t, pieces, engine):
    """Largest relative difference of the pieces' Phi, Phi_dot, kappa and A from the
    engine's (phi, phi_dot, row, kappa); TermCoverageError beyond AGREEMENT."""
    phi, phi_dot, row, kappa = engine
    row_scale = float(np.abs(row).max())
    checks = (
        ("Phi", pieces[PHI], phi, row_scale),
        ("Phi_dot", pieces[_A_QDOT] + pieces[PHI_T], phi_dot, pieces[_PHI_DOT_BOUND]),
        ("kappa", sum(pieces[p] for p in KAPPA_PIECES), kappa, pieces[_KAPPA_BOUND]),
        ("A", pieces[ROW], row, row_scale))
    worst = 0.0
    for what, mine, theirs, scale in checks:
        diff = float(np.max(np.abs(np.asarray(mine) - theirs)))
        err = diff / scale if scale > 0.0 else diff
        if not err <= AGREEMENT:
            raise TermCoverageError(
                f"{scenario.name}: constraint {name!r} ({kind}) at t = {t:.6g} s: its pieces "
                f"give {what} differing from the engine's (gpme_core.constraints."
                f"evaluate_constraints) by {diff:.3g}, {err:.3g} of the scale {scale:.3g} "
                f"(allowed {AGREEMENT:g}): the engine or this tool is wrong")
        worst = max(worst, err)
    return worst


def evaluate_terms(scenario, df, stride: int = 1) -> tuple:
    """({Term.key: TermValue}, mismatch) along the run ``df`` (every ``stride``-th
    recorded sample) of ``scenario``; mismatch as in ExampleCoverage."""
    model, system = scenario.model, scenario.system
    rfem = {}
    for link in model.flexible_links:
        if link.joint_indices:        # a beam of 0 segments is one rigid body: no sde
            rfem.setdefault(section_kind(link.beam), []).extend(link.joint_indices)
    flexible = {k for idx in rfem.values() for k in idx}
    chain = np.array([k for k in range(model.n_coordinates) if k not in flexible], dtype=int)
    rfem = {kind: np.array(sorted(idx), dtype=int) for kind, idx in rfem.items()}
    joints = {kind: np.array([k for k in chain if model.joints[k].kind == kind], dtype=int)
              for kind in JOINT_KINDS}
    specs, bound = system.constraint_specs, system.bound
    kinds = [constraint_kind(s) for s in specs]
    per_constraint = [_Maxima() for _ in bound]
    dyn = _Maxima()
    mismatch = 0.0
    names = model.coordinate_names
    rows = df.iloc[::stride]
    for t, q, q_dot in zip(rows["t"].to_numpy(dtype=float),
                           rows[list(names)].to_numpy(dtype=float),
                           rows[[f"{nm}_dot" for nm in names]].to_numpy(dtype=float)):
        terms = dynamics_terms(model, t, q, q_dot)
        for key, value in (("M", terms.M), ("h", terms.h), ("g", terms.g),
                           ("drive", terms.t), ("spring", terms.f[chain]),
                           ("damper", terms.d[chain]), ("speed", q_dot[chain])):
            dyn.put(key, value)
        dyn.put("force", (terms.h, terms.g, terms.f, terms.d, terms.t))
        for kind, idx in rfem.items():
            dyn.put(f"rfem spring {kind}", terms.f[idx])
            dyn.put(f"rfem damper {kind}", terms.d[idx])
        for kind, idx in joints.items():
            dyn.put(f"joint {kind}", q_dot[idx])
        phi, phi_dot, a, kappa = evaluate_constraints(model, bound, t, terms.kin, q_dot)
        for c, (spec, b) in enumerate(zip(specs, bound)):
            pieces = constraint_pieces(model, spec, b, t, terms.kin, q, q_dot)
            mismatch = max(mismatch, _check_agreement(
                scenario, b.name, kinds[c], t, pieces, (phi[c], phi_dot[c], a[c], kappa[c])))
            m = per_constraint[c]
            for piece in PIECES:
                m.put(piece, pieces[piece])
            m.put("phi_dot", pieces[_PHI_DOT_BOUND])
            m.put("kappa", pieces[_KAPPA_BOUND])
    force = dyn.get("force")
    values = {"M": TermValue(dyn.get("M"), dyn.get("M")),
              "h": TermValue(dyn.get("h"), force), "g": TermValue(dyn.get("g"), force)}
    if np.any(model.stiffness[chain]):
        values["spring"] = TermValue(dyn.get("spring"), force)
    if np.any(model.damping[chain]):
        values["damper"] = TermValue(dyn.get("damper"), force)
    if model.drives:
        values["drive"] = TermValue(dyn.get("drive"), force)
    for kind in rfem:
        for part in ("spring", "damper"):
            values[f"rfem {part} {kind}"] = TermValue(dyn.get(f"rfem {part} {kind}"), force)
    for kind, idx in joints.items():
        if idx.size:
            values[f"joint {kind}"] = TermValue(dyn.get(f"joint {kind}"), dyn.get("speed"))
    for kind, m in zip(kinds, per_constraint):
        scales = {"itself": m.get(ROW), "distance": m.get(ROW), "phi_dot": m.get("phi_dot"),
                  "kappa": m.get("kappa")}
        for piece in PIECES:
            if piece in STRUCTURALLY_ZERO.get(kind, ()):
                continue
            key = constraint_term_key(kind, piece)
            new = TermValue(m.get(piece), scales[_constraint_scale(piece)])
            old = values.get(key)
            if old is None or new.relative > old.relative:   # the kind's best constraint
                values[key] = new
    return MappingProxyType(values), mismatch


def _time_functions(scenario):
    out = [f"drive {d.joint}: {type(d.function).__name__}" for d in scenario.model.drives]
    for spec in scenario.constraints:
        fn = getattr(spec, "function", None)
        if fn is not None:
            out.append(f"{constraint_kind(spec)} {spec.name}: {type(fn).__name__}")
    return tuple(out)


def example_coverage(example: Example, t_end: Optional[float] = None, stride: int = 1,
                     compiled: bool = True) -> ExampleCoverage:
    """Run ``example`` (its quick run, or its first ``t_end`` s) and evaluate its terms
    at every ``stride``-th recorded sample."""
    scenario = example.load()
    df = run_example(scenario, t_end, compiled=compiled)
    values, mismatch = evaluate_terms(scenario, df, stride)
    kinds = MappingProxyType({s.name: constraint_kind(s) for s in scenario.constraints})
    return ExampleCoverage(example.name, example.origin, float(df["t"].iloc[-1]),
                           len(df.iloc[::stride]), values, mismatch, kinds,
                           _time_functions(scenario))


# ----------------------------------------------------------------------------- verdict
def uncovered_terms(coverages: Sequence[ExampleCoverage], level: str = WEAK,
                    required: bool = True) -> list:
    """Keys of the TERMS (only the required ones unless ``required`` is False) that no
    example exercises: level=ZERO, those zero or absent in every example; level=WEAK
    (default), those zero, weak or absent in every one."""
    bad = (ZERO, ABSENT) if level == ZERO else (ZERO, WEAK, ABSENT)
    return [term.key for term in TERMS if (term.required or not required)
            and all(cov.status(term.key) in bad for cov in coverages)]


def _cell(value: Optional[TermValue]) -> str:
    if value is None:
        return "—"
    text = f"{value.largest:.2e}"
    if value.status == ZERO:
        return f"**0** ({text})"
    if value.status == WEAK:
        return f"*weak* {text}"
    return text


def _best(term, coverages):
    found = [(c.values[term.key].relative, c.name) for c in coverages if term.key in c.values]
    if not found:
        return "—"
    rel, name = max(found)
    return f"{rel:.0e} {name}" if math.isfinite(rel) else name


def markdown_table(coverages: Sequence[ExampleCoverage]) -> str:
    """The table term x example: the largest absolute value along the run (SI, the term's
    unit); **0** zero, *weak* weak, — not in the example; the last column the largest
    largest/scale over the examples and where."""
    head = ["term", "unit"] + [c.name for c in coverages] + ["best: largest/scale"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for term in TERMS:
        label = term.label if term.required else f"{term.label} (†)"
        cells = ([label, term.unit] + [_cell(c.values.get(term.key)) for c in coverages]
                 + [_best(term, coverages)])
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def _labels(keys):
    label = {t.key: t.label for t in TERMS}
    return "; ".join(label[k] for k in keys) if keys else "none"


def verdict_text(coverages: Sequence[ExampleCoverage]) -> str:
    """The lists of required terms zero / at most weak in every example, and the
    information rows (†) that are."""
    zero = uncovered_terms(coverages, ZERO)
    weak = [k for k in uncovered_terms(coverages, WEAK) if k not in zero]
    info = [t.key for t in TERMS if not t.required
            and all(c.status(t.key) in (ZERO, WEAK, ABSENT) for c in coverages)]
    return "\n".join([
        f"- Required terms zero (at most {ZERO_RELATIVE:g} of their scale) or absent in "
        f"every example: {_labels(zero)}.",
        f"- Required terms at most weak (at most {WEAK_RELATIVE:g} of their scale) in every "
        f"example: {_labels(weak)}.",
        f"- Not required (†), zero or weak in every example: {_labels(info)}."])


def examples_text(coverages: Sequence[ExampleCoverage]) -> str:
    """One line per example: origin, run, constraints and their kinds, time functions,
    and how closely the pieces reproduce the engine's Phi, A, Phi_dot and kappa."""
    out = []
    for c in coverages:
        kinds = ", ".join(f"{n} ({k})" for n, k in c.constraints.items()) or "none"
        functions = ", ".join(c.time_functions) or "none"
        out.append(f"- **{c.name}**: {c.origin}; {c.t_end:g} s, {c.n_samples} samples; "
                   f"constraints {kinds}; time functions {functions}; the pieces reproduce "
                   f"the engine's Phi, A, Phi_dot, kappa to {c.mismatch:.0e} of their scales")
    return "\n".join(out)


def _largest_zero(coverages):
    return max([v.relative for c in coverages for v in c.values.values()
                if v.status == ZERO and math.isfinite(v.relative)], default=0.0)


def page_text(coverages: Sequence[ExampleCoverage], command: str) -> str:
    """docs/coverage.md: what the tool does, the thresholds and scales, the examples, the
    table and the verdict (generated: edit crosscheck/term_coverage.py, not the page)."""
    scales = "\n".join(f"- `{k}`: {v}." for k, v in SCALES.items())
    structural = "\n".join(
        f"- {kind}: " + (", ".join(sorted(STRUCTURALLY_ZERO[kind])) or "none")
        for kind in KINDS)
    return f"""# Term coverage of the shipped examples

<!-- generated by `{command}`; edit crosscheck/term_coverage.py, not this page -->

A fault in a term that is zero in every example passes every check (issue 23: the factor 2
of `2 grad(phi_t).p_dot` in kappa changed to 1.9 in the compiled path gave 0 failed checks
on the crane and every shipped example, whose constraints all had fixed gradients or
uniform circular motion).  `crosscheck/term_coverage.py` runs each shipped example's quick
run with gpme and evaluates at every recorded sample (t, q, q_dot) each term of

    M q_ddot = h - g - f - d + t + A^T lambda,   Phi_dot = A q_dot + Phi_t,
    kappa = grad(phi).d + p_dot^T Hess(phi) p_dot + 2 grad(phi_t).p_dot + phi_tt

separately, from the engine's public functions (`gpme_core.dynamics.dynamics_terms`,
`gpme_core.kinematics.point_kinematics`, each constraint's `local_terms`, a joint
programme's time function), and checks at every sample that the pieces reproduce the
engine's own Phi, A, Phi_dot and kappa (`gpme_core.constraints.evaluate_constraints`) to
{AGREEMENT:g} of their scales.

Regenerate this page (about 20 s once the examples' compiled kernels are in numba's
cache, a few minutes before; exit status 1 when a required term is exercised by no
example):

    .venv/bin/python -m crosscheck.term_coverage --write docs/coverage.md

`tests/test_term_coverage.py` runs the same on the first 0.2 s of every example and fails
when a required term is not exercised, and checks that this page names every shipped
example and every term.

## Thresholds

A term's largest value along the run is compared with a scale of its own equation:

{scales}

- **zero**: at most {ZERO_RELATIVE:g} of the scale.  Every term is computed in double
  precision (eps = 2.2e-16) from numbers of the size of its scale through at most a few
  hundred operations, so a term that is zero in exact arithmetic comes out below ~1e-13 of
  the scale; {ZERO_RELATIVE:g} leaves a factor 10 for cancellation.  The zero cells below
  are at most {_largest_zero(coverages):.0e} of their scales.
- **weak**: at most {WEAK_RELATIVE:g} of the scale: zero on the exact motion, non-zero only
  through the run's drift off its constraints (the UR5's rotating `angle` constraint has
  `2 grad(phi_t).p_dot` at ~5e-12 of its scale: on the circle its gradient's rate is
  radial and the velocity tangential).  A factor wrong by 10 % in such a term moves the
  acceleration by at most 1e-7 of the term's scale; whether a run comparison sees that
  depends on the integration error it allows, so such a term is not counted.  A required
  term counts as **exercised** only above {WEAK_RELATIVE:g} of its scale in some example.
- (†) not required: **Phi**.  A run that starts on its constraints (`on_constraints =
  true`, every example but the paper's crane) keeps Phi at round-off by design.  Phi off
  its zero set enters the equations of motion only through the Baumgarte term
  `beta^2 Phi`, one line shared by all kinds and exercised by the crane's off-manifold
  start (ellipse and coordinate rows); a Phi with a wrong zero set moves the run off its
  programme, which the reference engines see (`crosscheck/constraint_reference.py`
  derives Phi on their side).

Units: `[Phi]` is the constraint's own unit: 1 for an ellipse, m for a coordinate
programme, rad or m (the joint's) for a joint programme, the formula's for an expression
(m for a plane `z - c`, m^2 for a circle `x**2 + y**2 - r**2`).  Pieces a kind cannot have
are not rows (an ellipse does not depend on t; a coordinate programme `p[axis] - f(t)` has
a constant gradient; a joint programme has no point):

{structural}

RFEM rows are split by the section of the beam, recognised by which `BeamSection`
constructor reproduces its constants (A, I_y, I_z, J to {SECTION_MATCH:g}); the
sde coordinates are not counted as revolute joints.  Chain-joint springs and dampers
are those of the non-RFEM coordinates.

## Examples

{examples_text(coverages)}

## Largest value along the run

`**0**` zero, `*weak*` weak, `—` the example has no such term.  Where an example has
several constraints of one kind, a cell is that of the constraint in which the term is
largest relative to its scale.  Last column: the largest largest/scale over the examples
and which.

{markdown_table(coverages)}

## Verdict

{verdict_text(coverages)}

Not measured here: which kind of time function (`Constant`, `Sine`, `Cosine`,
`QuinticRamp`, `Tabulated`, `SympyTimeFunction`) gives f, f' and f'' of the programmes and
drives (listed per example above): the compiled kernels have one branch per kind, and a
drive uses only f.
"""


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m crosscheck.term_coverage",
        description="The largest value of every term of the equations along each shipped "
                    "example's quick run; exit status 1 when a required term is exercised "
                    "by no example (docs/coverage.md).")
    parser.add_argument("--write", metavar="PATH",
                        help="write the page there (docs/coverage.md)")
    parser.add_argument("--t-end", type=float, default=None, metavar="S",
                        help="run each example at most S s (default: its quick run)")
    parser.add_argument("--model", action="append", default=None, metavar="FILE",
                        help="only these model files (repeatable) instead of the shipped "
                             "examples")
    parser.add_argument("--python-path", action="store_true",
                        help="run RK4 on the Python reference path instead of the compiled "
                             "kernels (no numba compilation)")
    args = parser.parse_args(argv)
    if args.t_end is not None and not args.t_end > 0:
        parser.error(f"--t-end must be > 0 (s), got {args.t_end}")
    examples = ([example_from_file(Path(p)) for p in args.model] if args.model
                else shipped_examples())
    coverages = []
    for ex in examples:
        print(f"  {ex.name}: {ex.origin}", file=sys.stderr, flush=True)
        coverages.append(example_coverage(ex, args.t_end, compiled=not args.python_path))
    print(examples_text(coverages) + "\n\n" + markdown_table(coverages) + "\n\n"
          + verdict_text(coverages))
    if args.write:
        command = "python -m crosscheck.term_coverage " + " ".join(
            argv if argv is not None else sys.argv[1:])
        atomic_write_text(args.write, page_text(coverages, command.strip()))
    return 1 if uncovered_terms(coverages) else 0


if __name__ == "__main__":
    sys.exit(main())
