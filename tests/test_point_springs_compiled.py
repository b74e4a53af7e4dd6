"""Point springs in the compiled kernels (gpme_core.kernels._point_springs) against the
numpy path (tests/test_point_springs.py checks the numpy path against calculus and the
engines)."""
import numpy as np
import pytest

from gpme_core import fast
from test_point_springs import SPRINGS, _with_springs

pytestmark = pytest.mark.skipif(not fast.ENABLED, reason="GPME_NO_JIT=1: no compiled path")


def test_compiled_evaluation_and_run_equal_the_python_path(rng):
    """The compiled kernels' point springs (gpme_core.kernels._point_springs) against the
    numpy path: the evaluation at random states (with a constraint, and the paper-eq7
    damping form that counts the dampers twice), and a whole RK4 run."""
    from gpme_core import compiled
    from gpme_core.gpme import ProgrammedMotion
    from gpme_core.integrate import simulate
    from gpme_core.pair_constraints import Distance
    model = _with_springs(*SPRINGS)
    for form in ("lagrange", "paper-eq7"):
        system = ProgrammedMotion(model, [Distance("E", "F", 0.3)], damping_form=form)
        cs, why = compiled.for_system(system)
        assert cs is not None, why
        for _ in range(3):
            q, q_dot = rng.uniform(-1, 1, 7), rng.uniform(-1, 1, 7)
            part = system.with_pivoted_dependent(0.0, q, q_dot)
            status, q_ddot, lam, _ = cs.evaluate(0.0, q, q_dot, part.ic, part.dc)
            assert status == 0
            ref = part.solve(0.0, q, q_dot)
            np.testing.assert_allclose(q_ddot, ref.q_ddot, rtol=0,
                                       atol=1e-10 * np.abs(ref.q_ddot).max())
    free = ProgrammedMotion(model)
    q0, qd0 = np.linspace(-0.5, 0.5, 7), np.linspace(1.0, -1.0, 7)
    runs = [simulate(free, 0.2, q0, qd0, dt=1e-3, output_dt=0.02, compiled=c)
            for c in (True, False)]
    assert runs[0].attrs["compiled"] and not runs[1].attrs["compiled"]
    names = list(model.coordinate_names)
    np.testing.assert_allclose(runs[0][names].to_numpy(), runs[1][names].to_numpy(),
                               rtol=0, atol=1e-10)
    # the dissipated power is the dampers' (joint and spring): the energy balance closes
    np.testing.assert_allclose(runs[0]["W_dissipated"].to_numpy(),
                               runs[1]["W_dissipated"].to_numpy(), rtol=1e-10, atol=1e-12)
