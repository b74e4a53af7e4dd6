"""Read a URDF (any tree, through a chosen chain) into a gpme Model: the names of the
package gpme_io.urdf_read, importable from here as before its split by job.

The reader lives in gpme_io/urdf_read/ (parse, tree, frozen, placement, masses,
side_match, beams, build, read, load; its docstring lists what each does).  This module
only re-exports: the public API (:func:`load_urdf`, :func:`read_urdf`, :func:`parse_urdf`,
:func:`with_link_frames`, :class:`FlexibleLink`, :class:`UrdfReadResult`, FlexibleSpec).
New code may import from gpme_io.urdf_read directly (the tests import the tree's private
helpers from gpme_io.urdf_read.tree).
"""
from .urdf_read import (FlexibleLink, FlexibleSpec, UrdfReadResult, load_urdf, parse_urdf,
                        read_urdf, with_link_frames)

__all__ = ["FlexibleLink", "FlexibleSpec", "UrdfReadResult", "load_urdf", "parse_urdf",
           "read_urdf", "with_link_frames"]
