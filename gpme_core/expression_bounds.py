"""Bounds on the work an expression written by a user (constraint phi(x, y, z, t), programme
or drive f(t)) can cause, checked before SymPy evaluates or differentiates it.

SymPy evaluates integer powers, products of numbers and combinatorial functions of numbers
exactly as soon as they are built: ``9**9**9`` is a number of 3.7e8 digits that takes
longer than any CI job to compute, and ``(123456789*x)**1000`` distributes the power
onto the coefficient.  The GPME also differentiates every expression twice and writes the
derivatives as code, whose size grows with the product rule (a product of N factors has a
second derivative of about N^3 nodes).  So an expression is refused, with the bound it
passes and why, when

- its tree is deeper than :data:`MAX_DEPTH` or has more than :data:`MAX_NODES` nodes,
- a constant power, or the constant coefficient of a power, would have more than
  :data:`MAX_CONSTANT_DIGITS` digits (the estimate |exponent| x log10|base| is made
  before the power is built; nested constant powers a**b**c are evaluated only when the
  inner one is within the bound), or a number given has more,
- a power of a coordinate or of time has an exponent above :data:`MAX_EXPONENT`,
- a function is applied to a constant above 10**MAX_CONSTANT_DIGITS (``sin(exp(exp(
  exp(5))))``: reducing it modulo 2 pi needs 1e64 digits), or a combinatorial function
  (factorial, gamma, binomial, ...) to a number above :data:`MAX_COMBINATORIAL_ARGUMENT`,
- or the product-rule estimate of its second derivatives (:func:`derivative_nodes`) is
  above :data:`MAX_DERIVATIVE_NODES`.

The model-file reader (gpme_io.expressions) applies :func:`power_problem`,
:func:`constant_problem` and :func:`function_problem` while it converts the text's syntax
tree; the Python API (gpme_core.expression_checks.read_expression) reads a string without
evaluating it and rebuilds it node by node with :func:`evaluate_bounded`.  Both check
:func:`derivative_problem` before differentiating.
"""
import math
from typing import Optional

import sympy as sp

MAX_DEPTH = 100
"""Deepest nesting of operations and functions accepted.  The repository's models nest at
most 6 deep; 100 keeps every recursive walk (ours, SymPy's printer and differentiation)
far inside Python's recursion limit of 1000 frames."""
MAX_NODES = 2500
"""Most operations, functions, symbols and numbers in one expression (a model file's
5000 characters hold at most about 2500)."""
MAX_CONSTANT_DIGITS = 400
"""Most decimal digits of an exact constant (integer, or numerator or denominator of a
fraction).  float64 ends at 1.8e308 (309 digits): a larger constant is refused anyway by
expression_checks.constant_problems; the 91 further digits leave room for a quotient of
two large numbers.  Computing and printing 400 digits is instantaneous; 3.7e8 digits
(9**9**9) never ends."""
MAX_EXPONENT = 1000
"""Largest |exponent| of a power of a coordinate or of time: |u|**1000 overflows float64
for |u| > 2.03 and is below its smallest normal number for |u| < 0.49, so a larger one has
no finite, non-zero value along a motion except where its base is within a factor 2 of 1."""
MAX_COMBINATORIAL_ARGUMENT = 1000
"""Largest number a combinatorial function (factorial, gamma, binomial, fibonacci, ...) is
evaluated at: 1000! has 2568 digits, beyond float64 already."""
MAX_DERIVATIVE_NODES = 50_000
"""Largest product-rule estimate of the second derivatives' size (:func:`derivative_nodes`,
summed over the pairs of symbols).  Measured on this project's machine: ~1e5 takes 2 to 4 s
of SymPy differentiation and code generation (a product of 20 factors in x, y, z: 2e5,
8 s); the repository's largest model expression has 2,844."""

_COMBINATORIAL_MODULES = ("sympy.functions.combinatorial", "sympy.ntheory",
                          "sympy.functions.special.gamma_functions")


class BoundError(ValueError):
    """An expression passes one of this module's bounds (the message names the
    subexpression, the bound and why)."""


# ====================================================================== tree shape
def tree_problem(expr: sp.Basic) -> Optional[str]:
    """None, or why the tree of ``expr`` is too deep or too large (:data:`MAX_DEPTH`,
    :data:`MAX_NODES`).  Iterative: any depth is measured without recursion."""
    depth, nodes = shape(expr, lambda e: e.args if isinstance(e, sp.Basic) else ())
    return shape_problem(depth, nodes)


def shape(root, children, same_level=None) -> tuple:
    """(depth, nodes) of a tree given its ``children(node)``, without recursion; stops
    counting once either passes its bound.  ``same_level(parent, child)``: True where the
    child does not nest deeper (a + b + c parsed as (a + b) + c is one flat sum, as SymPy
    builds it)."""
    stack, depth, nodes = [(root, 1)], 0, 0
    while stack:
        node, d = stack.pop()
        nodes += 1
        depth = max(depth, d)
        if depth > MAX_DEPTH or nodes > MAX_NODES:
            break
        stack.extend((c, d if same_level is not None and same_level(node, c) else d + 1)
                     for c in children(node))
    return depth, nodes


def shape_problem(depth: int, nodes: int) -> Optional[str]:
    """The message for a tree of ``depth`` and ``nodes`` above the bounds, else None."""
    if depth > MAX_DEPTH:
        return (f"nested more than {MAX_DEPTH} deep (the bound on expression "
                "depth: SymPy differentiates and prints expressions recursively, and the "
                "second derivative of a deep nesting grows as its depth cubed)")
    if nodes > MAX_NODES:
        return (f"more than {MAX_NODES} operations, functions and numbers "
                "(the bound on expression size; the GPME differentiates it twice)")
    return None


# ====================================================================== constants
def digits(value: sp.Basic) -> float:
    """Decimal digits (log10) of an exact constant: of an integer, or the larger of a
    fraction's numerator and denominator; 0 for anything else."""
    if isinstance(value, sp.Rational):
        return max(_int_digits(value.p), _int_digits(value.q))
    return 0.0


def _int_digits(n: int) -> float:
    return math.log10(abs(int(n))) if n else 0.0     # exact for Python ints of any size


def constant_problem(value: sp.Basic) -> Optional[str]:
    """None, or why the exact constant ``value`` has too many digits."""
    d = digits(value)
    if d > MAX_CONSTANT_DIGITS:
        return (f"a constant of about {_about(d)} digits; exact constants are "
                f"limited to {MAX_CONSTANT_DIGITS} digits (float64 ends at 309)")
    return None


def _log10_abs(value: sp.Basic) -> Optional[float]:
    """log10 |value| of a number (any size: a fraction from its integers, others by a
    15-digit evalf), None for 0 or a value without a numeric magnitude."""
    if isinstance(value, sp.Rational):
        return None if value == 0 else _int_digits(value.p) - _int_digits(value.q)
    try:
        m = sp.Abs(value.evalf(15))
        if m.is_zero:
            return None
        return float(sp.log(m, 10).evalf(15))
    except (TypeError, ValueError, ArithmeticError):
        return None


def power_problem(base: sp.Basic, exponent: sp.Basic) -> Optional[str]:
    """None, or why ``base**exponent`` (both already built, bounded) must not be built:
    a constant result or constant coefficient above :data:`MAX_CONSTANT_DIGITS` digits,
    or an exponent above :data:`MAX_EXPONENT` on a coordinate or time."""
    if not (isinstance(exponent, sp.Expr) and exponent.is_number):
        return None                       # symbolic exponent: nothing evaluated
    e = _log10_abs(exponent)
    if e is None:
        return None                       # exponent 0
    size = math.inf if e > 300 else 10.0 ** e
    if isinstance(base, sp.Expr) and base.is_number:
        if isinstance(base, sp.Rational):
            per = digits(base)
        else:
            b = _log10_abs(base)
            per = 0.0 if b is None else abs(b)
        if per == 0.0:                    # 0 or +-1: nothing grows
            return None
        result = size * per
        if result > MAX_CONSTANT_DIGITS:
            return (f"a constant power with about {_about(result)} digits; "
                    f"powers of constants are limited to results of {MAX_CONSTANT_DIGITS} "
                    "digits (float64 ends at 309; SymPy evaluates an exact power at once, and "
                    "at this size it does not finish)")
        return None
    if size > MAX_EXPONENT:
        return (f"the exponent {_number_text(exponent)} of a coordinate or "
                f"time is above {MAX_EXPONENT} in size (|u|**{MAX_EXPONENT} already overflows "
                "float64 for |u| > 2.03 and vanishes for |u| < 0.49)")
    coefficient = base.as_coeff_Mul()[0] if isinstance(base, sp.Expr) else sp.S.One
    result = size * digits(coefficient)
    if result > MAX_CONSTANT_DIGITS:
        return (f"the power distributes onto the constant factor "
                f"{short(str(coefficient))}, a constant of about {_about(result)} digits; exact "
                f"constants are limited to {MAX_CONSTANT_DIGITS} digits")
    return None


def function_problem(func, args) -> Optional[str]:
    """None, or why ``func`` must not be applied to its (built, bounded) ``args``: a
    constant argument above 10**MAX_CONSTANT_DIGITS (sin, cos, tan of such a number need as
    many digits of pi to evaluate, and SymPy's evalf does not finish), or a combinatorial
    function (factorial, gamma, binomial, ...) of a number above
    :data:`MAX_COMBINATORIAL_ARGUMENT`."""
    combinatorial = str(getattr(func, "__module__", "")).startswith(_COMBINATORIAL_MODULES)
    for a in args:
        if not (isinstance(a, sp.Expr) and a.is_number):
            continue
        m = _log10_abs(a)
        if m is None:
            continue
        name = getattr(func, "__name__", str(func))
        if m > MAX_CONSTANT_DIGITS:
            return (f"{name}() of a constant of about 10**{_about(m)}; constant arguments "
                    f"are limited to 10**{MAX_CONSTANT_DIGITS} (float64 ends at 1.8e308, "
                    "and a periodic function of such a number needs as many digits of pi to "
                    "evaluate)")
        if combinatorial and m > math.log10(MAX_COMBINATORIAL_ARGUMENT):
            return (f"{name}() of a number about 10**{m:.3g}; combinatorial functions "
                    f"are evaluated only up to {MAX_COMBINATORIAL_ARGUMENT} "
                    f"({MAX_COMBINATORIAL_ARGUMENT}! has 2568 digits, beyond float64)")
    return None


def evaluate_bounded(expr: sp.Basic) -> sp.Basic:
    """``expr`` (built unevaluated, e.g. ``sympify(text, evaluate=False)``) evaluated node
    by node from the leaves, each power, product and combinatorial function checked
    before SymPy builds it; otherwise BoundError '<subexpression>: <bound and why>'.  The
    tree must have passed :func:`tree_problem` (its depth bounds this recursion)."""
    if not isinstance(expr, sp.Basic) or not expr.args:
        problem = constant_problem(expr) if isinstance(expr, sp.Basic) else None
        if problem:
            raise BoundError(f"a number given: {problem}")
        return expr
    args = [evaluate_bounded(a) for a in expr.args]
    if isinstance(expr, sp.Pow):
        problem = power_problem(args[0], args[1])
    elif isinstance(expr, sp.Mul):
        problem = product_problem(args)
    else:
        problem = function_problem(expr.func, args)
    if problem:
        raise BoundError(f"{short(str(expr))}: {problem}")
    built = expr.func(*args)
    problem = constant_problem(built) if isinstance(built, sp.Basic) else None
    if problem:
        raise BoundError(f"{short(str(expr))}: {problem}")
    return built


def product_problem(args) -> Optional[str]:
    """None, or why the product of ``args`` must not be built: its exact constant factors
    have more than twice :data:`MAX_CONSTANT_DIGITS` digits together."""
    total = sum(digits(a) for a in args)
    if total > 2 * MAX_CONSTANT_DIGITS:
        return (f"a product of constants of about {_about(total)} digits; exact "
                f"constants are limited to {MAX_CONSTANT_DIGITS} digits")
    return None


# ====================================================================== derivatives
def derivative_nodes(expr: sp.Basic) -> int:
    """Product-rule estimate of the number of nodes of the second derivatives of ``expr``
    as code: per symbol, the tree size of d2/du2 with every symbol counted as u (Leibniz's
    rule on products, the chain rule on functions and powers), times the number of pairs
    of symbols.  An overestimate for expressions SymPy simplifies; never computes a
    derivative.  The tree must have passed :func:`tree_problem`."""
    memo: dict = {}

    def sizes(e):                       # (value, first, second derivative) tree sizes
        hit = memo.get(e)
        if hit is not None:
            return hit
        if not e.free_symbols:
            r = (1, 0, 0)
        elif isinstance(e, sp.Symbol) or not e.args:
            r = (1, 1, 0)
        elif isinstance(e, sp.Add):
            parts = [sizes(a) for a in e.args]
            r = tuple(sum(p[k] for p in parts) + 1 for k in range(3))
        elif isinstance(e, sp.Mul):
            parts = [sizes(a) for a in e.args]
            a = parts[0]
            for b in parts[1:]:       # (ab)' = a'b + ab', (ab)'' = a''b + 2a'b' + ab''
                a = (a[0] + b[0] + 1, a[0] + a[1] + b[0] + b[1] + 3,
                     a[0] + a[1] + a[2] + b[0] + b[1] + b[2] + 6)
            r = a
        else:                           # f(u)' = f'(u) u', f(u)'' = f''(u) u'^2 + f'(u) u''
            parts = [sizes(a) for a in e.args]
            s0 = sum(p[0] for p in parts) + 1
            s1 = sum(p[1] for p in parts)
            s2 = sum(p[2] for p in parts)
            r = (s0, 3 * s0 + s1 + 4, 6 * s0 + 2 * s1 + s2 + 8)
        memo[e] = r
        return r
    n = max(len(getattr(expr, "free_symbols", ())), 1)
    return sizes(expr)[2] * n * n


def derivative_problem(expr: sp.Basic) -> Optional[str]:
    """None, or why the second derivatives of ``expr`` would be too large to derive and
    write as code (:data:`MAX_DERIVATIVE_NODES`)."""
    size = derivative_nodes(expr)
    if size > MAX_DERIVATIVE_NODES:
        return (f"its second derivatives would have about {_about(size)} nodes "
                f"(product-rule estimate); at most {MAX_DERIVATIVE_NODES:,} (the GPME "
                "differentiates every constraint and programme twice and compiles the "
                "result: about 1 to 2 s of work at the bound); write it with fewer nested "
                "functions or factors")
    return None


def _about(x: float) -> str:
    """'3.7e8' for 3.74e8, '520' for 520.3, 'inf'."""
    if not math.isfinite(x):
        return "more than 1e300"
    if x < 1e4:
        return f"{x:.0f}"
    mantissa, exponent = f"{x:.1e}".split("e")
    return f"{mantissa}e{int(exponent)}"


def _number_text(value: sp.Basic) -> str:
    return str(value) if digits(value) < 30 else f"about 10**{digits(value):.3g}"


def short(text: str, limit: int = 60) -> str:
    """``text`` on one line, cut to ``limit`` characters."""
    text = " ".join(str(text).split())
    return text if len(text) <= limit else text[:limit - 5] + " ..."
