"""Engines that do not take a non-physical inertia as written.

gpme, Pinocchio and Exudyn accept a link inertia whose principal moments break the triangle
inequality I1 + I2 >= I3 (robot descriptions carry such CAD round-off; gpme says so in an
information row, crosscheck.run_checks.inertia_rows).  Two engines do not compute with it
as written, so a comparison with them would compare two different bodies; for such a model
their steps give one information row each that says why, instead of failed checks that
are not about gpme:

- MuJoCo's compiler refuses the model ("inertia must satisfy A + B >= C"); its option
  ``balanceinertia`` would replace the three moments by their mean, a different body.
- Drake's URDF parser warns that the inertia "did not pass the test
  CouldBePhysicallyValid()" and then computes with another one: on
  tests/data/non_physical/cad_arm.toml its mass matrix differed from Pinocchio's and
  gpme's by 6.6 % (measured: `gpme verify --quick --model` of that file before this gate).
"""
from typing import Optional

import numpy as np

from .compare import Tolerance, compare

NOT_TAKEN = {
    "mujoco": "MuJoCo's compiler refuses an inertia whose principal moments break A + B >= C "
              "(its option balanceinertia would replace them by their mean: another body)",
    "drake": "Drake's URDF parser does not take an inertia that fails "
             "CouldBePhysicallyValid() as written (it warns and computes with another body)",
}
QUANTITY = "not compared: non-physical inertia"


def refusal(engine: str, scenario) -> Optional[str]:
    """Why ``engine`` cannot compare ``scenario`` (a gpme_io.scenario.Scenario), or None:
    the engine does not take its non-physical inertias as written."""
    lines = scenario.model.non_physical_inertias()
    if engine not in NOT_TAKEN or not lines:
        return None
    links = [line.split(":", 1)[0] for line in lines]
    verb = "breaks" if len(links) == 1 else "break"
    return f"{NOT_TAKEN[engine]}; {', '.join(links)} of this model {verb} I1 + I2 >= I3"


def refusal_row(engine: str, scenario, reason: str) -> dict:
    """The one information row of ``engine`` for ``scenario`` (crosscheck.compare's row)."""
    return compare(engine, scenario.name, QUANTITY, "-", [0.0], [0.0],
                   Tolerance(np.inf, 0.0, f"information: {reason}"), ["-"])
