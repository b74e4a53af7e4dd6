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

This module only knows the file: its path, its text, its validation.
"""
import dataclasses
import json
from pathlib import Path
from typing import Any, Optional

import numpy as np

from gpme_core import time_functions
from gpme_core.errors import ModelFileError
from gpme_core.model import STANDARD_GRAVITY, Model
from gpme_core.rfem import BeamProperties

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
    }


def side_file_text(side: dict) -> str:
    """The side-file dict as JSON text (floats written exactly, keys in order)."""
    return json.dumps(side, indent=2) + "\n"


def read_side_file(path) -> tuple:
    """(side dict or None, problems) of the side file at ``path``; never raises."""
    path = Path(path)
    label = f"side file {str(path)!r}"
    try:
        side = json.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        return None, [f"{label}: cannot read it ({exc})"]
    except json.JSONDecodeError as exc:
        return None, [f"{label}: not valid JSON ({exc})"]
    problems = side_file_problems(side, label)
    return (None if problems else side), problems


def load_side_file(path) -> dict:
    """The validated side-file dict at ``path`` (ModelFileError listing every problem)."""
    side, problems = read_side_file(path)
    if problems:
        raise ModelFileError(problems)
    return side


def _is_number(x: Any) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool)


def side_file_problems(side: Any, label: str = "side file") -> list:
    """Problems of a side-file dict (empty list when valid)."""
    if not isinstance(side, dict):
        return [f"{label}: expected a JSON object, got {type(side).__name__}"]
    problems = []
    if side.get("format") != SIDE_FORMAT or side.get("version") != SIDE_VERSION:
        problems.append(f"{label}: expected format {SIDE_FORMAT!r} version {SIDE_VERSION}, got "
                        f"{side.get('format')!r} version {side.get('version')!r}")
    g = side.get("gravity", list(STANDARD_GRAVITY))
    if not (isinstance(g, list) and len(g) == 3 and all(_is_number(x) for x in g)):
        problems.append(f"{label}: gravity must be 3 numbers (m/s^2), got {g!r}")
    joints = side.get("joints", {})
    if not isinstance(joints, dict):
        problems.append(f"{label}: joints must be an object name -> {{stiffness, spring_reference}}")
        joints = {}
    for name, rec in joints.items():
        if not isinstance(rec, dict) or set(rec) - {"stiffness", "spring_reference"}:
            problems.append(f"{label}: joint {name!r} must hold only stiffness and "
                            f"spring_reference, got {rec!r}")
            continue
        for key, val in rec.items():
            if not _is_number(val) or not np.isfinite(val) or (key == "stiffness" and val < 0):
                problems.append(f"{label}: joint {name!r} {key} must be a finite number"
                                f"{' >= 0' if key == 'stiffness' else ''}, got {val!r}")
    for key in ("massless_links", "flexible_links", "drives"):
        if not isinstance(side.get(key, []), list):
            problems.append(f"{label}: {key} must be a list, got {side.get(key)!r}")
    beam_fields = {f.name for f in dataclasses.fields(BeamProperties)}
    # optional: side files written before the section's extreme fibres were recorded
    optional_beam_fields = {"extreme_fibre_y", "extreme_fibre_z"}
    for rec in side.get("flexible_links", []) if isinstance(side.get("flexible_links"), list) else []:
        if not isinstance(rec, dict) or not isinstance(rec.get("beam"), dict) or \
                not beam_fields - optional_beam_fields <= set(rec["beam"]) <= beam_fields or not isinstance(rec.get("n_segments"), int) or \
                rec.get("n_segments", -1) < 0 or not isinstance(rec.get("joints"), list) or \
                not isinstance(rec.get("links"), list):
            problems.append(f"{label}: flexible link record {rec!r} must have name, n_segments "
                            f"(int >= 0), joints, links and beam with fields {sorted(beam_fields)} "
                            f"({sorted(optional_beam_fields)} optional)")
    for rec in side.get("drives", []) if isinstance(side.get("drives"), list) else []:
        if isinstance(rec, dict) and rec.get("function") == EXPRESSION_DRIVE:
            from gpme_io.modelfile.expressions import parse_expression
            params = rec.get("parameters")
            text = params.get("expr") if isinstance(params, dict) else None
            _, bad = parse_expression(text, {"t": "s"})
            problems += [f"{label}: drive record on {rec.get('joint')!r}: expr {p}" for p in bad]
            continue
        cls = getattr(time_functions, str(rec.get("function")) if isinstance(rec, dict) else "",
                      None)
        if not (isinstance(rec, dict) and isinstance(cls, type) and dataclasses.is_dataclass(cls)
                and issubclass(cls, time_functions.TimeFunction)
                and isinstance(rec.get("parameters"), dict)):
            problems.append(f"{label}: drive record {rec!r} must name a dataclass of "
                            "gpme_core.time_functions in 'function' with its 'parameters'")
    return problems


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
    gpme_io.modelfile.expressions, never evaluated as Python)."""
    if rec["function"] == EXPRESSION_DRIVE:
        from gpme_io.modelfile.expressions import parse_expression
        expr, _ = parse_expression(rec["parameters"]["expr"], {"t": "s"})
        return time_functions.SympyTimeFunction(expr)
    return getattr(time_functions, rec["function"])(**rec["parameters"])
