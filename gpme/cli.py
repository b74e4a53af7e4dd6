"""`gpme` command line: simulate the paper's crane, crosscheck against Pinocchio/MuJoCo,
verify everything.  Run `gpme --help`."""
import argparse
import sys
import time
from pathlib import Path


def _simulate(args):
    from gpme_examples import paper
    from gpme_core.errors import GpmeError
    cases = ["rigid", "flexible"] if args.case == "both" else [args.case]
    runs = {}
    for case in cases:
        label = case if case == "rigid" else f"flexible (n_rfe={args.n_rfe})"
        print(f"simulating {label}, t_end = {args.t_end} s ...", flush=True)
        try:
            runs[case] = paper.run_case(case, n_rfe=args.n_rfe, t_end=args.t_end, dt=args.dt,
                                        method=args.method, on_manifold=args.on_manifold,
                                        static_arm=args.static_arm,
                                        progress=not args.no_progress)
        except GpmeError as exc:
            print(f"error: {exc}", file=sys.stderr)
            return 2
        s = paper.summary(runs[case], transient=min(2.0, 0.5 * args.t_end))
        print(f"  wall time {s['wall_time_s']:.1f} s; max |Phi_1| = "
              f"{s['max_abs_Phi_1_after_transient']:.2e}, max |Phi_2| = "
              f"{s['max_abs_Phi_2_after_transient']:.2e} after the transient")
    paths = paper.write_outputs(runs, args.out)
    for p in paths.values():
        print(f"wrote {p}")
    return 0


def _crosscheck(args):
    if args.engine == "pinocchio":
        from crosscheck.pinocchio import check as check
    else:
        from crosscheck.mujoco import check
    out = Path(args.out) if args.out else Path("reports") / time.strftime(f"{args.engine}-%Y%m%d-%H%M%S")
    df = check.run(out, quick=args.quick, progress=not args.no_progress)
    failed = df[~df["passed"].astype(bool)]
    print(f"{len(df)} comparisons, {len(failed)} failed; report in {out}")
    if len(failed):
        print(failed[["model", "quantity", "case", "entry", "abs_error", "rel_error"]]
              .head(20).to_string(index=False))
    return 1 if len(failed) else 0


def _verify(args):
    from crosscheck import verify
    return verify.main(args)


def _sweep(args):
    from gpme_study import command
    return command.main(args)


def build_parser():
    parser = argparse.ArgumentParser(prog="gpme", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    sim = sub.add_parser("simulate", help="run the paper's crane and write CSV + figures")
    sim.add_argument("--case", choices=("rigid", "flexible", "both"), default="both")
    sim.add_argument("--n-rfe", type=int, default=3, help="RFEM segments of the flexible arm")
    sim.add_argument("--t-end", type=float, default=10.0, help="s")
    sim.add_argument("--dt", type=float, default=None,
                     help="RK4 step in s (default: 1e-4 rigid, 5e-5 flexible)")
    sim.add_argument("--method", choices=("RK4", "RK45", "DOP853", "Radau"), default="RK4")
    sim.add_argument("--on-manifold", action="store_true",
                     help="start on the constraints instead of the paper's off-manifold start")
    sim.add_argument("--static-arm", action="store_true",
                     help="start the flexible arm in its gravity sag (default: straight)")
    sim.add_argument("--out", default="reports/simulate", help="output directory")
    sim.add_argument("--no-progress", action="store_true")
    sim.set_defaults(func=_simulate)
    cc = sub.add_parser("crosscheck", help="compare gpme with Pinocchio or MuJoCo")
    cc.add_argument("engine", choices=("pinocchio", "mujoco"))
    cc.add_argument("--quick", action="store_true", help="CI-sized run")
    cc.add_argument("--out", default=None, help="report directory (default reports/<engine>-<time>)")
    cc.add_argument("--no-progress", action="store_true")
    cc.set_defaults(func=_crosscheck)
    ver = sub.add_parser("verify", help="the whole verification with HTML/CSV reports")
    ver.add_argument("--quick", action="store_true", help="CI-sized run")
    ver.add_argument("--only", choices=("paper", "pinocchio", "mujoco"), default=None)
    ver.add_argument("--out", default="reports", help="reports root directory")
    ver.add_argument("--no-progress", action="store_true")
    ver.set_defaults(func=_verify)
    from gpme_study.command import add_arguments as add_sweep_arguments
    sw = sub.add_parser("sweep", help="parameter sweep of the crane on a Dask cluster: table, "
                                      "heat maps, safe region (docs/sweep.md)")
    add_sweep_arguments(sw)
    sw.set_defaults(func=_sweep)
    return parser


def main(argv=None):
    args = build_parser().parse_args(argv)
    return args.func(args)


if __name__ == "__main__":
    sys.exit(main())
