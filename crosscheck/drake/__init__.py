"""Crosscheck against Drake (MultibodyPlant from gpme's URDF): term by term and free-motion
runs with Drake's own integrator (docs/crosscheck-drake.md).

Importing this package does not import pydrake: ``check`` (terms, ``run``), ``model`` (the
plant and the coordinate map) and ``runs`` (free runs) do.
"""
