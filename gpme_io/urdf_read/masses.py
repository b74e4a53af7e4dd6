"""The links' masses once the chain is placed: which problems matter, what is merged.

An invalid or missing <inertial> matters only on a link that moves (one fixed to the world
is dropped); links hanging on a chain link merge into it; a chain link may carry no mass;
and the whole must stay small enough to compute with (_MAGNITUDE).
"""
import math
from typing import Optional

import numpy as np

from .inertial import _MAGNITUDE
from .placement import _WORLD


def _inertial_problems(parsed, placement, problems, notes) -> list:
    """Append the <inertial> problems of moving links; note those of links fixed to the
    world (their mass is dropped).  Returns the links fixed to the world with an invalid
    <inertial>."""
    owner = placement.owner
    world_fixed_bad = [lk for lk in parsed.bad_inertia if owner.get(lk) == _WORLD]
    for lk, bad in parsed.bad_inertia.items():
        if lk not in world_fixed_bad:
            problems.extend(bad)
    if world_fixed_bad:
        notes.line("invalid <inertial> on links fixed to the world ignored (they do not move, "
                   "their mass is dropped): " + "; ".join(
                       p for lk in world_fixed_bad for p in parsed.bad_inertia[lk]))
    non_physical = [line for lk, inertia in parsed.inertias.items()
                    if inertia is not None and owner.get(lk) != _WORLD
                    for line in inertia.non_physical(f"link {lk!r} <inertial>")]
    if non_physical:
        notes.line("non-physical inertias of moving links accepted: " + "; ".join(non_physical))
    return world_fixed_bad


def _geometry_problems(parsed, placement, chain, allowed_massless, flexible,
                       problems) -> None:
    """Append a problem for each moving link with <visual>/<collision> but no <inertial>
    that is neither allowed massless nor flexible (its mass would silently be 0)."""
    for lk in parsed.geometry_only:
        k = placement.owner.get(lk, _WORLD)
        if k >= 0 and lk not in allowed_massless and lk not in flexible:
            problems.append(
                f"link {lk!r} has <visual>/<collision> geometry but no <inertial>, and it "
                f"moves (with joint {chain.joints[k].name!r}): its mass would be read as 0; "
                "give it an <inertial> (mass in kg, inertia in kg m^2 about its centre of "
                "mass), or an explicit zero <inertial> (mass 0, all six moments 0) if it "
                "truly carries no mass")


def _merge_notes(parsed, placement, chain, values, notes) -> None:
    """Note the links fixed to the world whose mass is dropped, and the frozen branches
    merged into each chain link."""
    owner, inertias = placement.owner, parsed.inertias
    dropped = [f"{lk} ({inertias[lk].mass:g} kg)" for lk in owner
               if owner[lk] == _WORLD and inertias.get(lk) is not None]
    if dropped:
        notes.line("links fixed to the world (they do not move; their mass has no effect on "
                   "the dynamics) dropped: " + ", ".join(dropped))
    frozen_joints = [j for j in parsed.joints if j.name in values]
    for k, lk in enumerate(chain.links):
        branch = [j.name for j in frozen_joints if owner.get(j.parent) == k]
        if branch:
            moved = [x for x in placement.attached.get(k, []) if inertias.get(x) is not None]
            notes.line(f"frozen joints {branch} hang on chain link {lk!r}: the links below "
                       f"them merged into it as mass and frames ({len(moved)} with mass)")


def _massless_note(parsed, placement, chain, allowed_massless, flexible, notes) -> None:
    """Note the chain links that carry no mass at all (nothing merged into them has any),
    other than those allowed massless, flexible, or with an <inertial> problem."""
    inertias = parsed.inertias
    massless = [lk for k, lk in enumerate(chain.links) if lk not in allowed_massless
                and lk not in flexible and inertias.get(lk) is None
                and lk not in parsed.bad_inertia and lk not in parsed.geometry_only
                and all(inertias.get(x) is None for x in placement.attached.get(k, []))]
    if massless:
        notes.line("chain links without mass (accepted: the mass matrix is checked positive "
                   "definite): " + ", ".join(massless))


def _size_problem(tree, owner, inertias) -> Optional[str]:
    """The problem when the moving masses at the lengths of the tree give an inertia about
    the root (sum m * L^2 + tr I, L the sum of every joint offset) above _MAGNITUDE."""
    offsets = [(math.hypot(*j.origin[:3, 3]), j.name)
               for js in tree.children.values() for j in js]
    moving = [inertias[lk] for lk, k in owner.items() if k >= 0 and inertias.get(lk) is not None]
    if not offsets or not moving:
        return None
    with np.errstate(over="ignore", invalid="ignore"):
        length = sum(d for d, _ in offsets) + max(math.hypot(*i.com_array) for i in moving)
        mass = sum(float(i.mass) for i in moving)
        size = mass * length * length + sum(float(np.trace(i.inertia_array)) for i in moving)
    if size < _MAGNITUDE:
        return None
    far, joint = max(offsets)
    return (f"the moving links' mass {mass:.3g} kg at up to {length:.3g} m from the root "
            f"(the largest joint offset: joint {joint!r}, {far:.3g} m) give an inertia of "
            f"{size:.3g} kg m^2, too large to compute with (at most {_MAGNITUDE:g}; real "
            "machines have < 1e12): check the units of <origin xyz> (m) and <mass> (kg); "
            "the assembled model was not checked because of it")
