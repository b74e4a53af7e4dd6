"""MuJoCo's cable as a second continuum model: the tables of docs/rfem-continuum.md, "MuJoCo's cable".

    python -m benchmarks.mujoco_cable [--t-end 20] [--ns 1,2,3,5,10,20] [--max-elements 64]

1. Statics, MuJoCo's side alone (crosscheck.continuum.mujoco_cable.static_cantilever):
   tip deflection under a tip force against F L^3/(3 E I) and the last edge's twist
   under a tip torque against T (L - l/2)/(G J), N = 4 .. 64, observed orders.
2. The spin-up beam (gpme_examples.spin_up): the cable's mesh study (elements doubled from
   8, step ~ 1/N at RK4's stability limit, until the tip deflection changes by less than
   MESH_FRACTION of its peak or the budget) and a step halving at the finest mesh but one;
   then the finest cable against Exudyn's geometrically exact beam (the documented
   reference: physical rod, 64 elements, dt 1.25e-3 s) and against RFEM at each n, and
   the cable at each N against Exudyn.  Largest difference over the run, relative to the
   reference's peak, observed orders between successive n or N.
Takes about 10 minutes on two cores (the 64-element cable about 4 of them).
"""
import argparse
import time

import numpy as np
import pandas as pd

from crosscheck.continuum.mujoco_cable import cable_model, programmed_run, static_cantilever
from crosscheck.continuum.runs import continuum_run
from crosscheck.continuum.study import max_difference, rfem_history
from gpme_examples.spin_up import SpinUpAngle, beam_properties, spin_up_system

QUANTITIES = ("defl_y_beam", "rot_z_beam", "defl_x_beam", "lambda_hub_angle")
# the cable's mesh is refined until the tip deflection changes by less than this fraction of
# its peak: RFEM is judged at 1 % and 0.1 % in docs/rfem-continuum.md, a reference must be
# finer than the finer of these
MESH_FRACTION = 1e-3
OUTPUT_DT = 0.1                 # s
STEP_AT_8 = 1e-3                # s: RK4 at 8 elements; the step scales as 1/N (measured
                                # stable at 8, 16, 32, 64 elements; the twist and bending
                                # modes' frequencies grow as N and N^2, the twist governs)
EXUDYN_ELEMENTS, EXUDYN_DT = 64, 1.25e-3


def _peak(df, col):
    return float(np.nanmax(np.abs(df[col].to_numpy())))


def _order(e_coarse, e_fine, n_coarse, n_fine):
    if e_coarse > 0 and e_fine > 0:
        return float(np.log(e_coarse / e_fine) / np.log(n_fine / n_coarse))
    return float("nan")


def statics_table(ns=(4, 8, 16, 32, 64)) -> pd.DataFrame:
    beam = beam_properties()
    ei = beam.youngs_modulus * beam.second_moment_z
    gj = beam.shear_modulus * beam.torsion_constant
    # N: linear regime ((w/L)^2 ~ 6e-10); N m: torsion is linear, sized above the
    # relaxation's round-off floor (tests/test_mujoco_cable.py)
    force, torque = 0.01, 1.0
    rows, last = [], None
    for n in ns:
        bend = static_cantilever(beam, n, tip_force=force)
        twist = static_cantilever(beam, n, tip_torque=torque)
        e_bend = bend.deflection / (force * beam.length ** 3 / (3 * ei)) - 1.0
        e_twist = twist.twist / (torque * twist.twist_station / gj) - 1.0
        rows.append(dict(N=n, bending_rel_error=e_bend,
                         trapezoid_prediction=1.0 / (2 * n * n),
                         order=_order(last[1], e_bend, last[0], n) if last else np.nan,
                         twist_rel_error=e_twist))
        last = (n, e_bend)
    return pd.DataFrame(rows)


def cable_run(n, dt, t_end):
    cable = cable_model(beam_properties(), n, timestep=dt)
    return programmed_run(cable, SpinUpAngle().reference_derivatives, t_end, OUTPUT_DT)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--t-end", type=float, default=20.0)
    parser.add_argument("--ns", default="1,2,3,5,10,20")
    parser.add_argument("--max-elements", type=int, default=64)
    args = parser.parse_args(argv)
    start = time.perf_counter()
    fmt = lambda v: f"{v:.4g}"
    with pd.option_context("display.width", 200):
        print("Statics (MuJoCo alone): relative error against the closed forms")
        print(statics_table().to_string(index=False, float_format=fmt))

        print("\nSpin-up: the cable's mesh study")
        cables, n, mesh_rows = {}, 8, []
        while True:
            dt = STEP_AT_8 * 8 / n
            cables[n] = cable_run(n, dt, args.t_end)
            a = cables[n].attrs
            row = dict(N=n, dt=dt, wall_s=a["wall_time_s"], max_edge_strain=a["max_edge_strain"],
                       hub_residual=a["max_hub_residual"])
            if n // 2 in cables:
                for c in QUANTITIES:
                    row[f"change_{c}"] = max_difference(cables[n], cables[n // 2], c)
            mesh_rows.append(row)
            print(f"  {n} elements, dt = {dt:g} s: {a['wall_time_s']:.0f} s", flush=True)
            done = n // 2 in cables and row["change_defl_y_beam"] < \
                MESH_FRACTION * _peak(cables[n], "defl_y_beam")
            if done or 2 * n > args.max_elements:
                break
            n *= 2
        finest = n
        print(pd.DataFrame(mesh_rows).to_string(index=False, float_format=fmt))
        step_n = max(8, finest // 2)
        halved = cable_run(step_n, STEP_AT_8 * 8 / step_n / 2, args.t_end)
        print(f"step halving at {step_n} elements (dt {STEP_AT_8 * 8 / step_n:g} -> "
              f"{STEP_AT_8 * 4 / step_n:g} s): " +
              ", ".join(f"{c} {max_difference(halved, cables[step_n], c):.3g}"
                        for c in QUANTITIES))
        print("peaks:", {c: f"{_peak(cables[finest], c):.4g}" for c in QUANTITIES})

        system, q0, v0 = spin_up_system(1)
        exu = continuum_run(system.model, q0, v0, args.t_end, EXUDYN_DT, OUTPUT_DT,
                            system.constraint_specs, elements=EXUDYN_ELEMENTS)
        print(f"\nExudyn continuum ({EXUDYN_ELEMENTS} elements, dt {EXUDYN_DT:g} s, physical "
              f"rod): {exu.attrs['wall_time_s']:.0f} s")
        rows, last = [], {}
        for n_c, df in cables.items():
            row = {"N": n_c}
            for c in QUANTITIES:
                e = max_difference(df, exu, c)
                row[c] = e
                row[f"rel_{c}"] = e / _peak(exu, c)
                row[f"order_{c}"] = _order(last[c][1], e, last[c][0], n_c) if c in last else np.nan
                last[c] = (n_c, e)
            rows.append(row)
        print("cable(N) - Exudyn: largest difference over the run (rel: of Exudyn's peak)")
        print(pd.DataFrame(rows).to_string(index=False, float_format=fmt))

        print(f"\nRFEM(n) against the cable ({finest} elements) and against Exudyn")
        rows, last = [], {}
        for n_r in [int(v) for v in args.ns.split(",")]:
            system, q0, v0 = spin_up_system(n_r)
            rf = rfem_history(system, q0, v0, args.t_end, OUTPUT_DT)
            row = {"n": n_r}
            for c in QUANTITIES:
                e = max_difference(rf, cables[finest], c)
                row[f"cable_{c}"] = e
                row[f"rel_{c}"] = e / _peak(cables[finest], c)
                row[f"order_{c}"] = _order(last[c][1], e, last[c][0], n_r) if c in last else np.nan
                row[f"exudyn_{c}"] = max_difference(rf, exu, c)
                last[c] = (n_r, e)
            rows.append(row)
        table = pd.DataFrame(rows)
        for c in QUANTITIES:
            print(table[["n", f"cable_{c}", f"rel_{c}", f"order_{c}", f"exudyn_{c}"]]
                  .to_string(index=False, float_format=fmt))
        print(f"\ncable({finest}) - Exudyn: " +
              ", ".join(f"{c} {max_difference(cables[finest], exu, c):.3g}" for c in QUANTITIES))
        late = exu[exu["t"] >= 16.0]
        late_c = cables[finest][cables[finest]["t"] >= 16.0]
        print(f"mean defl_x over 16-20 s: Exudyn {late['defl_x_beam'].mean():.4g} m, cable "
              f"{late_c['defl_x_beam'].mean():.4g} m")
    print(f"\n{time.perf_counter() - start:.0f} s")


if __name__ == "__main__":
    main()
