"""Turn a parsed model file (gpme_io.modelfile.schema.ModelFile) into a
gpme_io.scenario.Scenario.

Steps: build the source model (the builtin crane, or the URDF through
gpme_io.urdf_reader with the chain, frozen joints and flexible links); check every name
the file uses against it (joints, frames, links, coordinates; :func:`reference_problems`);
apply the [[joint]] springs and dampers, replace the drives by the file's [[drive]] list,
name the links used as constraint frames; bind the constraints; place the initial state;
choose the dependent coordinates and the RK4 step when the file leaves them out.
Everything the file leaves to a default, and everything the reader left out, is a line of
``Scenario.notes``.
"""
from dataclasses import dataclass
from pathlib import Path
from typing import Optional

import numpy as np

from gpme_core.echo import closest
from gpme_core.constraints import (CoordinateProgramme, EllipseConstraint, JointProgramme,
                                   SympyPointConstraint)
from gpme_core.errors import ConstraintError, ModelError, ModelFileError
from gpme_core.gpme import ProgrammedMotion
from gpme_core.kinematics import chain_kinematics
from gpme_core.model import Drive, Frame, Model, validate_model
from gpme_core.point_springs import PointSpring
from gpme_core.pair_constraints import (Distance, RelativeCoordinate, SympyPairConstraint,
                                        aligned, coincident, weld)
from gpme_core.rfem import BeamSection
from gpme_core.stability import STEP_SAFETY, rk4_limit, safe_step
from gpme_core.statics import static_equilibrium
from gpme_core.time_functions import SympyTimeFunction, Tabulated
from gpme_examples.crane import CraneParameters, build_crane
from gpme_io import expressions as ex
from gpme_io.scenario import Scenario
from gpme_io.side_file import side_file_path
from gpme_io.urdf_reader import FlexibleLink, load_urdf

from .schema import (CoordinateConstraintSpec, CraneSource, EllipseConstraintSpec,
                     ExpressionConstraintSpec, ModelFile, PairConstraintSpec, UrdfSource,
                     constraint_frames)

# STEP_SAFETY (gpme_core.stability): fraction of the RK4 stability step used when dt is not given


@dataclass(frozen=True)
class SourceModel:
    """The model built from the file's source, before the file's changes.

    model  : gpme_core.model.Model
    urdf   : the URDF read (None for builtin models)
    chain  : (root link, tip link) used, or None;  frozen : {joint: rad or m}
    notes  : what the reader left out or replaced, one line each
    """

    model: Model
    urdf: Optional[Path] = None
    chain: Optional[tuple] = None
    frozen: tuple = ()
    notes: tuple = ()


# ====================================================================== the source model
def build_source(spec: ModelFile) -> SourceModel:
    """The source model of ``spec`` (raises ModelFileError with 'model...' key paths)."""
    src = spec.model.source
    if isinstance(src, CraneSource):
        return _crane_model(spec)
    return _urdf_model(spec, src)


def _crane_parameters(spec: ModelFile):
    """CraneParameters of a builtin crane file: its [model.crane] overrides and gravity."""
    return CraneParameters(**{**dict(spec.model.source.overrides),
                              "gravity": tuple(spec.model.gravity)})


def _crane_model(spec: ModelFile) -> SourceModel:
    src = spec.model.source
    params = _crane_parameters(spec)
    try:
        model = build_crane(src.n_rfe, params, name=spec.model.name)
    except ModelError as exc:
        raise ModelFileError([f"model.crane: {p}" for p in exc.problems]) from None
    return SourceModel(model, None, None, (), ())


def _urdf_model(spec: ModelFile, src: UrdfSource) -> SourceModel:
    shapes = {"circle": BeamSection.solid_circle, "tube": BeamSection.tube,
              "rectangle": BeamSection.rectangle, "hollow_rectangle": BeamSection.hollow_rectangle}
    problems = []
    flexible = {}
    for f in spec.flexible:
        try:
            section = shapes[f.section.shape](**dict(f.section.dimensions))
            flexible[f.link] = FlexibleLink(
                section, f.youngs_modulus, f.shear_modulus, f.density, f.segments,
                bending_viscosity=f.bending_viscosity, torsion_viscosity=f.torsion_viscosity,
                axis=f.axis, length=f.length, section_y_axis=f.section_y_axis)
        except ModelError as exc:
            problems += [f"{f.key}.section: {p}" for p in exc.problems]
    # the URDF is read even when a [[flexible]] section is wrong (with the valid ones), so
    # that its problems are listed with the section's, not after it is fixed
    chain, tree = spec.chain, spec.tree
    if tree is not None:
        ends = None if tree.root is None else (tree.root,)
        frozen = dict(tree.frozen)
    else:
        ends = None if chain is None or (chain.root is None and chain.tip is None) \
            else (chain.root, chain.tip)
        frozen = dict(chain.frozen) if chain is not None else {}
    try:
        res = load_urdf(src.path, side_file=src.side_file if src.side_file else "auto",
                        chain=ends, frozen=frozen, flexible=flexible,
                        gravity=tuple(spec.model.gravity), name=spec.model.name,
                        whole_tree=tree is not None)
    except ModelError as exc:
        raise ModelFileError(problems + [f"model.urdf ({src.written}): {p}"
                                         for p in exc.problems]) from None
    if problems:
        raise ModelFileError(problems)
    notes = list(res.notes)
    if src.side_file is None and side_file_path(src.path).is_file():
        notes.append(f"side file {side_file_path(src.path).name} beside the URDF read (springs, "
                     "spring references, drives; gravity is the model file's)")
    return SourceModel(res.model, src.path, tuple(res.chain), tuple(dict(res.frozen).items()),
                       tuple(notes))


# ====================================================================== name checks
def _unknown(what: str, name: str, choices) -> str:
    choices = list(choices)
    # a looser cutoff: link and joint names of real URDFs are long and share prefixes
    close = closest(name, choices, cutoff=0.5)
    mean = f"did you mean {close[0]!r}? " if close else ""
    shown = ", ".join(choices[:30]) + (f", ... ({len(choices)} in all)" if len(choices) > 30
                                        else "")
    return f"no {what} {name!r}; {mean}the model has: {shown}"


def _flexible_coordinates(model: Model) -> dict:
    """{coordinate name: flexible link name} of the RFEM coordinates."""
    return {model.coordinate_names[k]: f.name for f in model.flexible_links
            for k in f.joint_indices}


def reference_problems(spec: ModelFile, model: Model) -> list:
    """'key.path: message' for every name in ``spec`` the model does not have, and the
    counts that do not fit it."""
    out = []
    coords = model.coordinate_names
    flex = _flexible_coordinates(model)
    rigid = [c for c in coords if c not in flex]
    for j in spec.joints:
        if j.name in flex:
            out.append(f"{j.key}.name: {j.name!r} is an RFEM coordinate of flexible link "
                       f"{flex[j.name]!r}; its spring and damper follow from the beam "
                       "(youngs_modulus, shear_modulus, bending_viscosity in [[flexible]])")
        elif j.name not in coords:
            out.append(f"{j.key}.name: " + _unknown("joint", j.name, rigid))
    for d in spec.drives:
        if d.joint not in coords:
            out.append(f"{d.key}.joint: " + _unknown("coordinate", d.joint, coords))
    frames = sorted(model.frames) + [lk.name for lk in model.links if lk.name not in model.frames]
    for c in spec.constraints:
        field = "frames" if isinstance(c, PairConstraintSpec) else "frame"
        for frame in constraint_frames(c):
            if frame not in frames:
                out.append(f"{c.key}.{field}: " + _unknown("frame or link", frame, frames))
    for x in spec.point_springs:
        ends = [("frame", x.frame)] + ([("anchor", x.anchor)] if isinstance(x.anchor, str)
                                       else [])
        for field, frame in ends:
            if frame not in frames:
                out.append(f"{x.key}.{field}: " + _unknown("frame or link", frame, frames))
    for p in spec.programmes:
        if p.joint not in coords:
            out.append(f"{p.key}.joint: " + _unknown("coordinate", p.joint, coords))
    m = spec.n_constraints
    if m > model.n_coordinates:
        out.append(f"constraint: {m} constraints ([[constraint]] + [[programme]]) on "
                   f"{model.n_coordinates} coordinates {list(coords)}; at most one per "
                   "coordinate")
    for ref in spec.references:
        for column in ref.values:
            name = column[:-4] if column.endswith("_dot") and column not in coords else column
            if name not in coords:
                key = "q_dot" if name != column else "q"
                out.append(f"{ref.key}.{key}.{name}: " + _unknown("coordinate", name, coords))
    for name in spec.solver.dependent or ():
        if name not in coords:
            out.append("solver.dependent: " + _unknown("coordinate", name, coords))
    for key, values in (("q", spec.initial.q), ("q_dot", spec.initial.q_dot)):
        for name in values:
            if name not in coords:
                out.append(f"initial.{key}.{name}: " + _unknown("coordinate", name, coords))
    if spec.initial.static_flexible:
        if not flex:
            out.append("initial.static_flexible: the model has no flexible links "
                       "([[flexible]] or [model.crane] n_rfe > 0)")
        given = sorted(set(spec.initial.q) & set(flex))
        if given:
            out.append(f"initial.q: {given} are set by static_flexible = true (their gravity "
                       "sag); remove them from initial.q or set static_flexible = false")
    return out


# ====================================================================== assembly
def assemble(spec: ModelFile, source: SourceModel) -> Scenario:
    """The Scenario of a valid ``spec`` on its ``source`` model (reference_problems empty).

    Raises ModelFileError (an expression not finite at the initial state, a model the
    file's springs make invalid) or ConstraintError (the initial state cannot be placed on
    the constraints, the constraint Jacobian is singular there).
    """
    label = str(spec.path)
    notes = list(source.notes)
    model = source.model
    changes = {}
    for j in spec.joints:
        changes[j.name] = {k: getattr(j, k) for k in ("stiffness", "spring_reference", "damping")
                           if getattr(j, k) is not None}
    drives = tuple(Drive(d.joint, d.function) for d in spec.drives)
    if model.drives and model.drives != drives:
        notes.append(("drives of the source replaced by the file's [[drive]] list" if drives
                      else "drives of the source dropped (the file has no [[drive]]; it lists "
                      "every drive)") + ": "
                     + ", ".join(f"{d.joint}: {d.function!r}" for d in model.drives))
    frames = dict(model.frames)
    link_index = {lk.name: k for k, lk in enumerate(model.links)}
    # a link named where a frame is asked for: its joint frame
    named = [(c, f) for c in spec.constraints for f in constraint_frames(c)] + \
        [(x, f) for x in spec.point_springs
         for f in [x.frame] + ([x.anchor] if isinstance(x.anchor, str) else [])]
    for entry, frame in named:
        if frame not in frames:
            frames[frame] = Frame(frame, link_index[frame], np.eye(4))
            notes.append(f"{entry.key}: frame {frame!r} is the frame of link {frame!r} (its "
                         "joint frame; the entry acts on its origin and axes)")
    for d in spec.drives:
        if isinstance(d.function, Tabulated):
            notes.append(_table_note(d.key, d.function, "N or N m"))
    for c in spec.constraints:
        if isinstance(c, CoordinateConstraintSpec) and isinstance(c.function, Tabulated):
            notes.append(_table_note(f"{c.key}.function", c.function, "m"))
    try:
        if changes:
            model = model.with_changes(joint_changes=changes)
        springs = model.point_springs + tuple(
            PointSpring(x.name, x.frame, x.anchor if isinstance(x.anchor, str)
                        else tuple(x.anchor), x.stiffness, x.free_length, x.damping)
            for x in spec.point_springs)
        model = Model(model.joints, model.links, frames, drives, model.gravity,
                      model.flexible_links, model.name, model.geometry, springs)
        validate_model(model)
    except ModelError as exc:
        raise ModelFileError([f"{label}: joint: {p}" for p in exc.problems]) from None

    constraints = [row for c in spec.constraints for row in _constraint(c)]
    constraints += [JointProgramme(p.joint, SympyTimeFunction(p.expression, ex.symbol("t")),
                                   name=p.name) for p in spec.programmes]
    system = ProgrammedMotion(model, constraints, dependent=spec.solver.dependent,
                              baumgarte=spec.solver.baumgarte)

    q0 = model.spring_reference.copy()
    for name, v in spec.initial.q.items():
        q0[model.index(name)] = v
    q_dot0 = np.zeros(model.n_coordinates)
    for name, v in spec.initial.q_dot.items():
        q_dot0[model.index(name)] = v
    flex = sorted(_flexible_coordinates(model), key=model.index)
    if spec.initial.static_flexible:
        q0 = static_equilibrium(model, q0, flex)
        notes.append(f"initial: {len(flex)} flexible coordinates in their static sag under "
                     "gravity (static_flexible = true)"
                     + (", computed again at the pose placed on the constraints"
                        if spec.initial.on_constraints else ""))
    _check_finite_at(spec, model, q0, label)
    if system.dependent is None:
        system = system.with_pivoted_dependent(0.0, q0, q_dot0)
        chosen = system.dependent
        if chosen:
            notes.append(f"solver: dependent coordinates {list(chosen)} chosen by pivoting on "
                         "the constraint Jacobian at q0 (give [solver] dependent to fix them)")
    if spec.initial.on_constraints:
        q0, q_dot0 = _on_constraints(system, q0, q_dot0, label)
        if spec.initial.static_flexible:
            # the sag of the placed pose, then placed again (the sag moves the frames a little)
            q0 = static_equilibrium(model, q0, flex)
            q0, q_dot0 = _on_constraints(system, q0, q_dot0, label)
        _check_finite_at(spec, model, q0, label)
    run = spec.run
    dt = run.dt
    if run.integrator == "RK4":
        # the springs, dampers, inertia and Baumgarte rates at q0 (gpme_core.stability)
        limit, _ = rk4_limit(system, 0.0, q0, np.zeros_like(q0), how="springs")
        if dt is None:
            dt = safe_step(limit, run.output_dt)      # = stability.rk4_step(system, q0, ...)
            notes.append(f"run: RK4 step dt = {dt:.3g} s suggested at q0 ({STEP_SAFETY:g} x the "
                         "RK4 stability limit of the springs, dampers and Baumgarte rates, at "
                         "most output_dt)")
        elif dt > limit:
            notes.append(f"run: dt = {dt:g} s is above the RK4 stability limit "
                         f"{limit:.3g} s estimated at q0; the run may diverge")
    return Scenario(name=model.name, model=model, constraints=tuple(constraints), system=system,
                    q0=q0, q_dot0=q_dot0, t_end=run.t_end, quick_t_end=run.quick_t_end,
                    integrator=run.integrator, dt=dt, output_dt=run.output_dt,
                    source=spec.path, urdf=source.urdf, chain=source.chain,
                    frozen=dict(source.frozen), notes=tuple(notes),
                    tolerances=spec.tolerance_map(), on_constraints=spec.initial.on_constraints,
                    engine_steps=spec.engine_step_map(), references=spec.references,
                    yield_strengths=_yield_strengths(spec, model))


def _yield_strengths(spec, model):
    """{flexible link name: Pa} from [[flexible]] yield_strength, or the crane's arm."""
    if isinstance(spec.model.source, CraneSource):
        strength = _crane_parameters(spec).arm_yield_strength
        return {f.name: strength for f in model.flexible_links}
    return {f.link: f.yield_strength for f in spec.flexible if f.yield_strength is not None}


def _constraint(c) -> list:
    """The gpme_core constraints of one [[constraint]] entry (several rows for a
    coincidence, an alignment or a weld), named as ``constraint_rows`` says."""
    if isinstance(c, PairConstraintSpec):
        return _pair_constraints(c)
    if isinstance(c, ExpressionConstraintSpec):
        return [SympyPointConstraint(c.phi, frame=c.frame, name=c.name)]
    if isinstance(c, EllipseConstraintSpec):
        return [EllipseConstraint(c.a, c.b, center=c.center, frame=c.frame, name=c.name)]
    return [CoordinateProgramme(c.function, axis=c.axis, frame=c.frame, name=c.name)]


def _pair_constraints(c) -> list:
    a, b = c.frames
    if c.kind == "expression":
        return [SympyPairConstraint(c.phi, a, b, name=c.name)]
    if c.kind == "relative":
        return [RelativeCoordinate(a, b, c.axis, c.function, name=c.name)]
    if c.kind == "distance":
        return [Distance(a, b, c.function, name=c.name)]
    rows = {"coincident": lambda: coincident(a, b, c.axes, name=c.name),
            "aligned": lambda: aligned(a, b, name=c.name),
            "weld": lambda: weld(a, b, name=c.name)}[c.kind]()
    assert tuple(r.name for r in rows) == c.row_names
    return rows


def _table_note(key: str, fn: Tabulated, unit: str) -> str:
    start, end = fn.end_rates()
    return (f"{key}: table held constant outside [{fn.times[0]:g}, {fn.times[-1]:g}] s; its "
            f"rate jumps to 0 there (from {start:.3g} and {end:.3g} {unit}/s)")


def _check_finite_at(spec: ModelFile, model: Model, q0, label: str) -> None:
    """Every expression constraint, its gradient, Hessian and time derivatives finite at
    (t = 0, q0); else ModelFileError naming where the expression is not smooth."""
    kin = chain_kinematics(model, q0)
    problems = []
    for c in spec.constraints:
        if isinstance(c, PairConstraintSpec) and c.kind == "expression":
            problem = _pair_expression_problem(model, kin, c, label)
            if problem:
                problems.append(problem)
            continue
        if not isinstance(c, ExpressionConstraintSpec):
            continue
        fr = model.frame(c.frame)
        p = (kin.T[fr.link_index] @ fr.transform[:, 3])[:3]
        bad = SympyPointConstraint(c.phi, frame=c.frame, name=c.name).non_finite_terms(p, 0.0)
        if not bad:
            continue
        sets = ex.singular_sets(c.phi)
        problems.append(
            f"{label}: {c.key}.phi: constraint {c.name!r} = {c.text!r} or its first or second "
            f"derivatives are not finite at the initial state (t = 0 s, frame {c.frame!r} at "
            f"x, y, z = {', '.join(f'{v:.6g}' for v in p)} m): {bad}"
            + (f"; it is not smooth {'; '.join(sets)}" if sets else "")
            + "; the GPME needs phi twice differentiable along the motion")
    if problems:
        raise ModelFileError(problems)


def _pair_expression_problem(model: Model, kin, c, label: str) -> str:
    """'' when a pair expression and its derivatives are finite at (t = 0, kin), else the
    problem (the frames' origins, what is not finite, where the formula is not smooth)."""
    spec = SympyPairConstraint(c.phi, *c.frames, name=c.name)
    ends = []
    for frame in c.frames:
        fr = model.frame(frame)
        ends.append((kin.T[fr.link_index] @ fr.transform[:, 3])[:3])
    try:
        spec.local_terms(np.concatenate(ends), 0.0)
        return ""
    except ConstraintError as exc:
        sets = ex.singular_sets(c.phi)
        return (f"{label}: {c.key}.phi: {exc}" + (f"; it is not smooth {'; '.join(sets)}"
                                                   if sets else ""))


def _on_constraints(system: ProgrammedMotion, q0, q_dot0, label: str):
    phi, _, _, _ = system.constraints(0.0, q0, q_dot0)
    values = ", ".join(f"{n} = {v:.6g}" for n, v in zip(system.constraint_names, phi))
    try:
        return system.consistent_state(0.0, q0, q_dot0)
    except ConstraintError as exc:
        raise ConstraintError(f"{label}: initial.on_constraints = true: {exc}. At the given "
                              f"q0 the constraints are {values}; change initial.q or the "
                              "constraints so that they can be met") from None
