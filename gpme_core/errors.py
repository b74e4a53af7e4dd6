"""Exception types raised by gpme_core.

Every error raised for user input names the offending value and what would be valid.
"""
import shutil
from pathlib import Path


class GpmeError(Exception):
    """Base class of all gpme errors."""


class ModelError(GpmeError, ValueError):
    """A model description is invalid (the message lists every problem found)."""

    subject = "the model"

    def __init__(self, problems):
        if isinstance(problems, str):
            problems = [problems]
        self.problems = list(problems)
        if len(self.problems) == 1:
            msg = self.problems[0]
        else:
            msg = f"{len(self.problems)} problems in {self.subject}:\n" + "\n".join(
                f"  - {p}" for p in self.problems)
        super().__init__(msg)


class ModelFileError(ModelError):
    """A model file (URDF, side file) is malformed or uses an unsupported feature."""

    subject = "the model file"


class ConstraintError(GpmeError):
    """The programmed constraints cannot be met (singular Jacobian, unreachable target)."""


class SimulationError(GpmeError):
    """A run diverged or produced non-finite values."""


class InertiaWarning(UserWarning):
    """A body's inertia is accepted but not physical (its principal moments break the
    triangle inequality I1 + I2 >= I3); the message names the link and the moments."""


class SectionWarning(UserWarning):
    """A beam's section constants are legal but suspicious (e.g. a circle's torsion constant
    J = I_y + I_z on a section with I_y != I_z); the message gives the values."""


class UnstableStepError(SimulationError):
    """A fixed step is above the stability limit of the model's stiffest mode (the message
    names the mode, the limit and a stable step)."""


class OutputWriteError(GpmeError, OSError):
    """An output file could not be written (disk full, read-only file system, a folder
    removed mid-run, no permission).  The message names the file, the system's reason and
    the space left where it was written; nothing half-written is left in its place.  The
    command line ends with status 74 (EX_IOERR, docs/ci.md)."""

    def __init__(self, path, cause: OSError):
        self.path = path
        self.cause = cause
        super().__init__(cause.errno, f"cannot write {path}: {cause.strerror or cause}"
                                      f"{_space_left(path)}")

    def __str__(self):
        return self.args[1] if len(self.args) > 1 else super().__str__()


def _space_left(path) -> str:
    """'; 12.3 kB free on /mount/dir' for the nearest existing folder of ``path`` (empty
    when it cannot be measured)."""
    folder = Path(path).absolute().parent
    while not folder.exists() and folder != folder.parent:
        folder = folder.parent
    try:
        free = shutil.disk_usage(folder).free
    except OSError:
        return ""
    for unit, scale in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if free >= scale:
            return f"; {free / scale:.3g} {unit} free in {folder}"
    return f"; {free} bytes free in {folder}"
