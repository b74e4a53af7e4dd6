"""URDF in and out for gpme models: the public names of gpme_io.urdf_reader,
gpme_io.urdf_writer and gpme_io.side_file in one place (kept so that existing imports
``from gpme_io.urdf import read_urdf, write_urdf`` keep working).

* gpme_io.urdf_reader : :func:`load_urdf` (any tree, through a chosen chain, frozen
  joints, flexible links, a report of what was ignored), :func:`read_urdf`,
  :class:`FlexibleLink`, :class:`UrdfReadResult`;
* gpme_io.urdf_writer : :func:`write_urdf`, :func:`urdf_documents`;
* gpme_io.side_file   : the ``<stem>.gpme.json`` side file.
"""
from .side_file import (SIDE_FORMAT, SIDE_SUFFIX, SIDE_VERSION, load_side_file,
                        side_file_path, side_file_problems, side_file_text)
from .urdf_reader import FlexibleLink, UrdfReadResult, load_urdf, parse_urdf, read_urdf
from .urdf_writer import (FIXED_SUFFIX, MUJOCO_BOUND, ROOT_LINK, UNLIMITED, urdf_documents,
                          write_urdf)

__all__ = ["FIXED_SUFFIX", "MUJOCO_BOUND", "ROOT_LINK", "SIDE_FORMAT", "SIDE_SUFFIX",
           "SIDE_VERSION", "UNLIMITED", "FlexibleLink", "UrdfReadResult", "load_side_file",
           "load_urdf", "parse_urdf", "read_urdf", "side_file_path", "side_file_problems",
           "side_file_text", "urdf_documents", "write_urdf"]
