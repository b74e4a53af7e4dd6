"""One sweep point: the rigid and the flexible crane at the same parameters, both started on
the constraint manifold (so no Baumgarte transient is mixed into the vibration measures),
reduced to one row of metrics (gpme_study.metrics).  A run that cannot meet its constraints,
diverges or gets invalid input is a recorded outcome (``status``, ``error``), not a crash.
"""
import dataclasses
import hashlib
import json
import math
import time
import traceback

import numpy as np

from gpme_examples.crane import CraneParameters, crane_system, initial_state
from gpme_core.errors import ConstraintError, ModelError, SimulationError
from gpme_core.elastic_loads import elastic_peaks
from gpme_core import stability
from gpme_core.integrate import simulate

from . import metrics as mx
from .spec import RunSettings, crane_changes

# Bump when a metric's definition changes: finished points of older versions are recomputed.
METRICS_VERSION = 4
# s, longest RK4 step of the rigid crane: its fastest dynamics (5 Hz support, Baumgarte
# 20 1/s) then have |h lambda| < 0.035, RK4's local error ~ |h lambda|^5 / 120 < 1e-9
# relative; measured: end-effector positions differ by 1.1e-9 m from dt = 3.3e-4 s over 3 s
# (A = 0.3 m, T = 1.5 s), five decades below the flexibility deviations being measured.
RIGID_DT_MAX = 1e-3
# s, longest RK4 step of the flexible crane (its step normally comes from gpme_core.stability.rk4_step)
FLEXIBLE_DT_MAX = 5e-4
STATUSES = ("ok", "infeasible", "diverged", "invalid", "error")
_STATUS_OF = ((ConstraintError, "infeasible"), (SimulationError, "diverged"),
              (ModelError, "invalid"))


def record_failure(row, exc, stage):
    """Put a failed point's outcome into ``row``: status (infeasible / diverged / invalid /
    error), the stage that failed, the message, and for an unexpected error (a bug, not a
    property of the point) where it was raised."""
    row["status"] = next((s for cls, s in _STATUS_OF if isinstance(exc, cls)), "error")
    row["failed_run"] = stage
    row["error"] = f"{type(exc).__name__}: {exc}"
    if row["status"] == "error":
        row["error"] += " | " + " <- ".join(
            f"{fr.name}:{fr.lineno}" for fr in traceback.extract_tb(exc.__traceback__)[-3:])


def resolved_parameters(point):
    """CraneParameters of a point (raises ModelError for unknown fields)."""
    try:
        return CraneParameters().with_changes(**crane_changes(point))
    except TypeError as exc:
        raise ModelError(f"point {point}: {exc}") from None


def point_key(point, settings):
    """16 hex digits identifying a point's results: a hash of every crane parameter (the
    point applied to the defaults), n_rfe, the run settings and METRICS_VERSION."""
    try:
        params = dataclasses.asdict(resolved_parameters(point))
    except ModelError:
        params = {"invalid": sorted(point.items())}
    payload = {"crane": params, "n_rfe": int(point.get("n_rfe", settings.n_rfe)),
               "run": settings.as_dict(), "metrics_version": METRICS_VERSION}
    text = json.dumps(payload, sort_keys=True, default=repr)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:16]


def rk4_step(system, q0, settings):
    """s: the RK4 step of one run: settings.dt if > 0, else gpme_core.stability.rk4_step capped at
    RIGID_DT_MAX or FLEXIBLE_DT_MAX; shortened so that settings.output_dt is a whole number
    of steps (the rigid and the flexible run of a point then record at the same times)."""
    if settings.dt > 0:
        h = settings.dt
    else:
        cap = FLEXIBLE_DT_MAX if mx.flexible_columns(system.model) else RIGID_DT_MAX
        h = stability.rk4_step(system, q0, cap=cap)
    return settings.output_dt / math.ceil(settings.output_dt / h - 1e-9)


def _run(n_rfe, params, settings):
    system = crane_system(n_rfe, params)
    q0, qd0 = initial_state(system.model, params)
    dt = rk4_step(system, q0, settings)
    df = simulate(system, settings.t_end, q0, qd0, dt=dt, method="RK4", on_manifold=True,
                  output_dt=settings.output_dt)
    return system, df


def run_point(point, settings=RunSettings()):
    """One row (dict) of the sweep table for ``point`` ({CraneParameters field: value,
    'n_rfe': int}); the metrics' names and units are in gpme_study.metrics.METRICS.

    Columns besides the metrics: key, status (one of STATUSES), error (message, '' if ok),
    failed_run ('rigid', 'flexible' or ''), the point's values,
    t_end_s, rigid_dt_s / flexible_dt_s (RK4 steps, s), rigid_sim_wall_s /
    flexible_sim_wall_s (integration only, s)."""
    start = time.perf_counter()
    n_rfe = int(point.get("n_rfe", settings.n_rfe))
    row = {"key": point_key(point, settings), "status": "ok", "error": "", "failed_run": ""}
    row.update(point)
    row["n_rfe"] = n_rfe
    row.update({name: np.nan for name in mx.METRICS})
    row.update(constraints_met=False, t_end_s=settings.t_end, rigid_dt_s=np.nan,
               flexible_dt_s=np.nan,
               rigid_sim_wall_s=np.nan, flexible_sim_wall_s=np.nan)
    stage = "rigid"
    try:
        params = resolved_parameters(point)
        rigid_sys, rigid = _run(0, params, settings)
        row["rigid_sim_wall_s"] = rigid.attrs["wall_time_s"]
        row["rigid_dt_s"] = rigid.attrs["dt"]
        row.update(mx.drive_peaks(rigid_sys, rigid, prefix="rigid_"))
        if n_rfe == 0:
            flex_sys, flex = rigid_sys, rigid
        else:
            stage = "flexible"
            flex_sys, flex = _run(n_rfe, params, settings)
            row["flexible_sim_wall_s"] = flex.attrs["wall_time_s"]
            row["flexible_dt_s"] = flex.attrs["dt"]
        row.update(_history_metrics(flex_sys, flex, rigid, settings, n_rfe))
        row["constraints_met"] = bool(
            max(row["phi1_max_abs"], row["phi2_max_abs_m"]) <= settings.phi_tolerance)
    except Exception as exc:    # every failure becomes a row: the sweep goes on
        record_failure(row, exc, stage)
    row["wall_time_s"] = time.perf_counter() - start
    return row


def _history_metrics(flex_sys, flex, rigid, settings, n_rfe):
    out = {}
    out.update(mx.drive_peaks(flex_sys, flex))
    out.update(mx.constraint_metrics(flex, settings.transient))
    if n_rfe == 0:
        return out
    cols = mx.flexible_columns(flex_sys.model)
    out.update(mx.flexible_coordinate_metrics(flex, cols))
    out["stress_peak_Pa"] = max(p.bending_stress for p in elastic_peaks(flex_sys.model, flex))
    fs = 1.0 / float(np.median(np.diff(flex.t.to_numpy())))
    dr = mx.end_effector_deviation(flex, rigid)
    out.update(mx.dependent_deviation(flex, rigid))
    out.update(mx.deviation_metrics(dr, fs, settings.min_frequency_hz, settings.transient))
    late = flex[flex.t >= settings.transient]
    out["vib_freq_hz"] = mx.dominant_frequency(late[cols].to_numpy(), fs,
                                               settings.min_frequency_hz)
    return out
