"""Crosscheck against Exudyn: programmed runs with the task as exact index-3 constraints.

Importing this package imports nothing from Exudyn (the optional-engine check imports the
package name only); ``model``, ``constraints``, ``runs`` and ``check`` need ``exudyn``.
"""
