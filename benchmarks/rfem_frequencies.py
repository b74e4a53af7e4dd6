"""RFEM against the continuum in natural frequencies along the crane's run: the table of
docs/rfem-continuum.md ("Natural frequencies along the run").

    python -m benchmarks.rfem_frequencies [--times 0,0.3125,0.625] [--count 5]
                                          [--ns 1,2,3,5,10,20] [--max-elements 256]

The paper's crane (gpme_io.scenario.crane_scenario, the model of crosscheck.crane_cases
CASES["continuum"], n = 3) runs in gpme from its start with straight beams to the last
time; at each time the stress-free configuration (crosscheck.continuum.frequencies: beams
straight, the support spring at its reference, the arm pitch and slider on the programmed
constraints at that time, loads off) is taken, the continuum's first ``count`` non-zero
frequencies are refined in the mesh (8, 16, ... elements) until they change by less than
1e-4 of themselves (or --max-elements), and RFEM's are computed at each n.  Prints markdown
tables: per configuration, per n and mode, the RFEM frequency, its relative error against
the continuum, the observed order between successive n; then from which n each frequency is
within 1 % and 0.1 %.  About 2 minutes on two cores.
"""
import argparse
import time

import numpy as np

from crosscheck.continuum import frequencies as fq
from gpme_io.scenario import crane_scenario


def _cell(row) -> str:
    if not np.isfinite(row.rfem_hz):
        return "-"
    order = "" if not np.isfinite(row.order) else f", {row.order:.2f}"
    return f"{row.rfem_hz:.5g} ({100 * row.relative_error:+.3g} %{order})"


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--times", default="0,0.3125,0.625")
    parser.add_argument("--output-dt", type=float, default=1.25e-3,
                        help="s, the run's sample spacing (the times must be multiples)")
    parser.add_argument("--count", type=int, default=5)
    parser.add_argument("--ns", default="1,2,3,5,10,20")
    parser.add_argument("--max-elements", type=int, default=fq.MAX_ELEMENTS)
    args = parser.parse_args(argv)
    times = [float(v) for v in args.times.split(",")]
    ns = [int(v) for v in args.ns.split(",")]
    start = time.perf_counter()
    scenario = crane_scenario(3, on_constraints=True)
    configs = fq.configurations_along_run(scenario, times, args.output_dt, log=print)
    refs = []
    for cfg in configs:
        q = fq.state_of(cfg, scenario.system)
        refs.append(fq.continuum_reference(scenario.model, cfg.t, q, scenario.constraints,
                                           args.count, max_elements=args.max_elements,
                                           log=print))
    table = fq.convergence_table(lambda n: crane_scenario(n, on_constraints=True).system,
                                 configs, refs, ns, args.count, log=print)
    for cfg, ref in zip(configs, refs):
        joints = ", ".join(f"{k} = {v:.4g}" for k, v in cfg.joints.items())
        print(f"\n### t = {cfg.t:g} s: {joints}; {ref.zero_modes} rigid mode(s)\n")
        print(f"continuum: {ref.elements} elements (settled: {ref.settled}); last mesh change "
              + ", ".join(f"{c / f:.1e}" for c, f in zip(ref.mesh_change, ref.frequencies_hz))
              + " (relative)\n")
        g = table[table["t"] == cfg.t]
        finest = g[g["n"] == max(ns)].sort_values("mode")
        print("| n | " + " | ".join(f"mode {m} ({lab.split()[0] if lab else '?'})"
                                     for m, lab in zip(finest["mode"], finest["label"])) + " |")
        print("|---" * (1 + args.count) + "|")
        print("| continuum | " + " | ".join(f"{f:.5g} Hz" for f in ref.frequencies_hz) + " |")
        others = []
        for n in ns:
            rows = g[g["n"] == n].sort_values("mode")
            labels = "; ".join(f"mode {r.mode} is {r.label}" for r in rows.itertuples()
                               if r.label and finest[finest["mode"] == r.mode]["label"].iloc[0]
                               .split()[0] != r.label.split()[0])
            print(f"| {n} | " + " | ".join(_cell(r) for r in rows.itertuples()) + " |")
            if labels:
                others.append(f"n = {n}: {labels}")
        if others:
            print("\nRFEM modes of another kind than at the finest n (compared by index): "
                  + "; ".join(others))
    reached = fq.accuracy_reached(table)
    print("\n### n from which RFEM is within 1 % and 0.1 % of the continuum\n")
    print(reached.to_string(index=False))
    print(f"\n{time.perf_counter() - start:.0f} s")


if __name__ == "__main__":
    main()
