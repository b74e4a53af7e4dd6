"""A ProgrammedMotion packed for the fused compiled kernels (gpme_core.kernels).

:func:`for_system` gives a :class:`CompiledSystem` (or None with the reason when the system
cannot be compiled).  What compiles:

* constraints: EllipseConstraint, CoordinateProgramme, JointProgramme,
  SympyPointConstraint and the pair constraints RelativeCoordinate, Distance,
  AxisAlignment and SympyPairConstraint (the SymPy ones' phi and derivatives generated as
  straight-line code after SymPy's common-subexpression elimination, compiled by numba
  once);
* time functions of programmes and drives: Constant, Cosine, Sine, QuinticRamp,
  Tabulated and SympyTimeFunction (generated the same way);
* point springs (gpme_core.point_springs), their ends in the same table of points.

Anything else (a PointConstraint or TimeFunction subclass of the user's, a drive given as
a plain Python callable) keeps the Python path: gpme_core.integrate uses it and says why.
The class of each object is checked exactly (a subclass may override what it computes).

Numeric parameters are passed to the kernels as arrays, so changing a mass, a length, an
ellipse or a programme's amplitude does not recompile; only SymPy expressions become code.
Systems without SymPy parts use gpme_core.kernels itself; with them, a module is
generated from gpme_core/kernels.py with the stub section replaced, written once per
distinct source under GPME_KERNEL_CACHE (default ~/.cache/gpme/kernels) and compiled by
numba with its on-disk cache, so a second process does not compile again.  That cache is
gpme_core.jit_cache's, as for gpme_core.kernels itself: its stamp covers the generated file
and the gpme_core modules it imports (fast.py), so an edit of fast.py compiles it again.
"""
import hashlib
import importlib.util
import os
import sys
import tempfile
from pathlib import Path
from typing import NamedTuple

import numpy as np
import sympy as sp
from sympy.printing.pycode import PythonCodePrinter

from . import fast, kernels
from .constraints import (CoordinateProgramme, EllipseConstraint, JointProgramme,
                          SympyPointConstraint)
from .errors import OutputWriteError
from .gpme import SINGULAR_RCOND
from .pair_constraints import (PAIR_SYMBOL_NAMES, AxisAlignment, Distance,
                               RelativeCoordinate, SympyPairConstraint)
from .time_functions import (Constant, Cosine, QuinticRamp, Sine, SympyTimeFunction,
                             Tabulated)

# |q| or |q_dot| above this means the run has blown up (SI units: m, rad, m/s, rad/s); the
# compiled loops and gpme_core.integrate (which imports it) stop a run there
DIVERGENCE_LIMIT = 1e6
_BEGIN = "# --- user functions: begin ---"
_END = "# --- user functions: end ---"



class NotCompilable(Exception):
    """The system holds a part the kernels cannot express (the message says which)."""


class _Tables:
    """Time functions, points and generated SymPy code collected while packing."""

    def __init__(self):
        self.f_kind, self.f_off, self.f_par = [], [], []
        self.user_times, self.user_points, self.user_pairs = [], [], []
        self.points = {}

    def time_function(self, fn, label):
        kind = type(fn)
        if kind is Constant:
            entry = (kernels.F_CONSTANT, [fn.level])
        elif kind is Cosine:
            entry = (kernels.F_COSINE, [fn.offset, fn.amplitude, fn.omega])
        elif kind is Sine:
            entry = (kernels.F_SINE, [fn.offset, fn.amplitude, fn.omega, fn.phase])
        elif kind is QuinticRamp:
            entry = (kernels.F_QUINTIC, [fn.level, fn.ramp_time])
        elif kind is Tabulated:
            coef = np.asarray(fn._coefficients, dtype=float).ravel()
            entry = (kernels.F_TABULATED, [len(fn.times), *fn.times, *coef, fn.values[0],
                                           fn.values[-1]])
        elif kind is SympyTimeFunction:
            self.user_times.append(fn)
            entry = (kernels.F_USER, [len(self.user_times) - 1])
        else:
            raise NotCompilable(f"{label} is a {kind.__name__}, which the compiled kernels do "
                                "not know (they know Constant, Cosine, Sine, QuinticRamp, "
                                "Tabulated and SympyTimeFunction)")
        self.f_kind.append(entry[0])
        self.f_off.append(sum(len(p) for p in self.f_par))
        self.f_par.append([float(v) for v in entry[1]])
        return len(self.f_kind) - 1

    def point(self, link, r_local, w=1.0):
        """Index of the vector (r_local (3,), homogeneous w: 1 a point, 0 a direction)
        fixed on ``link`` in the table of vectors whose kinematics the kernels compute."""
        key = (int(link), tuple(float(v) for v in r_local), float(w))
        return self.points.setdefault(key, len(self.points))


class UserCode(NamedTuple):
    """The SymPy parts of a system that become generated code: point constraints, pair
    constraints and time functions, each numbered in the order of this tuple."""

    points: tuple = ()
    pairs: tuple = ()
    times: tuple = ()


def pack(system):
    """(md, cd, UserCode) of ``system`` for gpme_core.kernels (layout in its docstring);
    NotCompilable names the first part that cannot be compiled."""
    model = system.model
    tables = _Tables()
    m = system.n_constraints
    c_kind = np.zeros(m, dtype=np.int64)
    c_point = np.zeros(m, dtype=np.int64)
    c_fun = np.full(m, -1, dtype=np.int64)
    c_point_b = np.full(m, -1, dtype=np.int64)
    c_par = np.zeros((m, 4))
    for c, (spec, bound) in enumerate(zip(system.constraint_specs, system.bound)):
        kind = type(spec)
        label = f"constraint {spec.name!r}"
        if kind in _PAIR_KINDS:
            c_kind[c] = _PAIR_KINDS[kind]
            if kind is SympyPairConstraint:
                tables.user_pairs.append(spec)
                c_par[c, 0] = len(tables.user_pairs) - 1
            else:
                c_fun[c] = tables.time_function(spec.function, f"the programme of {label}")
                if kind is RelativeCoordinate:
                    c_par[c, 0] = spec.axis
            (link_a, vec_a, w_a), (link_b, vec_b, w_b) = bound.ends
            c_point[c] = tables.point(link_a, vec_a, w_a)
            c_point_b[c] = tables.point(link_b, vec_b, w_b)
            continue
        if kind is JointProgramme:
            c_kind[c] = kernels.C_JOINT
            c_par[c, 0] = bound.k
            c_fun[c] = tables.time_function(spec.function, f"the programme of {label}")
            continue
        if kind is EllipseConstraint:
            c_kind[c] = kernels.C_ELLIPSE
            c_par[c] = (1.0 / spec.a ** 2, 1.0 / spec.b ** 2, spec.center[0], spec.center[1])
        elif kind is CoordinateProgramme:
            c_kind[c] = kernels.C_COORDINATE
            c_par[c, 0] = spec.axis
            c_fun[c] = tables.time_function(spec.function, f"the programme of {label}")
        elif kind is SympyPointConstraint:
            c_kind[c] = kernels.C_USER_POINT
            tables.user_points.append(spec)
            c_par[c, 0] = len(tables.user_points) - 1
        else:
            raise NotCompilable(f"{label} is a {kind.__name__}, which the compiled kernels do "
                                "not know (they know EllipseConstraint, CoordinateProgramme, "
                                "JointProgramme, SympyPointConstraint, RelativeCoordinate, "
                                "Distance, AxisAlignment and SympyPairConstraint)")
        c_point[c] = tables.point(bound.link, bound.r_local)
    d_coord, d_fun = [], []
    for d in model.drives:
        d_coord.append(model.index(d.joint))
        d_fun.append(tables.time_function(d.function, f"the drive on {d.joint!r}"))
    s_a, s_b, s_par = [], [], []
    for spring in model.point_springs:
        fr = model.frame(spring.frame)
        s_a.append(tables.point(fr.link_index, fr.transform[:3, 3]))
        if isinstance(spring.anchor, str):
            fb = model.frame(spring.anchor)
            s_b.append(tables.point(fb.link_index, fb.transform[:3, 3]))
            anchor = (0.0, 0.0, 0.0)
        else:
            s_b.append(-1)
            anchor = tuple(float(v) for v in spring.anchor)
        s_par += [spring.stiffness, spring.free_length, spring.damping, *anchor]
    p_link = [k[0] for k in tables.points]
    p_r = [v for k in tables.points for v in (*k[1], k[2])]
    f_par = [v for p in tables.f_par for v in p]
    ints = ([m, len(p_link), len(tables.f_kind), len(d_coord), len(s_a)] + c_kind.tolist()
            + c_point.tolist() + c_fun.tolist() + c_point_b.tolist() + p_link
            + tables.f_kind + tables.f_off
            + d_coord + d_fun + s_a + s_b)
    cd = (np.array(ints, dtype=np.int64),
          np.concatenate([c_par.ravel(), np.array(p_r, dtype=float),
                          np.array(s_par, dtype=float), np.array(f_par, dtype=float)]))
    mats = np.ascontiguousarray(np.stack([model.origins, model.generators,
                                          model.pseudo_inertias]), dtype=float)
    vecs = np.ascontiguousarray(np.stack([model.is_revolute.astype(float), model.stiffness,
                                          model.spring_reference, model.damping,
                                          model.lower_limits, model.upper_limits]),
                                dtype=float)
    md = (mats, vecs, np.ascontiguousarray(model.gamma, dtype=float),
          np.ascontiguousarray(model.parents, dtype=np.int64),
          np.ascontiguousarray(model.moves, dtype=np.bool_))
    return md, cd, UserCode(tuple(tables.user_points), tuple(tables.user_pairs),
                            tuple(tables.user_times))


_PAIR_KINDS = {RelativeCoordinate: kernels.C_RELATIVE, Distance: kernels.C_DISTANCE,
               AxisAlignment: kernels.C_AXIS_DOT, SympyPairConstraint: kernels.C_USER_PAIR}


# ---------------------------------------------------------------- code generation
def _straight_line(name, args, exprs, n_out):
    """Source of an njit function ``name(*args, out)`` writing exprs into out[0..n_out)
    after common-subexpression elimination (math module calls)."""
    printer = PythonCodePrinter({"fully_qualified_modules": True, "standard": "python3"})
    replacements, reduced = sp.cse(list(exprs), symbols=sp.numbered_symbols("_cse"))
    lines = ["@_jit_user", f"def {name}({', '.join(str(a) for a in args)}, out):"]
    for sym, sub in replacements:
        lines.append(f"    {sym} = {printer.doprint(sub)}")
    for k, e in enumerate(reduced):
        lines.append(f"    out[{k}] = float({printer.doprint(e)})")
    assert len(reduced) == n_out
    return "\n".join(lines)


def _named_symbols(expr, names):
    by_name = {s.name: s for s in expr.free_symbols}
    return [by_name.get(nm, sp.Symbol(nm)) for nm in names]


def _dispatch(name, args, impls, n_out):
    lines = ["@_jit", f"def {name}(index, {', '.join(args)}, out):"]
    for k, impl in enumerate(impls):
        lines.append(f"    {'if' if k == 0 else 'elif'} index == {k}:")
        lines.append(f"        {impl}({', '.join(args)}, out)")
    lines.append("    " + ("else:\n        " if impls else "") + f"for i in range({n_out}):")
    lines.append(("        " if impls else "    ") + "    out[i] = np.nan")
    return "\n".join(lines)


def user_source(user):
    """Python source of the user-function section for these SymPy constraints and time
    functions (a UserCode; gpme_core.kernels' stubs replaced)."""
    parts, point_impls, pair_impls, time_impls = [], [], [], []
    for k, spec in enumerate(user.points):
        x, y, z, t = _named_symbols(spec.expr, ("x", "y", "z", "t"))
        phi = spec.expr
        grad = [sp.diff(phi, v) for v in (x, y, z)]
        hess = [sp.diff(g, v) for g in grad for v in (x, y, z)]
        phi_t = sp.diff(phi, t)
        grad_t = [sp.diff(phi_t, v) for v in (x, y, z)]
        exprs = [phi, *grad, *hess, phi_t, *grad_t, sp.diff(phi_t, t)]
        fname = f"_user_point_{k}"
        parts.append(_straight_line(fname, (x, y, z, t), exprs, 18))
        point_impls.append(fname)
    for k, spec in enumerate(user.pairs):
        syms = _named_symbols(spec.expr, PAIR_SYMBOL_NAMES)
        s, t = syms[:6], syms[6]
        phi = spec.expr
        grad = [sp.diff(phi, v) for v in s]
        hess = [sp.diff(g, v) for g in grad for v in s]
        phi_t = sp.diff(phi, t)
        grad_t = [sp.diff(phi_t, v) for v in s]
        exprs = [phi, *grad, *hess, phi_t, *grad_t, sp.diff(phi_t, t)]
        fname = f"_user_pair_{k}"
        parts.append(_straight_line(fname, syms, exprs, kernels.N_PAIR_TERMS))
        pair_impls.append(fname)
    for k, fn in enumerate(user.times):
        t = fn.t_symbol
        exprs = [fn.expr, sp.diff(fn.expr, t), sp.diff(fn.expr, t, 2)]
        fname = f"_user_time_{k}"
        parts.append(_straight_line(fname, (t,), exprs, 3))
        time_impls.append(fname)
    parts.append(_dispatch("user_point_terms", ("x", "y", "z", "t"), point_impls, 18))
    parts.append(_dispatch("user_pair_terms", PAIR_SYMBOL_NAMES, pair_impls,
                           kernels.N_PAIR_TERMS))
    parts.append(_dispatch("user_time_terms", ("t",), time_impls, 3))
    return "\n\n\n".join(parts) + "\n"


def kernel_cache_dir():
    """Directory of the generated kernel modules (GPME_KERNEL_CACHE or ~/.cache/gpme/kernels)."""
    return Path(os.environ.get("GPME_KERNEL_CACHE") or Path.home() / ".cache" / "gpme" / "kernels")


_MODULES = {}


# Not gpme_io.atomic (the output writers, a layer above): the engine writes only its own
# cache of generated code, with this small atomic write of its own.
def _write_cached_module(path, source):
    """Write a generated kernel module into the engine's own disk cache atomically (a
    temporary file beside it moved into place), so another process never imports half a
    file.  This cache is the engine's compiled code, not output: the output writers live in
    gpme_io.atomic (the engine writes no results, issue 25).  A file-system failure raises
    OutputWriteError naming the file."""
    tmp = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(source)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)   # mkstemp makes 0600; readable as numba's cache is
        os.replace(tmp, path)
    except OSError as exc:
        if tmp is not None:
            try:
                os.unlink(tmp)
            except OSError:
                pass                    # already moved into place, or its folder went away
        raise OutputWriteError(path, exc) from None


def generated_kernels(user):
    """gpme_core.kernels itself without SymPy parts (a UserCode), else the generated
    module for them."""
    if not (user.points or user.pairs or user.times):
        return kernels
    template = Path(kernels.__file__).read_text(encoding="utf-8")
    head, rest = template.split(_BEGIN, 1)
    _, tail = rest.split(_END, 1)
    source = (head.replace("from .fast import (", "from gpme_core.fast import (_jit_user, ")
              + _BEGIN + "\n\n\n" + user_source(user) + "\n" + _END + tail)
    digest = hashlib.sha256(source.encode("utf-8")).hexdigest()[:20]
    if digest in _MODULES:
        return _MODULES[digest]
    path = kernel_cache_dir() / f"gpme_kernels_{digest}.py"
    if not path.exists() or path.read_text(encoding="utf-8") != source:
        _write_cached_module(path, source)
    name = f"gpme_generated_kernels_{digest}"
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    _MODULES[digest] = module
    return module


class CompiledSystem:
    """The arrays of one ProgrammedMotion and the kernels module that evaluates them.

    md, cd : data tuples (gpme_core.kernels); module: gpme_core.kernels or a generated one.
    The partition (ic, dc) is an argument of every call: it belongs to the run.
    """

    def __init__(self, system):
        self.system = system
        self.md, self.cd, user = pack(system)
        self.module = generated_kernels(user)
        self.n = system.model.n_coordinates
        self.m = system.n_constraints
        self.paper_eq7 = 1.0 if system.damping_form == "paper-eq7" else 0.0

    def options(self, switch_below=None):
        """The opts array of gpme_core.kernels (switch_below None: never switch)."""
        return np.array([self.system.alpha, self.system.beta, self.paper_eq7,
                         0.0 if switch_below is None else switch_below, SINGULAR_RCOND,
                         DIVERGENCE_LIMIT], dtype=float)

    @property
    def n_points(self):
        """Number of distinct constrained points."""
        return int(self.cd[0][1])

    def evaluate(self, t, q, q_dot, ic, dc, switch_below=None):
        """(status, q_ddot (n,), multipliers (m,), info (kernels.INFO_SIZE,)) at (t, q, q_dot)."""
        q_ddot = np.empty(self.n)
        lam = np.empty(self.m)
        info = np.empty(kernels.INFO_SIZE)
        status = fast.run(self.module.evaluate, float(t), fast.state_array(q),
                          fast.state_array(q_dot), self.md, self.cd,
                          self.options(switch_below), ic, dc, q_ddot, lam, info,
                          self.workspace())
        return status, q_ddot, lam, info

    def workspace(self):
        """A fresh float workspace for gpme_core.kernels.evaluate."""
        return np.empty(self.module.workspace_size(self.n, self.m, self.n_points))

    def accelerator(self, ic, dc):
        """A function (t, q, q_dot) -> q_ddot (n,) for a fixed partition, its buffers
        allocated once (the benchmark's one evaluation); raises RuntimeError with the
        status when an evaluation fails."""
        evaluate, md, cd, opts = self.module.evaluate, self.md, self.cd, self.options()
        q_ddot, lam, info = np.empty(self.n), np.empty(self.m), np.empty(kernels.INFO_SIZE)
        ws = self.workspace()

        def accelerations(t, q, q_dot):
            status = evaluate(t, q, q_dot, md, cd, opts, ic, dc, q_ddot, lam, info, ws)
            if status != kernels.OK:
                raise RuntimeError(f"compiled evaluation failed with status {status}")
            return q_ddot
        return accelerations


def for_system(system):
    """(CompiledSystem or None, reason): the compiled form of ``system``, cached on it; None
    when gpme_core.fast is disabled (GPME_NO_JIT=1) or a part cannot be compiled."""
    if not fast.ENABLED:
        return None, "compiled kernels disabled (GPME_NO_JIT)"
    cached = system.__dict__.get("_compiled")
    if cached is not None and cached[0] is system.bound:    # copies share the constraints
        return cached[1]
    try:
        result = (CompiledSystem(system), "")
    except NotCompilable as exc:
        result = (None, str(exc))
    system.__dict__["_compiled"] = (system.bound, result)
    return result
