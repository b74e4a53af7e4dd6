"""The entry points: a URDF file or text (and its side file) -> a gpme Model.

:func:`load_urdf` reads a file and its side file and reports what it made of them;
:func:`read_urdf` and :func:`parse_urdf` give the Model alone (of a file, of text).
"""
from pathlib import Path

from gpme_core.model import Model

from ..input_files import URDF_LIMIT, InputFileError, read_input_file
from ..side_file import check_side_file, read_side_file, side_file_path
from .read import UrdfReadResult, _read_guarded


def load_urdf(path, *, side_file="auto", chain=None, frozen=None, flexible=None,
              massless_links=(), gravity=None, name=None, whole_tree=False) -> UrdfReadResult:
    """Read the URDF at ``path`` into a gpme Model, through a chosen chain or as a whole
    tree.

    side_file     : "auto" (``<stem>.gpme.json`` beside the URDF if it exists), None (no
                    side file: stiffness 0, gravity standard) or a path.  It restores
                    stiffness, spring references, gravity, drives and RFEM records.
    chain         : (root link, tip link); None = from the URDF root to the single path of
                    moving joints (error listing the branch ends when there are several).
    whole_tree    : every moving joint below the root link (``chain`` = (root,) or None)
                    that is not in ``frozen`` is a coordinate: the model is a tree whose
                    branches all move (gpme_core.model), its joints parents first in the
                    file's order.  Also when the side file says ``"tree": true``.
    frozen        : {joint name: value (rad or m)} for joints off the chain; every other
                    moving joint off the chain is frozen at 0 (a mimic joint: multiplier *
                    value + offset of the joint it mimics).  Joints above the chain root
                    must be listed here.
    flexible      : {link name: FlexibleLink(...)} (or the older (BeamProperties, n)
                    along +x); the link's <inertial> is replaced by the RFEM beam.
    massless_links: moving links expected to carry no mass (no note for them, and a link
                    with geometry but no <inertial> is then accepted); a massless chain
                    link is accepted whenever M stays positive definite.
    gravity       : (3,) m/s^2 in the URDF root (= gpme world) frame; None: the side
                    file's, else (0, 0, -9.81).
    name          : model name; None: the side file's, else the URDF robot name.

    Returns an :class:`UrdfReadResult`; raises ModelFileError listing every problem found
    in one read: the XML, the side file (every key and record), the links' inertials, the
    joints, the tree, the chain choice, frozen values, flexible specs, the side file
    against the URDF and the built model.  A stage that cannot run because an earlier one
    failed (no tree, no chain) is named in the problem that stopped it.
    """
    path = Path(path)
    source = str(path)
    problems = []
    try:
        data = read_input_file(path, "URDF", URDF_LIMIT)
    except InputFileError as exc:
        data = None
        problems.append(f"cannot read the URDF: it {exc.reason}; a URDF is an XML file "
                        "<robot name=...> with <link> and <joint> elements")
    side = None
    if side_file == "auto":
        if side_file_path(path).exists():
            side, bad = read_side_file(side_file_path(path))
            problems += bad
    elif side_file is not None:
        side, bad = read_side_file(side_file)
        problems += bad
    return _read_guarded(data, side, problems, chain=chain, frozen=frozen, flexible=flexible,
                         massless_links=massless_links, gravity=gravity, name=name,
                         source=source, whole_tree=whole_tree)


def read_urdf(path, side_file="auto", flexible=None, massless_links=(), gravity=None,
              name=None, *, chain=None, frozen=None, whole_tree=False) -> Model:
    """The Model of :func:`load_urdf` (same arguments), without the report."""
    return load_urdf(path, side_file=side_file, chain=chain, frozen=frozen, flexible=flexible,
                     massless_links=massless_links, gravity=gravity, name=name,
                     whole_tree=whole_tree).model


def parse_urdf(text, side=None, flexible=None, massless_links=(), gravity=None, name=None,
               source="<urdf>", *, chain=None, frozen=None, whole_tree=False) -> Model:
    """:func:`read_urdf` on URDF ``text`` (str or bytes) and a side-file dict ``side`` (or
    None)."""
    problems = []
    if side is not None:
        side, problems = check_side_file(side)
    return _read_guarded(text, side, problems, chain=chain, frozen=frozen, flexible=flexible,
                         massless_links=massless_links, gravity=gravity, name=name,
                         source=source, whole_tree=whole_tree).model
