"""A sweep of a model file (``gpme sweep --model FILE``, or ``model = "file.toml"`` at the top
of a sweep file): its parameter paths, run settings and metrics, validated once.

Schema (the crane sweep's, gpme_study.spec, with these differences)::

    model = "../models/crane_rigid.toml"      # relative to the sweep file
    mode = "grid"
    [parameters]                              # dotted paths into the model file
    "constraint.Phi_2.function.amplitude" = [0.3, 0.5]
    "joint.shoulder.stiffness" = "10:40:4"
    [run]                                     # all optional; absent = the model file's own
    t_end = 0.3                               # s, replaces the file's run.t_end
    dt = 1e-3                                 # s, RK4 step (file's run.dt or its suggestion)
    output_dt = 1e-3                          # s, recorded rows
    transient = 0.0                           # s, start of the |Phi| window (default: the
                                              #   Baumgarte transient of each run's start)
    on_constraints = true                     # start every point on its constraints
    phi_tolerance = 1e-3                      # largest |Phi| after the transient that is "met"
    [limits]                                  # generic metric columns (model_metrics)
    "tau_peak.psi2" = 2.0

Parameter paths: gpme_study.model_paths.  The sweep's run settings are written into each
point's document ([run] t_end, dt, output_dt; [initial] on_constraints) before it is built,
so a point is exactly the model file with those values.
"""
import dataclasses
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Optional

from gpme_core.echo import shown
from gpme_core.errors import ConstraintError, ModelError
from gpme_io.modelfile.load import parse_model_data

from .model_metrics import metric_columns
from .model_paths import PathError, read_model_document
from .model_point import scenario_from_document
from .spec_points import (MAX_N_RFE, MODES, SweepSpec, SweepSpecError, fill_defaults,
                          grid_points, grid_values, lhs_points, limits_of, list_points, number,
                          plot_axes, swept_names, value_range)

MODEL_TOP_KEYS = ("model", "mode", "parameters", "points", "samples", "seed", "run", "limits",
                  "plot")
MODEL_RUN_KEYS = {"t_end": "s", "dt": "s", "output_dt": "s", "transient": "s",
                  "on_constraints": "true or false", "phi_tolerance": "[Phi]"}
DEFAULT_PHI_TOLERANCE = 1e-3


@dataclass(frozen=True)
class ModelRunSettings:
    """How every point of a model-file sweep runs; None = what the model file says.

    t_end, dt, output_dt : s, written into the point's [run] (dt is the RK4 step)
    transient            : s, start of the |Phi| window (None: the Baumgarte transient of
                           the run's initial violation, crosscheck.run_checks.transient_time)
    on_constraints       : written into [initial] on_constraints
    phi_tolerance        : largest max |Phi_k| after the transient counted as met (in each
                           constraint's unit)
    """

    t_end: Optional[float] = None
    dt: Optional[float] = None
    output_dt: Optional[float] = None
    transient: Optional[float] = None
    on_constraints: Optional[bool] = None
    phi_tolerance: float = DEFAULT_PHI_TOLERANCE

    def as_dict(self):
        return dataclasses.asdict(self)

    def apply(self, data: dict) -> dict:
        """``data`` (a model-file document, changed in place and returned) with these
        settings written in; quick_t_end is shortened to t_end when it would exceed it."""
        run = data.setdefault("run", {})
        if isinstance(run, dict):
            for key in ("t_end", "dt", "output_dt"):
                if getattr(self, key) is not None:
                    run[key] = getattr(self, key)
            q = run.get("quick_t_end")
            if self.t_end is not None and isinstance(q, (int, float)) and q > self.t_end:
                run["quick_t_end"] = self.t_end
        if self.on_constraints is not None:
            initial = data.setdefault("initial", {})
            if isinstance(initial, dict):
                initial["on_constraints"] = self.on_constraints
        return data


class ModelSpace:
    """The parameters of a model-file sweep: the sweepable paths of its document."""

    def __init__(self, document):
        self.document = document

    def name(self, name, where, problems):
        try:
            return self.document.canonical(str(name))
        except PathError as exc:
            problems.append(f"{where}: {exc}")
            return None

    def check(self, name, value, where, problems):
        named = where if where.endswith(name) else f"{where}: {name}"
        try:
            x = self.document.coerce(name, value)
        except (ValueError, TypeError) as exc:
            problems.append(f"{named}: {exc}")
            return
        if isinstance(x, int) and x > MAX_N_RFE:
            problems.append(f"{named}: at most {MAX_N_RFE} RFEM segments in a sweep, got {x} "
                            "(the RK4 step of a beam falls as 1/segments^2; "
                            "gpme_study.spec_points.MAX_N_RFE)")

    def is_integer(self, name):
        return isinstance(self.document.coerce(name, self.document.value(name)), int)

    def default(self, name):
        """The value a point that does not name ``name`` runs with: the file's."""
        return self.document.coerce(name, self.document.value(name))


def model_spec_from_dict(data: dict, base_dir=None) -> SweepSpec:
    """Validated SweepSpec of a model-file sweep (see the module docstring); raises
    SweepSpecError listing every problem, including the model file's own."""
    problems = []
    for key in data:
        if key not in MODEL_TOP_KEYS:
            problems.append(f"unknown key {shown(key)}; valid keys with a model file: "
                            f"{list(MODEL_TOP_KEYS)}")
    written = data.get("model")
    document = None
    if not isinstance(written, str) or not written.strip():
        problems.append(f"model must be the path of a model file (.toml), got {shown(written)}")
    else:
        path = Path(written).expanduser()
        if not path.is_absolute():
            path = Path(base_dir or ".") / path
        try:
            document = read_model_document(path)
        except PathError as exc:
            problems.append(f"model: {exc}")
    if document is None:
        raise SweepSpecError(problems)
    space = ModelSpace(document)
    mode = data.get("mode", "grid")
    if mode not in MODES:
        problems.append(f"mode must be one of {MODES}, got {shown(mode)}")
    run = _model_run_settings(data.get("run") or {}, problems)
    parameters = data.get("parameters") or {}
    if not isinstance(parameters, dict):
        problems.append(f"parameters must be a table path = values, got {shown(parameters)}")
        parameters = {}
    points = []
    if mode == "grid":
        points = grid_points(parameters, problems, space)
    elif mode == "lhs":
        points = lhs_points(parameters, data.get("samples"), data.get("seed", 0), problems,
                             space)
    elif mode == "list":
        points = list_points(data.get("points"), problems, space)
        if parameters:
            problems.append("mode 'list' takes its points from 'points', not 'parameters'")
    for key, wanted in (("samples", "lhs"), ("seed", "lhs"), ("points", "list")):
        if key in data and mode != wanted:
            problems.append(f"{shown(key)} is only used with mode {wanted!r} (mode is "
                            f"{shown(mode)})")
    fill_defaults(points, space)
    swept = swept_names(points)
    for key in ("t_end", "dt", "output_dt"):
        if getattr(run, key) is not None and f"run.{key}" in swept:
            problems.append(f"run.{key} is both swept (parameter run.{key}) and set in the "
                            "sweep's [run]; give it in one place")
    columns = _base_columns(document, run, problems)
    if columns:                   # the file itself builds: ask the loader about each value
        _value_problems(document, _candidate_values(document, data, mode, parameters), run,
                        problems)
    limits = limits_of(data.get("limits") or {}, problems, columns) if columns else {}
    plot = data.get("plot") or {}
    plot_x, plot_y = plot_axes(plot, swept, problems, space)
    if problems:
        raise SweepSpecError(problems)
    points = [{name: document.coerce(name, v) for name, v in pt.items()} for pt in points]
    return SweepSpec(mode, tuple(points), swept, run, limits, plot_x, plot_y, model=document,
                     metrics=columns)


def _model_run_settings(run, problems) -> ModelRunSettings:
    if not isinstance(run, dict):
        problems.append(f"run must be a table of settings, got {shown(run)}")
        return ModelRunSettings()
    values = {}
    for key, value in run.items():
        if key not in MODEL_RUN_KEYS:
            problems.append(f"run.{key}: not a setting of a model-file sweep; valid: "
                            + ", ".join(f"{k} ({u})" for k, u in MODEL_RUN_KEYS.items()))
            continue
        if key == "on_constraints":
            if not isinstance(value, bool):
                problems.append(f"run.on_constraints must be true or false, got {shown(value)}")
            else:
                values[key] = value
            continue
        try:
            x = number(value)
        except (ValueError, TypeError):
            problems.append(f"run.{key}: expected a number ({MODEL_RUN_KEYS[key]}), got "
                            f"{shown(value)}")
            continue
        rule_ok = math.isfinite(x) and (x >= 0 if key == "transient" else x > 0)
        if not rule_ok:
            rel = ">= 0" if key == "transient" else "> 0"
            problems.append(f"run.{key} must be finite and {rel} ({MODEL_RUN_KEYS[key]}), "
                            f"got {shown(value)}")
            continue
        values[key] = x
    t_end, tr = values.get("t_end"), values.get("transient")
    if t_end is not None and tr is not None and tr >= t_end:
        problems.append(f"run.transient ({tr:g} s) must be shorter than run.t_end "
                        f"({t_end:g} s): the |Phi| metrics after the transient need data")
    return ModelRunSettings(**values)


# at most this many single values are checked by the model-file loader before a sweep (a
# check is 3-7 ms); beyond it a refused value is a point with status "invalid"
MAX_CHECKED_VALUES = 2000


def _candidate_values(document, data, mode, parameters):
    """The distinct (path, value) pairs the sweep sets, as written (a grid's axis values, a
    list's values, a Latin hypercube's range ends), leaving out those already refused by
    name or value (their problems are listed): what the loader is asked about."""
    space = ModelSpace(document)
    pairs = []
    if mode == "list":
        points = data.get("points") if isinstance(data.get("points"), (list, tuple)) else []
        pairs = [(name, value) for pt in points if isinstance(pt, dict)
                 for name, value in pt.items()]
    elif isinstance(parameters, dict):
        for name, value in parameters.items():
            values = value_range(name, value, []) if mode == "lhs" else \
                grid_values(name, value, [])
            pairs += [(name, v) for v in values or ()]
    out = {}
    for name, value in pairs:
        try:
            path = document.canonical(str(name))
            x = number(value)
        except (PathError, ValueError, TypeError):
            continue
        ok = []
        space.check(path, x, "", ok)
        if not ok:
            out[(path, document.coerce(path, x))] = None
    return list(out)


def _value_problems(document, values, run, problems):
    """Check every value a sweep sets with the model-file loader before any run: each
    (path, value) of ``values`` alone in the file, with the sweep's run settings written
    in; and the RK4 step against the output spacing (run.dt <= run.output_dt).  A value
    refused only in combination with another one stays a point with status "invalid"."""
    singles = [{}] + [{name: v} for name, v in list(values)[:MAX_CHECKED_VALUES]]
    of_the_file = set()         # problems of the file itself: listed once, not per value
    for single in singles:
        data = run.apply(document.with_values(single))
        spec, found = parse_model_data(data, document.path)
        r = getattr(spec, "run", None)
        if not found and r is not None and r.integrator == "RK4" and r.dt is not None \
                and r.dt > r.output_dt:
            found = found + [f"run.dt ({r.dt:g} s) must not exceed run.output_dt "
                             f"({r.output_dt:g} s): output_dt >= dt"]
        if not single:
            of_the_file.update(found)
            problems += [f"the model file with the sweep's [run]: {p}" for p in found]
            continue
        where = ", ".join(f"parameters.{k} = {shown(v)}" for k, v in single.items())
        problems += [f"{where}: {p}" for p in found if p not in of_the_file]


def _base_columns(document, run, problems) -> dict:
    """The metric columns of the model file as it is (with the sweep's run settings), built
    without placing it on its constraints (only the names are needed); problems of the file
    are appended to ``problems``."""
    base = dataclasses.replace(run, on_constraints=False)
    try:
        scenario = scenario_from_document(document, {}, base)
    except ModelError as exc:
        problems += [f"model: {p}" for p in exc.problems]
        return {}
    except ConstraintError as exc:
        problems.append(f"model: {exc}")
        return {}
    if run.transient is not None and run.transient >= scenario.t_end:
        problems.append(f"run.transient ({run.transient:g} s) must be shorter than the run "
                        f"({scenario.t_end:g} s, the model file's run.t_end)")
    return metric_columns(scenario)
