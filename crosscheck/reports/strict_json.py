"""summary.json as strict JSON (RFC 8259): no NaN or Infinity tokens, which jq, JavaScript's
JSON.parse and most CI tools refuse.

A NaN becomes null; +-inf (the error of a check whose value was not finite, its error /
tolerance) becomes the string "inf" / "-inf", turned back into a float by :func:`loads`
for the numeric fields only.
"""
import json
import math

NUMERIC_FIELDS = frozenset({
    "worst_abs_error", "worst_rel_error", "tol_abs", "tol_rel", "tolerance",
    "error_over_tolerance", "previous", "current", "factor", "wall_time_s"})
_INF = {"inf": math.inf, "-inf": -math.inf}


def _strict(value):
    if isinstance(value, float):
        if value != value:
            return None
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return value
    if isinstance(value, dict):
        return {k: _strict(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_strict(v) for v in value]
    return value


def dumps(document, indent=1):
    """``document`` as strict JSON text (see the module docstring)."""
    return json.dumps(_strict(document), indent=indent, allow_nan=False)


def _restore(pairs):
    return {k: _INF[v] if k in NUMERIC_FIELDS and isinstance(v, str) and v in _INF else v
            for k, v in pairs}


def loads(text):
    """A document written by :func:`dumps` (or an older one with Infinity tokens), with
    "inf" / "-inf" in the numeric fields as floats again."""
    return json.loads(text, object_pairs_hook=_restore)
