"""`gpme verify` step "continuum": the model-validity section of every flexible model.

For each scenario whose model has flexible links (RFEM n >= 1), crosscheck.continuum.
validity gates RFEM at the model's n against the refined continuum model (Exudyn's
geometrically exact beams); models without flexible links get one information row.  The
page continuum.html shows per model the gate rows, the convergence table of RFEM in the
number of segments against the continuum (largest difference over the horizon per
quantity, relative to its peak, observed order between successive n; quick: n, 2 n; full:
1, 2, 3, 5, 10, 20 and the model's n, 2 n), the continuum's mesh and step study, and a
plot of the elastic tip deflection for several n against the continuum.

Information rows (never gated): the first natural frequencies of RFEM at the model's n
against the continuum's at the start configuration (crosscheck.continuum.frequencies:
beams straight, springs relaxed, loads off, constraints frozen at t = 0), with the
frequency gate's tolerance (RFEM's error predicted from n and 2 n, plus the continuum's
mesh change) named in the row's reason.
"""
import logging
import time
from pathlib import Path
from typing import Optional, Sequence

import exudyn as exu
import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from gpme_io.png import figure_png

from gpme_core.errors import GpmeError
from gpme_io.atomic import atomic_write_bytes, atomic_write_text

from ..compare import Tolerance, compare
from ..crane_cases import crane_cases
from ..reports.html import comparison_page, section, table
from ..reports.rows import own_rows, write_rows
from . import frequencies as fq
from .runs import ENGINE as RUN_ENGINE
from .study import max_difference, rfem_history
from .validity import (ENGINE, SECTION, Validity, check_scenario, has_flexible_links,
                       scenario_at, scenario_with_segments, straight_start)

log = logging.getLogger("gpme.verify")
TABLE_NS = (1, 2, 3, 5, 10, 20)
# s, RadauIIA's step for the convergence table's RFEM runs.  RK4's stable step falls as
# 1/n^2 with the torsion modes (crane, n = 20: 7.8e-7 s, 340 s of run per 2 s); RadauIIA
# is A-stable and takes 1-2 s.  Its own error is measured per run against dt/2 and shown
# beside RFEM's difference to the continuum (the table's "integration error" column; the
# crane, full run (2 s): <= 3.3e-3 of RFEM's difference at every n, largest at n = 20)
TABLE_DT = 5e-4
FREQUENCY_COUNT = 4                 # natural frequencies per information row
# the continuum's finest mesh for the frequency rows (quick: 64 elements, ~1 s on the
# crane; full: fq.MAX_ELEMENTS, ~15 s)
QUICK_FREQUENCY_ELEMENTS = 64
# what an information row adds when Exudyn's Newton failed (docs/rfem-continuum.md, "Exudyn's
# Newton on three zoo models"): measured on the Kinova's box beam, not a modelling error
NEWTON_LIMIT = (". Exudyn's Newton diverges on the Euler-Bernoulli continuum (axial and shear "
                "stiffness raised until their compliance is 1e-6 of the bending one) when the "
                "beam's unresolved axial and shear modes stay excited step after step; a "
                "smaller step runs but its torsion did not converge (Kinova: 0.14, 0.08 rad "
                "mesh changes, 0.026 rad at the last step halving), so there is no reference "
                "to gate against (docs/rfem-continuum.md)")


def default_scenarios(quick: bool = False) -> list:
    return crane_cases(ENGINE, quick)


def _info_row(scenario, quantity, text) -> dict:
    row = compare(ENGINE, scenario.model.name, quantity, "-", [0.0], [0.0],
                  Tolerance(float("inf"), 0.0, f"information: {text}"), ["-"])
    row["section"] = SECTION
    return row


def frequency_rows(scenario, quick: bool) -> list:
    """Information rows: RFEM's first FREQUENCY_COUNT natural frequencies at the model's n
    against the continuum's, at the start configuration (module docstring); one row per
    frequency, its reason giving the frequency gate's tolerance
    (crosscheck.continuum.frequencies.frequency_checks) and whether it would hold."""
    system = scenario.system
    cfg = fq.frequency_configuration(system, 0.0, straight_start(scenario)[0])
    q = fq.state_of(cfg, system)
    ref = fq.continuum_reference(scenario.model, cfg.t, q, scenario.constraints,
                                 FREQUENCY_COUNT, max_elements=QUICK_FREQUENCY_ELEMENTS
                                 if quick else fq.MAX_ELEMENTS,
                                 log=lambda m: log.info(f"  {m}"))
    doubled = scenario_at(scenario, 2).system
    at_n = fq.rfem_frequencies(system, cfg.t, q, FREQUENCY_COUNT)
    at_2n = fq.rfem_frequencies(doubled, cfg.t, fq.state_of(cfg, doubled), FREQUENCY_COUNT)
    n_text = ", ".join(f"{f.name}: n = {f.n_segments}" for f in scenario.model.flexible_links)
    case = (f"{n_text}; t = 0, beams straight, springs relaxed, loads off; continuum "
            f"{ref.elements} elements; {ref.zero_modes} rigid mode(s) left out")
    rows = []
    for check, label in zip(fq.frequency_checks(at_n, at_2n, ref), at_n.labels):
        verdict = "within" if check.passed else "outside"
        row = compare(ENGINE, scenario.model.name, f"natural frequency {check.mode} vs "
                      "continuum (Hz)", case, [check.rfem_n], [check.continuum],
                      Tolerance(float("inf"), 0.0,
                                f"information: RFEM ({label or 'mode'}) at n; {verdict} the "
                                f"frequency gate's {check.tolerance:.3g} Hz (RFEM's error "
                                f"predicted from n and 2 n: 2n gives {check.rfem_2n:.6g} Hz; "
                                f"the continuum's last mesh change {check.continuum_change:.2g} "
                                "Hz)"), [label or f"mode {check.mode}"])
        row["section"] = SECTION
        rows.append(row)
    return rows


def convergence_table(scenario, validity: Validity, ns: Sequence[int]) -> pd.DataFrame:
    """Rows (n, quantity, max difference, relative to the peak, observed order, integration
    error) of RFEM at each n (every flexible link) against the validity check's continuum
    reference.  The runs are RadauIIA at TABLE_DT (the largest step dividing the output
    spacing); "integration error" is 2 max_t |x(dt) - x(dt/2)|, a bound on that run's own
    error at any order >= 1, so the table shows when a difference is not RFEM's."""
    ref = validity.reference.frame.copy()
    out_dt = validity.output_dt
    dt = out_dt / np.ceil(out_dt / TABLE_DT - 1e-9)
    ref["t"] = np.round(ref["t"] / out_dt) * out_dt
    cols = [c for g in ("defl", "rot", "axial", "joint", "lambda") for c in validity.groups.get(g, [])]
    rows, last = [], {}
    for n in ns:
        sc = scenario_with_segments(scenario, lambda _old, n=n: n)
        q0, v0 = straight_start(sc)
        df = rfem_history(sc.system, q0, v0, validity.horizon, out_dt, dt=dt,
                          method="RadauIIA")
        half = rfem_history(sc.system, q0, v0, validity.horizon, out_dt, dt=dt / 2,
                            method="RadauIIA")
        validity.rfem.setdefault(f"n={n}", df)
        for c in cols:
            err = max_difference(df, ref, c)
            peak = float(np.nanmax(np.abs(ref[c].to_numpy())))
            order = np.nan
            if c in last and last[c][1] > 0 and err > 0:
                order = np.log(last[c][1] / err) / np.log(n / last[c][0])
            rows.append({"n": n, "quantity": c, "max difference": err,
                         "relative to peak": err / peak if peak else np.nan,
                         "observed order": order,
                         "integration error": 2.0 * max_difference(df, half, c)})
            last[c] = (n, err)
    return pd.DataFrame(rows)


def _plot(validity: Validity, model_name: str, path: Path):
    """Elastic tip deflection (the larger transverse component of the first beam) against
    time: RFEM at each n run, the continuum reference."""
    cols = validity.groups.get("defl", [])
    if not cols:
        return None
    ref = validity.reference.frame
    col = max(cols, key=lambda c: float(np.nanmax(np.abs(ref[c].to_numpy()))))
    fig = Figure(figsize=(7, 3.6))
    ax = fig.subplots()
    runs = {k: v for k, v in validity.rfem.items() if k.startswith("n=")} or \
        {k: v for k, v in validity.rfem.items() if k in ("n", "2n")}
    for label, df in sorted(runs.items(), key=lambda kv: int(kv[0][2:]) if kv[0][2:].isdigit()
                            else 0):
        if col not in df:
            continue
        ax.plot(df["t"], df[col] * 1e3, lw=1, label=f"RFEM {label}")
    ax.plot(ref["t"], ref[col] * 1e3, "k--", lw=1.5,
            label=f"continuum ({validity.reference.elements} elements)")
    ax.set_xlabel("t [s]")
    ax.set_ylabel(f"{col} [mm]")
    ax.set_title(f"{model_name}: elastic tip deflection")
    ax.legend(fontsize=7)
    atomic_write_bytes(path, figure_png(fig))
    return path


def run(out_dir: Path, scenarios: Optional[Sequence] = None, quick: bool = False,
        progress: bool = False) -> pd.DataFrame:
    """Model-validity rows of every scenario; writes out_dir/checks/continuum/ and
    out_dir/continuum.html (with its plots in out_dir/continuum/)."""
    scenarios = default_scenarios(quick) if scenarios is None else list(scenarios)
    start = time.perf_counter()
    parts = [scenario_part(out_dir, scenario, quick) for scenario in scenarios]
    return finish(out_dir, parts, quick, time.perf_counter() - start)


def scenario_part(out_dir: Path, scenario, quick: bool = False) -> dict:
    """What :func:`run` computes for one scenario (its plot written under
    ``out_dir``/continuum/): {"rows": comparison rows, "sections": page sections},
    picklable, for :func:`finish` (crosscheck.step_pool runs scenarios in separate
    processes)."""
    out_dir = Path(out_dir)
    rows, sections_ = [], []
    part = {"rows": rows, "sections": sections_}
    t0 = time.perf_counter()
    if not has_flexible_links(scenario.model):
        rows.append(_info_row(scenario, "no flexible link", "the model has no RFEM link "
                              "(n >= 1): there is no discretisation to judge"))
        return part
    log.info(f"  continuum: {scenario.name}")
    try:
        validity = check_scenario(scenario, quick, log=lambda m: log.info(f"  {m}"))
    except (GpmeError, RuntimeError, ValueError, exu.ExudynError) as exc:
        rows.append(_info_row(scenario, "not run", f"the continuum model could not be "
                              f"run: {type(exc).__name__}: {str(exc)[:300]}"
                              f"{NEWTON_LIMIT if 'reduction of step size' in str(exc) else ''}"))
        return part
    rows += validity.rows
    try:
        rows += frequency_rows(scenario, quick)
    except (GpmeError, RuntimeError, ValueError, exu.ExudynError) as exc:
        rows.append(_info_row(scenario, "natural frequencies not compared",
                              f"{type(exc).__name__}: {str(exc)[:300]}"))
    ns = sorted({f.n_segments for f in scenario.model.flexible_links}
                | {2 * f.n_segments for f in scenario.model.flexible_links}
                | (set() if quick else set(TABLE_NS)))
    try:
        table_df = convergence_table(scenario, validity, ns)
    except GpmeError as exc:
        # the table's RFEM runs (RadauIIA at TABLE_DT) are an illustration beside the gate;
        # their failure (the TriFinger's: RadauIIA's stages at 5e-4 s, its middle joint
        # starting at 57 rad/s) must not take the gated rows of every model with it
        rows.append(_info_row(scenario, "convergence table not computed",
                              f"{type(exc).__name__}: {str(exc)[:300]}"))
        table_df = pd.DataFrame()
    plot = _plot(validity, scenario.model.name,
                 out_dir / "continuum" / f"{scenario.model.name}_tip.png")
    ref = validity.reference
    study = pd.DataFrame([{"elements": ne, "dt (s)": h, "wall time (s)": round(w, 1)}
                          for ne, h, w in ref.history])
    text = [f"{scenario.model.name}: 0..{validity.horizon:g} s from the start with straight "
            f"beams, samples every {validity.output_dt:g} s; continuum {ref.elements} "
            f"elements per beam at dt = {ref.dt:g} s (generalized-alpha); its last mesh and "
            "step changes per quantity: " + ", ".join(
                f"{c} {ref.mesh_change[c]:.2g} / {ref.step_change[c]:.2g}"
                for c in ref.mesh_change) + f"; {time.perf_counter() - t0:.0f} s."]
    sections_.append(section(f"{scenario.model.name}: RFEM against the continuum", text,
                             table(table_df, status_column="-",
                                   left_columns=("quantity",)),
                             figures=[(plot.relative_to(out_dir), "elastic tip deflection, "
                                       "RFEM at several n and the continuum")] if plot else ()))
    sections_.append(section(f"{scenario.model.name}: the continuum's mesh and step study",
                             table=table(study, status_column="-")))
    return part


def finish(out_dir: Path, parts, quick: bool, wall: float) -> pd.DataFrame:
    """The scenarios' parts (:func:`scenario_part`, in scenario order) as one table: its rows
    and out_dir/continuum.html written (atomically), the table returned.  wall: s."""
    out_dir = Path(out_dir)
    rows = [r for part in parts for r in part["rows"]]
    sections_ = [x for part in parts for x in part["sections"]]
    df = pd.DataFrame(rows)
    out_dir.mkdir(parents=True, exist_ok=True)
    write_rows(own_rows(df, ENGINE), out_dir, ENGINE)
    intro = [f"{len(df)} comparisons over {len(parts)} scenarios; "
             f"{'quick' if quick else 'full'} run, {wall:.1f} s."]
    atomic_write_text(out_dir / "continuum.html", comparison_page(
        ENGINE, "RFEM vs continuum beams (model validity)", exu.__version__, df, intro,
        sections_, CONVENTIONS))
    return df


CONVENTIONS = (
    "The continuum model (crosscheck.continuum) is the same machine in Exudyn with each "
    "flexible link as geometrically exact beam elements (axial, shear, torsion and bending "
    "strains; section from the link's material and section constants) and the rigid links as "
    "rigid bodies on generic joints; programmed joint coordinates are joint offsets, "
    "programmed points a constrained point. Both models start with straight beams. Compared: "
    "the elastic tip deflection and rotation in the beam's root frame, the rigid joint "
    "coordinates and the multipliers (gpme's sign). Gate: RFEM's own error at n predicted "
    "from its runs at n and 2 n (order 2, x2 margin), plus the continuum's measured mesh and "
    f"step error, plus the shear and axial compliance RFEM leaves out. Rows of {RUN_ENGINE}.")
