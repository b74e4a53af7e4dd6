"""The gpme side file ``<stem>.gpme.json``: what URDF cannot hold.

URDF has no place for joint springs and their references, gravity, drives, or the RFEM
records of a discretised beam; gpme_io.urdf_writer puts them in a JSON file beside the
URDF (``crane_rigid.urdf`` -> ``crane_rigid.gpme.json``) and gpme_io.urdf_reader reads it
back.  docs/urdf.md shows the layout:

    format, version : "gpme-urdf-side-file", 1
    model           : model name
    gravity         : [gx, gy, gz] m/s^2, world frame
    joints          : {coordinate: {"stiffness": N m/rad or N/m, "spring_reference": rad or m}}
    massless_links  : [link names the writer knows carry no mass]
    flexible_links  : [{"name", "n_segments", "beam": BeamProperties fields, "joints", "links"}]
    drives          : [{"joint", "function": a gpme_core.time_functions class name, "parameters"}]
    point_springs   : [{"name", "frame", "anchor": [x, y, z] m or a frame name, "stiffness"
                      N/m, "free_length" m, "damping" N s/m}] (gpme_core.point_springs)
    tree            : true when every moving joint of the URDF is a coordinate (a model whose
                      branches all move; written only then, the reader then reads the
                      whole tree instead of one chain)

This module only knows the file: its path, its text, its validation (our own code, not a
schema library, on purpose: docs/architecture.md, "Input validation").
"""
import dataclasses
import json
import math
import warnings
from collections import Counter
from pathlib import Path
from typing import Any, Optional

from gpme_core.echo import did_you_mean, shown
from gpme_core import time_functions
from gpme_core.errors import ModelError, ModelFileError, SectionWarning
from gpme_core.model import Model
from gpme_core.rfem import MAX_SEGMENTS, BeamProperties

from .expressions import parse_expression
from .input_files import SIDE_FILE_LIMIT, InputFileError, read_input_file

SIDE_SUFFIX = ".gpme.json"
SIDE_FORMAT = "gpme-urdf-side-file"
SIDE_VERSION = 1


def side_file_path(urdf_path) -> Path:
    """Path of the side file beside ``urdf_path``: ``<stem>.gpme.json``."""
    p = Path(urdf_path)
    return p.with_name(p.stem + SIDE_SUFFIX)


def side_document(model: Model, drives: list) -> dict:
    """The side-file dict of ``model`` with the given drive records (see drive_record)."""
    return {
        "format": SIDE_FORMAT, "version": SIDE_VERSION, "model": model.name,
        "gravity": [float(g) for g in model.gravity],
        "joints": {j.name: {"stiffness": float(j.stiffness),
                            "spring_reference": float(j.spring_reference)} for j in model.joints},
        "massless_links": [lk.name for lk in model.links if lk.inertia is None],
        "flexible_links": [
            {"name": f.name, "n_segments": int(f.n_segments), "beam": dataclasses.asdict(f.beam),
             "joints": [model.coordinate_names[k] for k in f.joint_indices],
             "links": [model.links[k].name for k in f.link_indices]}
            for f in model.flexible_links],
        "drives": drives,
        **({} if model.is_chain else {"tree": True}),
        **({"point_springs": [
            {"name": p.name, "frame": p.frame,
             "anchor": p.anchor if isinstance(p.anchor, str) else [float(v) for v in p.anchor],
             "stiffness": float(p.stiffness), "free_length": float(p.free_length),
             "damping": float(p.damping)} for p in model.point_springs]}
           if model.point_springs else {}),
    }


def side_file_text(side: dict) -> str:
    """The side-file dict as JSON text (floats written exactly, keys in order)."""
    return json.dumps(side, indent=2) + "\n"


def read_side_file(path) -> tuple:
    """(side dict or None, problems) of the side file at ``path``; never raises.

    The dict holds the valid parts only (:func:`check_side_file`), so that the URDF reader
    can still check them against the URDF and report those problems together with the
    file's own; None when the file cannot be read or is not JSON."""
    path = Path(path)
    label = f"side file {str(path)!r}"
    try:
        data = read_input_file(path, "side file", SIDE_FILE_LIMIT)
    except InputFileError as exc:
        return None, [f"{label}: cannot read it: it {exc.reason}; nothing in it was "
                      f"checked (a side file is the JSON file <stem>{SIDE_SUFFIX} beside the "
                      "URDF)"]
    repeated = []

    def no_repeats(pairs):            # JSON allows a key twice; the last would win silently
        out = {}
        for key, value in pairs:
            if key in out and key not in repeated:
                repeated.append(key)
            out[key] = value
        return out

    try:
        side = json.loads(data, object_pairs_hook=no_repeats)
    except json.JSONDecodeError as exc:
        return None, [f"{label}: not valid JSON at line {exc.lineno}, column {exc.colno} "
                      f"({exc.msg}); nothing in it was checked"]
    except (ValueError, RecursionError) as exc:   # bytes not UTF-8/16/32, nested too deep
        what = "nested too deeply" if isinstance(exc, RecursionError) else str(exc)
        return None, [f"{label}: not JSON text ({what}); nothing in it was checked"]
    side, problems = check_side_file(side, label)
    if repeated:
        problems.insert(0, f"{label}: keys given twice in one object: {shown(repeated)} (JSON "
                           "keeps only the last; give each once)")
    return side, problems


def load_side_file(path) -> dict:
    """The validated side-file dict at ``path`` (ModelFileError listing every problem)."""
    side, problems = read_side_file(path)
    if problems:
        raise ModelFileError(problems)
    return side


def side_file_problems(side: Any, label: str = "side file") -> list:
    """Problems of a side-file dict (empty list when valid)."""
    return check_side_file(side, label)[1]


def check_side_file(side: Any, label: str = "side file") -> tuple:
    """(the valid parts of ``side``, problems); never raises.

    Every key and every record is checked; each problem names the record (``joint 'z1'``,
    ``flexible link record 'arm' (flexible_links #1)``, ``drive record on 'shoulder'
    (drives #2, QuinticRamp)``), the value and what would be valid.  The returned dict
    keeps only the valid keys and records (None when ``side`` is not a JSON object), so
    that the URDF reader can check them against the URDF too; it equals ``side`` when
    there is no problem."""
    if not isinstance(side, dict):
        return None, [f"{label}: expected a JSON object {{\"format\": {SIDE_FORMAT!r}, "
                      f"\"version\": {SIDE_VERSION}, ...}}, got a JSON {_json_type(side)}"]
    problems = _unknown_keys(label, side, SIDE_KEYS)
    if side.get("format") != SIDE_FORMAT or side.get("version") != SIDE_VERSION:
        problems.append(f"{label}: expected format {SIDE_FORMAT!r} version {SIDE_VERSION}, got "
                        f"{shown(side.get('format'))} version {shown(side.get('version'))}")
    clean = {"format": SIDE_FORMAT, "version": SIDE_VERSION}
    if "model" in side:
        if isinstance(side["model"], str) and side["model"].strip():
            clean["model"] = side["model"]
        else:
            problems.append(f"{label}: model must be the model's name (a non-empty string), "
                            f"got {shown(side['model'])}")
    if "gravity" in side:
        g = side["gravity"]
        if isinstance(g, list) and len(g) == 3 and all(_is_number(x) for x in g):
            clean["gravity"] = list(g)
        else:
            problems.append(f"{label}: gravity must be 3 finite numbers (m/s^2, world frame), "
                            f"got {shown(g)}")
    if "joints" in side:
        clean["joints"] = _check_joints(side["joints"], label, problems)
    if "massless_links" in side:
        links = side["massless_links"]
        if not isinstance(links, list):
            problems.append(f"{label}: massless_links must be a list of link names, got "
                            f"{shown(links)}")
        else:
            bad = [x for x in links if not (isinstance(x, str) and x)]
            if bad:
                problems.append(f"{label}: massless_links must hold link names (non-empty "
                                f"strings), got {shown(bad)}")
            clean["massless_links"] = [x for x in links if isinstance(x, str) and x]
    if "tree" in side:
        if isinstance(side["tree"], bool):
            clean["tree"] = side["tree"]
        else:
            problems.append(f"{label}: tree must be true or false (whether every moving joint "
                            f"of the URDF is a coordinate), got {shown(side['tree'])}")
    for key, check in (("flexible_links", _check_flexible), ("drives", _check_drive),
                       ("point_springs", _check_point_spring)):
        if key not in side:
            continue
        records = side[key]
        if not isinstance(records, list):
            problems.append(f"{label}: {key} must be a list of records, got {shown(records)}")
            continue
        clean[key] = []
        for k, rec in enumerate(records, start=1):
            bad = []
            check(rec, label, k, bad)
            problems += bad
            if not bad:
                clean[key].append(rec)
    names = [r["name"] for r in clean.get("flexible_links", [])]
    dup = sorted(n for n, k in Counter(names).items() if k > 1)
    if dup:
        problems.append(f"{label}: flexible_links has more than one record for {dup} (one "
                        "record per link)")
    return clean, problems


SIDE_KEYS = ("format", "version", "model", "gravity", "joints", "massless_links",
             "flexible_links", "drives", "tree", "point_springs")
POINT_SPRING_KEYS = ("name", "frame", "anchor", "stiffness", "free_length", "damping")
JOINT_KEYS = ("stiffness", "spring_reference")
FLEXIBLE_KEYS = ("name", "n_segments", "beam", "joints", "links")
DRIVE_KEYS = ("joint", "function", "parameters")
# beam fields a side file may leave out (written before the section's extreme fibres were
# recorded, or defaults) and those that may be null
OPTIONAL_BEAM_FIELDS = frozenset(("bending_viscosity", "torsion_viscosity", "extreme_fibre_y",
                                  "extreme_fibre_z"))
NULLABLE_BEAM_FIELDS = frozenset(("torsion_viscosity", "extreme_fibre_y", "extreme_fibre_z"))


def _is_number(x: Any) -> bool:
    """A finite number (not a bool; an int too large for a float is not finite)."""
    if isinstance(x, bool) or not isinstance(x, (int, float)):
        return False
    try:
        return math.isfinite(float(x))
    except OverflowError:
        return False


def _json_type(x: Any) -> str:
    return {dict: "object", list: "array", str: "string", bool: "true/false",
            type(None): "null", int: "number", float: "number"}.get(type(x), type(x).__name__)


def _unknown_keys(where: str, given, known) -> list:
    """'<where>: unknown key 'x' (did you mean 'y'?); the keys are ...' for each key of
    ``given`` not in ``known``."""
    out = []
    for key in given:
        if key in known:
            continue
        out.append(f"{where}: unknown key {key!r}{did_you_mean(key, known)}; the keys are "
                   f"{', '.join(known)}")
    return out


def _check_joints(joints: Any, label: str, problems: list) -> dict:
    """{joint: {stiffness, spring_reference}} of the valid joint records."""
    if not isinstance(joints, dict):
        problems.append(f"{label}: joints must be an object {{joint name: {{\"stiffness\": "
                        f"N m/rad or N/m, \"spring_reference\": rad or m}}}}, got {shown(joints)}")
        return {}
    out = {}
    for name, rec in joints.items():
        where = f"{label}: joint {name!r}"
        if not isinstance(rec, dict):
            problems.append(f"{where} must hold only stiffness and spring_reference (an "
                            f"object), got {shown(rec)}")
            continue
        bad = _unknown_keys(where, rec, JOINT_KEYS)
        for key in JOINT_KEYS:
            if key not in rec:
                continue
            val = rec[key]
            if not _is_number(val) or (key == "stiffness" and val < 0):
                unit = "N m/rad or N/m" if key == "stiffness" else "rad or m"
                bad.append(f"{where} {key} must be a finite number"
                           f"{' >= 0' if key == 'stiffness' else ''} ({unit}), got {shown(val)}")
        problems += bad
        if not bad:
            out[name] = dict(rec)
    return out


def _check_flexible(rec: Any, label: str, k: int, bad: list) -> None:
    """Problems of flexible_links record number ``k`` (1-based) into ``bad``."""
    where = f"{label}: flexible link record (flexible_links #{k})"
    if not isinstance(rec, dict):
        bad.append(f"{where}: expected an object with {', '.join(FLEXIBLE_KEYS)}, got {shown(rec)}")
        return
    name = rec.get("name")
    if isinstance(name, str) and name:
        where = f"{label}: flexible link record {name!r} (flexible_links #{k})"
    else:
        bad.append(f"{where}: name must be the link's name (a non-empty string), got {shown(name)}")
    bad += _unknown_keys(where, rec, FLEXIBLE_KEYS)
    missing = [key for key in FLEXIBLE_KEYS if key not in rec and key != "name"]
    if missing:
        bad.append(f"{where}: missing {', '.join(missing)} (a record has "
                   f"{', '.join(FLEXIBLE_KEYS)})")
    n = rec.get("n_segments")
    if "n_segments" in rec and (not isinstance(n, int) or isinstance(n, bool)
                                or not 0 <= n <= MAX_SEGMENTS):
        bad.append(f"{where}: n_segments must be an integer from 0 to {MAX_SEGMENTS}, "
                   f"got {shown(n)}")
    for key, what in (("joints", "joint"), ("links", "link")):
        v = rec.get(key)
        if key in rec and not (isinstance(v, list)
                               and all(isinstance(x, str) and x for x in v)):
            bad.append(f"{where}: {key} must be a list of {what} names (strings), got {shown(v)}")
    if "beam" in rec:
        _check_beam(rec["beam"], f"{where} beam", bad)


def _check_beam(beam: Any, where: str, bad: list) -> None:
    fields = [f.name for f in dataclasses.fields(BeamProperties)]
    if not isinstance(beam, dict):
        bad.append(f"{where}: expected an object with the BeamProperties fields "
                   f"{', '.join(fields)}, got {shown(beam)}")
        return
    n_before = len(bad)
    bad += _unknown_keys(where, beam, fields)
    missing = [key for key in fields if key not in beam and key not in OPTIONAL_BEAM_FIELDS]
    if missing:
        bad.append(f"{where}: missing {', '.join(missing)} (optional: "
                   f"{', '.join(sorted(OPTIONAL_BEAM_FIELDS))})")
    for key, val in beam.items():
        if key not in fields or (val is None and key in NULLABLE_BEAM_FIELDS):
            continue
        if not _is_number(val):
            bad.append(f"{where}: {key} must be a finite number"
                       f"{' or null' if key in NULLABLE_BEAM_FIELDS else ''}, got {shown(val)}")
    if len(bad) == n_before:
        with warnings.catch_warnings():         # the reader warns once, when it builds it
            warnings.simplefilter("ignore", SectionWarning)
            bad += BeamProperties(**beam).problems(where)


def _drive_classes() -> dict:
    """{name: class} of the time functions a drive record may name: the frozen dataclasses
    of gpme_core.time_functions."""
    return {name: cls for name, cls in vars(time_functions).items()
            if isinstance(cls, type) and issubclass(cls, time_functions.TimeFunction)
            and dataclasses.is_dataclass(cls) and cls.__module__ == time_functions.__name__}


def _parameters(cls) -> tuple:
    """(field names, required field names, 'level, ramp_time' text) of a time function."""
    fields = dataclasses.fields(cls)
    required = [f.name for f in fields if f.default is dataclasses.MISSING
                and f.default_factory is dataclasses.MISSING]
    text = ", ".join(f.name + ("" if f.name in required else " (optional)") for f in fields)
    return [f.name for f in fields], required, text


def _check_point_spring(rec: Any, label: str, k: int, bad: list) -> None:
    """Problems of point_springs record number ``k`` (1-based) into ``bad``."""
    where = f"{label}: point spring record (point_springs #{k})"
    if not isinstance(rec, dict):
        bad.append(f"{where}: expected an object with {', '.join(POINT_SPRING_KEYS)}, got "
                   f"{shown(rec)}")
        return
    bad += _unknown_keys(where, rec, POINT_SPRING_KEYS)
    for key in ("name", "frame"):
        if not (isinstance(rec.get(key), str) and rec.get(key)):
            bad.append(f"{where}: {key} must be a non-empty string, got {shown(rec.get(key))}")
    anchor = rec.get("anchor")
    if not ((isinstance(anchor, str) and anchor) or (
            isinstance(anchor, list) and len(anchor) == 3 and all(_is_number(x) for x in anchor))):
        bad.append(f"{where}: anchor must be a frame name or 3 finite numbers (m, world "
                   f"frame), got {shown(anchor)}")
    for key, unit in (("stiffness", "N/m"), ("free_length", "m"), ("damping", "N s/m")):
        v = rec.get(key)
        if not (_is_number(v) and v >= 0):
            bad.append(f"{where}: {key} must be a finite number >= 0 ({unit}), got {shown(v)}")


def _check_drive(rec: Any, label: str, k: int, bad: list) -> None:
    """Problems of drives record number ``k`` (1-based) into ``bad``."""
    classes = _drive_classes()
    kinds = ", ".join(sorted(classes) + [EXPRESSION_DRIVE])
    where = f"{label}: drive record (drives #{k})"
    if not isinstance(rec, dict):
        bad.append(f"{where}: expected an object {{\"joint\": ..., \"function\": one of "
                   f"{kinds}, \"parameters\": {{...}}}}, got {shown(rec)}")
        return
    joint = rec.get("joint")
    if isinstance(joint, str) and joint:
        where = f"{label}: drive record on {joint!r} (drives #{k}"
    else:
        bad.append(f"{where}: joint must be the driven joint's name (a non-empty string), "
                   f"got {shown(joint)}")
        where = f"{label}: drive record (drives #{k}"
    function, params = rec.get("function"), rec.get("parameters")
    if function == EXPRESSION_DRIVE:
        fields, required, takes = ["expr"], ["expr"], "expr (an expression in t, s)"
    elif isinstance(function, str) and function in classes:
        fields, required, takes = _parameters(classes[function])
    else:
        bad += _unknown_keys(where + ")", rec, DRIVE_KEYS)
        bad.append(f"{where}): function must be one of {kinds}, got {shown(function)}")
        return
    where = f"{where}, {function})"
    bad += _unknown_keys(where, rec, DRIVE_KEYS)
    if not isinstance(params, dict):
        bad.append(f"{where}: parameters must be an object; {function} takes {takes}; got "
                   f"{shown(params)}")
        return
    unknown = [p for p in params if p not in fields]
    missing = [p for p in required if p not in params]
    if unknown or missing:
        parts = []
        for p in unknown:
            parts.append(f"unknown parameter {p!r}{did_you_mean(p, fields)}")
        if missing:
            parts.append(f"missing parameter{'s' if len(missing) > 1 else ''} "
                         f"{', '.join(missing)}")
        bad.append(f"{where}: {'; '.join(parts)}; {function} takes {takes}")
        return
    if function == EXPRESSION_DRIVE:
        _, problems = parse_expression(params["expr"], {"t": "s"})
        bad += [f"{where}: expr {p}" for p in problems]
        if problems:
            return
    try:
        drive_function(rec)
    except ModelError as exc:
        bad += [f"{where}: {p}" for p in exc.problems]
    except (TypeError, ValueError, ArithmeticError) as exc:
        bad.append(f"{where}: parameters {shown(params)} rejected ({exc}); {function} takes "
                   f"{takes}")


# a drive given as a SymPy expression in t: stored as its text, read back without eval
EXPRESSION_DRIVE = "SympyTimeFunction"


def drive_record(drive) -> Optional[dict]:
    """{"joint", "function", "parameters"} of a drive (None when its function cannot be
    stored): a dataclass of gpme_core.time_functions by its fields, a SympyTimeFunction by
    its expression text."""
    joint, function = drive.joint, drive.function
    if isinstance(function, time_functions.SympyTimeFunction):
        return {"joint": joint, "function": EXPRESSION_DRIVE,
                "parameters": {"expr": str(function.expr)}}
    if dataclasses.is_dataclass(function) and \
            getattr(time_functions, type(function).__name__, None) is type(function):
        return {"joint": joint, "function": type(function).__name__,
                "parameters": dataclasses.asdict(function)}
    return None


def drive_function(rec: dict):
    """The time function of a validated side-file drive record (expressions parsed by
    gpme_io.expressions, never evaluated as Python; ModelError for a record
    that :func:`check_side_file` would refuse)."""
    if rec["function"] == EXPRESSION_DRIVE:
        expr, problems = parse_expression(rec["parameters"]["expr"], {"t": "s"})
        if problems:
            raise ModelError([f"expr {p}" for p in problems])
        return time_functions.SympyTimeFunction(expr)
    return getattr(time_functions, rec["function"])(**rec["parameters"])
