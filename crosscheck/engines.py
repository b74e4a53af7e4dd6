"""The reference engines of the harness: which ones there are, which are optional, whether
each is installed and at what version.

Pinocchio and MuJoCo are dependencies of gpme; Drake and Exudyn are optional extras
(``pip install 'gpme[drake]'``, ``'gpme[exudyn]'``, both: ``'gpme[engines]'``).  A missing
optional engine is reported by :func:`missing_message` (one sentence saying what to
install), never by an ImportError from deep inside a crosscheck module.
"""
from dataclasses import dataclass
from importlib import import_module, metadata
from typing import Optional


@dataclass(frozen=True)
class Engine:
    """One reference engine.

    name        : the verify step and report name ("pinocchio", ...)
    title       : its name in text ("Pinocchio", ...)
    module      : the Python module the crosscheck imports ("pinocchio", "pydrake", ...)
    distribution: the package that installs it ("pin", "drake", ...)
    extra       : the gpme extra that installs it (None for a required dependency)
    compares    : what the harness compares against it (report text)
    """

    name: str
    title: str
    module: str
    distribution: str
    extra: Optional[str]
    compares: str


ENGINES = {e.name: e for e in (
    Engine("pinocchio", "Pinocchio", "pinocchio", "pin", None,
           "terms (CRBA, RNEA, ABA, frames), constrained accelerations and multipliers, "
           "exactly realised programmed runs"),
    Engine("mujoco", "MuJoCo", "mujoco", "mujoco", None,
           "terms, free runs and programmed runs (soft equality constraints)"),
    Engine("drake", "Drake", "pydrake", "drake", "drake",
           "terms of a MultibodyPlant read from the URDF (mass matrix, bias, gravity, "
           "spring/damper force elements, free accelerations) and free runs with its own "
           "integrator"),
    Engine("exudyn", "Exudyn", "exudyn", "exudyn", "exudyn",
           "programmed runs with the task as exact (index-3) algebraic constraints and "
           "their reactions, with its own implicit integrator"),
    Engine("continuum", "Exudyn (continuum beams)", "exudyn", "exudyn", "exudyn",
           "model validity: each RFEM link as geometrically exact beam elements in whole "
           "programmed runs (tip deflection and rotation, joint coordinates, multipliers)"),
)}


def is_installed(name: str) -> bool:
    """Whether engine ``name``'s module imports."""
    try:
        import_module(ENGINES[name].module)
    except ImportError:
        return False
    return True


def missing_message(name: str) -> Optional[str]:
    """None when engine ``name`` is installed, else one sentence saying what to install."""
    if is_installed(name):
        return None
    engine = ENGINES[name]
    how = (f"pip install 'gpme[{engine.extra}]' (or 'gpme[engines]' for every optional "
           f"engine)" if engine.extra else f"pip install {engine.distribution} (a dependency "
           "of gpme: reinstall gpme)")
    return (f"{engine.title} is not installed (Python module {engine.module!r} not found), so "
            f"the {engine.name} crosscheck ({engine.compares}) was not run; install it with: "
            f"{how}")


def version(name: str) -> str:
    """The installed version of engine ``name``'s package, or "not installed"."""
    try:
        return metadata.version(ENGINES[name].distribution)
    except metadata.PackageNotFoundError:
        return "not installed"
