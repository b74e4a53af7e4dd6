"""Model files: a robot and its task in one TOML file (docs/models.md).

    from gpme_io.modelfile import load_model_file
    scenario = load_model_file("models/crane_rigid.toml")     # a gpme_io.scenario.Scenario

Every problem of a file, the ones in the file itself and the names it uses that the
built model does not have, comes in one :class:`gpme_core.errors.ModelFileError`, one
line each: ``<file>: <key path>: <what is wrong, the value, what would be valid>``.
An initial state that cannot be placed on the constraints raises
:class:`gpme_core.errors.ConstraintError` with the constraint values.

Modules: schema (the parsed file's dataclasses), load (TOML -> schema, with every check),
build (schema -> Scenario); the file's formulas are read by gpme_io.expressions (safe
SymPy reading, shared with the URDF's side file).
"""
from pathlib import Path

from gpme_core.errors import ModelFileError
from gpme_io.scenario import Scenario

from .build import assemble, build_source, reference_problems
from .load import parse_model_file
from .schema import ModelFile

__all__ = ["load_model_file", "load_model_files", "read_model_file", "build_scenario",
           "ModelFile"]

# problems in these sections leave the source model unbuildable or incomplete
_SOURCE_KEYS = ("model", "chain", "tree", "flexible")


def read_model_file(path) -> ModelFile:
    """The parsed, validated file at ``path`` (names are not checked against the model;
    :func:`load_model_file` does that).  Raises ModelFileError listing every problem."""
    spec, problems = parse_model_file(path)
    if problems:
        raise ModelFileError([f"{path}: {p}" for p in problems])
    return spec


def build_scenario(spec: ModelFile) -> Scenario:
    """The Scenario of a parsed file (see :func:`load_model_file`)."""
    return _build(spec, [])


def load_model_file(path) -> Scenario:
    """The :class:`gpme_io.scenario.Scenario` the model file at ``path`` describes.

    Raises ModelFileError listing every problem (file and model names together where the
    source model could be built), ConstraintError when ``[initial] on_constraints = true``
    and the constraints cannot be met from the given state.
    """
    path = Path(path)
    spec, problems = parse_model_file(path)
    return _build(spec, problems)


def _build(spec: ModelFile, problems: list) -> Scenario:
    problems = list(problems)
    source = None
    source_ok = spec.model is not None and not any(
        p.split(":", 1)[0].split(".", 1)[0].split("[", 1)[0] in _SOURCE_KEYS for p in problems)
    blocking = {p.split(":", 1)[0].split(".", 1)[0].split("[", 1)[0] for p in problems} & set(
        _SOURCE_KEYS)
    if source_ok:
        try:
            source = build_source(spec)
        except ModelFileError as exc:
            problems += exc.problems
    elif spec.model is not None and blocking == {"flexible"}:
        # only a [[flexible]] entry is wrong: still read the URDF (with the valid entries) so
        # that its problems are listed now, not after the entry is fixed
        try:
            build_source(spec)
        except ModelFileError as exc:
            problems += [p for p in exc.problems if p not in problems]
    if source is not None:
        problems += reference_problems(spec, source.model)
    if problems or source is None:
        raise ModelFileError([f"{spec.path}: {p}" for p in problems])
    return assemble(spec, source)


def load_model_files(paths) -> list:
    """Scenarios of the model files ``paths`` (a GpmeError lists the problems of each; two
    files whose models have the same name are refused: their outputs would overwrite each
    other)."""
    scenarios = [load_model_file(Path(p)) for p in paths]
    seen, problems = {}, []
    for path, scenario in zip(paths, scenarios):
        if scenario.name in seen:
            problems.append(f"{path} and {seen[scenario.name]} both name their model "
                            f"{scenario.name!r} ([model] name); their outputs would "
                            "overwrite each other: give each model file its own name, or "
                            "each file once")
        seen.setdefault(scenario.name, path)
    if problems:
        raise ModelFileError(problems)
    return scenarios
