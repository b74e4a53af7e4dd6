"""Parameter studies of the crane's or any model file's programmed motion (`gpme sweep`).

Modules, one job each:
  spec     what to sweep: grid / list / Latin-hypercube points over CraneParameters
           fields and n_rfe, read from the command line or a TOML/YAML file, validated
  metrics  the metrics' definitions and units, computed from run histories
  point    one point -> one row of metrics (a failed run is a recorded outcome)
  store    the resume store: one JSON file per finished point, keyed by a hash
  runner   runs the pending points on a Dask cluster (local by default), writes the table
  plots    heat maps over two parameters with the infeasible and the safe region marked
  cost     the wall time, output and memory of a sweep, estimated before it starts
           (measured warm-up runs), and the limits it is refused above without --force
  arguments the `gpme sweep` options (imports nothing: the `gpme` parser is built for
           every command)
  command  the checks of every input, then the estimate, the run, the table and the plots
           (imported by `gpme sweep` only)
With a model file (`gpme sweep --model FILE`) instead of the built-in crane:
  model_paths    the sweepable numbers of a model file, named by dotted paths
  model_spec     the sweep's run settings and validation for a model file
  model_point    one point: the document with the point's values -> Scenario -> one row
  model_metrics  the generic metrics (|Phi|, lambda, drive, reaction, q_dot, RFEM, limits,
                 sigma_min of the constraint Jacobian) and their units
docs/sweep.md describes the metrics and their units.  Imported when needed only: Dask (a
sweep on a cluster, runner) and matplotlib (the heat maps, plots).
"""
