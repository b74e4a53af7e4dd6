"""Expressions written in a model file (constraints phi(x, y, z, t), programmes q(t),
drives f(t)) or in a URDF's side file (drives f(t)), read into SymPy without ever
evaluating the user's text as Python.  Its own module, not gpme_io.modelfile's: the side
file (gpme_io.side_file) reads them too, and gpme_io.modelfile builds on the side file.

The text is parsed by Python's ``ast`` module (syntax only) and the tree is converted node
by node into SymPy: numbers, the allowed symbols, ``pi``, ``E``, ``+ - * / **`` and the
smooth functions of :data:`FUNCTIONS`.  Anything else (attribute access, indexing,
keywords, strings, comparisons, unknown names) is a problem naming what was found and
what is allowed.  Functions whose second derivative does not exist everywhere (abs,
sign, Heaviside, Piecewise, Max/Min, floor, ...) are refused with the reason: the GPME
needs the second derivative of every constraint and programme (kappa, the programmed
acceleration).  Functions smooth only on part of the line (sqrt, log, division, ...)
are accepted; :func:`singular_sets` names where they are not smooth, for the message
given when an expression is not finite at the initial state.  The refused functions, their
reasons and singular_sets are gpme_core.expression_checks', shared with the Python API.
"""
import ast
import math
from typing import Mapping, Optional

import sympy as sp

from gpme_core.echo import did_you_mean
from gpme_core import expression_bounds as bounds
from gpme_core import expression_checks as checks

# name in the file -> (SymPy function, number of arguments)
FUNCTIONS = {
    "sin": (sp.sin, 1), "cos": (sp.cos, 1), "tan": (sp.tan, 1),
    "asin": (sp.asin, 1), "acos": (sp.acos, 1), "atan": (sp.atan, 1), "atan2": (sp.atan2, 2),
    "sinh": (sp.sinh, 1), "cosh": (sp.cosh, 1), "tanh": (sp.tanh, 1),
    "asinh": (sp.asinh, 1), "acosh": (sp.acosh, 1), "atanh": (sp.atanh, 1),
    "exp": (sp.exp, 1), "log": (sp.log, 1), "sqrt": (sp.sqrt, 1),
}
CONSTANTS = {"pi": sp.pi, "E": sp.E}
# the functions refused and why, and where the accepted ones are not smooth: one table with
# the Python API (gpme_core.constraints.SympyPointConstraint, time_functions.SympyTimeFunction)
_SMOOTH_HINT = checks.SMOOTH_HINT
NON_SMOOTH = checks.NON_SMOOTH
singular_sets = checks.singular_sets
MAX_LENGTH = 5000          # characters; longer text is refused before parsing


class _Refused(Exception):
    """One problem found while converting the tree (stops the conversion)."""


def describe_symbols(symbols: Mapping[str, str]) -> str:
    """'x, y, z (m) and t (s)' for {'x': 'm', 'y': 'm', 'z': 'm', 't': 's'}."""
    groups: dict = {}
    for name, unit in symbols.items():
        groups.setdefault(unit, []).append(name)
    parts = [f"{', '.join(names)} ({unit})" for unit, names in groups.items()]
    return parts[0] if len(parts) == 1 else ", ".join(parts[:-1]) + " and " + parts[-1]


def symbol(name: str) -> sp.Symbol:
    """The SymPy symbol used for ``name`` (plain, no assumptions: the same symbols as
    gpme_core.constraints.SympyPointConstraint and SympyTimeFunction)."""
    return sp.Symbol(name)


def parse_expression(text: object, symbols: Mapping[str, str]) -> tuple:
    """(SymPy expression or None, [problem, ...]) of ``text``.

    symbols : {allowed symbol name: unit}, e.g. {'x': 'm', 'y': 'm', 'z': 'm', 't': 's'}

    Problems are messages without a key path (the caller adds it).
    """
    if not isinstance(text, str):
        return None, [f"must be a string holding an expression in "
                      f"{describe_symbols(symbols)}, got {text!r}"]
    if not text.strip():
        return None, ["is empty; write an expression in " + describe_symbols(symbols)]
    if len(text) > MAX_LENGTH:
        return None, [f"is {len(text)} characters long; at most {MAX_LENGTH}"]
    source = text.strip()
    try:
        tree = ast.parse(source, mode="eval")
    except SyntaxError as exc:
        return None, [f"{text!r} is not an expression ({exc.msg} at column {exc.offset})"]
    except (RecursionError, MemoryError):
        return None, [f"{_shown(text)}: {bounds.shape_problem(bounds.MAX_DEPTH + 1, 0)}"]
    shape = bounds.shape_problem(*bounds.shape(tree.body, _operands, _same_chain))
    if shape:
        return None, [f"{_shown(text)}: {shape}"]
    try:
        expr = _convert(tree.body, symbols, source)
    except _Refused as exc:
        return None, [f"{_shown(text)}: {exc}"]
    except RecursionError:                 # SymPy's own recursion inside the depth bound
        return None, [f"{_shown(text)}: {bounds.shape_problem(bounds.MAX_DEPTH + 1, 0)}"]
    size = bounds.derivative_problem(expr)
    if size:
        return None, [f"{_shown(text)}: {size}"]
    problems = []
    bad = sorted({type(a).__name__ for a, _ in checks.non_smooth_parts(expr)})
    if bad:
        problems.append(f"{text!r} becomes {bad} in SymPy, which is not smooth; {_SMOOTH_HINT}")
    problems += checks.constant_problems(expr, f"{_shown(text)} = {bounds.short(str(expr), 80)}")
    return (None if problems else expr), problems


def _convert(node: ast.AST, symbols: Mapping[str, str], source: str) -> sp.Expr:
    """SymPy of ``node``; every number, power and product bounded before it is built
    (gpme_core.expression_bounds); _Refused naming the part of ``source`` and why."""
    if isinstance(node, ast.Constant):
        v = node.value
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise _Refused(f"{v!r} is not a number; only real numbers are allowed")
        if isinstance(v, float) and not math.isfinite(v):
            raise _Refused(f"a number overflows to {v!r}; numbers must be finite")
        number = sp.Integer(v) if isinstance(v, int) else sp.Float(v)
        _bounded(bounds.constant_problem(number), node, source)
        return number
    if isinstance(node, ast.Name):
        name = node.id
        if name in symbols:
            return symbol(name)
        if name in CONSTANTS:
            return CONSTANTS[name]
        if name in FUNCTIONS or name in NON_SMOOTH:
            raise _Refused(f"{name!r} is a function: call it, e.g. {name}(t)")
        raise _Refused(f"unknown symbol {name!r}{_did_you_mean(name, list(symbols) + list(CONSTANTS))}"
                       f"; allowed {describe_symbols(symbols)}, and the constants pi, E")
    if isinstance(node, ast.UnaryOp):
        arg = _convert(node.operand, symbols, source)
        if isinstance(node.op, ast.USub):
            return -arg
        if isinstance(node.op, ast.UAdd):
            return arg
        raise _Refused(f"the operator {_op_text(node.op)!r} is not allowed; use + - * / **")
    if isinstance(node, ast.BinOp):
        op = node.op
        if isinstance(op, ast.BitXor):
            raise _Refused("'^' is not a power here: write a**b")
        if isinstance(op, (ast.Mod, ast.FloorDiv)):
            raise _Refused(f"the operator {_op_text(op)!r} is not smooth ({NON_SMOOTH['Mod']}); "
                           + _SMOOTH_HINT)
        if type(op) in _CHAIN:
            return _convert_chain(node, symbols, source)
        if not isinstance(op, ast.Pow):
            raise _Refused(f"the operator {_op_text(op)!r} is not allowed; use + - * / **")
        left, right = _convert(node.left, symbols, source), _convert(node.right, symbols, source)
        _bounded(bounds.power_problem(left, right), node, source)
        out = left ** right
        _bounded(bounds.constant_problem(out), node, source)
        return out
    if isinstance(node, ast.Call):
        if not isinstance(node.func, ast.Name):
            raise _Refused("only the named functions "
                           f"{', '.join(FUNCTIONS)} can be called")
        name = node.func.id
        if name in NON_SMOOTH:
            raise _Refused(f"{name}() is not smooth: {NON_SMOOTH[name]}; {_SMOOTH_HINT}")
        if name not in FUNCTIONS:
            raise _Refused(f"unknown function {name!r}{_did_you_mean(name, list(FUNCTIONS))}; "
                           f"allowed: {', '.join(FUNCTIONS)}")
        if node.keywords or any(isinstance(a, ast.Starred) for a in node.args):
            raise _Refused(f"{name}() takes plain arguments only")
        fn, arity = FUNCTIONS[name]
        if len(node.args) != arity:
            raise _Refused(f"{name}() takes {arity} argument{'s' if arity > 1 else ''}, "
                           f"got {len(node.args)}")
        args = [_convert(a, symbols, source) for a in node.args]
        _bounded(bounds.function_problem(fn, args), node, source)
        return fn(*args)
    if isinstance(node, ast.Attribute):
        raise _Refused(f"attribute access ('.{node.attr}') is not allowed")
    if isinstance(node, (ast.Compare, ast.BoolOp, ast.IfExp)):
        raise _Refused("comparisons and conditions make a function piecewise, which is not "
                       "smooth; " + _SMOOTH_HINT)
    raise _Refused(f"{type(node).__name__} is not allowed; write numbers, "
                   f"{describe_symbols(symbols)}, pi, E, + - * / ** and the functions "
                   f"{', '.join(FUNCTIONS)}")


# a + b - c and a * b / c: chains parsed as nested pairs ((a + b) - c) that SymPy builds
# as one flat sum or product; converted along their left spine without recursion
_CHAIN = {ast.Add: "sum", ast.Sub: "sum", ast.Mult: "product", ast.Div: "product"}


def _operands(node: ast.AST) -> list:
    """The subexpressions of ``node`` (not its operator and context nodes): what the bound
    on expression size counts."""
    return [c for c in ast.iter_child_nodes(node) if isinstance(c, ast.expr)]


def _same_chain(parent: ast.AST, child: ast.AST) -> bool:
    """Whether ``child`` continues ``parent``'s sum or product (no deeper nesting)."""
    return (isinstance(parent, ast.BinOp) and isinstance(child, ast.BinOp)
            and _CHAIN.get(type(parent.op)) is not None
            and _CHAIN.get(type(parent.op)) == _CHAIN.get(type(child.op)))


def _convert_chain(node: ast.BinOp, symbols: Mapping[str, str], source: str) -> sp.Expr:
    """One SymPy Add or Mul of a chain of + and - (or * and /), its operands bounded; the
    product's exact constants are bounded before it is built."""
    family, spine, first = _CHAIN[type(node.op)], [], node
    while isinstance(node, ast.BinOp) and _CHAIN.get(type(node.op)) == family:
        spine.append(node)
        node = node.left
    terms = [_convert(node, symbols, source)]
    for link in reversed(spine):
        operand = _convert(link.right, symbols, source)
        if isinstance(link.op, ast.Sub):
            operand = -operand
        elif isinstance(link.op, ast.Div):
            operand = sp.Pow(operand, -1)
        _bounded(bounds.constant_problem(operand), link, source)
        terms.append(operand)
    if family == "product":
        _bounded(bounds.product_problem(terms), first, source)
    out = sp.Add(*terms) if family == "sum" else sp.Mul(*terms)
    _bounded(bounds.constant_problem(out), first, source)
    return out


def _shown(text: str) -> str:
    """repr of a user's text for a message, cut to 80 characters."""
    return repr(text) if len(text) <= 80 else repr(text[:75]) + " ..."


def _bounded(problem: Optional[str], node: ast.AST, source: str) -> None:
    """Raise _Refused '<the node's text>: <problem>' when ``problem`` is not None."""
    if problem:
        part = ast.get_source_segment(source, node) or ""
        raise _Refused(problem if part == source else f"{bounds.short(part)}: {problem}")


def _op_text(op: ast.AST) -> str:
    return {ast.BitAnd: "&", ast.BitOr: "|", ast.LShift: "<<", ast.RShift: ">>",
            ast.MatMult: "@", ast.Mod: "%", ast.FloorDiv: "//", ast.Invert: "~",
            ast.Not: "not"}.get(type(op), type(op).__name__)


def _did_you_mean(name: str, choices: list) -> str:
    return did_you_mean(name, choices)


def depends_on(expr: sp.Expr, names) -> bool:
    """Whether ``expr`` contains any of the symbols ``names``."""
    return bool(expr.free_symbols & {symbol(n) for n in names})


def expression_text(expr: Optional[sp.Expr]) -> str:
    """Short text of an expression for notes and messages."""
    return "" if expr is None else str(expr)
