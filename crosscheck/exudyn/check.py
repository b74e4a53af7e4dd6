"""Crosscheck of gpme's programmed runs against Exudyn (docs/crosscheck-exudyn.md).

For each scenario (gpme_io.scenario.Scenario):

    section "model"  the Exudyn kinematic tree built from the model's data
                     (crosscheck.exudyn.model) against Pinocchio (crosscheck.pinocchio.model.
                     from_gpme): Exudyn's system mass matrix M and ODE2 right-hand side f
                     (M q_ddot = f: gravity, velocity products, springs, dampers, drives)
                     against pin.crba and tau - rnea(q, v, 0), at the scenario's start and at
                     seeded random states (crosscheck.sampling.state_ranges);
    section "runs"   the programmed run realised in Exudyn with the constraints as exact
                     index-3 algebraic equations (crosscheck.exudyn.runs), every coordinate,
                     velocity, constraint value and multiplier against gpme's RK4 run, gated
                     by both integrators' errors measured by halving their steps
                     (crosscheck.halving_gates), with one observed-order row per engine and
                     the start's consistency row.

A run that fails (Newton divergence, singular Jacobian, start off the constraints) is one
failed row with Exudyn's message.
"""
import logging
import time
import zlib
from pathlib import Path
from typing import Optional, Sequence

import exudyn as exu
import numpy as np
import pandas as pd
import pinocchio as pin
from tqdm import tqdm

from gpme_core.errors import GpmeError
from gpme_io.atomic import atomic_write_text

from ..crane_cases import crane_cases
from ..compare import Tolerance, compare
from ..reports.html import comparison_page, section, table
from ..reports.rows import own_rows, write_rows
from ..sampling import state_ranges
from ..pinocchio.model import from_gpme
from . import runs as exu_runs
from .model import mass_and_forces, tree_layout

ENGINE = "exudyn"
SEED = 20261123
SECTIONS = ("model", "runs")
log = logging.getLogger("gpme.crosscheck.exudyn")

MODEL_STATES = {True: 2, False: 10}      # random states of the model rows (quick, full)
_ROUND_OFF = ("round-off only: Exudyn's kinematic-tree recursion and Pinocchio's crba/rnea "
              "evaluate the same closed-form quantity in double precision (measured: ~1e-16 "
              "relative)")
TOLERANCES = {
    "M": Tolerance(1e-14, 1e-12, _ROUND_OFF + "; normwise relative to max|M| (kg, kg m, "
                   "kg m^2)"),
    "f": Tolerance(1e-12, 1e-11, _ROUND_OFF + "; f = tau - C v - g cancels terms of size "
                   "|M| |v|^2 and the spring forces, which can be 100x its result (N, N m)"),
}


def default_scenarios(quick: bool = False) -> list:
    """The paper's crane, rigid and with 3 RFEM segments, started on the constraints
    (crosscheck.crane_cases); the same in quick."""
    return crane_cases("exudyn", quick)


def model_rows(scenario, quick: bool) -> list:
    """Rows of section "model": Exudyn's M and f against Pinocchio at the start and at
    MODEL_STATES[quick] seeded random states (t uniform in [0, t_end])."""
    model = scenario.model
    ps = from_gpme(model)
    data = ps.model.createData()
    rng = np.random.default_rng(zlib.crc32(scenario.name.encode()) ^ SEED)
    lo, hi, rate = state_ranges(model, None, scenario.q0)
    states = [("start", 0.0, np.asarray(scenario.q0, float), np.asarray(scenario.q_dot0, float))]
    for k in range(MODEL_STATES[quick]):
        states.append((f"random {k:03d}", float(rng.uniform(0.0, scenario.t_end)),
                       rng.uniform(lo, hi), rng.uniform(-rate, rate)))
    names = list(model.coordinate_names)
    unaligned = tree_layout(model).unaligned
    rows = []
    for label, t, q, v in states:
        m_exu, f_exu = mass_and_forces(model, t, q, v, scenario.system.damping_form)
        m_pin = np.array(pin.crba(ps.model, data, ps.q_pin(q)))
        m_pin = np.triu(m_pin) + np.triu(m_pin, 1).T        # crba fills the upper triangle
        m_pin = ps.columns_to_gpme(ps.to_gpme(m_pin))
        tau = ps.applied_forces(q, v, model.drive_forces(t))
        f_pin = tau - ps.to_gpme(pin.rnea(ps.model, data, ps.q_pin(q), ps.to_pin(v),
                                          np.zeros(ps.model.nv)))
        case = f"{label}, t = {t:.4g} s"
        rows.append(compare(ENGINE, scenario.name, "tree mass matrix M vs pin.crba", case,
                            m_exu, m_pin, TOLERANCES["M"], (names, names)))
        rows.append(compare(ENGINE, scenario.name, "tree forces f vs tau - rnea", case,
                            f_exu, f_pin, TOLERANCES["f"], names))
    for r in rows:
        r["section"] = "model"
        if unaligned:
            r["case"] += f" (axes rotated: {', '.join(unaligned)})"
    return rows


def _failed(scenario, section, exc) -> dict:
    row = compare(ENGINE, scenario.name, f"{exu_runs.EXACT}: failed" if section == "runs"
                  else "model build: failed", section, [np.nan], [0.0],
                  Tolerance(0.0, 0.0, f"the {section} step failed: {exc}"[:600]), ["-"])
    row["section"] = section
    return row


def run(out_dir: Path, scenarios: Optional[Sequence] = None, quick: bool = False,
        progress: bool = False, sections: Sequence[str] = SECTIONS) -> pd.DataFrame:
    """Compare gpme with Exudyn for every scenario; write the rows
    (crosscheck.reports.rows: out_dir/checks/exudyn/) and out_dir/exudyn.html (atomically)
    and return the tidy table (crosscheck.compare.COLUMNS plus ``section``).

    scenarios: gpme_io.scenario.Scenario objects; None: default_scenarios(quick).
    quick    : runs of min(quick_t_end, 0.2 s) and 2 random model states, else the whole
               run (up to crosscheck.exudyn.runs.FULL_T_END) and 10 states.
    sections : "model" and/or "runs".
    """
    unknown = sorted(set(sections) - set(SECTIONS))
    if unknown:
        raise ValueError(f"unknown sections {unknown}; choose from {SECTIONS}")
    scenarios = default_scenarios(quick) if scenarios is None else list(scenarios)
    start = time.perf_counter()
    parts = []
    bar = _progress(progress, len(scenarios))
    for scenario in scenarios:
        parts.append(scenario_part(out_dir, scenario, quick, sections))
        if bar:
            bar.update()
    if bar:
        bar.close()
    return finish(out_dir, parts, quick, time.perf_counter() - start)


def scenario_part(out_dir: Path, scenario, quick: bool = False,
                  sections: Sequence[str] = SECTIONS) -> dict:
    """What :func:`run` computes for one scenario: {"rows": comparison rows, "timing":
    (scenario name, s)}, picklable, for :func:`finish` (crosscheck.step_pool runs scenarios
    in separate processes).  Writes no file."""
    t0 = time.perf_counter()
    rows = []
    if "model" in sections:
        try:
            rows += model_rows(scenario, quick)
        except (GpmeError, exu.ExudynError, RuntimeError) as exc:
            rows.append(_failed(scenario, "model", exc))
    if "runs" in sections:
        try:
            rows += exu_runs.run_section(scenario, quick, log.info)
        except (GpmeError, ValueError, RuntimeError, exu.ExudynError) as exc:
            # a run that cannot be made (or a model Exudyn refuses) is a failed row
            rows.append(_failed(scenario, "runs", exc))
    return {"rows": rows, "timing": (scenario.name, time.perf_counter() - t0)}


def finish(out_dir: Path, parts: Sequence[dict], quick: bool, wall: float) -> pd.DataFrame:
    """The scenarios' parts (:func:`scenario_part`, in scenario order) as one table: its rows
    (crosscheck.reports.rows) and out_dir/exudyn.html written (atomically), the table
    returned.  wall: s, the time the parts took."""
    out_dir = Path(out_dir)
    df = pd.DataFrame([r for part in parts for r in part["rows"]])
    out_dir.mkdir(parents=True, exist_ok=True)
    write_rows(own_rows(df, ENGINE), out_dir, ENGINE)
    atomic_write_text(out_dir / "exudyn.html",
                      _html(df, [part["timing"] for part in parts], wall, quick))
    return df


def _progress(enabled, total):
    if not enabled:
        return None
    return tqdm(total=total, desc="exudyn crosscheck", unit="scenario")


CONVENTIONS = (
    "Conventions: gpme M q̈ = h + Q + Aᵀλ; Exudyn M q̈ + C_qᵀ λ_exu = f with C = Φ(t, q) = 0 "
    "enforced at every step (index 3), so λ = -λ_exu (the rows show gpme's sign). Exudyn's "
    "tree, spring-dampers, drive loads and gravity are built from the model's data; the "
    "end-effector kinematics inside the constraint user functions are Pinocchio's, the task "
    "derivatives SymPy's (crosscheck.constraint_reference). Gates: each engine's error "
    "measured by halving its own step (gpme classical RK4, order 4; Exudyn generalized-alpha, "
    "order 2), taken at the lowest accepted order p - 1, plus round-off and Exudyn's Newton "
    "floor; an observed-order row per engine checks the asymptotic regime.")


def _html(df, timings, wall, quick):
    """exudyn.html (crosscheck.reports.html.comparison_page)."""
    times = pd.DataFrame([{"scenario": n, "wall time (s)": round(w, 1)} for n, w in timings])
    intro = [f"{len(df)} comparisons over {len(timings)} scenarios; "
             f"{'quick' if quick else 'full'} run, {wall:.1f} s."]
    scenarios = section("Scenarios", table=table(times, status_column="-",
                                                 left_columns=("scenario",)))
    return comparison_page(ENGINE, "gpme vs Exudyn", exu.__version__, df, intro, [scenarios],
                           CONVENTIONS)
