"""Exception types raised by gpme_core.

Every error raised for user input names the offending value and what would be valid.
"""


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


class SectionWarning(UserWarning):
    """A beam's section constants are legal but suspicious (e.g. a circle's torsion constant
    J = I_y + I_z on a section with I_y != I_z); the message gives the values."""


class UnstableStepError(SimulationError):
    """A fixed step is above the stability limit of the model's stiffest mode (the message
    names the mode, the limit and a stable step)."""
