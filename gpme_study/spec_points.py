"""What every sweep description shares, the crane's (gpme_study.spec) and a model file's
(gpme_study.model_spec): the validated :class:`SweepSpec` and its error, reading the file,
and the points of the three modes (grid, list, Latin-hypercube sample), the safe-region
limits and the heat-map axes, each checked against a parameter space (an object with the
methods name, check, is_integer and default: gpme_study.spec.CraneSpace,
gpme_study.model_spec.ModelSpace).  gpme_study.sweep_spec chooses which description a dict
is.  Validation is our own code, not a schema library, on purpose (docs/architecture.md,
"Input validation").
"""
import itertools
import json
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.stats import qmc

from gpme_core.echo import ECHO_LIMIT, shown, shown_text
from gpme_core.errors import ModelError
from gpme_io.input_files import SWEEP_FILE_LIMIT, InputFileError, read_input_file

from .bounded_yaml import load_yaml
from .metrics import METRICS

MODES = ("grid", "list", "lhs")
# more points than this is almost certainly a typo in a grid (hours of runs per point)
MAX_POINTS = 100_000
# most RFEM segments of a flexible link in a sweep: the RK4 step falls as 1 / n_rfe^2
# (measured on the crane's arm with point.rk4_step: 3.3e-4 s at 1, 2.4e-7 s at 30, 1.4e-8 s
# at 100 segments, i.e. 7e7 steps per simulated second), so more is never a sweep anyone
# can finish
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
class SweepSpec:
    """A validated sweep.

    points : tuple of dicts {field name: value}, only the values that differ from
             CraneParameters() defaults by being swept; n_rfe always present (int)
    swept  : names (field names, n_rfe) that vary over the points
    run    : the settings every point runs with: gpme_study.spec.RunSettings (the crane)
             or gpme_study.model_spec.ModelRunSettings (a model file)
    model  : None for the built-in crane; for a model-file sweep its
             gpme_study.model_paths.ModelDocument (points are then {path: value})
    metrics: {column: (unit, definition, can be bounded)} of the table (None: the crane's
             gpme_study.metrics.METRICS)
    """

    mode: str
    points: tuple
    swept: tuple
    run: object
    limits: dict = field(default_factory=dict)
    plot_x: str = None
    plot_y: str = None
    model: object = None
    metrics: object = None

    @property
    def metric_table(self):
        """{column: (unit, definition, can be bounded)} of this sweep's metrics."""
        return METRICS if self.metrics is None else self.metrics


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


def number(value):
    """float of a number or of a string holding one; ValueError naming the value else."""
    if isinstance(value, bool) or not isinstance(value, (int, float, str, np.number)):
        raise ValueError(f"expected a number, got {shown(value)}")
    try:
        return float(value.strip() if isinstance(value, str) else value)
    except ValueError:
        raise ValueError(f"expected a number, got {shown(value)}") from None


def grid_values(name, value, problems):
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
            num = number(value["num"])
            if not math.isfinite(num) or num != int(num) or num < 1:
                raise ValueError(f"num must be a positive integer, got {shown(value['num'])}")
            if num > MAX_POINTS:
                raise ValueError(f"num = {int(num)} values; at most {MAX_POINTS} (check the "
                                 "grid)")
            start, stop = number(value["start"]), number(value["stop"])
            for key, v in (("start", start), ("stop", stop)):
                if not math.isfinite(v):
                    raise ValueError(f"{key} must be a finite number, got {shown(value[key])}")
            return [float(v) for v in np.linspace(start, stop, int(num))]
        if isinstance(value, (list, tuple)):
            if not value:
                raise ValueError("empty list of values")
            return [number(v) for v in value]
        return [number(value)]
    except (ValueError, TypeError) as exc:
        problems.append(f"parameters.{name}: {exc}")
        return []


def value_range(name, value, problems):
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
        lo, hi = number(value[0]), number(value[1])
        if not (math.isfinite(lo) and math.isfinite(hi)):
            raise ValueError(f"low and high must be finite numbers, got [{lo:g}, {hi:g}]")
        if not lo < hi:
            raise ValueError(f"low must be < high (a range to sample), got [{lo:g}, {hi:g}]; "
                             "for one value use mode 'grid'")
        return lo, hi
    except (ValueError, TypeError) as exc:
        problems.append(f"parameters.{name}: {exc}")
        return None


def grid_points(parameters, problems, space):
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
        values = grid_values(name, value, problems)
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


def whole_number(value):
    return (not isinstance(value, bool) and isinstance(value, (int, float))
            and math.isfinite(value) and value == int(value))


def lhs_points(parameters, samples, seed, problems, space):
    """Latin-hypercube points; each range's ends are checked as values of the parameter."""
    if not parameters:
        problems.append("mode 'lhs' needs at least one parameter range in 'parameters'")
    if samples is None or not whole_number(samples) or not 1 <= samples <= MAX_POINTS:
        problems.append(f"mode 'lhs' needs samples = an integer from 1 to {MAX_POINTS}, "
                        f"got {shown(samples)}")
        samples = None
    if not whole_number(seed) or seed < 0:
        problems.append(f"seed must be an integer >= 0, got {shown(seed)}")
        seed = None
    ranges = {}
    for name, value in (parameters or {}).items():
        c = space.name(name, f"parameters.{name}", problems)
        if c is None:
            continue
        r = value_range(name, value, problems)
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


def list_points(points, problems, space):
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
                clean[c] = number(value)
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


def swept_names(points):
    names = []
    for pt in points:
        for name in pt:
            if name not in names:
                names.append(name)
    return tuple(nm for nm in names
                 if len({json.dumps(pt.get(nm)) for pt in points}) > 1 or nm != "n_rfe")


def limits_of(limits, problems, metrics=METRICS):
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
            out[name] = number(value)
        except (ValueError, TypeError):
            problems.append(f"limits.{name}: expected a number, got {shown(value)}")
            continue
        if not (math.isfinite(out[name]) and out[name] >= 0):
            problems.append(f"limits.{name} must be finite and >= 0 "
                            f"({metrics[name][0]}), got {shown(value)}")
    return out


def plot_axes(plot, swept, problems, space):
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
