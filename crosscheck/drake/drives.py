"""The drive forces t(t) of a gpme model as Drake systems, in Drake's own C++ where it has
the function, for the applied generalized force input port of the plant.

* ``QuinticRamp(level, ramp_time)`` (paper eq. 9): the polynomial level (10 s^3 - 15 s^4 +
  6 s^5), s = t / ramp_time, written here in t (coefficients 10 L / T^3, -15 L / T^4, 6 L /
  T^5 of t^3, t^4, t^5) as a one-piece ``PiecewisePolynomial`` on [0, ramp_time] in a
  ``TrajectorySource``.  Drake evaluates a piecewise polynomial at t clamped to its breaks,
  so it is 0 before the ramp and ``level`` after it: the ramp's own definition.
* ``Constant(level)``: a ``ConstantVectorSource``.

The drives' scalars are stacked (``Multiplexer``) and put in Drake's velocity order by a
``MatrixGain`` B (nv x drives; B[v, k] = 1 where drive k acts on the joint at velocity
index v; two drives of one joint add, as in the gpme model).  A model with any other time
function (cosine, sine, tabulated, SymPy) keeps :class:`PythonDrives`, a LeafSystem whose
output calls the model's drive_forces(t) at every evaluation.

Why: that Python call cost ~6 us of Drake's ~20 us per derivative evaluation of the
flexible crane (measured, cProfile and wall), at 7 evaluations per runge_kutta5 step.
The values agree with the model's to round-off (tests/test_drake.py).
"""
from typing import Optional

import numpy as np
from pydrake.polynomial import Polynomial
from pydrake.systems.framework import LeafSystem
from pydrake.systems.primitives import (ConstantVectorSource, MatrixGain, Multiplexer,
                                        TrajectorySource)
from pydrake.trajectories import PiecewisePolynomial

from gpme_core.time_functions import Constant, QuinticRamp


class PythonDrives(LeafSystem):
    """Output: the gpme model's drive forces t(t) (N, N m) in Drake's velocity order,
    from the model's own drive_forces (any time function)."""

    def __init__(self, model, ds):
        super().__init__()
        self._model, self._ds = model, ds
        self.DeclareVectorOutputPort("drives", ds.plant.num_velocities(), self._calc)

    def _calc(self, context, output):
        output.SetFromVector(self._ds.to_drake(self._model.drive_forces(context.get_time())))


def quintic_ramp_trajectory(ramp: QuinticRamp) -> PiecewisePolynomial:
    """The ramp as a 1 x 1 Drake PiecewisePolynomial on [0, ramp_time] (held outside)."""
    level, duration = float(ramp.level), float(ramp.ramp_time)
    coefficients = [0.0, 0.0, 0.0, 10.0 * level / duration ** 3,
                    -15.0 * level / duration ** 4, 6.0 * level / duration ** 5]
    return PiecewisePolynomial([np.array([[Polynomial(coefficients)]])], [0.0, duration])


def _native_source(function):
    """A Drake source system of the scalar ``function``, or None when Drake has none here."""
    if type(function) is QuinticRamp:
        return TrajectorySource(quintic_ramp_trajectory(function))
    if type(function) is Constant:
        return ConstantVectorSource([float(function.level)])
    return None


def drive_output(builder, model, ds) -> Optional[object]:
    """The output port (nv,) of the drive forces of ``model`` added to ``builder`` (Drake's
    systems where every drive's function has one, else :class:`PythonDrives`); None when
    the model has no drives."""
    if not model.drives:
        return None
    sources = [_native_source(d.function) for d in model.drives]
    if any(s is None for s in sources):
        return builder.AddSystem(PythonDrives(model, ds)).get_output_port()
    selection = np.zeros((ds.plant.num_velocities(), len(sources)))
    for k, drive in enumerate(model.drives):
        selection[ds.v_index[model.index(drive.joint)], k] += 1.0
    stack = builder.AddSystem(Multiplexer(len(sources)))
    for k, source in enumerate(sources):
        builder.Connect(builder.AddSystem(source).get_output_port(), stack.get_input_port(k))
    gain = builder.AddSystem(MatrixGain(selection))
    builder.Connect(stack.get_output_port(), gain.get_input_port())
    return gain.get_output_port()
