"""The sweepable parameters of a model file: dotted paths to the numbers of its TOML document.

A model file (docs/models.md) is read as a plain TOML document; every number in it that a
gpme run depends on can be swept, named by its path:

  plain tables, key by key        run.t_end   model.crane.support_stiffness   initial.q.psi3
  arrays of tables, by the entry's identifying key
                                  flexible.<link>.youngs_modulus   flexible.<link>.segments
                                  joint.<name>.stiffness           drive.<joint>.level
                                  constraint.<name>.a              constraint.<name>.function.amplitude
  or by position (from 0, in file order), always accepted
                                  drive[0].level                   constraint[1].b

A constraint without ``name`` is addressed by the name the loader gives it, Phi_<k+1>.  An
entry whose identifying key is missing or repeated is listed by position only.

Only numbers can be swept.  Arrays (``model.gravity``, ``solver.baumgarte``,
``constraint.<name>.center``), strings (expressions, names) and booleans are refused with the
reason; the model-file format has no named parameters inside expressions, so an expression
is changed by writing its number in a key of its own (e.g. a ``kind = "coordinate"``
constraint's ``function.amplitude``).  ``[[tolerance]]`` entries and ``run.quick_t_end``
do not change a sweep's run and are not listed.  Keys are swept as they appear in the file:
to sweep a value the file leaves at its default (e.g. a joint's damping), write it in the
file.

``segments`` and ``n_rfe`` are integers (the loader refuses 3.0 there); every other number is
written as a float.
"""
import copy
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Mapping, Optional

from gpme_core.echo import did_you_mean
from gpme_io.input_files import MODEL_FILE_LIMIT, InputFileError, read_input_file
from gpme_io.modelfile.load import CRANE_FIELDS

# array-of-tables section -> the key that names an entry
IDENTIFYING_KEYS = {"flexible": "link", "joint": "name", "drive": "joint",
                    "constraint": "name", "programme": "name"}
# parts of a model file that do not change a sweep point's gpme run
NOT_SWEPT = {("tolerance",): "[[tolerance]] gates crosschecks only",
             ("run", "quick_t_end"): "a sweep runs run.t_end (or the sweep's own t_end)"}
INTEGER_KEYS = ("segments", "n_rfe")
# unit of a swept value by its last key (model.crane fields: gpme_io.modelfile.load)
UNITS = {"t_end": "s", "dt": "s", "output_dt": "s", "youngs_modulus": "Pa",
         "shear_modulus": "Pa", "density": "kg/m^3", "segments": "", "n_rfe": "",
         "bending_viscosity": "Pa s", "torsion_viscosity": "Pa s", "length": "m",
         "diameter": "m", "outer_diameter": "m", "wall_thickness": "m", "width_y": "m",
         "height_z": "m", "stiffness": "N m/rad or N/m", "spring_reference": "rad or m",
         "damping": "N m s/rad or N s/m", "a": "m", "b": "m", "ramp_time": "s",
         "period": "s", "phase": "rad"}
# keys whose unit is that of the function's value (drive: N or N m; coordinate constraint: m)
VALUE_KEYS = ("level", "offset", "amplitude")


class PathError(ValueError):
    """A parameter path that cannot be swept; ``str()`` says why and what is valid."""


@dataclass(frozen=True)
class ModelDocument:
    """A model file read as a TOML document, with its sweepable numbers.

    path       : the model file (absolute); relative paths inside it are resolved from
                 its folder
    data       : the parsed TOML (never modified: :meth:`with_values` copies)
    parameters : {path: location} of every sweepable number, in file order; a location
                 is the tuple of keys and indices leading to it in ``data``
    aliases    : {positional path such as "drive[0].level": its listed path}
    """

    path: Path
    data: Mapping
    parameters: Mapping[str, tuple] = field(default_factory=dict)
    aliases: Mapping[str, str] = field(default_factory=dict)

    def __post_init__(self):
        object.__setattr__(self, "parameters", MappingProxyType(dict(self.parameters)))
        object.__setattr__(self, "aliases", MappingProxyType(dict(self.aliases)))

    def __reduce__(self):
        # the read-only mappings do not pickle; rebuilt from the document (Dask workers)
        return (_document, (self.path, self.data))

    def canonical(self, name: str) -> str:
        """The listed path of ``name`` (a listed or a positional path); raises PathError."""
        if name in self.parameters:
            return name
        if name in self.aliases:
            return self.aliases[name]
        raise PathError(self._why_not(name))

    def value(self, name: str):
        """The number at path ``name`` in the file."""
        return _get(self.data, self.parameters[self.canonical(name)])

    def unit(self, name: str) -> str:
        """Unit of the number at ``name`` ('' when dimensionless or unknown)."""
        name = self.canonical(name)
        loc = self.parameters[name]
        last = loc[-1]
        if loc[:2] == ("model", "crane") and len(loc) == 3:
            return CRANE_FIELDS.get(last, ("",))[0]
        if loc[0] == "initial" and len(loc) == 3:
            return "rad or m" if loc[1] == "q" else "rad/s or m/s"
        if loc[0] == "chain" and len(loc) == 3:
            return "rad or m"
        if last in VALUE_KEYS:
            if loc[0] == "drive":
                return "N or N m"
            if loc[0] == "constraint":
                return "m"
        return UNITS.get(last, "")

    def coerce(self, name: str, value) -> float:
        """``value`` as written into the document at ``name``: int for INTEGER_KEYS
        (raises ValueError unless integral), float otherwise (raises unless finite)."""
        loc = self.parameters[self.canonical(name)]
        if isinstance(value, bool):
            raise ValueError(f"expected a number, got {value!r}")
        x = float(value)
        if not math.isfinite(x):
            raise ValueError(f"expected a finite number, got {value!r}")
        if loc[-1] in INTEGER_KEYS:
            if x != int(x):
                raise ValueError(f"{loc[-1]} is an integer, got {value!r}")
            return int(x)
        return x

    def with_values(self, values: Mapping[str, float]) -> dict:
        """A deep copy of the document with ``values`` {path: number} written in (each
        coerced by :meth:`coerce`); the document itself is not changed."""
        data = copy.deepcopy(dict(self.data))
        for name, v in values.items():
            loc = self.parameters[self.canonical(name)]
            _get(data, loc[:-1])[loc[-1]] = self.coerce(name, v)
        return data

    def _why_not(self, name: str) -> str:
        """Message for a path that is not sweepable: what it is, and the valid paths."""
        valid = list(self.parameters)
        listing = "; valid paths in " + f"{self.path.name}: " + ", ".join(valid)
        loc = _locate(self.data, name)
        if loc is not None:
            v = _get(self.data, loc)
            for prefix, reason in NOT_SWEPT.items():
                if loc[:len(prefix)] == prefix:
                    return f"{name!r} is not swept: {reason}" + listing
            if isinstance(v, list):
                return (f"{name!r} is an array ({v!r}); only single numbers can be swept"
                        + listing)
            if isinstance(v, bool):
                return f"{name!r} is a boolean ({v!r}); only numbers can be swept" + listing
            if isinstance(v, str):
                return (f"{name!r} is a string ({v!r}); only numbers can be swept (the "
                        "model-file format has no named parameters inside expressions: "
                        "write the number in a key of its own, e.g. a kind = \"coordinate\" "
                        "constraint's function.amplitude)" + listing)
            if isinstance(v, dict):
                return f"{name!r} is a table; name one of its numbers" + listing
        if name.startswith("param."):
            return (f"{name!r}: model files have no [param] table of named numbers for "
                    "expressions (gpme_io.modelfile does not read one)" + listing)
        return f"unknown parameter path {name!r}{did_you_mean(name, valid, n=3)}" + listing


def read_model_document(path) -> ModelDocument:
    """The ModelDocument of the model file at ``path``; raises PathError when the file
    cannot be read or is not TOML (its content is checked when points are built)."""
    path = Path(path).resolve()
    try:
        text = read_input_file(path, "model file", MODEL_FILE_LIMIT).decode("utf-8")
    except InputFileError as exc:
        raise PathError(f"model file {str(path)!r} cannot be read: it {exc.reason}") from None
    except UnicodeDecodeError as exc:
        raise PathError(f"model file {str(path)!r} is not UTF-8 text ({exc})") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise PathError(f"model file {str(path)!r} is not valid TOML: {exc}") from None
    except RecursionError:
        raise PathError(f"model file {str(path)!r}: its arrays or tables are nested too "
                        "deeply to read") from None
    return _document(path, data)


def _document(path: Path, data: Mapping) -> ModelDocument:
    parameters, aliases = sweepable_paths(data)
    return ModelDocument(path, data, parameters, aliases)


def sweepable_paths(data: Mapping) -> tuple:
    """({path: location}, {positional path: path}) of every sweepable number of ``data``
    (a parsed model file), in file order; see the module docstring for the names."""
    parameters: dict = {}
    aliases: dict = {}

    def number(v):
        return isinstance(v, (int, float)) and not isinstance(v, bool)

    def walk(table, name, loc):
        for key, v in table.items():
            sub_loc = loc + (key,)
            if any(sub_loc[:len(p)] == p for p in NOT_SWEPT):
                continue
            sub_name = f"{name}.{key}" if name else str(key)
            if isinstance(v, dict):
                walk(v, sub_name, sub_loc)
            elif number(v):
                parameters[sub_name] = sub_loc

    for key, v in data.items():
        if (key,) in NOT_SWEPT:
            continue
        if key in IDENTIFYING_KEYS and isinstance(v, list) and all(isinstance(e, dict)
                                                                   for e in v):
            ids = [_entry_id(key, k, e) for k, e in enumerate(v)]
            for k, (entry, ident) in enumerate(zip(v, ids)):
                unique = ident is not None and ids.count(ident) == 1
                listed = f"{key}.{ident}" if unique else f"{key}[{k}]"
                before = set(parameters)
                walk(entry, listed, (key, k))
                if unique:
                    for p in set(parameters) - before:
                        aliases[f"{key}[{k}]" + p[len(listed):]] = p
        elif isinstance(v, dict):
            walk(v, key, (key,))
        elif number(v):
            parameters[key] = (key,)
    return parameters, aliases


def _entry_id(section: str, k: int, entry: Mapping) -> Optional[str]:
    ident = entry.get(IDENTIFYING_KEYS[section])
    if section == "constraint" and ident is None:
        return f"Phi_{k + 1}"          # the loader's default name
    if section == "programme" and ident is None:
        joint = entry.get("joint")
        return f"Phi_{joint}" if isinstance(joint, str) else None
    return ident if isinstance(ident, str) and ident else None


def _get(data, loc):
    for k in loc:
        data = data[k]
    return data


def _locate(data: Mapping, name: str) -> Optional[tuple]:
    """Location of ``name`` in ``data`` whatever its value's type (None: no such key),
    trying the array-of-tables forms <section>.<id> and <section>[k]."""
    def descend(node, rest, loc):
        if rest == "":
            return loc
        if isinstance(node, dict):
            for key in sorted(node, key=len, reverse=True):
                if rest == key or rest.startswith(key + "."):
                    found = descend(node[key], rest[len(key) + 1:], loc + (key,))
                    if found is not None:
                        return found
        return None

    for section in IDENTIFYING_KEYS:
        entries = data.get(section)
        if not isinstance(entries, list):
            continue
        for k, e in enumerate(entries):
            if not isinstance(e, dict):
                continue
            ident = _entry_id(section, k, e)
            for head in filter(None, (f"{section}[{k}]", ident and f"{section}.{ident}")):
                if name == head or name.startswith(head + "."):
                    found = descend(e, name[len(head) + 1:], (section, k))
                    if found is not None:
                        return found
    return descend(data, name, ())
