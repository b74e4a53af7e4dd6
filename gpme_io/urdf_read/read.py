"""One read of a URDF, stage by stage, into an :class:`UrdfReadResult`.

The stages, in order: the XML (parse), the tree and the chain (tree), the frozen values
(frozen), where every link sits (placement), the masses (masses), the side file against
the URDF (side_match), the flexible links' plans (beams) and the model (build).  Every
stage appends its problems to one list; a stage that cannot run without the one before
(no XML, no tree, no chain, sizes too large to compute with) stops the read with the
problems so far, and the rest raise together at the end, in one ModelFileError.
"""
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Mapping

from gpme_core.errors import ModelError, ModelFileError
from gpme_core.model import Model

from .beams import _beam_plans
from .build import _assemble, _builder
from .frozen import _frozen_values
from .masses import (_geometry_problems, _inertial_problems, _massless_note, _merge_notes,
                     _size_problem)
from .notes import _Notes
from .parse import _parse, _parse_xml
from .placement import _WORLD, _Chain, _parents, _place
from .shapes import link_shapes, robot_materials
from .side_match import _match_side
from .tree import _CHAIN_SKIPPED, _path, _select_chain, _select_tree, _tree


@dataclass(frozen=True)
class UrdfReadResult:
    """What :func:`load_urdf` made of a URDF.

    model        : the validated gpme Model
    notes        : what was ignored or changed, one line per class of element (friction,
                   limits, extension tags, replaced inertias, merged branches, ...)
    frozen       : {URDF joint name: value (rad or m)} of every joint frozen off the chain
    chain        : (root link, tip link) actually used
    chain_joints : the URDF joints that are the model's coordinates, in order (before any
                   RFEM coordinates are inserted; the model's coordinate_names has those)
    frames       : the model's named frames (every link merged into a chain link)
    """

    model: Model
    notes: tuple
    frozen: Mapping[str, float]
    chain: tuple
    chain_joints: tuple
    frames: tuple


def _fail(source, problems):
    """Raise the ModelFileError of ``problems``, each prefixed with ``source`` (the file)
    unless it names it or the side file already."""
    raise ModelFileError([p if p.startswith(source) or p.startswith("side file")
                          else f"{source}: {p}" for p in problems])


def _read_guarded(text, side, problems, **kwargs) -> UrdfReadResult:
    """:func:`_read`, with any exception that escaped the checks turned into a
    ModelFileError naming the file, the exception and every problem found before it
    (the checks are meant to catch every malformed input first; this is the net)."""
    source = kwargs["source"]
    try:
        return _read(text, side, problems, **kwargs)
    except ModelFileError:
        raise
    except ModelError as exc:
        _fail(source, problems + list(exc.problems))
    except (ArithmeticError, AttributeError, LookupError, TypeError, ValueError,
            RecursionError) as exc:
        _fail(source, problems + [
            f"reading stopped at an unexpected {type(exc).__name__} ({exc}): a malformed "
            "input gpme's URDF checks do not name yet; the problems above were found "
            "before it (please report the file)"])


def _read(text, side, problems, *, chain, frozen, flexible, massless_links, gravity, name,
          source, whole_tree=False) -> UrdfReadResult:
    """The read of URDF ``text`` (str, bytes or None: unreadable, its problem in
    ``problems``) with the checked side-file dict ``side`` (or None); the keywords are
    :func:`load_urdf`'s, ``source`` names the file in the problems.  Raises
    ModelFileError with every problem found."""
    notes = _Notes()
    robot = _parse_xml(text, problems)
    if robot is None:
        _fail(source, problems)
    frozen = dict(frozen or {})
    flexible = dict(flexible or {})
    side = side or {}
    parsed = _parse(robot, problems, notes)
    whole_tree = whole_tree or bool(side.get("tree"))
    tree, picked = _choose_chain(parsed, chain, frozen, problems, source, whole_tree)
    above = _path(tree, tree.root, picked.root)
    values = _frozen_values(tree, parsed.joints, picked.joints, above, frozen, problems, notes)
    placement = _place(tree, picked.index, values)
    world_fixed_bad = _inertial_problems(parsed, placement, problems, notes)
    side_massless = list(side.get("massless_links", []))
    allowed_massless = set(massless_links) | set(side_massless)
    _geometry_problems(parsed, placement, picked, allowed_massless, flexible, problems)
    _merge_notes(parsed, placement, picked, values, notes)
    side_use = _match_side(side, tree, picked, side_massless, problems)
    parents = _parents(picked, placement)
    plans = _beam_plans(flexible, side_use.flexible, picked.links,
                        _next_origins(parents, placement.chain_origin), problems)
    _massless_note(parsed, placement, picked, allowed_massless, flexible, notes)
    size_problem = _size_problem(tree, placement.owner, parsed.inertias)
    if size_problem:
        problems.append(size_problem)
        _fail(source, problems)

    # build (also when earlier problems exist, to report the model's own problems too)
    builder = _builder(robot, side, gravity, name, notes)
    shapes = _read_shapes(robot, parsed, placement, flexible, source, notes)
    model, frames = None, ()
    try:
        model, frames = _assemble(builder, picked, parents, placement, side_use,
                                  parsed.inertias, flexible, plans, notes, shapes)
    except ModelError as exc:
        suffix = (" (found with the invalid <inertial> elements above left out)"
                  if set(parsed.bad_inertia) - set(world_fixed_bad) else "")
        problems += [p + suffix for p in exc.problems]
    if problems:
        _fail(source, problems)
    return UrdfReadResult(model, notes.lines(), MappingProxyType(dict(values)),
                          (picked.root, picked.tip), tuple(picked.names), frames)


def _read_shapes(robot, parsed, placement, flexible, source, notes) -> dict:
    """{moving link: its shapes (gpme_io.urdf_read.shapes.link_shapes)}; the shapes of
    links fixed to the world and of flexible links (replaced by the RFEM elements') are
    left out, noted."""
    path = Path(source) if source != "<urdf>" and Path(source).is_file() else None
    materials = robot_materials(robot)
    out = {}
    for link, el in parsed.link_elements.items():
        shapes = link_shapes(el, path, materials, notes)
        if not shapes:
            continue
        if placement.owner.get(link, _WORLD) == _WORLD:
            notes.add("world_shapes", link)
        elif link in flexible:
            notes.add("flexible_shapes", link)
        else:
            out[link] = shapes
    return out


def _next_origins(parents, chain_origin) -> dict:
    """{k: (4, 4) frame of the one joint mounted on link k, in link k's frame} for the
    links that carry exactly one joint (a beam's default axis points at it; a link with
    several or none has no default)."""
    children = {}
    for k, p in enumerate(parents):
        children.setdefault(p, []).append(k)
    return {p: chain_origin[ks[0]] for p, ks in children.items() if len(ks) == 1 and p >= 0}


def _choose_chain(parsed, chain, frozen, problems, source, whole_tree=False) -> tuple:
    """(_Tree, _Chain) of the parsed links and joints and the ``chain`` choice (or, with
    ``whole_tree``, every moving joint below the root ``chain[0]``); without a tree or a
    chain, raises ModelFileError with the problems so far (the invalid <inertial>
    elements first: whether they matter cannot be told without a chain)."""
    tree = _tree(parsed.links, parsed.joints, problems, parsed.left_out)
    if tree is not None and whole_tree:
        if chain is not None and len(chain) == 2 and chain[1] is not None:
            problems.append(f"a whole tree has no tip link, got chain {chain!r}: give only "
                            "its root")
            picked = None
        else:
            picked = _select_tree(tree, None if chain is None else chain[0], frozen,
                                  problems)
    else:
        picked = _select_chain(tree, chain, frozen, problems) if tree is not None else None
    if picked is None:
        if tree is not None:
            problems[-1] += _CHAIN_SKIPPED
        _fail(source, [p for bad in parsed.bad_inertia.values() for p in bad] + problems)
    return tree, _Chain(*picked)
