"""Published values of a motion against gpme's run: the rows of a model file's
[[reference]] entries (gpme_io.scenario.ReferenceValues).

One row per entry and group (coordinates, velocities): the run's values at the entry's time
against the published ones, within the entry's tolerance (abs + rel x the group's largest
|value|, normwise like every tolerance of the harness), the source and the reason shown
in the row.  The reference is the publication's, not an engine's: the engine column reads
"published".  A run that ends before the entry's time (a quick run) gives one information
row saying so; so does a time that is not one of the run's samples.
"""
import numpy as np

from .compare import Tolerance, compare

ENGINE = "gpme"
# |t_sample - t| accepted as the same time (s): samples are multiples of output_dt, so a
# published time on that grid lands within round-off of a sample
SAME_TIME = 1e-9


def reference_rows(scenario, df) -> list:
    """Rows of ``scenario.references`` against the run ``df`` (gpme's history table)."""
    rows = []
    times = df["t"].to_numpy(dtype=float)
    for ref in scenario.references:
        k = int(np.argmin(np.abs(times - ref.t)))
        groups = {"coordinates": [c for c in ref.values if not c.endswith("_dot")
                                  or c in scenario.model.coordinate_names],
                  "velocities": [c for c in ref.values if c.endswith("_dot")
                                 and c not in scenario.model.coordinate_names]}
        for group, columns in groups.items():
            if not columns:
                continue
            quantity = f"published {group} at t = {ref.t:g} s"
            case = f"{ref.key}: {ref.source}"
            if ref.t > times[-1] + SAME_TIME or abs(times[k] - ref.t) > SAME_TIME:
                why = (f"the run ends at {times[-1]:g} s, before {ref.t:g} s (a quick run)"
                       if ref.t > times[-1] else
                       f"{ref.t:g} s is not a sample time of the run (output_dt)")
                rows.append(compare(ENGINE, scenario.name, quantity, case, [0.0], [0.0],
                                    Tolerance(np.inf, 0.0, f"information: not compared: {why}"),
                                    ["-"]))
                continue
            published = np.array([ref.values[c] for c in columns])
            tol = Tolerance(ref.abs, ref.rel, f"from the model file ({ref.key}): {ref.reason}")
            rows.append(compare(ENGINE, scenario.name, quantity, case,
                                df[columns].iloc[k].to_numpy(float), published, tol, columns))
    return rows
