"""Read a model file (TOML) and check every value: :func:`parse_model_file`.

Every problem is collected with its key path (``run.t_end``, ``constraint[1].phi``,
``flexible[0].section.outer_diameter``; arrays of tables counted from 0 in file order),
the value found and what would be valid; unknown keys get a "did you mean".  The checks
that need the built model (joint, frame and link names, coordinate counts) are done by
gpme_io.modelfile.build and listed with these (gpme_io.modelfile.load_model_file).
docs/models.md describes the format.
"""
import importlib.metadata
import math
import tomllib
from pathlib import Path
from typing import Any, Optional

import numpy as np

from gpme_core.echo import closest
from gpme_core import time_functions as tfn
from gpme_core.errors import ConstraintError, ModelError
from gpme_core.methods import FIXED_STEP_METHODS
from gpme_examples.crane import CraneParameters, build_crane
from gpme_io.input_files import (MODEL_FILE_LIMIT, SIDE_FILE_LIMIT, URDF_LIMIT,
                                 InputFileError, check_input_file, read_input_file)
from gpme_io.scenario import INTEGRATORS, EngineStep, ReferenceValues, ToleranceOverride
from gpme_io.xml_text import xml_char_problem

from gpme_io import expressions as ex
from .schema import (AXES, BUILTIN_MODELS, CONSTRAINT_KINDS, PAIR_KINDS, PAIR_SYMBOLS,
                     POINT_SYMBOLS, SECTION_SHAPES, TIME_SYMBOLS, ChainSection,
                     CoordinateConstraintSpec, CraneSource, DriveSpec, EllipseConstraintSpec,
                     ExpressionConstraintSpec, FlexibleSpec, InitialSpec, JointSpec, ModelFile,
                     ModelSection, PairConstraintSpec, PointSpringSpec, ProgrammeSpec,
                     RunSpec, SectionSpec,
                     SolverSpec, TreeSection, UrdfSource, constraint_rows)

TOP_LEVEL = ("model", "chain", "tree", "flexible", "joint", "drive", "point_spring",
             "constraint", "programme", "reference",
             "solver", "initial", "run", "tolerance", "engine_step")
ARRAYS_OF_TABLES = ("flexible", "joint", "drive", "point_spring", "constraint", "programme",
                    "tolerance", "reference",
                    "engine_step")
ROBOT_DATA_PREFIX = "example-robot-data:"
ROBOT_DATA_DISTRIBUTION = "example-robot-data"
ROBOT_DATA_ROOT = "cmeel.prefix/share/example-robot-data/robots/"
ROBOTS_EXTRA_HINT = "install the optional extra: pip install -e '.[robots]'"
# gpme: the run checks (crosscheck.run_checks) and the observed order of its own runs
TOLERANCE_ENGINES = ("gpme", "pinocchio", "mujoco", "drake", "exudyn", "continuum")
# engines that integrate with their own scheme and step ([[engine_step]]); Pinocchio's and
# MuJoCo's runs use gpme's RK4 step ([run] dt)
STEP_ENGINES = ("drake", "exudyn")
DEFAULT_BAUMGARTE = (20.0, 20.0)
QUICK_T_END = 1.0           # s, default quick_t_end = min(t_end, 1 s)
DEFAULT_OUTPUT_DT = 1e-3    # s
SAMPLES = 201               # times checked in [0, t_end] for each function of time

# CraneParameters fields that describe the task, set in the file's own sections instead
CRANE_TASK_FIELDS = {
    "drive_torque": "[[drive]]", "drive_ramp_time": "[[drive]]",
    "ellipse_a": "[[constraint]]", "ellipse_b": "[[constraint]]", "z0": "[[constraint]]",
    "amplitude": "[[constraint]]", "period": "[[constraint]]",
    "baumgarte_alpha": "[solver].baumgarte", "baumgarte_beta": "[solver].baumgarte",
    "initial_psi3": "[initial].q", "initial_z4": "[initial].q", "gravity": "[model].gravity",
}
# mechanism fields of CraneParameters: (unit, rule) with rule ">0", ">=0", "range" or "size"
CRANE_FIELDS = {
    "support_stiffness": ("N/m", ">=0"), "support_damping": ("N s/m", ">=0"),
    "base_mass": ("kg", ">0"), "base_size": ("m", "size"), "column_mass": ("kg", ">0"),
    "column_height": ("m", ">0"), "column_radius": ("m", ">0"),
    "column_inner_radius": ("m", ">=0"), "arm_length": ("m", ">0"),
    "arm_diameter": ("m", ">0"), "arm_wall_thickness": ("m", ">=0"),
    "arm_yield_strength": ("Pa", ">0"), "steel_youngs_modulus": ("Pa", ">0"),
    "steel_shear_modulus": ("Pa", ">0"), "steel_density": ("kg/m^3", ">0"),
    "arm_viscosity": ("Pa s", ">=0"), "slider_mass": ("kg", ">0"),
    "slider_length": ("m", ">0"), "slider_radius": ("m", ">0"),
    "slider_stroke": ("m", "range"), "arm_pitch_range": ("rad", "range"),
}
# drive / time-function types: (parameters, TimeFunction class or None for "expression")
FUNCTION_TYPES = {
    "constant": (("level",), tfn.Constant),
    "quintic": (("level", "ramp_time"), tfn.QuinticRamp),
    "sine": (("offset", "amplitude", "period", "phase"), tfn.Sine),
    "cosine": (("offset", "amplitude", "period"), tfn.Cosine),
    "table": (("times", "values"), tfn.Tabulated),
    "expression": (("f",), None),
}
OPTIONAL_PARAMETERS = {"phase": 0.0}
_PARAMETER_UNITS = {"ramp_time": "s", "period": "s", "phase": "rad", "times": "s"}


def _type_name(v: Any) -> str:
    return {bool: "a boolean", str: "a string", dict: "a table", list: "an array",
            int: "an integer", float: "a number"}.get(type(v), type(v).__name__)


class _Checker:
    """Typed access to TOML tables, collecting 'key.path: message' problems.  Our own
    checker, not a schema library, on purpose: docs/architecture.md, "Input validation"."""

    def __init__(self):
        self.problems: list = []

    def add(self, path: str, message: str) -> None:
        self.problems.append(f"{path}: {message}")

    # ------------------------------------------------------------------ keys
    def keys(self, table: dict, allowed, path: str, hint: str = "") -> None:
        """Every key of ``table`` must be in ``allowed``."""
        allowed = list(allowed)
        for key in table:
            if key not in allowed:
                close = closest(key, allowed)
                mean = f"did you mean {close[0]!r}? " if close else ""
                self.add(_join(path, key), f"unknown key; {mean}allowed here: "
                         f"{', '.join(allowed)}{hint}")

    def table(self, parent: dict, key: str, path: str, required: bool = False) -> Optional[dict]:
        if key not in parent:
            if required:
                self.add(_join(path, key), "missing table")
            return None
        v = parent[key]
        if not isinstance(v, dict):
            self.add(_join(path, key), f"must be a table, got {_type_name(v)} {v!r}")
            return None
        return v

    # ------------------------------------------------------------------ scalars
    def number(self, table: dict, key: str, path: str, unit: str, required: bool = True,
               default: Optional[float] = None, rule: str = "") -> Optional[float]:
        """A finite number; rule '>0' or '>=0'.  Returns None when missing or bad."""
        where = _join(path, key)
        if key not in table:
            if required:
                self.add(where, f"missing; a number ({unit})")
            return default
        return self.check_number(table[key], where, unit, rule)

    def check_number(self, v: Any, where: str, unit: str, rule: str = "") -> Optional[float]:
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            self.add(where, f"must be a number ({unit}), got {_type_name(v)} {v!r}")
            return None
        if not math.isfinite(v):
            self.add(where, f"must be a finite number ({unit}), got {v!r}")
            return None
        if rule == ">0" and not v > 0:
            self.add(where, f"must be > 0 ({unit}), got {v!r}")
            return None
        if rule == ">=0" and not v >= 0:
            self.add(where, f"must be >= 0 ({unit}), got {v!r}")
            return None
        return float(v)

    def integer(self, table: dict, key: str, path: str, what: str, required: bool = True,
                default: Optional[int] = None, minimum: int = 0) -> Optional[int]:
        where = _join(path, key)
        if key not in table:
            if required:
                self.add(where, f"missing; {what}")
            return default
        v = table[key]
        if isinstance(v, bool) or not isinstance(v, int):
            self.add(where, f"must be an integer ({what}), got {_type_name(v)} {v!r}")
            return default if not required else None
        if v < minimum:
            self.add(where, f"must be an integer >= {minimum} ({what}), got {v!r}")
            return None
        return v

    def string(self, table: dict, key: str, path: str, what: str, required: bool = True,
               choices=None) -> Optional[str]:
        where = _join(path, key)
        if key not in table:
            if required:
                self.add(where, f"missing; {what}")
            return None
        v = table[key]
        if not isinstance(v, str) or not v.strip():
            self.add(where, f"must be a non-empty string ({what}), got {_type_name(v)} {v!r}")
            return None
        bad = xml_char_problem("string", v)
        if bad:                  # names go into URDF, MJCF and reports, which cannot hold it
            self.add(where, f"{bad} (names and expressions go into URDF, MJCF and the "
                     "report; use printable characters)")
            return None
        if choices is not None and v not in choices:
            same_case = [ch for ch in choices if ch.lower() == v.lower()]
            close = same_case or closest(v, choices)
            mean = f"; did you mean {close[0]!r}?" if close else ""
            self.add(where, f"{v!r} is not one of {', '.join(map(repr, choices))}{mean}")
            return None
        return v

    def boolean(self, table: dict, key: str, path: str, default: bool) -> bool:
        if key not in table:
            return default
        v = table[key]
        if not isinstance(v, bool):
            self.add(_join(path, key), f"must be true or false, got {_type_name(v)} {v!r}")
            return default
        return v

    def vector(self, table: dict, key: str, path: str, length: int, unit: str,
               required: bool = True, nonzero: bool = False) -> Optional[tuple]:
        where = _join(path, key)
        if key not in table:
            if required:
                self.add(where, f"missing; {length} numbers ({unit})")
            return None
        v = table[key]
        if not isinstance(v, list) or len(v) != length:
            self.add(where, f"must be an array of {length} numbers ({unit}), got "
                     f"{_type_name(v)} {v!r}")
            return None
        out = [self.check_number(x, f"{where}[{k}]", unit) for k, x in enumerate(v)]
        if any(x is None for x in out):
            return None
        if nonzero and not any(out):
            self.add(where, f"must not be the zero vector, got {v!r}")
            return None
        return tuple(out)

    def number_map(self, table: dict, key: str, path: str, unit: str) -> dict:
        """{name: finite number} from a table of numbers."""
        sub = self.table(table, key, path)
        if sub is None:
            return {}
        out = {}
        for name, v in sub.items():
            x = self.check_number(v, _join(_join(path, key), name), unit)
            if x is not None:
                out[name] = x
        return out


def _join(path: str, key: str) -> str:
    return f"{path}.{key}" if path else key


# ====================================================================== entry point
def parse_model_file(path) -> tuple:
    """(ModelFile, [problem, ...]) of the model file at ``path``; problems are
    'key.path: message' strings (empty list: the file is valid as a file; names of joints,
    frames and links are checked when the model is built)."""
    path = Path(path)
    try:
        raw = read_input_file(path, "model file", MODEL_FILE_LIMIT)
    except InputFileError as exc:
        return ModelFile(path, None), [f"cannot read the model file: it {exc.reason}"]
    try:
        data = tomllib.loads(raw.decode("utf-8"))
    except UnicodeDecodeError as exc:
        return ModelFile(path, None), [f"not UTF-8 text ({exc})"]
    except RecursionError:
        return ModelFile(path, None), ["not read as TOML: its arrays or tables are nested too "
                                       "deeply (a model file needs a few levels)"]
    except tomllib.TOMLDecodeError as exc:
        hint = ""
        if raw.lstrip().startswith(b"<") or path.suffix.lower() in (".urdf", ".xml", ".xacro"):
            hint = ("; this looks like a URDF: --model takes a TOML model file that names it "
                    "(`[model] urdf = \"robot.urdf\"` with its constraints, docs/models.md; "
                    "examples/my_arm/my_arm.toml is one)")
        return ModelFile(path, None), [f"not valid TOML: {exc}{hint}"]
    return parse_model_data(data, path)


def parse_model_data(data: dict, path: Path) -> tuple:
    """(ModelFile, problems) of already-parsed TOML ``data``; relative paths are resolved
    against ``path``'s folder."""
    c = _Checker()
    c.keys(data, TOP_LEVEL, "")
    for key in ARRAYS_OF_TABLES:
        if key in data and not (isinstance(data[key], list)
                                and all(isinstance(e, dict) for e in data[key])):
            c.add(key, f"must be an array of tables, written [[{key}]], got "
                  f"{_type_name(data[key])}")
    entries = {key: data[key] if key in data and isinstance(data[key], list)
               and all(isinstance(e, dict) for e in data[key]) else [] for key in ARRAYS_OF_TABLES}

    model = _model_section(c, data, path)
    is_builtin = model is not None and isinstance(model.source, CraneSource)
    chain = _chain_section(c, data, is_builtin)
    tree = _tree_section(c, data, is_builtin)
    if chain is not None and tree is not None:
        c.add("tree", "a model is one chain ([chain]) or a whole tree ([tree]), not both; "
              "remove one of the sections")
    run = _run_section(c, data)
    t_end = run.t_end if run is not None else None
    flexible = tuple(f for k, e in enumerate(entries["flexible"])
                     if (f := _flexible(c, e, f"flexible[{k}]", is_builtin)) is not None)
    _unique(c, [(f.key, f.link) for f in flexible], "link", "flexible link")
    joints = tuple(j for k, e in enumerate(entries["joint"])
                   if (j := _joint(c, e, f"joint[{k}]")) is not None)
    _unique(c, [(j.key, j.name) for j in joints], "name", "joint")
    drives = tuple(d for k, e in enumerate(entries["drive"])
                   if (d := _drive(c, e, f"drive[{k}]", t_end)) is not None)
    point_springs = tuple(x for k, e in enumerate(entries["point_spring"])
                          if (x := _point_spring(c, e, f"point_spring[{k}]")) is not None)
    _unique(c, [(x.key, x.name) for x in point_springs], "name", "point spring")
    constraints = tuple(x for k, e in enumerate(entries["constraint"])
                        if (x := _constraint(c, e, f"constraint[{k}]", t_end)) is not None)
    programmes = tuple(p for k, e in enumerate(entries["programme"])
                       if (p := _programme(c, e, f"programme[{k}]", t_end)) is not None)
    all_complete = len(constraints) == len(entries["constraint"]) and \
        len(programmes) == len(entries["programme"])
    names = [(x.key, row) for x in constraints for row in constraint_rows(x)] + \
        [(p.key, p.name or f"Phi_{p.joint}") for p in programmes]
    _unique(c, names, "name", "constraint")
    n_constraints = sum(len(constraint_rows(x)) for x in constraints) + len(entries["programme"])
    solver = _solver_section(c, data, n_constraints if all_complete else None)
    initial = _initial_section(c, data)
    tolerances = tuple(t for k, e in enumerate(entries["tolerance"])
                       if (t := _tolerance(c, e, f"tolerance[{k}]")) is not None)
    _unique(c, [(f"tolerance[{k}]", t.check) for k, t in enumerate(tolerances)], "check",
            "tolerance")
    references = tuple(x for k, e in enumerate(entries["reference"])
                       if (x := _reference(c, e, f"reference[{k}]", t_end)) is not None)
    engine_steps = tuple(x for k, e in enumerate(entries["engine_step"])
                         if (x := _engine_step(c, e, f"engine_step[{k}]", t_end)) is not None)
    _unique(c, [(f"engine_step[{k}]", x.engine) for k, x in enumerate(engine_steps)],
            "engine", "engine_step")
    mf = ModelFile(path=path, model=model, chain=chain, tree=tree, flexible=flexible,
                   joints=joints,
                   drives=drives, point_springs=point_springs, constraints=constraints,
                   programmes=programmes,
                   solver=solver, initial=initial, run=run, tolerances=tolerances,
                   references=references,
                   engine_steps=engine_steps)
    return mf, c.problems


def _unique(c: _Checker, keyed_names, field_name: str, what: str) -> None:
    seen: dict = {}
    for key, name in keyed_names:
        if name in seen:
            c.add(f"{key}.{field_name}", f"{what} {name!r} is already given in {seen[name]}; "
                  "each must appear once")
        else:
            seen[name] = key


# ====================================================================== [model]
def _model_section(c: _Checker, data: dict, path: Path) -> Optional[ModelSection]:
    t = c.table(data, "model", "", required=True)
    if t is None:
        return None
    c.keys(t, ("name", "urdf", "builtin", "side_file", "gravity", "crane"), "model")
    name = c.string(t, "name", "model", "the model's name, used in reports")
    gravity = c.vector(t, "gravity", "model", 3, "m/s^2, world frame, e.g. [0, 0, -9.81]")
    source = None
    has_urdf, has_builtin = "urdf" in t, "builtin" in t
    if has_urdf == has_builtin:
        c.add("model", "give exactly one source: urdf = \"path/to/robot.urdf\" (relative to "
              "this file, or \"example-robot-data:<path>\") or builtin = \"crane\""
              + (", not both" if has_urdf else ""))
    elif has_urdf:
        source = _urdf_source(c, t, path)
        if "crane" in t:
            c.add("model.crane", "only for builtin = \"crane\"")
    else:
        kind = c.string(t, "builtin", "model", "a builtin model", choices=BUILTIN_MODELS)
        if "side_file" in t:
            c.add("model.side_file", "only for urdf models")
        if kind == "crane":
            source = _crane_source(c, t)
    if name is None or gravity is None or source is None:
        return None
    return ModelSection(name, source, gravity)


def _urdf_source(c: _Checker, t: dict, path: Path) -> Optional[UrdfSource]:
    written = c.string(t, "urdf", "model", "path of the URDF")
    if written is None:
        return None
    resolved = resolve_urdf(written, path, c)
    side = None
    side_written = c.string(t, "side_file", "model", "path of a gpme side file", required=False)
    if side_written is not None:
        side = (path.parent / side_written).resolve()
        if not side.exists():
            c.add("model.side_file", f"no file at {str(side)!r} (paths are relative to the "
                  f"model file's folder {str(path.parent)!r})")
            side = None
        else:
            try:
                check_input_file(side, "side file", SIDE_FILE_LIMIT)
            except InputFileError as exc:
                c.add("model.side_file", str(exc))
                side = None
    return None if resolved is None else UrdfSource(resolved, written, side)


def resolve_urdf(written: str, model_file: Path, c: Optional[_Checker] = None) -> Optional[Path]:
    """Path of the URDF ``written`` in ``model_file``: relative to the model file's folder,
    or ``example-robot-data:<path under robots/>`` inside that package.  Problems go to
    ``c`` (None: ModelError)."""
    problems = []
    out = None
    if written.startswith(ROBOT_DATA_PREFIX):
        rel = written[len(ROBOT_DATA_PREFIX):].lstrip("/")
        try:
            dist = importlib.metadata.distribution(ROBOT_DATA_DISTRIBUTION)
        except importlib.metadata.PackageNotFoundError:
            problems.append(f"{written!r} needs the package {ROBOT_DATA_DISTRIBUTION}, which is "
                            f"not installed; {ROBOTS_EXTRA_HINT}")
        else:
            files = {str(f)[len(ROBOT_DATA_ROOT):]: f for f in (dist.files or [])
                     if str(f).startswith(ROBOT_DATA_ROOT)}
            if rel in files:
                out = Path(dist.locate_file(files[rel])).resolve()
            else:
                urdfs = [k for k in files if k.endswith(".urdf")]
                close = closest(rel, urdfs, n=3, cutoff=0.5)     # long paths: looser
                problems.append(f"{ROBOT_DATA_DISTRIBUTION} {dist.version} has no {rel!r} under "
                                f"robots/; " + (f"close matches: {close}" if close else
                                                f"it has {len(urdfs)} URDFs, e.g. {urdfs[:3]}"))
    else:
        p = Path(written)
        out = (p if p.is_absolute() else model_file.parent / p).resolve()
        if not out.exists():
            problems.append(f"no file at {str(out)!r} (paths are relative to the model file's "
                            f"folder {str(model_file.parent.resolve())!r})")
            out = None
        else:
            try:
                check_input_file(out, "URDF", URDF_LIMIT)
            except InputFileError as exc:
                problems.append(str(exc))
                out = None
    if out is not None and not out.is_file():
        problems.append(f"{str(out)!r} is listed by {ROBOT_DATA_DISTRIBUTION} but missing; "
                        f"reinstall it: {ROBOTS_EXTRA_HINT}")
        out = None
    for p in problems:
        if c is None:
            raise ModelError(f"model.urdf: {p}")
        c.add("model.urdf", p)
    return out


def _crane_source(c: _Checker, t: dict) -> Optional[CraneSource]:
    sub = c.table(t, "crane", "model")
    if sub is None:
        return CraneSource({}, 0)
    allowed = list(CRANE_FIELDS) + ["n_rfe"]
    overrides = {}
    n_rfe = 0
    ok = True
    for key, v in sub.items():
        where = f"model.crane.{key}"
        if key == "n_rfe":
            n = c.integer(sub, "n_rfe", "model.crane", "RFEM segments of the arm, 0 = rigid")
            ok &= n is not None
            n_rfe = n if n is not None else 0
        elif key in CRANE_TASK_FIELDS:
            c.add(where, f"a task parameter of the crane; set it in {CRANE_TASK_FIELDS[key]} "
                  "of this file")
            ok = False
        elif key in CRANE_FIELDS:
            unit, rule = CRANE_FIELDS[key]
            if rule in (">0", ">=0"):
                x = c.check_number(v, where, unit, rule)
            else:
                n = 3 if rule == "size" else 2
                x = c.vector(sub, key, "model.crane", n, unit)
                if x is not None and rule == "size" and not all(e > 0 for e in x):
                    c.add(where, f"every size must be > 0 ({unit}), got {list(x)}")
                    x = None
                if x is not None and rule == "range" and not x[0] < x[1]:
                    c.add(where, f"must be [lower, upper] with lower < upper ({unit}), got "
                          f"{list(x)}")
                    x = None
            ok &= x is not None
            overrides[key] = x
        else:
            c.keys({key: v}, allowed, "model.crane")
            ok = False
    inner = overrides.get("column_inner_radius", CraneParameters.column_inner_radius)
    outer = overrides.get("column_radius", CraneParameters.column_radius)
    if inner is not None and outer is not None and not inner < outer:
        c.add("model.crane.column_inner_radius", f"must be < column_radius = {outer!r} m, got "
              f"{inner!r}")
        ok = False
        overrides.pop("column_inner_radius", None)
    ok &= _crane_trial_build(c, {k: v for k, v in overrides.items() if v is not None}, n_rfe)
    return CraneSource(overrides, n_rfe) if ok else None


def _crane_trial_build(c: _Checker, valid: dict, n_rfe: int) -> bool:
    """Build the crane from the keys that passed their own checks (defaults for the rest),
    so that a combination no single key shows (an arm wall as thick as the arm's radius) is
    listed together with the keys' own problems, not after they are fixed."""
    try:
        build_crane(max(n_rfe, 0), CraneParameters(**valid))
    except ModelError as exc:
        for problem in exc.problems:
            c.add("model.crane", problem)
        return False
    return True


# ====================================================================== [chain], [[flexible]]
def _chain_section(c: _Checker, data: dict, is_builtin: bool) -> Optional[ChainSection]:
    t = c.table(data, "chain", "")
    if t is None:
        return None
    if is_builtin:
        c.add("chain", "only for urdf models (a builtin model is a chain already)")
        return None
    c.keys(t, ("root", "tip", "frozen"), "chain")
    root = c.string(t, "root", "chain", "the URDF link the chain starts from", required=False)
    tip = c.string(t, "tip", "chain", "the URDF link the chain ends at", required=False)
    frozen = c.number_map(t, "frozen", "chain", "rad or m")
    return ChainSection(root, tip, frozen)


def _tree_section(c: _Checker, data: dict, is_builtin: bool) -> Optional[TreeSection]:
    t = c.table(data, "tree", "")
    if t is None:
        return None
    if is_builtin:
        c.add("tree", "only for urdf models (a builtin model is a chain already)")
        return None
    c.keys(t, ("root", "frozen"), "tree")
    root = c.string(t, "root", "tree", "the URDF link the tree hangs from", required=False)
    frozen = c.number_map(t, "frozen", "tree", "rad or m")
    return TreeSection(root, frozen)


def _flexible(c: _Checker, e: dict, path: str, is_builtin: bool) -> Optional[FlexibleSpec]:
    c.keys(e, ("link", "section", "youngs_modulus", "shear_modulus", "density", "segments",
               "bending_viscosity", "torsion_viscosity", "axis", "length", "section_y_axis",
               "yield_strength"), path)
    if is_builtin:
        c.add(path, "a builtin model sets its flexible links itself (crane: [model.crane] "
              "n_rfe); [[flexible]] is for urdf models")
        return None
    n0 = len(c.problems)
    link = c.string(e, "link", path, "the URDF link to discretise")
    section = _section(c, e, path)
    vals = {k: c.number(e, k, path, u, rule=">0") for k, u in
            (("youngs_modulus", "Pa"), ("shear_modulus", "Pa"), ("density", "kg/m^3"))}
    segments = c.integer(e, "segments", path, "RFEM segments, 0 = one rigid body")
    eta_e = c.number(e, "bending_viscosity", path, "Pa s, 0 = undamped", rule=">=0")
    eta_g = c.number(e, "torsion_viscosity", path, "Pa s", required=False, rule=">=0")
    axis = c.vector(e, "axis", path, 3, "link frame", required=False, nonzero=True)
    length = c.number(e, "length", path, "m", required=False, rule=">0")
    y_axis = c.vector(e, "section_y_axis", path, 3, "link frame", required=False, nonzero=True)
    yield_strength = c.number(e, "yield_strength", path, "Pa", required=False, rule=">0")
    if axis is not None and y_axis is not None:
        a, y = np.array(axis), np.array(y_axis)
        if np.linalg.norm(np.cross(a, y)) <= 1e-9 * np.linalg.norm(a) * np.linalg.norm(y):
            c.add(f"{path}.section_y_axis", f"must not be parallel to axis {list(axis)}, got "
                  f"{list(y_axis)}")
    if len(c.problems) > n0:
        return None
    return FlexibleSpec(path, link, section, vals["youngs_modulus"], vals["shear_modulus"],
                        vals["density"], segments, eta_e, eta_g, axis, length, y_axis,
                        yield_strength)


def _section(c: _Checker, e: dict, path: str) -> Optional[SectionSpec]:
    t = c.table(e, "section", path, required=True)
    if t is None:
        return None
    where = f"{path}.section"
    shape = c.string(t, "shape", where, "one of " + ", ".join(SECTION_SHAPES),
                     choices=tuple(SECTION_SHAPES))
    if shape is None:
        return None
    dims = SECTION_SHAPES[shape]
    c.keys(t, ("shape",) + dims, where, hint=f" (a {shape} has {', '.join(dims)})")
    vals = {d: c.number(t, d, where, "m", rule=">0") for d in dims}
    if any(v is None for v in vals.values()):
        return None
    if shape == "tube" and not vals["wall_thickness"] < 0.5 * vals["outer_diameter"]:
        c.add(f"{where}.wall_thickness", f"must be < outer_diameter / 2 = "
              f"{0.5 * vals['outer_diameter']!r} m, got {vals['wall_thickness']!r}")
        return None
    return SectionSpec(shape, vals)


# ====================================================================== [[joint]], [[drive]]
def _joint(c: _Checker, e: dict, path: str) -> Optional[JointSpec]:
    c.keys(e, ("name", "stiffness", "spring_reference", "damping"), path)
    n0 = len(c.problems)
    name = c.string(e, "name", path, "a joint of the chain")
    k = c.number(e, "stiffness", path, "N m/rad or N/m", required=False, rule=">=0")
    ref = c.number(e, "spring_reference", path, "rad or m", required=False)
    d = c.number(e, "damping", path, "N m s/rad or N s/m", required=False, rule=">=0")
    if not any(key in e for key in ("stiffness", "spring_reference", "damping")):
        c.add(path, "sets nothing; give stiffness, spring_reference and/or damping")
    if len(c.problems) > n0:
        return None
    return JointSpec(path, name, k, ref, d)


def _time_function(c: _Checker, t: dict, path: str, unit: str, t_end: Optional[float],
                   extra_keys=()) -> Optional[tfn.TimeFunction]:
    """A TimeFunction from a table with ``type`` and its parameters (value in ``unit``)."""
    kind = c.string(t, "type", path, "one of " + ", ".join(FUNCTION_TYPES),
                    choices=tuple(FUNCTION_TYPES))
    if kind is None:
        return None
    params, cls = FUNCTION_TYPES[kind]
    c.keys(t, tuple(extra_keys) + ("type",) + params, path,
           hint=f" (type {kind!r} takes {', '.join(params)})")
    n0 = len(c.problems)
    if cls is None:
        expr, problems = ex.parse_expression(t.get("f"), TIME_SYMBOLS)
        if "f" not in t:
            c.add(f"{path}.f", f"missing; an expression in t (s) giving {unit}")
            return None
        for p in problems:
            c.add(f"{path}.f", p)
        if expr is None:
            return None
        fn = tfn.SympyTimeFunction(expr, ex.symbol("t"))
        where = f"{path}.f"
    else:
        values = {}
        for p in params:
            punit = _PARAMETER_UNITS.get(p, unit)
            if p in ("times", "values"):
                v = t.get(p)
                if p not in t:
                    c.add(f"{path}.{p}", f"missing; an array of numbers ({punit})")
                elif not isinstance(v, list) or not all(
                        isinstance(x, (int, float)) and not isinstance(x, bool) for x in v):
                    c.add(f"{path}.{p}", f"must be an array of numbers ({punit}), got "
                          f"{_type_name(v)} {v!r}")
                else:
                    values[p] = v
            else:
                rule = ">0" if p in ("ramp_time", "period") else ""
                x = c.number(t, p, path, punit, required=p not in OPTIONAL_PARAMETERS,
                             default=OPTIONAL_PARAMETERS.get(p), rule=rule)
                values[p] = x
        if len(c.problems) > n0 or any(v is None for v in values.values()):
            return None
        try:
            fn = cls(**values)
        except ModelError as exc:
            for p in exc.problems:
                c.add(path, p)
            return None
        where = path
    if t_end is not None:
        bad = function_problems(fn, t_end)
        if bad:
            c.add(where, bad)
            return None
    return fn


def function_problems(fn: tfn.TimeFunction, t_end: float) -> str:
    """'' or a message naming the first time in [0, t_end] (SAMPLES times) where the value,
    rate or acceleration of ``fn`` is not finite."""
    with np.errstate(all="ignore"):
        for t in np.linspace(0.0, t_end, SAMPLES):
            try:
                vals = (fn.value(t), fn.rate(t), fn.acceleration(t))
            except (ConstraintError, ArithmeticError, ValueError, TypeError):
                vals = (math.nan,) * 3      # a SympyTimeFunction raises where not finite
            if not all(np.isfinite(v) for v in vals):
                where = ""
                if isinstance(fn, tfn.SympyTimeFunction):
                    sets = ex.singular_sets(fn.expr)
                    where = f"; not smooth {'; '.join(sets)}" if sets else ""
                return (f"not finite at t = {t:.6g} s (value, rate, acceleration = "
                        f"{', '.join(f'{v:.6g}' for v in vals)}) within the run [0, {t_end:g}] s"
                        f"{where}")
    return ""


def _drive(c: _Checker, e: dict, path: str, t_end) -> Optional[DriveSpec]:
    n0 = len(c.problems)
    joint = c.string(e, "joint", path, "the driven coordinate")
    fn = _time_function(c, e, path, "N or N m", t_end, extra_keys=("joint",))
    if len(c.problems) > n0 or fn is None:
        return None
    return DriveSpec(path, joint, fn)


def _point_spring(c: _Checker, e: dict, path: str) -> Optional[PointSpringSpec]:
    c.keys(e, ("name", "frame", "anchor", "stiffness", "free_length", "damping"), path)
    n0 = len(c.problems)
    index = int(path[path.index("[") + 1:-1])
    name = f"spring_{index + 1}"
    if "name" in e:
        name = c.string(e, "name", path, "the spring's name")
    frame = c.string(e, "frame", path, "a named frame or link of the model")
    anchor = e.get("anchor")
    if isinstance(anchor, str) and anchor:
        pass
    elif "anchor" in e and isinstance(anchor, list):
        anchor = c.vector(e, "anchor", path, 3, "m, a world point")
    else:
        c.add(f"{path}.anchor", f"must be a frame name or a world point [x, y, z] (m), got "
              f"{_type_name(anchor)} {anchor!r}" if "anchor" in e else
              "missing; the other end: a frame name or a world point [x, y, z] (m)")
    stiffness = c.number(e, "stiffness", path, "N/m", rule=">=0")
    free_length = c.number(e, "free_length", path, "m, the length at which it is relaxed",
                           rule=">=0")
    damping = c.number(e, "damping", path, "N s/m", required=False, rule=">=0")
    if len(c.problems) > n0:
        return None
    return PointSpringSpec(path, name, frame, anchor, stiffness, free_length,
                           0.0 if damping is None else damping)


# ====================================================================== constraints
def _constraint(c: _Checker, e: dict, path: str, t_end):
    index = int(path[path.index("[") + 1:-1])
    kind = e.get("kind", "expression")
    if "kind" in e:
        kind = c.string(e, "kind", path, "one of " + ", ".join(CONSTRAINT_KINDS),
                        choices=CONSTRAINT_KINDS)
        if kind is None:
            return None
    if kind in PAIR_KINDS or (kind == "expression" and "frames" in e):
        return _pair_constraint(c, e, path, kind, index, t_end)
    keys = {"expression": ("phi",), "ellipse": ("a", "b", "center"),
            "coordinate": ("axis", "function")}[kind]
    c.keys(e, ("name", "frame", "kind") + keys, path,
           hint=f" (kind {kind!r} takes {', '.join(keys)})")
    n0 = len(c.problems)
    name = f"Phi_{index + 1}"
    if "name" in e:
        name = c.string(e, "name", path, "the constraint's name (output column)")
    frame = c.string(e, "frame", path, "a named frame or link of the model")
    if kind == "expression":
        if "phi" not in e:
            c.add(f"{path}.phi", "missing; phi(x, y, z, t) = 0 as a string in x, y, z (m, world "
                  "frame) and t (s), e.g. \"x**2 + y**2 - 0.25\"")
            return None
        expr, problems = ex.parse_expression(e["phi"], POINT_SYMBOLS)
        for p in problems:
            c.add(f"{path}.phi", p)
        if expr is not None and not ex.depends_on(expr, ("x", "y", "z")):
            c.add(f"{path}.phi", f"{e['phi']!r} depends on t only; a constraint must involve "
                  "the frame's position x, y or z (use [[programme]] for a joint's q(t))")
        if len(c.problems) > n0:
            return None
        return ExpressionConstraintSpec(path, name, frame, expr, e["phi"])
    if kind == "ellipse":
        a = c.number(e, "a", path, "m, semi-axis along world x", rule=">0")
        b = c.number(e, "b", path, "m, semi-axis along world y", rule=">0")
        center = c.vector(e, "center", path, 2, "m, world (x, y)", required=False) or (0.0, 0.0)
        if len(c.problems) > n0:
            return None
        return EllipseConstraintSpec(path, name, frame, a, b, center)
    axis = c.string(e, "axis", path, "world axis x, y or z", choices=tuple(AXES))
    fn_table = c.table(e, "function", path, required=True)
    fn = None if fn_table is None else _time_function(c, fn_table, f"{path}.function", "m", t_end)
    if len(c.problems) > n0 or fn is None:
        return None
    return CoordinateConstraintSpec(path, name, frame, AXES[axis], fn)


_PAIR_KEYS = {"relative": ("axis", "function"), "distance": ("length", "function"),
              "coincident": ("axes",), "aligned": (), "weld": (), "expression": ("phi",)}


def _pair_constraint(c: _Checker, e: dict, path: str, kind: str, index: int,
                     t_end) -> Optional[PairConstraintSpec]:
    """A [[constraint]] between two frames (``frames = [a, b]``; PairConstraintSpec)."""
    keys = _PAIR_KEYS[kind]
    c.keys(e, ("name", "frames", "kind") + keys, path,
           hint=f" (kind {kind!r} takes frames = [a, b]"
                + (f" and {', '.join(keys)})" if keys else ")"))
    n0 = len(c.problems)
    name = f"Phi_{index + 1}"
    if "name" in e:
        name = c.string(e, "name", path, "the constraint's name (output column)")
    frames = e.get("frames")
    if not (isinstance(frames, list) and len(frames) == 2
            and all(isinstance(f, str) and f for f in frames)):
        c.add(f"{path}.frames", f"must be two frame names [a, b] (named frames or links of "
              f"the model), got {_type_name(frames)} {frames!r}")
        return None
    if frames[0] == frames[1] and kind != "expression":
        c.add(f"{path}.frames", f"names frame {frames[0]!r} twice; a constraint between two "
              "frames needs two different frames")
    spec = {"key": path, "name": name, "kind": kind, "frames": tuple(frames)}
    if kind == "expression":
        expr, problems = ex.parse_expression(e.get("phi"), PAIR_SYMBOLS) if "phi" in e else \
            (None, ["missing; phi(x_a, y_a, z_a, x_b, y_b, z_b, t) = 0 as a string in the "
                    "world coordinates of the two frames' origins (m) and t (s), e.g. "
                    "\"x_b - x_a - 0.4\""])
        for p in problems:
            c.add(f"{path}.phi", p)
        if expr is not None and not ex.depends_on(expr, tuple(PAIR_SYMBOLS)[:6]):
            c.add(f"{path}.phi", f"{e['phi']!r} depends on t only; a constraint between two "
                  "frames must involve their coordinates x_a ... z_b")
        spec.update(phi=expr, text=e.get("phi"))
    elif kind == "relative":
        axis = c.string(e, "axis", path, "world axis x, y or z", choices=tuple(AXES))
        spec["axis"] = AXES.get(axis)
        spec["function"] = _pair_function(c, e, path, t_end, "the offset of b from a along "
                                          "the axis", default=0.0)
    elif kind == "distance":
        if "length" in e and "function" in e:
            c.add(path, "give length (a rigid rod, m) or function (a programmed distance), "
                  "not both")
        elif "length" in e:
            length = c.number(e, "length", path, "m, the distance between the origins",
                              rule=">0")
            spec["function"] = None if length is None else tfn.Constant(length)
        else:
            spec["function"] = _pair_function(c, e, path, t_end, "the distance", default=None)
    elif kind == "coincident":
        axes = e.get("axes", "xyz")
        if not (isinstance(axes, str) and axes and set(axes) <= set(AXES)
                and len(set(axes)) == len(axes)):
            c.add(f"{path}.axes", f"must be a string of distinct world axes among x, y, z "
                  f"(e.g. \"xy\" for a planar loop), got {axes!r}")
        else:
            spec["axes"] = axes
    if len(c.problems) > n0:
        return None
    return PairConstraintSpec(**spec)


def _pair_function(c: _Checker, e: dict, path: str, t_end, what: str, default):
    """The TimeFunction of a pair constraint's ``function`` table (m), or Constant(default)
    when absent and a default exists (else a problem)."""
    if "function" not in e:
        if default is None:
            c.add(f"{path}.function", f"missing; {what} as a function of time "
                  "{type = ..., parameters in m} (or length = ... for a rigid rod)")
            return None
        return tfn.Constant(default)
    table = c.table(e, "function", path, required=True)
    return None if table is None else _time_function(c, table, f"{path}.function", "m", t_end)


def _programme(c: _Checker, e: dict, path: str, t_end) -> Optional[ProgrammeSpec]:
    c.keys(e, ("joint", "q", "name"), path)
    n0 = len(c.problems)
    joint = c.string(e, "joint", path, "the programmed coordinate")
    name = c.string(e, "name", path, "the programme's name", required=False)
    if "q" not in e:
        c.add(f"{path}.q", "missing; q(t) as a string in t (s) giving rad or m, e.g. "
              "\"0.3*sin(2*t)\"")
        return None
    expr, problems = ex.parse_expression(e["q"], TIME_SYMBOLS)
    for p in problems:
        c.add(f"{path}.q", p)
    if expr is None or len(c.problems) > n0:
        return None
    if t_end is not None:
        bad = function_problems(tfn.SympyTimeFunction(expr, ex.symbol("t")), t_end)
        if bad:
            c.add(f"{path}.q", bad)
            return None
    return ProgrammeSpec(path, joint, expr, e["q"], name)


# ====================================================================== [solver], [initial]
def _solver_section(c: _Checker, data: dict, n_constraints: Optional[int]) -> SolverSpec:
    t = c.table(data, "solver", "")
    if t is None:
        return SolverSpec(None, DEFAULT_BAUMGARTE)
    c.keys(t, ("dependent", "baumgarte"), "solver")
    dependent = None
    if "dependent" in t:
        v = t["dependent"]
        if not isinstance(v, list) or not all(isinstance(x, str) and x for x in v):
            c.add("solver.dependent", f"must be an array of coordinate names, got "
                  f"{_type_name(v)} {v!r}")
        else:
            dup = sorted({x for x in v if v.count(x) > 1})
            if dup:
                c.add("solver.dependent", f"names repeat: {dup}; give {len(v)} distinct "
                      "coordinates")
            elif n_constraints is not None and len(v) != n_constraints:
                c.add("solver.dependent", f"gives {len(v)} coordinates {v} for {n_constraints} "
                      "constraints ([[constraint]] + [[programme]]); give exactly one per "
                      "constraint, or leave it out to choose them by pivoting at q0")
            else:
                dependent = tuple(v)
    baumgarte = DEFAULT_BAUMGARTE
    if "baumgarte" in t:
        bg = c.vector(t, "baumgarte", "solver", 2, "1/s, [alpha, beta]")
        if bg is not None and min(bg) < 0:
            c.add("solver.baumgarte", f"alpha and beta must be >= 0 (1/s), got {list(bg)}")
        elif bg is not None:
            baumgarte = bg
    return SolverSpec(dependent, baumgarte)


def _initial_section(c: _Checker, data: dict) -> InitialSpec:
    t = c.table(data, "initial", "")
    if t is None:
        return InitialSpec()
    c.keys(t, ("q", "q_dot", "on_constraints", "static_flexible"), "initial")
    return InitialSpec(q=c.number_map(t, "q", "initial", "rad or m"),
                       q_dot=c.number_map(t, "q_dot", "initial", "rad/s or m/s"),
                       on_constraints=c.boolean(t, "on_constraints", "initial", False),
                       static_flexible=c.boolean(t, "static_flexible", "initial", False))


# ====================================================================== [run], [[tolerance]]
def _run_section(c: _Checker, data: dict) -> Optional[RunSpec]:
    t = c.table(data, "run", "", required=True)
    if t is None:
        return None
    c.keys(t, ("t_end", "quick_t_end", "integrator", "dt", "output_dt"), "run")
    n0 = len(c.problems)
    t_end = c.number(t, "t_end", "run", "s, length of the full run", rule=">0")
    quick = c.number(t, "quick_t_end", "run", "s, length of the CI run", required=False,
                     rule=">0")
    integrator = "RK4"
    if "integrator" in t:
        integrator = c.string(t, "integrator", "run", "the time integrator", choices=INTEGRATORS)
    dt = c.number(t, "dt", "run", "s, RK4 or RadauIIA step", required=False, rule=">0")
    output_dt = c.number(t, "output_dt", "run", "s, spacing of the recorded samples",
                         required=False, rule=">0")
    if t_end is not None:
        for key, v in (("quick_t_end", quick), ("dt", dt), ("output_dt", output_dt)):
            if v is not None and v > t_end:
                c.add(f"run.{key}", f"must be <= t_end = {t_end!r} s, got {v!r}")
    if dt is not None and integrator not in (None,) + FIXED_STEP_METHODS:
        c.add("run.dt", f"is the RK4 or RadauIIA step; integrator {integrator!r} chooses its "
              "own steps (remove dt or set integrator = \"RK4\" or \"RadauIIA\")")
    if len(c.problems) > n0:
        return None
    return RunSpec(t_end, quick if quick is not None else min(t_end, QUICK_T_END), integrator,
                   dt, output_dt if output_dt is not None else min(DEFAULT_OUTPUT_DT, t_end))


MAX_ENGINE_HALVINGS = 8     # 2^8 = 256 x the first step's cost for the last run


def _engine_step(c: _Checker, e: dict, path: str, t_end) -> Optional[EngineStep]:
    c.keys(e, ("engine", "dt", "reason", "max_halvings"), path)
    n0 = len(c.problems)
    engine = c.string(e, "engine", path, "the engine whose first step this is",
                      choices=STEP_ENGINES)
    dt = c.number(e, "dt", path, "s, the engine's first (coarsest) step", rule=">0")
    reason = c.string(e, "reason", path, "why this step suits this model")
    halvings = None
    if "max_halvings" in e:
        v = e["max_halvings"]
        if isinstance(v, bool) or not isinstance(v, int) or not 0 <= v <= MAX_ENGINE_HALVINGS:
            c.add(f"{path}.max_halvings", f"must be a whole number from 0 to "
                  f"{MAX_ENGINE_HALVINGS} (halvings beyond the first three runs), got {v!r}")
        else:
            halvings = v
    if dt is not None and t_end is not None and dt > t_end:
        c.add(f"{path}.dt", f"must be <= t_end = {t_end!r} s, got {dt!r}")
    if len(c.problems) > n0:
        return None
    return EngineStep(engine, dt, reason, halvings)


def _reference(c: _Checker, e: dict, path: str, t_end) -> Optional[ReferenceValues]:
    """[[reference]]: published values of the motion at time t (docs/models.md)."""
    c.keys(e, ("t", "q", "q_dot", "abs", "rel", "source", "reason"), path)
    n0 = len(c.problems)
    t = c.number(e, "t", path, "s, the time of the published values", rule=">=0")
    if t is not None and t_end is not None and t > t_end:
        c.add(f"{path}.t", f"{t:g} s is after the run's end t_end = {t_end:g} s")
    values = dict(c.number_map(e, "q", path, "rad or m"))
    values.update({f"{k}_dot": v for k, v in c.number_map(e, "q_dot", path,
                                                          "rad/s or m/s").items()})
    if not values and "q" not in e and "q_dot" not in e:
        c.add(path, "give the published values: q = {coordinate = value} and/or q_dot = "
              "{coordinate = value}")
    tol_abs = c.number(e, "abs", path, "the values' units", rule=">=0")
    tol_rel = c.number(e, "rel", path, "relative to the largest value", rule=">=0")
    source = c.string(e, "source", path, "where the values are published")
    reason = c.string(e, "reason", path, "why the tolerance holds")
    if len(c.problems) > n0:
        return None
    return ReferenceValues(path, t, values, tol_abs, tol_rel, source, reason)


def _tolerance(c: _Checker, e: dict, path: str) -> Optional[ToleranceOverride]:
    c.keys(e, ("check", "abs", "rel", "reason"), path)
    n0 = len(c.problems)
    check = c.string(e, "check", path, "\"<engine>/<quantity>\", e.g. \"pinocchio/M\"")
    if check is not None:
        engine, _, quantity = check.partition("/")
        if engine not in TOLERANCE_ENGINES or not quantity.strip():
            c.add(f"{path}.check", f"{check!r} must be \"<engine>/<quantity>\" with engine one "
                  f"of {', '.join(TOLERANCE_ENGINES)}, e.g. \"pinocchio/M\"")
    a = c.number(e, "abs", path, "the quantity's unit", rule=">=0")
    r = c.number(e, "rel", path, "relative to the largest reference entry", rule=">=0")
    reason = c.string(e, "reason", path, "why this tolerance holds for this model")
    if len(c.problems) > n0:
        return None
    return ToleranceOverride(check, a, r, reason)
