"""Short compiled runs of the examples, run by faults.run inside a copy of the sources.

    python -m faults.probe OUT.npz [--crane] [--model FILE ...] [--t-end S]

For the crane (rigid and 3-segment flexible, gpme_io.scenario.crane_scenario; the flexible
one also free, without its constraints) and each model file, integrates the first
``--t-end`` seconds from the scenario's initial state with its
own integrator and step (gpme_io.runs.simulate_scenario) and saves, per scenario, the columns
the compiled loop integrates: every coordinate, its velocity and the three work integrals
(W_dissipated, W_drive, W_reaction).  A planted fault that changes these has changed what
the compiled loops compute, whatever the numpy reference does.

OUT.json beside OUT.npz names the files the packages were imported from (faults.run checks
that they are the copy's, not the installed work tree's), whether each run was compiled
(df.attrs["compiled"]) and which kernels module evaluated it.
"""
import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

PROBE_T_END = 0.1          # s: thousands of RK4 steps, a few seconds once compiled
WORK_COLUMNS = ("W_dissipated", "W_drive", "W_reaction")


def _scenarios(crane, model_files):
    """[(key, Scenario)]: "crane n_rfe=0", "crane n_rfe=3", "crane n_rfe=3 free" (the arm
    held in the slider's stroke, no constraints: the free serial-chain solve, which the
    programmed runs do not take), then each model file's path."""
    from crosscheck.mujoco.cases import free_variant
    from gpme_io.modelfile import load_model_file
    from gpme_io.scenario import crane_scenario
    out = [(f"crane n_rfe={n}", crane_scenario(n)) for n in (0, 3)] if crane else []
    if crane:
        out.append(("crane n_rfe=3 free", free_variant(crane_scenario(3))))
    return out + [(str(p), load_model_file(Path(p))) for p in model_files]


def _kernels_module(scenario):
    from gpme_core.compiled import for_system
    compiled, reason = for_system(scenario.system)
    if compiled is None:
        return None, reason
    return compiled.module.__name__, getattr(compiled.module, "__file__", "")


def main(argv=None):
    parser = argparse.ArgumentParser(prog="python -m faults.probe", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("out", type=Path, help="OUT.npz (OUT.json beside it)")
    parser.add_argument("--crane", action="store_true", help="the crane, rigid and flexible")
    parser.add_argument("--model", action="append", default=[], help="a model file")
    parser.add_argument("--t-end", type=float, default=PROBE_T_END, help="s of each run")
    args = parser.parse_args(argv)
    import crosscheck
    import gpme
    import gpme_core
    import gpme_io
    from gpme_io.runs import simulate_scenario
    record = {"imported": {m.__name__: m.__file__ for m in (gpme_core, gpme, gpme_io,
                                                            crosscheck)},
              "sys_path0": sys.path[0], "runs": {}}
    arrays = {}
    for key, scenario in _scenarios(args.crane, args.model):
        start = time.perf_counter()
        df = simulate_scenario(scenario, t_end=min(args.t_end, scenario.t_run(True)))
        names = [*scenario.model.coordinate_names,
                 *(f"{c}_dot" for c in scenario.model.coordinate_names), *WORK_COLUMNS]
        arrays[key] = df[names].to_numpy(dtype=float)
        record["runs"][key] = {
            "columns": names, "compiled": bool(df.attrs.get("compiled")),
            "compiled_reason": df.attrs.get("compiled_reason", ""), "model": scenario.name,
            "kernels": _kernels_module(scenario), "method": df.attrs.get("method"),
            "dt": df.attrs.get("dt"), "rows": len(df),
            "wall_s": round(time.perf_counter() - start, 2)}
    np.savez(args.out, **arrays)
    args.out.with_suffix(".json").write_text(json.dumps(record, indent=1), encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
