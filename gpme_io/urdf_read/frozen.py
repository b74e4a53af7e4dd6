"""The values of the moving joints off the chain: given (``frozen=``), mimicked or 0.

Every moving joint that is not a gpme coordinate becomes a fixed joint at its value (rad
or m): the value given in ``frozen``, else multiplier * value + offset of the joint it
mimics (a mimic of a mimic resolved in passes), else 0 (floating and planar joints: their
origin).  Joints above the chain root must be given, and a chain joint must be neither a
mimic nor of a type gpme cannot make a coordinate of.
"""
import math

from .joint import _UNSUPPORTED


def _frozen_values(tree, joints, chain_joints, above, frozen, problems, notes) -> dict:
    """{joint: value (rad or m)} of every moving joint off the chain (given, mimicked or
    0); the problems of ``frozen`` and of the chain's joints are appended, what was
    defaulted or mimicked is noted.  ``above``: the joints from the URDF root to the chain
    root."""
    by_name = {j.name: j for j in joints}
    on_chain = {j.name for j in chain_joints}
    values = _given_values(by_name, joints, on_chain, frozen, problems)
    _unfrozen_problems(above, chain_joints, frozen, problems)
    defaults, mimicked, unsupported = _fill_values(by_name, joints, on_chain, frozen, values,
                                                   problems)
    _note_filled(by_name, defaults, mimicked, unsupported, notes)
    return values


def _given_values(by_name, joints, on_chain, frozen, problems) -> dict:
    """{joint: value} of the valid entries of ``frozen`` (a moving joint off the chain, a
    finite value within its <limit>); the others' problems appended."""
    values = {}
    for name, v in frozen.items():
        j = by_name.get(name)
        off = sorted(k.name for k in joints if k.moving and k.name not in on_chain)
        if j is None:
            problems.append(f"frozen joint {name!r}: no such joint; moving joints off the "
                            f"chain: {off}")
            continue
        if not j.moving:
            problems.append(f"frozen joint {name!r} is a fixed joint (nothing to freeze)")
            continue
        if name in on_chain:
            problems.append(f"frozen joint {name!r} is on the chain (a gpme coordinate); "
                            "choose another chain or do not freeze it")
            continue
        if j.type in _UNSUPPORTED:
            problems.append(f"frozen joint {name!r}: a {j.type} joint off the chain is frozen "
                            "at its origin; a value cannot be given")
            continue
        try:
            x = float(v)
        except (TypeError, ValueError):
            x = math.nan
        if not math.isfinite(x):
            problems.append(f"frozen joint {name!r}: value must be a finite number (rad or m), "
                            f"got {v!r}")
            continue
        lo, hi = j.limits
        if not lo <= x <= hi:
            unit = "m" if j.type == "prismatic" else "rad"
            problems.append(f"frozen joint {name!r} = {x!r} {unit} is outside its <limit> "
                            f"[{lo!r}, {hi!r}]")
            continue
        values[name] = x
    return values


def _unfrozen_problems(above, chain_joints, frozen, problems) -> None:
    """Append the problems of moving joints above the chain root not in ``frozen``, and of
    chain joints that mimic or are of an unsupported type."""
    for j in above:
        if j.moving and j.name not in frozen:
            problems.append(f"joint {j.name!r} ({j.type}) lies above the chain root and would "
                            f"move the whole chain: freeze it with frozen={{{j.name!r}: value}} "
                            "or start the chain higher")
    for j in chain_joints:
        if j.mimic is not None:
            problems.append(f"joint {j.name!r} on the chain mimics {j.mimic[0]!r}: every gpme "
                            "coordinate is independent; choose a chain without it or freeze "
                            "it off the chain")
        if j.type in _UNSUPPORTED:
            problems.append(f"joint {j.name!r} on the chain: type {j.type!r} is not supported "
                            f"({_UNSUPPORTED[j.type]}); gpme coordinates are revolute or "
                            "prismatic")


def _fill_values(by_name, joints, on_chain, frozen, values, problems) -> tuple:
    """Put into ``values`` every moving joint off the chain not in ``frozen``: 0, or its
    mimic's multiplier * value + offset (a mimic that cannot be resolved is a problem).
    Returns (joints defaulted to 0, lines "j = m * src + o = v", floating/planar joints)."""
    defaults, mimicked, unsupported = [], [], []
    todo = [j for j in joints if j.moving and j.name not in on_chain and j.name not in values
            and j.name not in frozen]
    for _ in range(len(todo) + 1):          # mimic of a mimic: resolve in passes
        left = []
        for j in todo:
            if j.type in _UNSUPPORTED:
                values[j.name] = 0.0
                unsupported.append(j.name)
            elif j.mimic is None:
                values[j.name] = 0.0
                defaults.append(j.name)
            elif j.mimic[0] in values:
                src, mult, off = j.mimic
                values[j.name] = mult * values[src] + off
                mimicked.append(f"{j.name} = {mult!r} * {src} + {off!r} = {values[j.name]!r}")
            else:
                left.append(j)
        if len(left) == len(todo):
            break
        todo = left
    for j in todo:
        src = j.mimic[0]
        why = ("is on the chain" if src in on_chain else
               "is not a joint of the file" if src not in by_name else "cannot be resolved")
        problems.append(f"joint {j.name!r} off the chain mimics {src!r}, which {why}: give "
                        f"its value with frozen={{{j.name!r}: value}}")
    return defaults, mimicked, unsupported


def _note_filled(by_name, defaults, mimicked, unsupported, notes) -> None:
    """Note the joints frozen at 0 (and those whose <limit> excludes 0), the mimics and
    the floating/planar joints frozen at their origin."""
    outside = []
    for name in defaults:
        lo, hi = by_name[name].limits
        if not lo <= 0.0 <= hi:
            outside.append(f"{name} [{lo:g}, {hi:g}]")
    if defaults:
        notes.line(f"{len(defaults)} joints off the chain frozen at the default 0 (rad or m): "
                   + ", ".join(defaults))
    if outside:
        notes.line(f"the default 0 is outside the <limit> of frozen joints "
                   f"{', '.join(outside)}: give their values in frozen= if it matters")
    if mimicked:
        notes.line("mimic joints off the chain frozen where they follow the joint they mimic "
                   "(multiplier * value + offset): " + "; ".join(mimicked))
    if unsupported:
        notes.line("floating/planar joints off the chain frozen at their origin: "
                   + ", ".join(unsupported))
