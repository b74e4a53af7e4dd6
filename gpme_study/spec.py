"""What a sweep runs: the points (grid, explicit list or Latin-hypercube sample) over crane
parameters and n_rfe, the run settings, the safe-region limits and the heat-map axes.

A spec comes from a dict (read from a TOML or YAML file, or built by the command line) and
is validated once, here: :class:`SweepSpecError` lists every problem found.  Schema::

    mode = "grid"                  # "grid" | "list" | "lhs"
    [parameters]                   # grid: values per parameter, the Cartesian product is run
    A = [0.2, 0.35, 0.5]           #   a list, one number, {start, stop, num} or "start:stop:num"
    T = "1.5:3.5:5"
    # lhs: a range per parameter, [low, high] or {low, high} or "low:high"
    # samples = 20                 # lhs only: number of points
    # seed = 0                     # lhs only: seed of the sample
    # points = [{A = 0.3, T = 2.0}, ...]   # list only: the points themselves
    [run]                          # settings that change the results (part of each point's key)
    t_end = 6.0                    # s, simulated time of each run
    n_rfe = 1                      # RFEM segments when n_rfe is not swept (0 = rigid arm only)
    transient = 1.0                # s, start of the window of the |Phi| and spectrum metrics
    output_dt = 2e-3               # s, spacing of the recorded rows (Nyquist 250 Hz)
    dt = 0                         # s, RK4 step; 0 = per point from gpme_core.stability.rk4_step
    min_frequency_hz = 2.0         # Hz, lower edge of the vibration-frequency search
    phi_tolerance = 1e-3           # largest |Phi| after the transient that counts as met
    [limits]                       # safe region: metric name = largest allowed value
    dev_peak_m = 0.01
    drive_psi3_peak_Nm = 30.0
    [plot]
    x = "A"                        # heat-map axes (default: the first two swept parameters)
    y = "T"

Parameter names are CraneParameters fields (amplitude, period, ellipse_a, ...) or the
aliases in :data:`ALIASES` (A, T, a, b, E, ...), plus n_rfe.  Tables use the field names.

With a top-level ``model = "path/to/file.toml"`` (relative to the sweep file) the sweep runs
that model file instead of the built-in crane: parameters are dotted paths into the file
and the run settings and metrics are generic (gpme_study.model_spec).
"""
import dataclasses
import math
from dataclasses import dataclass

from gpme_core.echo import did_you_mean as echo_did_you_mean
from gpme_core.echo import shown
from gpme_examples.crane import CraneParameters

from .spec_points import (MAX_N_RFE, MODES, SweepSpec, SweepSpecError, fill_defaults, grid_points,
                          limits_of, list_points, lhs_points, number, plot_axes, swept_names)

from .metrics import METRICS

# short names accepted everywhere a parameter is named -> CraneParameters field
ALIASES = {"A": "amplitude", "T": "period", "a": "ellipse_a", "b": "ellipse_b",
           "E": "steel_youngs_modulus", "beam_stiffness": "steel_youngs_modulus",
           "youngs_modulus": "steel_youngs_modulus", "t_dr0": "drive_torque",
           "t0": "drive_ramp_time", "s_z": "support_stiffness", "d_z": "support_damping"}
# field -> (unit, smallest valid value, whether that value itself is allowed)
PARAMETERS = {
    "amplitude": ("m", 0.0, True),
    "period": ("s", 0.0, False),
    "ellipse_a": ("m", 0.0, False),
    "ellipse_b": ("m", 0.0, False),
    "z0": ("m", -math.inf, False),
    "drive_torque": ("N m", -math.inf, False),
    "drive_ramp_time": ("s", 0.0, False),
    "support_stiffness": ("N/m", 0.0, False),
    "support_damping": ("N s/m", 0.0, True),
    "steel_youngs_modulus": ("Pa", 0.0, False),
    "steel_shear_modulus": ("Pa", 0.0, False),
    "arm_diameter": ("m", 0.0, False),
    "arm_wall_thickness": ("m", 0.0, True),
    "arm_length": ("m", 0.0, False),
    "arm_viscosity": ("Pa s", 0.0, True),
    "slider_mass": ("kg", 0.0, False),
    "n_rfe": ("", 0, True),
}
RUN_DEFAULTS = {"t_end": 6.0, "n_rfe": 1, "transient": 1.0, "output_dt": 2e-3, "dt": 0.0,
                "min_frequency_hz": 2.0, "phi_tolerance": 1e-3}
TOP_KEYS = ("mode", "parameters", "points", "samples", "seed", "run", "limits", "plot",
            "model")


@dataclass(frozen=True)
class RunSettings:
    """Settings every point is run with (see the module docstring for units)."""

    t_end: float = RUN_DEFAULTS["t_end"]
    n_rfe: int = RUN_DEFAULTS["n_rfe"]
    transient: float = RUN_DEFAULTS["transient"]
    output_dt: float = RUN_DEFAULTS["output_dt"]
    dt: float = RUN_DEFAULTS["dt"]
    min_frequency_hz: float = RUN_DEFAULTS["min_frequency_hz"]
    phi_tolerance: float = RUN_DEFAULTS["phi_tolerance"]

    def as_dict(self):
        return dataclasses.asdict(self)


def canonical(name):
    """Field name of a parameter given by field name or alias (unknown names unchanged)."""
    return ALIASES.get(name, name)


def unit_of(name):
    """Unit string of a parameter or metric column."""
    name = canonical(name)
    if name in PARAMETERS:
        return PARAMETERS[name][0]
    return METRICS.get(name, ("",))[0]


def _n_rfe_problem(value):
    """'n_rfe must be ...' when ``value`` is not a valid number of RFEM segments, else None."""
    if math.isfinite(value) and value == int(value) and 0 <= value <= MAX_N_RFE:
        return None
    return (f"n_rfe must be an integer from 0 to {MAX_N_RFE} (RFEM segments of the arm), "
            f"got {shown(value)}")


def _check_value(name, value, where, problems):
    unit, lo, inclusive = PARAMETERS[name]
    if name == "n_rfe":
        if _n_rfe_problem(value):
            problems.append(f"{where}: {_n_rfe_problem(value)}")
        return
    if not math.isfinite(value) or value < lo or (value == lo and not inclusive):
        rel = ">=" if inclusive else ">"
        problems.append(f"{where}: {name} must be finite and {rel} {lo:g} {unit}, "
                        f"got {shown(value)}")


def did_you_mean(name, valid):
    """' (did you mean 'x', 'y'?)' for the names of ``valid`` close to ``name``, or ''."""
    return echo_did_you_mean(name, valid, n=3)


def _check_name(name, where, problems):
    c = canonical(name)
    if c not in PARAMETERS:
        mean = did_you_mean(name, list(PARAMETERS) + list(ALIASES))
        problems.append(f"{where}: unknown parameter {shown(name)}{mean}; valid: "
                        f"{sorted(PARAMETERS)} or aliases {sorted(ALIASES)}")
        return None
    return c


class CraneSpace:
    """The parameters of the built-in crane sweep: CraneParameters fields and n_rfe.  A
    model-file sweep has its own space (gpme_study.model_spec.ModelSpace) with the same
    four methods."""

    def name(self, name, where, problems):
        """The table name of parameter ``name``, or None (a problem is appended)."""
        return _check_name(name, where, problems)

    def check(self, name, value, where, problems):
        """Append a problem when ``value`` is not valid for parameter ``name``."""
        _check_value(name, value, where, problems)

    def is_integer(self, name):
        return name == "n_rfe"

    def default(self, name):
        """The value a point that does not name ``name`` runs with (n_rfe: None, the run's
        n_rfe is filled in by crane_spec_from_dict)."""
        return None if name == "n_rfe" else float(default_value(name))


CRANE = CraneSpace()


def crane_spec_from_dict(data):
    """Validated :class:`SweepSpec` of the built-in crane from a dict of the schema in the
    module docstring (without ``model``: gpme_study.sweep_spec chooses)."""
    data = dict(data or {})
    problems = []
    for key in data:
        if key not in TOP_KEYS:
            problems.append(f"unknown key {shown(key)}; valid keys: {list(TOP_KEYS)}")
    mode = data.get("mode", "grid")
    if mode not in MODES:
        problems.append(f"mode must be one of {MODES}, got {shown(mode)}")
    run = _run_settings(data.get("run") or {}, problems)
    parameters = data.get("parameters") or {}
    if not isinstance(parameters, dict):
        problems.append(f"parameters must be a table name = values, got {shown(parameters)}")
        parameters = {}
    points = []
    if mode == "grid":
        points = grid_points(parameters, problems, CRANE)
    elif mode == "lhs":
        points = lhs_points(parameters, data.get("samples"), data.get("seed", 0), problems,
                            CRANE)
    elif mode == "list":
        points = list_points(data.get("points"), problems, CRANE)
        if parameters:
            problems.append("mode 'list' takes its points from 'points', not 'parameters'")
    for key, wanted in (("samples", "lhs"), ("seed", "lhs"), ("points", "list")):
        if key in data and mode != wanted:
            problems.append(f"{shown(key)} is only used with mode {wanted!r} (mode is "
                            f"{shown(mode)})")
    for pt in points:
        pt.setdefault("n_rfe", run.n_rfe)
    fill_defaults(points, CRANE)
    swept = swept_names(points)
    limits = limits_of(data.get("limits") or {}, problems)
    plot = data.get("plot") or {}
    plot_x, plot_y = plot_axes(plot, swept, problems, CRANE)
    if problems:
        raise SweepSpecError(problems)
    for pt in points:
        pt["n_rfe"] = int(pt["n_rfe"])
    return SweepSpec(mode, tuple(points), swept, run, limits, plot_x, plot_y)


def _run_settings(run, problems):
    if not isinstance(run, dict):
        problems.append(f"run must be a table of settings, got {shown(run)}")
        return RunSettings()
    values = dict(RUN_DEFAULTS)
    for key, value in run.items():
        if key not in RUN_DEFAULTS:
            problems.append(f"run.{key}: unknown setting; valid: {sorted(RUN_DEFAULTS)}")
            continue
        try:
            values[key] = number(value)
        except (ValueError, TypeError):
            problems.append(f"run.{key}: expected a number, got {shown(value)}")
    v = values
    valid = {}
    for key in ("t_end", "output_dt", "phi_tolerance"):
        valid[key] = math.isfinite(v[key]) and v[key] > 0
        if not valid[key]:
            problems.append(f"run.{key} must be finite and > 0, got {shown(v[key])}")
    for key in ("transient", "dt", "min_frequency_hz"):
        valid[key] = math.isfinite(v[key]) and v[key] >= 0
        if not valid[key]:
            problems.append(f"run.{key} must be finite and >= 0, got {shown(v[key])}")
    n_rfe_problem = _n_rfe_problem(v["n_rfe"])
    if n_rfe_problem:
        problems.append(f"run.{n_rfe_problem}")
    # the relations are checked only between valid values (no second message for one typo)
    if valid["transient"] and valid["t_end"] and v["transient"] >= v["t_end"]:
        problems.append(f"run.transient ({v['transient']:g} s) must be shorter than run.t_end "
                        f"({v['t_end']:g} s): the metrics after the transient need data")
    if valid["output_dt"] and valid["t_end"] and v["output_dt"] > 0.1 * v["t_end"]:
        problems.append(f"run.output_dt ({v['output_dt']:g} s) must be at most a tenth of "
                        f"run.t_end ({v['t_end']:g} s)")
    if valid["dt"] and valid["output_dt"] and v["dt"] > v["output_dt"]:
        problems.append(f"run.dt ({v['dt']:g} s) must not exceed run.output_dt "
                        f"({v['output_dt']:g} s): output_dt >= dt (0 = per point)")
    if not n_rfe_problem:
        v["n_rfe"] = int(v["n_rfe"])
    return RunSettings(**v)


def crane_changes(point):
    """The CraneParameters fields of a point (n_rfe removed)."""
    return {k: v for k, v in point.items() if k != "n_rfe"}


def default_value(name):
    """Value of a parameter in CraneParameters() (n_rfe: the run default)."""
    if name == "n_rfe":
        return RUN_DEFAULTS["n_rfe"]
    return getattr(CraneParameters(), name)
