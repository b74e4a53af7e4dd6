"""The `gpme sweep` options on an argparse parser.

Its own module, importing nothing: the `gpme` command line builds its parser, this
sweep's options included, for every command, while gpme_study.command, which runs the
sweep, loads the engine, SymPy, SciPy and pandas and is imported only by `gpme sweep`.
"""


def add_arguments(parser):
    """The `gpme sweep` options on an argparse (sub)parser."""
    parser.add_argument("--config", metavar="FILE",
                        help="TOML or YAML sweep file (docs/sweep.md); options below override it")
    parser.add_argument("--model", default=None, metavar="FILE",
                        help="sweep this model file (docs/models.md) instead of the built-in "
                             "crane; --param PATH=VALUES with dotted paths into it, e.g. "
                             "joint.shoulder.stiffness=10:40:4")
    parser.add_argument("--mode", choices=("grid", "list", "lhs"), default=None,
                        help="grid (default), list (with --point) or lhs (Latin hypercube)")
    parser.add_argument("--param", action="append", default=[], metavar="NAME=VALUES",
                        help="grid: A=0.2,0.3,0.4 or A=0.2:0.6:5 (start:stop:num); "
                             "lhs: A=0.2:0.6 (low:high); repeat per parameter")
    parser.add_argument("--point", action="append", nargs="+", default=[],
                        metavar="NAME=VALUE", help="one point of a list sweep, e.g. "
                                                   "--point A=0.3 T=2; repeat per point")
    parser.add_argument("--samples", type=int, default=None, help="lhs: number of points")
    parser.add_argument("--seed", type=int, default=None, help="lhs: seed (default 0)")
    parser.add_argument("--t-end", type=float, default=None, help="s, each run (default 6)")
    parser.add_argument("--n-rfe", type=int, default=None,
                        help="RFEM segments when n_rfe is not swept (default 1; 0 = rigid)")
    parser.add_argument("--transient", type=float, default=None,
                        help="s, start of the |Phi| and spectrum window (default 1)")
    parser.add_argument("--output-dt", type=float, default=None,
                        help="s, recorded row spacing (default 2e-3)")
    parser.add_argument("--dt", type=float, default=None,
                        help="s, RK4 step (default: per point from gpme_core.stability.rk4_step)")
    parser.add_argument("--min-frequency", type=float, default=None,
                        help="Hz, lower edge of the vibration band (default 2)")
    parser.add_argument("--phi-tolerance", type=float, default=None,
                        help="largest |Phi| after the transient counted as met (default 1e-3)")
    parser.add_argument("--on-constraints", action="store_true", default=None,
                        help="with --model: start every point on its constraints "
                             "([initial] on_constraints = true)")
    parser.add_argument("--limit", action="append", default=[], metavar="METRIC=MAX",
                        help="safe-region bound, e.g. vib_peak_m=1e-4 drive_psi3_peak_Nm=6")
    parser.add_argument("--plot-x", default=None, help="heat-map x parameter")
    parser.add_argument("--plot-y", default=None, help="heat-map y parameter")
    parser.add_argument("--out", default="reports/sweep",
                        help="output directory; a rerun with the same --out resumes")
    parser.add_argument("--scheduler", default=None, metavar="ADDRESS",
                        help="existing Dask scheduler, e.g. tcp://10.0.0.5:8786 "
                             "(default: a local cluster)")
    parser.add_argument("--workers", type=int, default=None,
                        help="local cluster worker processes (default: one per core)")
    parser.add_argument("--in-process", action="store_true",
                        help="run the points one after another in this process, without Dask "
                             "(tiny sweeps, debugging)")
    parser.add_argument("--retry-errors", action="store_true",
                        help="recompute stored points whose status is 'error'")
    parser.add_argument("--force", action="store_true",
                        help="run even when the estimate is above the limits (2 h wall "
                             "time, 2 GB written, 2 GB of history per run in memory)")
    parser.add_argument("--quiet", action="store_true", help="no progress lines")
    return parser
