"""Model validity: is RFEM at the model's n as close to the continuum as it should be?

For a scenario whose model has flexible links (n >= 1 segments each), over a horizon of
VALIDITY_T_END (quick: QUICK_T_END) seconds from the scenario's start with the beams
straight (the RFEM angles set to 0 and the dependent coordinates put back on the
constraints, so both models start from the same state):

1. the continuum reference (crosscheck.continuum.study.continuum_reference: mesh doubled,
   step halved until the gated quantities change by less than 1e-4 of their peak; its last
   changes are its measured error e_ref);
2. gpme's runs of the model at n and at 2 n segments (the same file with ``segments``
   doubled, :func:`scenario_at`);
3. per quantity group, the difference d = max_t |RFEM(n) - continuum| is gated at

       tol = 2 x (4/3) |RFEM(n) - RFEM(2 n)| + e_ref + e_limit x peak

   (4/3) |RFEM(n) - RFEM(2 n)| is RFEM's own error at n if it converges with order 2
   (Richardson: e(n) = e(n) - e(2n) + e(n)/4); the factor 2 covers an observed order down to
   0.8 (e(n) = |d_n| / (1 - 2^-p) is 2 |d_n| at p = 1); e_limit the fraction by which the
   continuum's limit differs from RFEM's for the beam (shear and axial compliance against
   bending, 3 E I / (k G A L^2) + E I / (E A L^2) for each beam, the largest taken): RFEM
   leaves both out.  It multiplies the elastic part of the quantity: the peak itself for
   the tip deflection and rotation, max_t |RFEM(n) - rigid| (the same model with rigid
   links, n = 0) for the joint coordinates and multipliers.

Gated groups: the elastic tip deflection across the beam (y, z of the root frame, m), the
elastic tip rotation (rad), the rigid joint coordinates, the multipliers.  The tip
displacement along the beam is an information row: RFEM has no axial stretch, so its limit
differs by the stretch (centrifugal, gravity along the beam), which the row reports.
"""
import dataclasses
from dataclasses import dataclass
from typing import Optional

import numpy as np
import pandas as pd

from gpme_core.errors import GpmeError

from ..compare import Tolerance, compare
from .layout import continuum_layout
from .runs import ENGINE
from .section import continuum_section
from .study import REFERENCE_FRACTION, continuum_reference, max_difference, rfem_history

SECTION = "model validity"
VALIDITY_T_END = 2.0           # s, horizon of the full check
QUICK_T_END = 0.5              # s, of --quick
SAMPLES = 50                   # output samples over the horizon
STEPS_PER_PERIOD = 40          # continuum's first step: this many per bare-beam period
RICHARDSON_ORDER2 = 4.0 / 3.0
ORDER_MARGIN = 2.0
QUANTITY = {"defl": "tip deflection vs continuum", "rot": "tip rotation vs continuum",
            "joint": "rigid coordinates vs continuum", "lambda": "multipliers vs continuum",
            "axial": "axial tip displacement vs continuum (RFEM has no stretch)"}


def has_flexible_links(model) -> bool:
    return any(f.n_segments > 0 for f in model.flexible_links)


def scenario_at(scenario, factor: int):
    """The scenario with every flexible link's segment count multiplied by ``factor``:
    rebuilt from its model file (``segments`` of each [[flexible]], or the crane's
    ``n_rfe``), or, for the paper's crane built in code, gpme_io.scenario.crane_scenario."""
    if scenario.source is not None:
        from gpme_io.modelfile import build_scenario, read_model_file
        from gpme_io.modelfile.schema import CraneSource
        spec = read_model_file(scenario.source)
        if isinstance(spec.model.source, CraneSource):
            src = dataclasses.replace(spec.model.source, n_rfe=spec.model.source.n_rfe * factor)
            spec = dataclasses.replace(spec, model=dataclasses.replace(spec.model, source=src))
        else:
            spec = dataclasses.replace(spec, flexible=tuple(
                dataclasses.replace(f, segments=f.segments * factor) for f in spec.flexible))
        return build_scenario(spec)
    if scenario.model.name.startswith("crane_flexible"):
        from gpme_io.scenario import crane_scenario
        n = scenario.model.flexible_links[0].n_segments
        return crane_scenario(n * factor, on_constraints=scenario.on_constraints)
    raise GpmeError(f"{scenario.name}: no way to rebuild the model with other segment counts "
                    "(a model file or the built-in crane)")


def straight_start(scenario):
    """(q0, q_dot0): the scenario's start with every RFEM angle and rate 0, the dependent
    coordinates and rates put back on the constraints (gpme's consistent_state)."""
    model = scenario.model
    q0 = np.array(scenario.q0, dtype=float)
    v0 = np.array(scenario.q_dot0, dtype=float)
    for f in model.flexible_links:
        q0[list(f.joint_indices)] = 0.0
        v0[list(f.joint_indices)] = 0.0
    if scenario.system.n_constraints:
        q0, v0 = scenario.system.consistent_state(0.0, q0, v0)
    return q0, v0


def limit_fraction(layout) -> float:
    """e_limit of the module docstring (dimensionless)."""
    out = 0.0
    for b in layout.beams:
        cs = continuum_section(b.beam)
        ei = max(cs.stiffness[4], cs.stiffness[5])
        length = b.beam.length
        out = max(out, 3.0 * ei / (cs.stiffness[1] * length ** 2) + ei / (cs.stiffness[0] * length ** 2))
    return out


def first_step(layout, horizon, samples=SAMPLES) -> tuple:
    """(dt s, output_dt s): output every horizon / samples, and a step that divides it with
    STEPS_PER_PERIOD steps per period of the bare cantilever's first bending mode
    (1.875^2 / L^2 sqrt(E I / (rho A)) rad/s; a tip mass only lowers it)."""
    output_dt = horizon / samples
    omega = 0.0
    for b in layout.beams:
        cs = continuum_section(b.beam)
        ei = max(cs.stiffness[4], cs.stiffness[5])
        omega = max(omega, 1.875 ** 2 / b.beam.length ** 2 * np.sqrt(ei / cs.mass_per_length))
    dt = output_dt
    while omega and dt > 2.0 * np.pi / omega / STEPS_PER_PERIOD:
        dt /= 2.0
    return dt, output_dt


@dataclass
class Validity:
    """The pieces of one scenario's check: reference (study.Reference), rfem {n: frame},
    groups {group: columns}, rows (tidy rows)."""

    reference: object
    rfem: dict
    groups: dict
    rows: list
    horizon: float
    output_dt: float


def column_groups(frame_columns, layout, model, constraint_names) -> dict:
    groups = {"defl": [], "rot": [], "axial": [], "joint": [], "lambda": []}
    for b in layout.beams:
        groups["defl"] += [f"defl_y_{b.name}", f"defl_z_{b.name}"]
        groups["rot"] += [f"rot_{a}_{b.name}" for a in "xyz"]
        groups["axial"].append(f"defl_x_{b.name}")
    groups["joint"] = [model.joints[k].name for k in layout.joints]
    groups["lambda"] = [f"lambda_{c}" for c in constraint_names]
    return {g: [c for c in cols if c in frame_columns] for g, cols in groups.items() if cols}


def _aligned(frame, ref, cols, output_dt):
    a = frame.copy()
    a["t"] = np.round(a["t"] / output_dt) * output_dt
    m = a[["t", *cols]].merge(ref[["t", *cols]], on="t", suffixes=("", "_ref")).dropna()
    return m[list(cols)].to_numpy(), m[[f"{c}_ref" for c in cols]].to_numpy()


def check_scenario(scenario, quick: bool, log=print, rebuild=scenario_at) -> Validity:
    """The model-validity rows of one scenario (module docstring)."""
    model = scenario.model
    layout = continuum_layout(model)
    horizon = min(QUICK_T_END if quick else VALIDITY_T_END, scenario.t_end)
    dt, output_dt = first_step(layout, horizon)
    q0, v0 = straight_start(scenario)
    specs = scenario.constraints
    names = tuple(getattr(c, "name", "") for c in specs)
    probe = rfem_history(scenario.system, q0, v0, output_dt, output_dt)
    groups = column_groups(probe.columns, layout, model, names)
    gated = [c for g in ("defl", "rot", "joint", "lambda") for c in groups.get(g, [])]
    reference = continuum_reference(model, q0, v0, horizon, output_dt, specs,
                                    gated + groups.get("axial", []),
                                    elements=4, dt=dt, max_elements=64,
                                    min_dt=dt / 8, log=log, groups=groups)
    doubled = rebuild(scenario, 2)
    q0_2, v0_2 = straight_start(doubled)
    rigid = rebuild(scenario, 0)
    q0_r, v0_r = straight_start(rigid)
    rfem = {"n": rfem_history(scenario.system, q0, v0, horizon, output_dt),
            "2n": rfem_history(doubled.system, q0_2, v0_2, horizon, output_dt),
            "rigid": rfem_history(rigid.system, q0_r, v0_r, horizon, output_dt,
                                  flexible_of=model)}
    n_text = ", ".join(f"{f.name}: n = {f.n_segments}" for f in model.flexible_links)
    e_limit = limit_fraction(layout)
    rows = []
    ref = reference.frame.copy()
    ref["t"] = np.round(ref["t"] / output_dt) * output_dt
    for group, cols in groups.items():
        x, y = _aligned(rfem["n"], ref, cols, output_dt)
        x2, _ = _aligned(rfem["2n"], ref, cols, output_dt)
        peak = float(np.abs(y).max()) if y.size else 0.0
        if group in ("joint", "lambda"):
            # what the beams' elasticity does to these: the flexible run against the rigid
            # one; shear and axial compliance change that part by the fraction e_limit
            xr, _ = _aligned(rfem["rigid"], ref, cols, output_dt)
            elastic = float(np.abs(x - xr).max()) if x.size else 0.0
        else:
            elastic = peak
        e_ref = max(reference.mesh_change.get(c, 0.0) + reference.step_change.get(c, 0.0)
                    for c in cols)
        predicted = RICHARDSON_ORDER2 * float(np.abs(x - x2).max()) if x.size else 0.0
        case = (f"{n_text}; continuum {reference.elements} elements, dt = {reference.dt:g} s, "
                f"0..{horizon:g} s")
        if group == "axial":
            tol = Tolerance(np.inf, 0.0, "information: RFEM's rigid segments do not stretch; "
                            "the difference is the continuum's axial displacement of the tip "
                            "(centrifugal and gravity load along the beam) plus RFEM's "
                            f"foreshortening error (RFEM n to 2n: {predicted:.3g} m)")
        else:
            tol_abs = ORDER_MARGIN * predicted + e_ref + e_limit * elastic
            tol = Tolerance(tol_abs, 0.0,
                            f"RFEM's error at n predicted from n and 2n (order 2, x{ORDER_MARGIN:g} "
                            f"for an observed order down to 0.8): {predicted:.3g}; the continuum's "
                            f"measured mesh and step error {e_ref:.3g}; shear and axial "
                            f"compliance RFEM leaves out: {e_limit:.2g} x the elastic part {elastic:.3g}")
        row = compare(ENGINE, model.name, QUANTITY[group], case, x.T.ravel(), y.T.ravel(), tol,
                      [f"{c} sample {i}" for c in cols for i in range(len(x))])
        row["section"] = SECTION
        rows.append(row)
    return Validity(reference, rfem, groups, rows, horizon, output_dt)
