"""RFEM against the continuum on the spin-up beam: the convergence table of docs/rfem-continuum.md.

    python -m benchmarks.rfem_continuum [--t-end 20] [--ns 1,2,3,5,10,20]

The spin-up of Kane, Ryan & Banerjee (gpme_examples.spin_up: hub angle programmed, 10 m
beam, no gravity).  The continuum reference (Exudyn's geometrically exact beam with the
section's own axial and shear stiffness, crosscheck.continuum) is refined, mesh then step,
until the compared quantities change by less than 1e-4 of their peak (or the budget:
64 elements, dt 1.25e-3 s); then RFEM at each n runs with gpme's RK4 (stability step).
Prints the reference's mesh/step study and, per n and quantity, the largest difference
over the run, relative to the reference's peak, and the observed order between
successive n.  Takes about 4 minutes on two cores.
"""
import argparse
import time

import pandas as pd

from crosscheck.continuum.study import continuum_reference, convergence_table
from gpme_examples.spin_up import spin_up_system

QUANTITIES = ("defl_y_beam", "rot_z_beam", "defl_x_beam", "lambda_hub_angle")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--t-end", type=float, default=20.0)
    parser.add_argument("--ns", default="1,2,3,5,10,20")
    args = parser.parse_args(argv)
    ns = [int(v) for v in args.ns.split(",")]
    start = time.perf_counter()
    system, q0, v0 = spin_up_system(1)
    ref = continuum_reference(system.model, q0, v0, args.t_end, 0.1, system.constraint_specs,
                              QUANTITIES, elements=8, dt=0.01, max_elements=64,
                              min_dt=1.25e-3, log=print)
    print(f"\nreference: {ref.elements} elements, dt = {ref.dt:g} s")
    print("last mesh change:", {c: f"{v:.3g}" for c, v in ref.mesh_change.items()})
    print("last step change:", {c: f"{v:.3g}" for c, v in ref.step_change.items()})
    print("peaks:", {c: f"{float(abs(ref.frame[c]).max()):.4g}" for c in QUANTITIES})
    table = convergence_table(spin_up_system, ref, QUANTITIES, args.t_end, 0.1, ns=ns)
    with pd.option_context("display.width", 160):
        print(table.to_string(index=False, float_format=lambda v: f"{v:.4g}"))
    print(f"\n{time.perf_counter() - start:.0f} s")


if __name__ == "__main__":
    main()
