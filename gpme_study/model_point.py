"""One point of a model-file sweep: the model file's document with the point's values (and
the sweep's run settings) written in, built into a Scenario by the model-file loader
(gpme_io.modelfile, from the document directly: no file is written), run with gpme
(gpme_io.runs.simulate_scenario: the file's integrator and step unless the sweep overrides
them) and reduced to the generic metrics of gpme_study.model_metrics.

A point that cannot be built (a value the loader refuses: ``invalid``), cannot meet its
constraints (an unreachable start with on_constraints, a joint limit reached: ``infeasible``)
or diverges (``diverged``) is a recorded row, never a crash; anything else is ``error``.
"""
import hashlib
import json
import time
from typing import Mapping, Optional

import numpy as np

from gpme_core.errors import ModelError, ModelFileError
from gpme_io.input_files import SIDE_FILE_LIMIT, URDF_LIMIT, InputFileError, read_input_file
from gpme_io.modelfile import build_scenario
from gpme_io.modelfile.load import parse_model_data, resolve_urdf
from gpme_io.runs import simulate_scenario

from . import model_metrics as mm
from .model_paths import ModelDocument
from .point import record_failure

# Bump when a metric's definition changes: finished points of older versions are recomputed.
MODEL_METRICS_VERSION = 1


def scenario_from_document(document: ModelDocument, point: Mapping[str, float], settings):
    """The gpme_io.scenario.Scenario of ``document`` (a model_paths.ModelDocument) with
    ``point`` {path: value} and ``settings`` (model_spec.ModelRunSettings) written in.

    Raises ModelFileError listing every problem the loader finds (file path prefixed),
    ConstraintError when the start cannot be placed on the constraints."""
    data = settings.apply(document.with_values(point))
    spec, problems = parse_model_data(data, document.path)
    if problems:
        raise ModelFileError([f"{document.path}: {p}" for p in problems])
    return build_scenario(spec)


def file_digests(document: ModelDocument, data: Optional[Mapping] = None) -> dict:
    """{key: sha256 of the file's bytes} of the files the document names (model.urdf,
    model.side_file), so a changed URDF changes every point's key; unreadable files are
    left out (the point then fails as invalid and says why)."""
    model = (data if data is not None else document.data).get("model")
    out = {}
    if not isinstance(model, dict):
        return out
    paths = {}
    if isinstance(model.get("urdf"), str):
        try:
            paths["urdf"] = resolve_urdf(model["urdf"], document.path)
        except ModelError:
            pass
    if isinstance(model.get("side_file"), str):
        paths["side_file"] = document.path.parent / model["side_file"]
    limits = {"urdf": ("URDF", URDF_LIMIT), "side_file": ("side file", SIDE_FILE_LIMIT)}
    for key, p in paths.items():
        try:
            out[key] = hashlib.sha256(read_input_file(p, *limits[key])).hexdigest()
        except InputFileError:
            pass
    return out


def model_point_key(document: ModelDocument, point: Mapping[str, float], settings) -> str:
    """16 hex digits identifying a point's results: a hash of the document with the point's
    values written in, the files it names, the run settings and MODEL_METRICS_VERSION."""
    try:
        data = document.with_values(point)
    except (ValueError, TypeError):
        data = {"invalid": sorted((k, repr(v)) for k, v in point.items())}
    payload = {"document": data, "files": file_digests(document, data),
               "run": settings.as_dict(), "metrics_version": MODEL_METRICS_VERSION}
    text = json.dumps(payload, sort_keys=True, default=str)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:16]


def run_model_point(document: ModelDocument, point: Mapping[str, float], settings) -> dict:
    """One row (dict) of a model-file sweep table for ``point`` {path: value}.

    Columns: key, status (ok, infeasible, diverged, invalid, error), error ('' if ok),
    failed_run ('build' or 'run' when it failed), the point's values, the metrics of
    gpme_study.model_metrics (absent when the point failed), constraints_met,
    note (why the |Phi| window is empty, if it is), integrator, dt_s (RK4 step, s), t_end_s,
    sim_wall_s (integration only, s), wall_time_s (the whole point, s).
    """
    start = time.perf_counter()
    row = {"key": model_point_key(document, point, settings), "status": "ok", "error": "",
           "failed_run": "", **point, "constraints_met": False, "note": "",
           "integrator": "", "dt_s": np.nan, "t_end_s": np.nan, "sim_wall_s": np.nan}
    stage = "build"
    try:
        scenario = scenario_from_document(document, point, settings)
        stage = "run"
        row["integrator"] = scenario.integrator
        df = simulate_scenario(scenario)
        row["dt_s"] = df.attrs["dt"] if df.attrs.get("dt") is not None else np.nan
        row["t_end_s"] = float(df["t"].iloc[-1])
        row["sim_wall_s"] = df.attrs["wall_time_s"]
        stage = "metrics"
        row.update(mm.run_metrics(scenario, df, settings.transient, settings.phi_tolerance))
        if row["transient_s"] >= row["t_end_s"] and scenario.system.constraint_names:
            row["note"] = (f"the run ends inside the Baumgarte transient "
                           f"({row['transient_s']:.3g} s): |Phi| not checked; start on the "
                           "constraints (run.on_constraints = true) or run longer")
    except Exception as exc:    # every failure becomes a row: the sweep goes on
        record_failure(row, exc, stage)
    row["wall_time_s"] = time.perf_counter() - start
    return row
