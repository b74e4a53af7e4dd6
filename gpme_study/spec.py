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
import itertools
import json
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.stats import qmc

from gpme_core.echo import ECHO_LIMIT, shown, shown_text
from gpme_core.echo import did_you_mean as echo_did_you_mean
from gpme_core.errors import ModelError
from gpme_examples.crane import CraneParameters
from gpme_io.input_files import SWEEP_FILE_LIMIT, InputFileError, read_input_file

from .bounded_yaml import load_yaml

from .metrics import METRICS

MODES = ("grid", "list", "lhs")
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
# more points than this is almost certainly a typo in a grid (hours of runs per point)
MAX_POINTS = 100_000
# most RFEM segments of the crane's arm: the RK4 step falls as 1 / n_rfe^2 (measured with
# point.rk4_step: 3.3e-4 s at 1, 2.4e-7 s at 30, 1.4e-8 s at 100 segments, i.e. 7e7 steps
# per simulated second), so more is never a sweep anyone can finish
MAX_N_RFE = 100


# problems of one sweep description the message lists (all are in .problems), and the
# characters of each: a hostile file (thousands of unknown keys, a megabyte key) must not
# print megabytes; the first ones are what a user fixes first anyway.
MAX_LISTED_PROBLEMS = 50
MAX_PROBLEM_CHARS = 4000


class SweepSpecError(ModelError):
    """A sweep description is invalid; the message lists every problem found (the first
    MAX_LISTED_PROBLEMS, each cut at MAX_PROBLEM_CHARS characters; .problems has all)."""

    def __init__(self, problems):
        super().__init__(problems)
        listed = [shown_text(p, MAX_PROBLEM_CHARS) for p in self.problems[:MAX_LISTED_PROBLEMS]]
        more = len(self.problems) - len(listed)
        if more:
            listed.append(f"... and {more} more problems (fix the ones above first)")
        if len(self.problems) > 1:
            self.args = (f"{len(self.problems)} problems in the sweep description:\n"
                         + "\n".join(f"  - {p}" for p in listed),)
        else:
            self.args = (listed[0],)


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


@dataclass(frozen=True)
class SweepSpec:
    """A validated sweep.

    points : tuple of dicts {field name: value}, only the values that differ from
             CraneParameters() defaults by being swept; n_rfe always present (int)
    swept  : names (field names, n_rfe) that vary over the points
    model  : None for the built-in crane; for a model-file sweep its
             gpme_study.model_paths.ModelDocument (points are then {path: value} and run
             is a gpme_study.model_spec.ModelRunSettings)
    metrics: {column: (unit, definition, can be bounded)} of the table (None: the crane's
             gpme_study.metrics.METRICS)
    """

    mode: str
    points: tuple
    swept: tuple
    run: RunSettings
    limits: dict = field(default_factory=dict)
    plot_x: str = None
    plot_y: str = None
    model: object = None
    metrics: object = None

    @property
    def metric_table(self):
        """{column: (unit, definition, can be bounded)} of this sweep's metrics."""
        return METRICS if self.metrics is None else self.metrics


def canonical(name):
    """Field name of a parameter given by field name or alias (unknown names unchanged)."""
    return ALIASES.get(name, name)


def unit_of(name):
    """Unit string of a parameter or metric column."""
    name = canonical(name)
    if name in PARAMETERS:
        return PARAMETERS[name][0]
    return METRICS.get(name, ("",))[0]


def load_spec(path):
    """SweepSpec from a TOML (.toml) or YAML (.yaml, .yml) file (a ``model`` path in it is
    relative to the file's folder)."""
    return spec_from_dict(read_spec_file(path), base_dir=Path(path).parent)


def read_spec_file(path):
    """The raw dict of a TOML or YAML sweep file (validated later by spec_from_dict)."""
    path = Path(path)
    try:
        raw = read_input_file(path, "sweep file", SWEEP_FILE_LIMIT)
    except InputFileError as exc:
        raise SweepSpecError(str(exc)) from None
    suffix = path.suffix.lower()
    try:
        text = raw.decode("utf-8")
        if suffix == ".toml":
            data = tomllib.loads(text)
        elif suffix in (".yaml", ".yml"):
            data = load_yaml(text) or {}
        else:
            raise SweepSpecError(f"sweep file {str(path)!r}: expected a .toml, .yaml or .yml "
                                 f"file, got suffix {shown(suffix)}")
    except SweepSpecError:
        raise
    except RecursionError:
        raise SweepSpecError(f"sweep file {str(path)!r} cannot be parsed: its lists or tables "
                             "are nested too deeply") from None
    except Exception as exc:     # the parsers' own errors, with their line numbers
        raise SweepSpecError(f"sweep file {str(path)!r} cannot be parsed: "
                             f"{shown_text(str(exc), 2 * ECHO_LIMIT)}") from None
    if not isinstance(data, dict):
        raise SweepSpecError(f"sweep file {str(path)!r}: expected a table/mapping at the top, "
                             f"got {type(data).__name__}")
    return data


def _number(value):
    """float of a number or of a string holding one; ValueError naming the value else."""
    if isinstance(value, bool) or not isinstance(value, (int, float, str, np.number)):
        raise ValueError(f"expected a number, got {shown(value)}")
    try:
        return float(value.strip() if isinstance(value, str) else value)
    except ValueError:
        raise ValueError(f"expected a number, got {shown(value)}") from None


def _grid_values(name, value, problems):
    """Values of one grid axis from a list, a number, {start, stop, num} or 'a:b:n'."""
    try:
        if isinstance(value, str) and ":" in value:
            parts = value.split(":")
            if len(parts) != 3:
                raise ValueError(f"expected 'start:stop:num', got {shown(value)}")
            value = {"start": parts[0], "stop": parts[1], "num": parts[2]}
        elif isinstance(value, str) and "," in value:
            value = [v for v in value.split(",") if v.strip()]
        if isinstance(value, dict):
            extra = set(value) - {"start", "stop", "num"}
            if extra or len(value) != 3:
                raise ValueError(f"expected keys start, stop, num, got {shown(sorted(value))}")
            num = _number(value["num"])
            if not math.isfinite(num) or num != int(num) or num < 1:
                raise ValueError(f"num must be a positive integer, got {shown(value['num'])}")
            if num > MAX_POINTS:
                raise ValueError(f"num = {int(num)} values; at most {MAX_POINTS} (check the "
                                 "grid)")
            start, stop = _number(value["start"]), _number(value["stop"])
            for key, v in (("start", start), ("stop", stop)):
                if not math.isfinite(v):
                    raise ValueError(f"{key} must be a finite number, got {shown(value[key])}")
            return [float(v) for v in np.linspace(start, stop, int(num))]
        if isinstance(value, (list, tuple)):
            if not value:
                raise ValueError("empty list of values")
            return [_number(v) for v in value]
        return [_number(value)]
    except (ValueError, TypeError) as exc:
        problems.append(f"parameters.{name}: {exc}")
        return []


def _range(name, value, problems):
    """(low, high) of one Latin-hypercube axis from [lo, hi], {low, high} or 'lo:hi'."""
    try:
        if isinstance(value, str):
            value = value.split(":")
        if isinstance(value, dict):
            if set(value) != {"low", "high"}:
                raise ValueError(f"expected keys low, high, got {shown(sorted(value))}")
            value = [value["low"], value["high"]]
        if not isinstance(value, (list, tuple)) or len(value) != 2:
            raise ValueError(f"expected a range [low, high] or 'low:high', got {shown(value)}")
        lo, hi = _number(value[0]), _number(value[1])
        if not (math.isfinite(lo) and math.isfinite(hi)):
            raise ValueError(f"low and high must be finite numbers, got [{lo:g}, {hi:g}]")
        if not lo < hi:
            raise ValueError(f"low must be < high (a range to sample), got [{lo:g}, {hi:g}]; "
                             "for one value use mode 'grid'")
        return lo, hi
    except (ValueError, TypeError) as exc:
        problems.append(f"parameters.{name}: {exc}")
        return None


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
        n_rfe is filled in by spec_from_dict)."""
        return None if name == "n_rfe" else float(default_value(name))


CRANE = CraneSpace()


def spec_from_dict(data, base_dir=None):
    """Validated :class:`SweepSpec` from a dict of the schema in the module docstring.

    base_dir : folder a relative ``model`` path is taken from (default: the current one)
    """
    data = dict(data or {})
    if "model" in data:
        # import cycle spec <-> model_spec: model_spec builds on this module's points,
        # limits and SweepSpec; the dispatch to it is here
        from .model_spec import model_spec_from_dict
        return model_spec_from_dict(data, base_dir)
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
        points = _grid_points(parameters, problems)
    elif mode == "lhs":
        points = _lhs_points(parameters, data.get("samples"), data.get("seed", 0), problems)
    elif mode == "list":
        points = _list_points(data.get("points"), problems)
        if parameters:
            problems.append("mode 'list' takes its points from 'points', not 'parameters'")
    for key, wanted in (("samples", "lhs"), ("seed", "lhs"), ("points", "list")):
        if key in data and mode != wanted:
            problems.append(f"{shown(key)} is only used with mode {wanted!r} (mode is "
                            f"{shown(mode)})")
    for pt in points:
        pt.setdefault("n_rfe", run.n_rfe)
    fill_defaults(points, CRANE)
    swept = _swept(points)
    limits = _limits(data.get("limits") or {}, problems)
    plot = data.get("plot") or {}
    plot_x, plot_y = _plot_axes(plot, swept, problems)
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
            values[key] = _number(value)
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


def _grid_points(parameters, problems, space=CRANE):
    """Points of a grid: the Cartesian product of the axes; every axis value is checked
    once (``parameters.<name>``), the size before the product is built."""
    if not parameters:
        problems.append("mode 'grid' needs at least one parameter in 'parameters'")
        return []
    axes = {}
    for name, value in parameters.items():
        c = space.name(name, f"parameters.{name}", problems)
        if c is None:
            continue
        if c in axes:
            problems.append(f"parameters.{name}: {c} given twice")
        values = _grid_values(name, value, problems)
        n0 = len(problems)
        for v in dict.fromkeys(values):
            space.check(c, v, f"parameters.{name}", problems)
        axes[c] = values if len(problems) == n0 else []
    size = math.prod(len(v) for v in axes.values())
    if size > MAX_POINTS:
        problems.append(f"the grid has {' x '.join(str(len(v)) for v in axes.values())} = "
                        f"{size} points; at most {MAX_POINTS} (check the grid)")
        return []
    if not all(axes.values()) or not axes:
        return []
    names = list(axes)
    return [dict(zip(names, combo)) for combo in itertools.product(*axes.values())]


def _whole_number(value):
    return (not isinstance(value, bool) and isinstance(value, (int, float))
            and math.isfinite(value) and value == int(value))


def _lhs_points(parameters, samples, seed, problems, space=CRANE):
    """Latin-hypercube points; each range's ends are checked as values of the parameter."""
    if not parameters:
        problems.append("mode 'lhs' needs at least one parameter range in 'parameters'")
    if samples is None or not _whole_number(samples) or not 1 <= samples <= MAX_POINTS:
        problems.append(f"mode 'lhs' needs samples = an integer from 1 to {MAX_POINTS}, "
                        f"got {shown(samples)}")
        samples = None
    if not _whole_number(seed) or seed < 0:
        problems.append(f"seed must be an integer >= 0, got {shown(seed)}")
        seed = None
    ranges = {}
    for name, value in (parameters or {}).items():
        c = space.name(name, f"parameters.{name}", problems)
        if c is None:
            continue
        r = _range(name, value, problems)
        if r is None:
            continue
        n0 = len(problems)
        for v in r:
            space.check(c, v, f"parameters.{name}", problems)
        if len(problems) == n0:
            ranges[c] = r
    if samples is None or seed is None or not ranges or len(ranges) != len(parameters):
        return []
    u = qmc.LatinHypercube(d=len(ranges), seed=np.random.default_rng(int(seed))).random(
        int(samples))
    points = []
    for row in u:
        pt = {}
        for (name, (lo, hi)), uk in zip(ranges.items(), row):
            if space.is_integer(name):     # integers lo..hi, each with equal probability
                pt[name] = float(min(int(hi), int(math.floor(lo + uk * (int(hi) - lo + 1)))))
            else:
                pt[name] = float(lo + uk * (hi - lo))
        points.append(pt)
    return points


def _list_points(points, problems, space=CRANE):
    """The points of a list, each value checked (``point <k>``)."""
    if not isinstance(points, (list, tuple)) or not points:
        problems.append("mode 'list' needs points = a non-empty list of tables, got "
                        f"{shown(points)}")
        return []
    if len(points) > MAX_POINTS:
        problems.append(f"{len(points)} points; at most {MAX_POINTS}")
        return []
    out = []
    for k, pt in enumerate(points):
        if not isinstance(pt, dict):
            problems.append(f"point {k}: expected a table name = value, got {shown(pt)}")
            continue
        clean = {}
        for name, value in pt.items():
            c = space.name(name, f"point {k}", problems)
            if c is None:
                continue
            if c in clean:
                problems.append(f"point {k}: {c} given twice")
            try:
                clean[c] = _number(value)
            except (ValueError, TypeError):
                problems.append(f"point {k}: {name} must be a number, got {shown(value)}")
                continue
            space.check(c, clean[c], f"point {k}", problems)
        out.append(clean)
    return out


def fill_defaults(points, space):
    """Give every point every parameter some point names (in place): a list sweep whose
    points set different parameters runs each point at the default of what it does not
    set (the crane's CraneParameters, a model file's own value), and the table and the
    plots show those values.  Names without a default (None) are left as they are."""
    names = []
    for pt in points:
        names += [nm for nm in pt if nm not in names]
    for nm in names:
        if any(nm not in pt for pt in points):
            value = space.default(nm)
            if value is not None:
                for pt in points:
                    pt.setdefault(nm, value)
    return points


def _swept(points):
    names = []
    for pt in points:
        for name in pt:
            if name not in names:
                names.append(name)
    return tuple(nm for nm in names
                 if len({json.dumps(pt.get(nm)) for pt in points}) > 1 or nm != "n_rfe")


def _limits(limits, problems, metrics=METRICS):
    if not isinstance(limits, dict):
        problems.append(f"limits must be a table metric = largest value, got {shown(limits)}")
        return {}
    out = {}
    for name, value in limits.items():
        if name not in metrics or not metrics[name][2]:
            valid = [k for k, v in metrics.items() if v[2]]
            valid = sorted(valid) if metrics is METRICS else valid
            problems.append(f"limits.{name}: not a metric that can be bounded; valid: {valid}")
            continue
        try:
            out[name] = _number(value)
        except (ValueError, TypeError):
            problems.append(f"limits.{name}: expected a number, got {shown(value)}")
            continue
        if not (math.isfinite(out[name]) and out[name] >= 0):
            problems.append(f"limits.{name} must be finite and >= 0 "
                            f"({metrics[name][0]}), got {shown(value)}")
    return out


def _plot_axes(plot, swept, problems, space=CRANE):
    if not isinstance(plot, dict) or set(plot) - {"x", "y"}:
        problems.append(f"plot must be a table with keys x, y, got {shown(plot)}")
        return None, None
    axes = []
    for key in ("x", "y"):
        if key in plot:
            c = space.name(plot[key], f"plot.{key}", problems)
            if c is not None and swept and c not in swept:
                problems.append(f"plot.{key} = {shown(plot[key])} is not swept; swept: "
                                f"{list(swept)}")
            axes.append(c)
        else:
            axes.append(None)
    free = [s for s in swept if s not in axes]
    x, y = axes
    if x is None and free:
        x = free.pop(0)
    if y is None and free:
        y = free.pop(0)
    if x is not None and x == y:
        problems.append(f"plot.x and plot.y must differ, both are {shown(x)}")
    return x, y


def crane_changes(point):
    """The CraneParameters fields of a point (n_rfe removed)."""
    return {k: v for k, v in point.items() if k != "n_rfe"}


def default_value(name):
    """Value of a parameter in CraneParameters() (n_rfe: the run default)."""
    if name == "n_rfe":
        return RUN_DEFAULTS["n_rfe"]
    return getattr(CraneParameters(), name)
