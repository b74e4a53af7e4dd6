"""Checks of the SymPy expressions a user gives gpme_core (constraints phi(x, y, z, t),
programmes and drives f(t)): what is refused when the expression is built, and the words
used when its value is not finite during a run.

The GPME needs the second derivative of every constraint and programme (kappa, the
programmed acceleration), so an expression is refused at construction, with every problem
listed at once, when it

- is not a scalar SymPy expression (or a string SymPy reads as one),
- uses a symbol other than the allowed ones, or an undefined function ``f(x)``,
- holds a constant that is not a finite real number (``I``, ``zoo``, ``oo``, ``nan``,
  ``asin(2)``, a float beyond float64's range),
- holds a function whose second derivative does not exist everywhere
  (:data:`NON_SMOOTH_TYPES`: Abs, sign, Heaviside, DiracDelta, Piecewise, Max, Min, floor,
  ceiling, frac, Mod, re, im, arg, conjugate, ...), or whose SymPy derivatives contain one,
- or cannot be written as code by ``sympy.lambdify`` (a function Python's math module
  and numpy do not know, an unevaluated Derivative or Integral):
  :func:`compile_expressions` finds it when the code is generated, not at the first call.

The compiled expressions are evaluated in the inner loop with Python's math module on
floats (as fast as numpy on scalars without ``np.errstate``, which costs more than the
evaluation; math raises instead of warning out of a domain), and only where that fails or
gives a value that is not finite, again with numpy in float64 under ``np.errstate`` to
name which values are not finite (:data:`MODULES`).

Functions smooth only on part of the line (sqrt, log, division, asin, ...) are accepted;
:func:`singular_sets` names where they are not smooth or leave their domain, for the
message given when a value is not finite.  The table of refused functions and its reasons
is the one gpme_io.expressions uses for model files (:data:`NON_SMOOTH`).
"""
import builtins
import dis
import math
from typing import Callable, Mapping, Sequence

import numpy as np
import sympy as sp
from sympy.core.function import AppliedUndef

from . import expression_bounds as bounds

SMOOTH_HINT = ("the GPME needs the second derivative of every constraint and programme "
               "(kappa, the programmed acceleration); write a smooth form")

_ABS = "its derivative jumps where its argument is 0 (use e.g. sqrt(u**2 + eps**2))"
_STEP = "it jumps at 0 (use e.g. tanh(u/eps))"
_KINK = ("it has a kink where its arguments are equal (use e.g. (a + b + sqrt((a - b)**2 "
         "+ eps**2))/2 for Max, with - for Min)")
_INTEGER = "it jumps at every integer"
_COMPLEX = ("it is a part of a complex number and SymPy gives it no derivative on the real "
            "line; constraints and programmes are real: write the real expression itself")
# (SymPy class or None, names in a model file, why it is refused)
_TABLE = (
    (sp.Abs, ("abs", "Abs"), _ABS),
    (sp.sign, ("sign", "sgn"), _STEP),
    (sp.Heaviside, ("Heaviside",), _STEP),
    (sp.DiracDelta, ("DiracDelta",), "it is a distribution, not a function"),
    (sp.Piecewise, ("Piecewise",), "its pieces meet without a continuous second derivative"),
    (sp.Max, ("Max", "max"), _KINK),
    (sp.Min, ("Min", "min"), _KINK),
    (sp.floor, ("floor",), _INTEGER),
    (sp.ceiling, ("ceiling", "ceil"), _INTEGER),
    (None, ("round",), "it jumps at every half-integer"),
    (sp.frac, ("frac",), _INTEGER),
    (sp.Mod, ("Mod",), "it jumps at every multiple of its modulus (use sin and cos of an "
                       "angle rather than the angle modulo 2 pi)"),
    (sp.re, ("re",), _COMPLEX),
    (sp.im, ("im",), _COMPLEX),
    (sp.conjugate, ("conjugate",), _COMPLEX),
    (sp.arg, ("arg",), "it jumps at 0 on the real line (0 for u > 0, pi for u < 0)"),
    (sp.KroneckerDelta, ("KroneckerDelta",), "it jumps where its arguments are equal"),
    (sp.SingularityFunction, ("SingularityFunction",),
     "its derivatives are Heaviside steps and DiracDelta distributions"),
)
NON_SMOOTH = {name: reason for _, names, reason in _TABLE for name in names}
"""{function name as written in a model file: why it is refused}."""
NON_SMOOTH_TYPES = {cls: reason for cls, _, reason in _TABLE if cls is not None}
"""{SymPy class: why it is refused}."""


def non_smooth_parts(expr: sp.Basic) -> list:
    """[(subexpression, reason), ...] of the refused functions in ``expr``, in text order."""
    found = expr.atoms(*NON_SMOOTH_TYPES)
    return [(a, next(r for c, r in NON_SMOOTH_TYPES.items() if isinstance(a, c)))
            for a in sorted(found, key=str)]


def singular_sets(expr: sp.Expr) -> list:
    """Where the parts of ``expr`` that are smooth only on part of the line are not:
    e.g. ['sqrt: where x**2 - 1 <= 0', 'division: where x - 2 = 0']."""
    seen: dict = {}
    return [seen.setdefault(s, s) for s, _ in singular_parts(expr) if s not in seen]


def singular_parts(expr: sp.Expr) -> list:
    """[(where, w), ...]: each part of ``expr`` smooth only on part of the line, in words as
    :func:`singular_sets` gives it, with the expression w whose zero bounds that set
    (sqrt(u), log(u), 1/u, u**r: u; asin(u), acos(u), atanh(u): 1 - u**2; acosh(u): u - 1;
    tan(u): cos(u); atan2(y, x): x**2 + y**2).  Repeated parts are listed once."""
    out = []
    for sub in sp.preorder_traversal(expr):
        if isinstance(sub, sp.Pow):
            base, e = sub.args
            if base.is_number:
                continue
            if not e.is_number:
                out.append((f"power: where {base} <= 0", base))
            elif e.is_integer:
                if e.is_negative:
                    out.append((f"division: where {base} = 0", base))
            elif e == sp.Rational(1, 2):
                out.append((f"sqrt: where {base} <= 0", base))
            elif e == sp.Rational(-1, 2):
                out.append((f"1/sqrt: where {base} <= 0", base))
            else:
                out.append((f"power {e}: where {base} <= 0", base))
        elif isinstance(sub, sp.log):
            out.append((f"log: where {sub.args[0]} <= 0", sub.args[0]))
        elif isinstance(sub, (sp.asin, sp.acos, sp.atanh)):
            out.append((f"{type(sub).__name__}: where |{sub.args[0]}| >= 1",
                        1 - sub.args[0] ** 2))
        elif isinstance(sub, sp.acosh):
            out.append((f"acosh: where {sub.args[0]} <= 1", sub.args[0] - 1))
        elif isinstance(sub, sp.tan):
            out.append((f"tan: where cos({sub.args[0]}) = 0", sp.cos(sub.args[0])))
        elif isinstance(sub, sp.atan2):
            out.append((f"atan2: where {sub.args[0]} = {sub.args[1]} = 0",
                        sub.args[0] ** 2 + sub.args[1] ** 2))
    seen: dict = {}
    return [seen.setdefault(p[0], p) for p in out if p[0] not in seen]


def term_scale(w: sp.Expr) -> sp.Expr:
    """The size of the terms ``w`` is made of: the |.| of every term of a sum, added, and of
    every factor of a product, multiplied; so |w| / term_scale(w) is 1 without
    cancellation and small where w's terms cancel (w near its zero relative to them)."""
    if isinstance(w, sp.Add):
        return sp.Add(*[term_scale(a) for a in w.args])
    if isinstance(w, sp.Mul):
        return sp.Mul(*[term_scale(a) for a in w.args])
    if isinstance(w, sp.Pow) and w.exp.is_Integer and w.exp > 0:
        return term_scale(w.base) ** w.exp
    return sp.Abs(w)


def why_not_finite(expr: sp.Expr, inputs) -> str:
    """'; where it is not smooth or out of its domain: <singular sets>' for a message about
    ``expr`` evaluated at the numbers ``inputs``, or why else its value is not finite."""
    if not all(math.isfinite(float(v)) for v in inputs):
        return "; the state it was evaluated at is itself not finite"
    sets = singular_sets(expr)
    if sets:
        return f"; where it is not smooth or out of its domain: {'; '.join(sets)}"
    return ("; it has no singular point known here: a value overflowed float64, or SymPy's "
            "formula of a derivative is 0/0 at this point (as sinc's at 0)")


# ====================================================================== construction
def read_expression(value: object, symbols: Mapping[str, sp.Symbol], label: str,
                    allowed: str) -> tuple:
    """(SymPy expression or None, [problem, ...]) of a user's ``value``.

    value   : a SymPy expression or a string read by ``sympy.sympify`` (code you trust:
              sympify evaluates it as Python; gpme_io.modelfile parses a file's text
              without eval).  A string is read unevaluated and evaluated node by node
              within gpme_core.expression_bounds (no power of 3.7e8 digits is started);
              any expression whose second derivatives would be too large is refused
    symbols : {name: symbol} of the allowed symbols; a symbol of the same name but other
              assumptions (``Symbol('x', real=True)``) is taken as the allowed one
    label   : what the expression is, starting every problem (e.g. "constraint 'Phi'")
    allowed : the allowed symbols in words, e.g. "x, y, z (world coordinates, m) and t (s)"

    Every check of the expression itself is made and every problem listed; the
    derivatives are checked by :func:`compile_expressions`.
    """
    if isinstance(value, str):
        try:
            unevaluated = sp.sympify(value, evaluate=False)
            shape = bounds.tree_problem(unevaluated)
            if shape:
                return None, [f"{label}: {_short(value)}: {shape}"]
            expr = bounds.evaluate_bounded(unevaluated)
        except bounds.BoundError as exc:
            return None, [f"{label}: {_short(value)}: {exc}"]
        except RecursionError:
            return None, [f"{label}: {_short(value)}: "
                          f"{bounds.shape_problem(bounds.MAX_DEPTH + 1, 0)}"]
        except Exception as exc:           # sympify evaluates the text: any error is possible
            cause = getattr(exc, "base_exc", None) or exc
            return None, [f"{label}: cannot read {_short(value)} as a SymPy expression "
                          f"({type(cause).__name__}: {_first_line(cause)})"]
    else:
        try:
            expr = sp.sympify(value, strict=True)
        except (sp.SympifyError, TypeError, ValueError) as exc:
            return None, [f"{label}: {_short(value)} is neither a SymPy expression nor a string "
                          f"({type(exc).__name__}; got a {type(value).__name__})"]
    if not isinstance(expr, sp.Expr) or isinstance(expr, (sp.MatrixBase, sp.MatrixExpr)):
        return None, [f"{label}: {_short(value)} is not a scalar expression in "
                      f"{', '.join(symbols)} "
                      f"(got a {type(expr).__name__})"]
    size = bounds.tree_problem(expr) or bounds.derivative_problem(expr)
    if size:                               # a deep tree is not printed (recursive printer)
        shown = _short(value) if isinstance(value, str) else "the expression"
        return None, [f"{label}: {shown}: {size}"]
    by_name = {s.name: s for s in symbols.values()}
    rename = {s: by_name[s.name] for s in expr.free_symbols
              if isinstance(s, sp.Symbol) and not isinstance(s, sp.Dummy)
              and s.name in by_name and s != by_name[s.name]}
    if rename:
        expr = expr.xreplace(rename)
    problems = []
    unknown = expr.free_symbols - set(symbols.values())
    if unknown:
        problems.append(f"{label}: expression {str(expr)!r} uses {sorted(map(str, unknown))}; "
                        f"only {allowed} {'is' if len(symbols) == 1 else 'are'} allowed")
    for f in sorted(expr.atoms(AppliedUndef), key=str):
        problems.append(f"{label}: {f} is an undefined function (sympy.Function("
                        f"{type(f).__name__!r})): gpme needs its formula to differentiate and "
                        "evaluate it; write the formula instead")
    problems += constant_problems(expr, label)
    for sub, reason in non_smooth_parts(expr):
        problems.append(f"{label}: {sub} is not smooth: {reason}; {SMOOTH_HINT}")
    return (None if problems else expr), problems


def constant_problems(expr: sp.Basic, label: str) -> list:
    """Problems of the constant parts of ``expr`` that are not finite real float64s."""
    out = []

    def walk(e):
        if not isinstance(e, sp.Expr):
            for a in e.args:
                walk(a)
            return
        if e.is_number and e.has(sp.zoo, sp.oo, sp.nan):
            out.append(f"{label}: {e} is infinite or undefined; constraints and programmes "
                       "must be finite")
            return
        if e.is_number and e.has(sp.I):
            out.append(f"{label}: {e} is complex; constraints and programmes are real")
            return
        if e.is_number:
            try:
                c = complex(e.evalf(20))
            except (TypeError, ValueError, ArithmeticError):
                return                     # not a plain number: compile_expressions judges it
            if not (math.isfinite(c.real) and math.isfinite(c.imag)):
                out.append(f"{label}: the constant {_short(e)} is beyond float64's range "
                           f"(|value| > {np.finfo(float).max:.3g})")
            elif c.imag != 0.0:
                out.append(f"{label}: the constant {_short(e)} = {c:.6g} is not a real number; "
                           "constraints and programmes are real")
            return
        for a in e.args:
            walk(a)
    walk(expr)
    seen: dict = {}
    return [seen.setdefault(s, s) for s in out if s not in seen]


MODULES = ("math", "numpy")
"""What the compiled expressions are evaluated with: Python's math module on floats in the
inner loop (fast; raises ValueError, ZeroDivisionError or OverflowError out of a domain,
never warns), numpy on float64 under ``np.errstate`` to say which values are not finite."""


def compile_expressions(args: Sequence[sp.Symbol], exprs: Sequence[sp.Expr], label: str,
                        source: sp.Expr) -> tuple:
    """({module: function} or None, [problem, ...]).

    For each module of :data:`MODULES`, ``sympy.lambdify(args, list(exprs), module)``,
    after checking that the derivatives ``exprs`` of ``source`` hold no refused function
    and that every name in the generated code exists (lambdify writes a function it
    cannot translate by its SymPy name, which would fail only when called)."""
    problems = []
    own = {a for a, _ in non_smooth_parts(source)}
    for e in exprs:
        for sub, reason in non_smooth_parts(e):
            if sub not in own:
                problems.append(f"{label}: SymPy's derivatives of {source} contain {sub}, "
                                f"which is not smooth: {reason}; {SMOOTH_HINT}")
    if problems:
        return None, list(dict.fromkeys(problems))
    out = {}
    for module in MODULES:
        try:
            f = sp.lambdify(tuple(args), list(exprs), module)
        except Exception as exc:           # the printer's own error, e.g. Unsupported: fresnels
            text = _first_line(exc)
            name = text.rsplit(":", 1)[-1].strip().strip("<>").replace("class ", "").strip("'")
            name = name.rsplit(".", 1)[-1]
            return None, [f"{label}: {_example(name, source, exprs)} (in {source} or its "
                          f"derivatives) cannot be written as {module} code ({text}); "
                          f"{_ELEMENTARY}"]
        missing = _unresolved_names(f)
        if missing:
            shown = ", ".join(_example(n, source, exprs) for n in missing)
            return None, [f"{label}: {shown} (in {source} or its derivatives) has no {module} "
                          "form: sympy.lambdify would write it as an unknown name that fails "
                          f"when called; {_ELEMENTARY}"]
        out[module] = f
    return out, []


_ELEMENTARY = ("write it with elementary functions (sin, cos, tan, asin, acos, atan, atan2, "
               "sinh, cosh, tanh, exp, log, sqrt, powers)")


def _example(name: str, source: sp.Expr, exprs: Sequence[sp.Expr]) -> str:
    """A subexpression of type ``name``: the first in ``source`` if it has one, else the
    shortest in its derivatives ``exprs``, else ``name`` itself."""
    for group in ((source,), exprs):
        found = sorted({str(s) for e in group for s in sp.preorder_traversal(e)
                        if type(s).__name__ == name}, key=lambda text: (len(text), text))
        if found:
            return found[0]
    return name


def _unresolved_names(f: Callable) -> list:
    """Global names the generated function ``f`` reads that neither its namespace nor
    Python's builtins define."""
    names = {i.argval for i in dis.get_instructions(f)
             if i.opname in ("LOAD_GLOBAL", "LOAD_NAME")}
    return sorted(n for n in names if n not in f.__globals__ and not hasattr(builtins, n))


def _short(value: object, limit: int = 80) -> str:
    """repr of ``value`` on one line, a long number in 6 digits, other long text cut."""
    if isinstance(value, sp.Basic) and value.is_number and len(str(value)) > limit:
        try:
            return str(sp.N(value, 6))
        except (TypeError, ValueError, ArithmeticError):
            pass
    text = " ".join((repr(value) if isinstance(value, str) else str(value)).split())
    return text if len(text) <= limit else text[:limit - 5] + " ..."


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip()
    return text.splitlines()[0] if text else type(exc).__name__


# ====================================================================== evaluation
def non_finite_text(names: Sequence[str], values: np.ndarray) -> str:
    """'phi = inf, grad[y] = -inf' for the entries of ``values`` (flat) that are not finite,
    named by ``names`` (same length)."""
    bad = np.flatnonzero(~np.isfinite(values))
    return ", ".join(f"{names[k]} = {values[k]:g}" for k in bad)


def evaluate_along(f: Callable, args: Sequence[np.ndarray], count: int) -> np.ndarray:
    """(k, count) values of a numpy function made by :func:`compile_expressions` at k
    points (``args``: one (k,) float64 array per argument); NaN where a value is not finite
    (never warns), and everywhere when evaluating raises."""
    k = len(args[0])
    with np.errstate(all="ignore"):
        try:
            values = f(*[np.asarray(a, dtype=np.float64) for a in args])
            out = np.column_stack([np.broadcast_to(np.asarray(v, dtype=float), (k,))
                                   for v in values]) if count else np.empty((k, 0))
        except (ArithmeticError, ValueError, TypeError):
            return np.full((k, count), np.nan)
    out[~np.isfinite(out)] = np.nan
    return out


def format_point(p) -> str:
    """'x, y, z = 0.1, -2, 0.3 m'."""
    return "x, y, z = " + ", ".join(f"{float(v):.6g}" for v in p) + " m"


def evaluation_failure(exc: BaseException) -> str:
    """'ZeroDivisionError: division by zero' for a message."""
    return f"{type(exc).__name__}: {_first_line(exc)}"
