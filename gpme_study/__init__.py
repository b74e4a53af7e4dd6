"""Parameter studies of the crane's programmed motion (`gpme sweep`).

Modules, one job each:
  spec     what to sweep: grid / list / Latin-hypercube points over CraneParameters
           fields and n_rfe, read from the command line or a TOML/YAML file, validated
  point    one point -> one row of metrics (a failed run is a recorded outcome)
  store    the resume store: one JSON file per finished point, keyed by a hash
  runner   runs the pending points on a Dask cluster (local by default), writes the table
  plots    heat maps over two parameters with the infeasible and the safe region marked
docs/sweep.md describes the metrics and their units.
"""
from .spec import SweepSpec, SweepSpecError, load_spec  # noqa: F401
from .point import run_point  # noqa: F401
from .runner import run_sweep  # noqa: F401
