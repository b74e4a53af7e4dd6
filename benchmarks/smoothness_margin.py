"""False-alarm margin of the smoothness check (gpme_core.smoothness) on the repository's
model files: each one that has a SymPy constraint or programme is run as `gpme simulate
--quick` runs it (its own step, quick t_end), and for every expression the largest kink
measure and the smallest relative distance |w| / scale to a singular set are printed with
their margins to the gates (KINK_TOL / kink, distance / REACH_TOL).

    python -m benchmarks.smoothness_margin [FILE ...]   (default: models/*.toml,
                                                         models/zoo/*.toml, examples/*/*.toml)
"""
import argparse
import math
import sys
from pathlib import Path

import numpy as np
import sympy as sp

from gpme_io.runs import simulate_scenario
from gpme_core.constraints import SympyPointConstraint
from gpme_core.expression_checks import evaluate_along, singular_parts, term_scale
from gpme_core.smoothness import KINK_TOL, REACH_TOL, check_run
from gpme_core.time_functions import SympyTimeFunction
from gpme_io.modelfile import load_model_file

ROOT = Path(__file__).resolve().parents[1]
DEFAULT = ("models/*.toml", "models/zoo/*.toml", "examples/*/*.toml")


def _expressions(system):
    """(symbols, expr, (k, d) sample columns of df) of each checked expression."""
    for spec in system.constraint_specs:
        if isinstance(spec, SympyPointConstraint):
            yield spec.symbols, spec.expr, [f"{a}_{spec.frame}" for a in "xyz"] + ["t"]
        fn = getattr(spec, "function", None)
        if isinstance(fn, SympyTimeFunction):
            yield (fn.t_symbol,), fn.expr, ["t"]


def closest_singular_distance(system, df) -> float:
    """Smallest |w| / scale over the run and every singular part of every expression (inf
    when no expression has one)."""
    smallest = math.inf
    for symbols, expr, columns in _expressions(system):
        args = [df[c].to_numpy(dtype=float) for c in columns]
        for _, w in singular_parts(expr):
            f = sp.lambdify(tuple(symbols), [w, term_scale(w)], "numpy")
            values = evaluate_along(f, args, 2)
            with np.errstate(invalid="ignore", divide="ignore"):
                smallest = min(smallest, float(np.nanmin(np.abs(values[:, 0]) / values[:, 1])))
    return smallest


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("files", nargs="*")
    args = parser.parse_args(argv)
    files = [Path(f) for f in args.files] or sorted(p for g in DEFAULT for p in ROOT.glob(g))
    worst_kink, closest = 0.0, math.inf
    for path in files:
        scenario = load_model_file(path)
        if not any(True for _ in _expressions(scenario.system)):
            print(f"{path.relative_to(ROOT) if path.is_absolute() else path}: no SymPy "
                  "expression", flush=True)
            continue
        df = simulate_scenario(scenario, quick=True)
        checks = check_run(scenario.system, df)
        distance = closest_singular_distance(scenario.system, df)
        closest = min(closest, distance)
        for c in checks:
            worst_kink = max(worst_kink, c.kink)
            print(f"{path.name}: {c.who}: {c.expression}: kink {c.kink:.3g} at "
                  f"t = {c.kink_t:.4f} s, {'smooth' if c.smooth else 'NOT SMOOTH'}",
                  flush=True)
        print(f"{path.name}: closest singular set |w|/scale = {distance:.3g}", flush=True)
    print(f"largest kink measure {worst_kink:.3g}: margin {KINK_TOL / max(worst_kink, 1e-300):.3g}"
          f" to KINK_TOL = {KINK_TOL:g}; closest singular set {closest:.3g}: margin "
          f"{closest / REACH_TOL:.3g} to REACH_TOL = {REACH_TOL:g}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
