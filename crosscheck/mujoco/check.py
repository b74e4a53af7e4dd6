"""The MuJoCo crosscheck of any scenario: `gpme crosscheck mujoco [--quick] [--out DIR]`.

Sections, per scenario (one tidy row per case x column x metric, all through
crosscheck.compare.compare; docs/crosscheck-mujoco.md):

1. terms        : M, bias, passive and drive forces at seeded states (round-off).
2. free         : the model without constraints, drive on, both engines RK4 at the same
                  dt (the crane with holding springs); gated by gpme's own RK4 error
                  (crosscheck.run_gates).
3. exact        : the programmed run realised exactly in MuJoCo (multipliers computed in
                  mjcb_control at every RK4 stage, crosscheck.mujoco.runs); gated by gpme's
                  own RK4 error, with the observed order as its own row.
4. mechanism    : only when the constraints are one EllipseConstraint and one Cosine height
                  programme (the crane): MuJoCo's soft equality constraints through the
                  auxiliary mechanism, a second, approximate realisation.  The differences
                  are information; the gated rows require them to shrink as the soft
                  constraint's tc^2 law says when timeconst and dt are halved.
4b. loops       : only when every constraint is a loop closure MuJoCo writes itself
                  (crosscheck.mujoco.loops: <connect>, <weld>): its own soft equalities,
                  gated by the same tc^2 law; otherwise one information row says why.
5. off-manifold : the rigid crane from the paper's start off the constraints, Baumgarte
                  against MuJoCo's constraint stabilisation; information only.
6. wall time    : information.
"""
import logging
import time
import zlib
from pathlib import Path

import mujoco
import numpy as np
import pandas as pd

from gpme_core.errors import GpmeError
from gpme_core.integrate import simulate
from gpme_io.animation import write_motion
from gpme_io.file_names import named_path
from gpme_io.runs import resolved_step

from .. import inertia_gate, run_gates
from ..sampling import compared_output_dt
from ..crane_cases import crane_cases
from ..compare import Tolerance, compare
from . import cases
from . import loops as mj_loops
from . import mechanism as mech
from . import runs
from .mjcf import mjcf_text
from .report import write_report
from .sim import simulate_mujoco
from .terms import ENGINE, sample_states, term_rows

INFO = "information: {}"
EXACT = "exact programmed run"
FREE = "free run"

logger = logging.getLogger("gpme.crosscheck.mujoco")


def _info(reason):
    return Tolerance(np.inf, 0.0, INFO.format(reason))


def _tag(rows, section, coordinate, metric):
    for r in rows:
        r.update(section=section, coordinate=coordinate, metric=metric)
    return rows


def _run_rows(section, scenario, refined, df, columns, label, case):
    """run_gates rows tagged with their column (the order row: 'all')."""
    rows = run_gates.run_rows(ENGINE, scenario, refined, df, columns, label, case)
    for r, c in zip(rows, list(columns) + ["all"]):
        _tag([r], section, c, "max |gpme - mujoco| over time" if c != "all"
             else "observed RK4 order (dt/2 vs dt/4)")
    return rows


def default_scenarios(quick: bool = False) -> list:
    """The paper's crane, rigid and RFEM n = 1, on the constraints (crosscheck.crane_cases)."""
    return crane_cases("mujoco", quick)


def _dt(scenario):
    """s, the scenario's RK4 step, the one gpme's own run takes (gpme_io.runs)."""
    return resolved_step(scenario)


def _state_columns(model):
    names = list(model.coordinate_names)
    return names + [f"{c}_dot" for c in names]


# ------------------------------------------------------------------ sections
def terms_section(scenario, p, log):
    model = scenario.model
    mj = runs.load(model, _dt(scenario))
    seed = cases.TERM_SEED + zlib.crc32(scenario.name.encode())
    rows = term_rows(model, mj, sample_states(model, p.term_states, seed))
    log(f"terms {scenario.name}: done")
    return _tag(rows, "terms", "all", "max |gpme - mujoco| over entries")


def free_section(scenario, p, log, plots):
    free = cases.free_variant(scenario)
    t_end, dt = p.t_end(scenario), _dt(scenario)
    case = f"{FREE}, drive on, {t_end:g} s, RK4 dt = {dt:g} s"
    try:
        refined = run_gates.refined_gpme_runs(free.system, free.q0, free.q_dot0, t_end, dt,
                                              compared_output_dt(t_end, dt))
    except GpmeError as exc:
        row = compare(ENGINE, free.name, f"{FREE}: not compared", case, [0.0], [0.0],
                      _info(f"the free motion cannot be run to {t_end:g} s: {exc}"), ["-"])
        return _tag([row], "free", "all", "not run")
    case = f"{FREE}, drive on, {t_end:g} s, RK4 dt = {refined.dt:g} s"
    mj = runs.free_run(free, t_end, refined.dt, compared_output_dt(t_end, dt))
    plots[("free", free.name)] = (free.model, refined.coarse, mj)
    log(f"free {free.name}: gpme {refined.coarse.attrs['wall_time_s']:.1f} s, mujoco "
        f"{mj.attrs['wall_time_s']:.1f} s")
    return _run_rows("free", free, refined, mj, _state_columns(free.model), FREE, case)


def exact_section(scenario, p, log, plots):
    """Rows, and the gpme RefinedRuns and start (for the mechanism section)."""
    t_end, dt = p.t_end(scenario), _dt(scenario)
    q0, qd0 = cases.on_manifold(scenario)
    spacing = compared_output_dt(t_end, dt)
    refined = run_gates.refined_gpme_runs(scenario.system, q0, qd0, t_end, dt, spacing)
    mj = runs.programmed_run(scenario, t_end, refined.dt, spacing, q0=q0, q_dot0=qd0)
    plots[("exact", scenario.name)] = (scenario.model, refined.coarse, mj)
    case = f"{EXACT}, on-manifold start, {t_end:g} s, RK4 dt = {refined.dt:g} s"
    names = list(scenario.system.constraint_names)
    columns = _state_columns(scenario.model) + names + [f"lambda_{c}" for c in names]
    log(f"exact {scenario.name}: gpme x3 {sum(r.attrs['wall_time_s'] for r in refined.runs):.1f} s, "
        f"mujoco {mj.attrs['wall_time_s']:.1f} s")
    return _run_rows("exact", scenario, refined, mj, columns, EXACT, case), refined, (q0, qd0)


def _mechanism_run(scenario, programme, dt, timeconst, t_end, q0, qd0, yoke_timeconst=None):
    model = scenario.model
    settings = mech.MechanismSettings(timeconst=timeconst, yoke_timeconst=yoke_timeconst)
    mj = mujoco.MjModel.from_xml_string(mjcf_text(model, dt, scenario.constraints, settings))
    p_e, v_e = mech.frame_motion(model, programme.frame, q0, qd0)
    aux = mech.auxiliary_state(programme, p_e, v_e, 0.0)
    return simulate_mujoco(mj, model, t_end, q0, qd0, compared_output_dt(t_end, dt),
                           programme=programme,
                           aux=aux)


def mechanism_section(scenario, programme, refined, start, p, log, plots):
    """MuJoCo's auxiliary mechanism at (dt, tc = dt) and (dt/2, tc/2) against gpme at dt/4:
    absolute differences as information, their ratio gated by MECHANISM_RATIO."""
    settings = [(refined.dt / 2 ** k, refined.dt / 2 ** k) for k in range(cases.MECHANISM_STEPS)]
    mjs = [_mechanism_run(scenario, programme, dt, tc, refined.t_end, *start)
           for dt, tc in settings]
    plots[("mechanism", scenario.name)] = (scenario.model, refined.finest, mjs[-1])
    names = list(scenario.model.coordinate_names) + list(scenario.system.constraint_names)
    rows, table = soft_rows(scenario, refined, settings, mjs, "mechanism",
                            "soft-equality mechanism", names)
    log(f"mechanism {scenario.model.name}: {len(settings)} settings")
    return rows, table


def loops_section(scenario, loops, refined, start, p, log, plots):
    """The loops closed by MuJoCo's own <connect>/<weld> equalities (crosscheck.mujoco.loops)
    at (dt, tc = dt) and (dt/2, tc/2) against gpme at dt/4, gated as the mechanism is."""
    settings = [(refined.dt / 2 ** k, refined.dt / 2 ** k) for k in range(cases.MECHANISM_STEPS)]
    spacing = compared_output_dt(refined.t_end, _dt(scenario))
    mjs = [mj_loops.loop_run(scenario, loops, dt, tc, refined.t_end, *start, spacing)
           for dt, tc in settings]
    plots[("loops", scenario.name)] = (scenario.model, refined.finest, mjs[-1])
    rows, table = soft_rows(scenario, refined, settings, mjs, "loops",
                            "MuJoCo's own loop equalities (" + mj_loops.describe(loops) + ")",
                            list(scenario.model.coordinate_names))
    log(f"loops {scenario.model.name}: {len(settings)} settings")
    return rows, table


def soft_rows(scenario, refined, settings, mjs, section, what, columns):
    """Rows of MuJoCo's soft equality constraints at ``settings`` [(dt, timeconst)] (runs
    ``mjs``) against gpme's finest run: the differences of ``columns`` as information, and
    per coordinate the ratio of the differences at tc/2 and tc gated by MECHANISM_RATIO
    (the soft constraint's tc^2 law) where the coarse difference is resolved above
    round-off; and the convergence table."""
    model, t_end = scenario.model, refined.t_end
    g = refined.finest
    names = list(model.coordinate_names)
    rows, table = [], []
    times = [f"t={t:.4g}" for t in g["t"]]
    for (dt, tc), mj in zip(settings, mjs):
        case = f"{what}, dt = timeconst = {tc:g} s, {t_end:g} s"
        entry = {"model": model.name, "dt [s]": dt, "timeconst [s]": tc}
        for c in columns:
            r = compare(ENGINE, model.name, f"{section} {c} max |difference| over time", case,
                        g[c].to_numpy(), mj[c].to_numpy(),
                        _info("MuJoCo's soft equality constraints lag by ~tc^2 (see the "
                              "convergence rows); gpme reference at dt/4"), times)
            rows += _tag([r], section, c, f"max |gpme - mujoco {section}|")
            entry[f"max |d {c}|"] = r["abs_error"]
        for c in [c for c in mj.columns if c.startswith("viol_")]:
            r = compare(ENGINE, model.name, f"{section} {c} max over time [m]", case, [0.0],
                        [np.abs(mj[c]).max()], _info("equality constraint violation (MuJoCo "
                                                     "only); its effect is the differences"),
                        ["max"])
            rows += _tag([r], section, c, "equality constraint violation")
        entry["mujoco wall s per simulated s"] = mj.attrs["wall_time_s"] / t_end
        table.append(entry)
    coarse, fine = mjs[0], mjs[-1]
    n_steps = int(round(t_end / settings[-1][0]))
    case = (f"{what}, timeconst and dt {settings[0][1]:g} -> {settings[-1][1]:g} s, "
            f"{t_end:g} s")
    state_scale = float(np.abs(g[names].to_numpy(float)).max(initial=0.0))
    for c in names:
        d_coarse = float(np.abs(coarse[c] - g[c]).max())
        d_fine = float(np.abs(fine[c] - g[c]).max())
        ratio = d_fine / d_coarse if d_coarse > 0 else np.nan
        rate = float(np.abs(g[f"{c}_dot"]).max())
        # + the cross-talk of the solve that mixes every coordinate (a random walk,
        # eps sqrt(N) max|q|, as run_gates.column_floor): a torsion the motion leaves at
        # ~1e-9 rad differs by round-off of the whole state, not of itself (measured: the
        # ratio of two ~1e-19 rad differences moved 0.26 -> 0.39 with a viscosity changed
        # by 1e-10, failing correct models)
        floor = run_gates.roundoff_floor(float(np.abs(g[c]).max()), n_steps,
                                         coupled=settings[-1][0] * rate) \
            + 2.0 * run_gates.EPS * np.sqrt(n_steps) * state_scale
        tol = cases.MECHANISM_RATIO if d_coarse > cases.MECHANISM_RESOLVED * floor else _info(
            f"the coarse difference {d_coarse:.1e} is within {cases.MECHANISM_RESOLVED:g} "
            f"round-off floors ({floor:.1e}): no convergence can be observed")
        r = compare(ENGINE, model.name, f"{section} {c} difference ratio, tc/2 over tc", case,
                    [ratio if np.isfinite(ratio) else 0.0], [0.0], tol, ["ratio"])
        rows += _tag([r], section, c, "difference ratio (fine / coarse)")
    return rows, pd.DataFrame(table)


def off_manifold_section(scenario, programme, p, log, plots):
    """From a start off the constraints: gpme's Baumgarte (alpha, beta) against MuJoCo's
    mechanism with (a) timeconst = dt and (b) timeconst = 1/alpha, whose reference
    acceleration -2/tc Phi_dot - Phi/tc^2 equals Baumgarte's.  Information only."""
    start = cases.off_manifold_start(scenario)
    if start is None or scenario.flexible_coordinates:
        return []          # the snap onto the constraints excites RFEM modes beyond RK4's reach
    model = scenario.model
    t_end, dt = p.t_end(scenario), _dt(scenario)
    alpha = scenario.system.alpha
    g = simulate(scenario.system, t_end, *start, dt=dt, output_dt=compared_output_dt(t_end, dt))
    variants = {"timeconst = dt": _mechanism_run(scenario, programme, dt, dt, t_end, *start),
                f"timeconst = 1/alpha = {1 / alpha:g} s":
                    _mechanism_run(scenario, programme, dt, 1.0 / alpha, t_end, *start,
                                   yoke_timeconst=dt)}
    plots[("off-manifold", model.name)] = (model, g, variants)
    rows = []
    dep = list(scenario.system.dependent or ())
    for label, mj in variants.items():
        case = f"off-manifold start, mujoco {label}, {t_end:g} s"
        for c in dep + list(scenario.system.constraint_names):
            r = compare(ENGINE, model.name, f"off-manifold {c} max |difference| over time", case,
                        g[c].to_numpy(), mj[c].to_numpy(),
                        _info("the engines stabilise differently (see the plots and docs)"),
                        [f"t={t:.4g}" for t in g["t"]])
            rows += _tag([r], "off-manifold", c, "max |gpme - mujoco|")
    log(f"off-manifold {model.name}: done")
    return rows


def wall_time_rows(plots):
    rows = []
    for (section, name), (model, g, mj) in plots.items():
        if not isinstance(mj, pd.DataFrame):
            continue
        t_end = float(g["t"].iloc[-1])
        r = compare(ENGINE, name, "wall time per simulated second [s/s]", section,
                    [g.attrs["wall_time_s"] / t_end], [mj.attrs["wall_time_s"] / t_end],
                    _info("wall time of one run of each engine"), ["wall"])
        rows += _tag([r], "wall time", "all", "gpme vs mujoco wall time per simulated s")
    return rows


def run(out_dir: Path, scenarios=None, quick: bool = False,
        progress: bool = False) -> pd.DataFrame:
    """Run every section for every scenario (gpme_io.scenario.Scenario; None: the crane
    rigid and n = 1 on the constraints), write its rows (crosscheck.reports.rows), plots and
    out_dir/mujoco.html atomically and return the tidy table (columns status: pass / fail / info, passed)."""
    scenarios = list(default_scenarios(quick) if scenarios is None else scenarios)
    parts = [scenario_part(out_dir, s, quick, progress) for s in scenarios]
    return finish(out_dir, parts, quick, progress=progress)


def scenario_part(out_dir: Path, s, quick: bool = False, progress: bool = False) -> dict:
    """What :func:`run` computes for one scenario ``s``: {"name": its name, "rows":
    comparison rows, "plots": {(section, name): (model, gpme run, MuJoCo run)}, "tables":
    convergence tables}, picklable, for :func:`finish` (crosscheck.step_pool runs scenarios in separate
    processes).  Writes no file."""
    p = cases.plan(quick)
    start = time.perf_counter()

    def log(msg):
        if progress:
            logger.info(f"[mujoco {time.perf_counter() - start:6.1f} s] {msg}")

    plots, rows, tables = {}, [], []
    part = {"name": s.name, "rows": rows, "plots": plots, "tables": tables}
    refused = inertia_gate.refusal(ENGINE, s)
    if refused:
        log(f"{s.name}: {refused}")
        rows += _tag([inertia_gate.refusal_row(ENGINE, s, refused)], "terms", "all",
                     "not compared")
        return part
    rows += terms_section(s, p, log)
    skip = run_gates.over_budget(p.t_end(s), _dt(s))
    if skip:
        log(f"runs {s.name}: {skip}")
        rows += _tag([compare(ENGINE, s.name, "runs: not run", f"{p.t_end(s):g} s", [0.0],
                              [0.0], _info(skip), ["-"])], "exact", "all", "not run")
        return part
    rows += free_section(s, p, log, plots)
    exact_rows, refined, start_state = exact_section(s, p, log, plots)
    rows += exact_rows
    loops, why = mj_loops.native_loops(s)
    if loops:
        loop_rows, table = loops_section(s, loops, refined, start_state, p, log, plots)
        rows += loop_rows
        tables.append(table)
    elif why:
        rows += _tag([compare(ENGINE, s.name, "loops: not compared", "MuJoCo's own loop "
                              "equalities", [0.0], [0.0], _info(why), ["-"])],
                     "loops", "all", "not compared")
    prog = cases.programme(s)
    if prog is not None:
        mech_rows, table = mechanism_section(s, prog, refined, start_state, p, log, plots)
        rows += mech_rows
        tables.append(table)
        rows += off_manifold_section(s, prog, p, log, plots)
    return part


def finish(out_dir: Path, parts, quick: bool, wall: float = None,
           progress: bool = False) -> pd.DataFrame:
    """The scenarios' parts (:func:`scenario_part`, in scenario order) as one table: its
    rows, plots, motion pages and out_dir/mujoco.html written (atomically), the table
    returned.  wall: s, the time the parts took (this page does not show it)."""
    out_dir = Path(out_dir)
    rows = [r for part in parts for r in part["rows"]]
    plots = {k: v for part in parts for k, v in part["plots"].items()}
    tables = [t for part in parts for t in part["tables"]]
    rows += wall_time_rows(plots)
    df = pd.DataFrame(rows)
    front = ["section", "case", "model", "coordinate", "metric"]
    df = df[front + [c for c in df.columns if c not in front]]
    convergence = pd.concat(tables, ignore_index=True) if tables else pd.DataFrame()
    write_report(out_dir, df, convergence, plots, quick, [part["name"] for part in parts])
    for (section, name), (model, gpme_run, mujoco_run) in plots.items():
        if section == "exact":        # gpme's motion with MuJoCo's as a ghost, overlaid
            write_motion(model, gpme_run, named_path(out_dir, f"mujoco_{name}", "_motion.html"),
                         "exact programmed run, gpme", overlay=("MuJoCo", mujoco_run))
    if progress:
        logger.info(f"[mujoco] written the rows under {out_dir / 'checks'} and "
                    f"{out_dir / 'mujoco.html'}")
    return df
