"""Model validity: is RFEM at the model's n as close to the continuum as it should be?

For a scenario whose model has flexible links (n >= 1 segments each), over a horizon of
VALIDITY_T_END (quick: QUICK_T_END) seconds from the scenario's start with the beams
straight (the RFEM angles set to 0 and the dependent coordinates put back on the
constraints, so both models start from the same state):

1. the continuum reference in RFEM's limit (crosscheck.continuum.study.continuum_reference
   with euler_bernoulli: axial and shear stiffness raised 1e4-fold, the inextensible,
   shear-rigid rod RFEM converges to): mesh doubled, step halved until the gated
   quantities change by less than 1e-4 of their peak; its last changes are its measured
   error e_ref;
2. gpme's runs of the model at n and at 2 n segments (the same file with ``segments``
   doubled, :func:`scenario_at`);
3. per quantity group, the difference d = max_t |RFEM(n) - continuum| is gated at

       tol = 2 x (4/3) |RFEM(n) - RFEM(2 n)| + 3 e_ref

   (4/3) |RFEM(n) - RFEM(2 n)| is RFEM's own error at n if it converges with order 2
   (Richardson: e(n) = e(n) - e(2n) + e(n)/4); the factor 2 covers an observed order down to
   0.8 (e(n) = |d_n| / (1 - 2^-p) is 2 |d_n| at p = 1); 3 e_ref bounds the continuum's
   own error for an observed order down to 0.42 (REFERENCE_ORDER_MARGIN);
4. the physical continuum (the section's own E A and k G A) at the reference's mesh and
   step (full runs only: its stiff axial modes make it the slowest run): its difference to
   the reference is what RFEM leaves out (shear and axial compliance, axial stretch, the
   axial modes), reported as information rows.

The reference is refined until its changes are below REFERENCE_SHARE of RFEM's predicted
error (or 1e-4 of the quantity's peak): it is made as accurate as the judgement needs.

Gated groups: the elastic tip deflection across the beam (y, z of the root frame, m), the
elastic tip rotation (rad), the rigid joint coordinates.  Information rows: the tip
displacement along the beam (RFEM has no stretch), the multipliers (they carry the beams'
higher torsion and axial modes, which RFEM at any n and the continuum represent
differently: measured on the UR5 forearm, joint coordinates and deflections agree to
1e-4 of their peak while the multipliers differ by 7 % at a few instants), and the
physical-continuum differences of step 4.
"""
import dataclasses
from dataclasses import dataclass
import numpy as np

from gpme_core.errors import GpmeError, ModelError
from gpme_io.modelfile import build_scenario, read_model_file
from gpme_io.modelfile.schema import CraneSource
from gpme_io.scenario import crane_scenario

from ..compare import Tolerance, compare
from .layout import continuum_layout
from .section import continuum_section
from .runs import continuum_run
from .study import continuum_reference, max_difference, rfem_history

SECTION = "model validity"
ENGINE = "continuum"          # the verify step and engine name of the rows
VALIDITY_T_END = 2.0           # s, horizon of the full check
QUICK_T_END = 0.5              # s, of --quick
SAMPLES = 200                  # output samples over the horizon (several per period of
                               # the examples' first bending modes: 22 Hz crane arm)
STEPS_PER_PERIOD = 40          # continuum's first step: this many per bare-beam period
RICHARDSON_ORDER2 = 4.0 / 3.0
# the continuum is refined until its mesh and step changes are below this share of the
# RFEM error it judges (or 1e-4 of the peak, study.REFERENCE_FRACTION): its own error
# then adds at most 10 % to the gate
REFERENCE_SHARE = 0.1
# the continuum's error at its finest mesh and step is its last change / (2^p - 1) for an
# observed order p; this factor bounds it for any p >= 0.42 (one halving does not show p:
# on the Talos arm, a free wrist joint's step change was 1.0e-4 rad at the last halving,
# and RFEM differed from the continuum by 1.3e-4 rad with a predicted RFEM error of 5e-6)
REFERENCE_ORDER_MARGIN = 3.0
# refinement budget of the reference (elements per beam, first step / smallest step): a
# reference that has not settled within it is used with its measured last changes in the
# gate (the beams' higher torsion modes, 2 kHz on the UR5 forearm, keep the tip's torsion
# angle changing by ~3e-7 rad as the step falls)
MAX_ELEMENTS, HALVINGS_DIVISOR = 64, 8
QUICK_MAX_ELEMENTS, QUICK_HALVINGS_DIVISOR = 32, 4
ORDER_MARGIN = 2.0
GATED = ("defl", "rot", "joint")
QUANTITY = {"defl": "tip deflection vs continuum", "rot": "tip rotation vs continuum",
            "joint": "rigid coordinates vs continuum", "lambda": "multipliers vs continuum",
            "axial": "axial tip displacement vs continuum (RFEM has no stretch)"}


def stated_tolerances(scenario) -> dict:
    """{gated group: ToleranceOverride} the scenario's model file states for
    "continuum/<quantity>" ([[tolerance]], docs/models.md), quantity one of the gated rows'
    (QUANTITY of GATED); ModelError naming the valid checks when one names another row (an
    information row has no gate to replace)."""
    groups = {QUANTITY[g]: g for g in GATED}
    out = {}
    for check, override in (getattr(scenario, "tolerances", None) or {}).items():
        engine, _, quantity = check.partition("/")
        if engine != ENGINE:
            continue
        if quantity not in groups:
            raise ModelError(
                f"{scenario.name}: [[tolerance]] check {check!r} names no gated model-validity "
                f"row; the gated ones are {[f'{ENGINE}/{QUANTITY[g]}' for g in GATED]} (the "
                "others are information rows)")
        out[groups[quantity]] = override
    return out


def has_flexible_links(model) -> bool:
    return any(f.n_segments > 0 for f in model.flexible_links)


def scenario_at(scenario, factor: int):
    """The scenario with every flexible link's segment count multiplied by ``factor``."""
    return scenario_with_segments(scenario, lambda n: n * factor)


def scenario_with_segments(scenario, segments):
    """The scenario with each flexible link's segment count n replaced by segments(n):
    rebuilt from its model file (``segments`` of each [[flexible]], or the crane's
    ``n_rfe``), or, for the paper's crane built in code, gpme_io.scenario.crane_scenario."""
    if scenario.source is not None:
        spec = read_model_file(scenario.source)
        if isinstance(spec.model.source, CraneSource):
            src = dataclasses.replace(spec.model.source, n_rfe=segments(spec.model.source.n_rfe))
            spec = dataclasses.replace(spec, model=dataclasses.replace(spec.model, source=src))
        else:
            spec = dataclasses.replace(spec, flexible=tuple(
                dataclasses.replace(f, segments=segments(f.segments)) for f in spec.flexible))
        return build_scenario(spec)
    if scenario.model.name.startswith("crane_flexible"):
        n = scenario.model.flexible_links[0].n_segments
        return crane_scenario(segments(n), on_constraints=scenario.on_constraints)
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
    groups = {"defl": [], "rot": [], "joint": [], "axial": [], "lambda": []}
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


def check_scenario(scenario, quick: bool, log=print, rebuild=scenario_at,
                   horizon=None) -> Validity:
    """The model-validity rows of one scenario (module docstring); horizon: s, instead of
    QUICK_T_END or VALIDITY_T_END."""
    model = scenario.model
    stated = stated_tolerances(scenario)         # a bad [[tolerance]] fails before the runs
    layout = continuum_layout(model)
    horizon = min(horizon or (QUICK_T_END if quick else VALIDITY_T_END), scenario.t_end)
    dt, output_dt = first_step(layout, horizon)
    q0, v0 = straight_start(scenario)
    specs = scenario.constraints
    names = tuple(getattr(c, "name", "") for c in specs)
    probe = rfem_history(scenario.system, q0, v0, output_dt, output_dt)
    groups = column_groups(probe.columns, layout, model, names)
    gated = [c for g in GATED for c in groups.get(g, [])]
    doubled = rebuild(scenario, 2)
    q0_2, v0_2 = straight_start(doubled)
    rfem = {"n": rfem_history(scenario.system, q0, v0, horizon, output_dt),
            "2n": rfem_history(doubled.system, q0_2, v0_2, horizon, output_dt)}
    # the reference must be REFERENCE_SHARE of RFEM's predicted error finer than RFEM
    targets = {}
    for group, cols in groups.items():
        change = max(max_difference(rfem["n"], rfem["2n"], c) for c in cols)
        targets.update({c: REFERENCE_SHARE * RICHARDSON_ORDER2 * change for c in cols})
    reference = continuum_reference(model, q0, v0, horizon, output_dt, specs, gated,
                                    elements=4, dt=dt,
                                    max_elements=QUICK_MAX_ELEMENTS if quick else MAX_ELEMENTS,
                                    min_dt=dt / (QUICK_HALVINGS_DIVISOR if quick else
                                                 HALVINGS_DIVISOR),
                                    log=log, groups=groups, euler_bernoulli=True,
                                    targets=targets)
    physical = None
    if not quick:
        physical = continuum_run(model, q0, v0, horizon, reference.dt, output_dt, specs,
                                 elements=reference.elements)
        log(f"  continuum with the section's own axial and shear stiffness: "
            f"{physical.attrs['wall_time_s']:.1f} s")
    n_text = ", ".join(f"{f.name}: n = {f.n_segments}" for f in model.flexible_links)
    rows = []
    ref = reference.frame.copy()
    ref["t"] = np.round(ref["t"] / output_dt) * output_dt
    case = (f"{n_text}; continuum {reference.elements} elements, dt = {reference.dt:g} s, "
            f"0..{horizon:g} s")
    for group, cols in groups.items():
        x, y = _aligned(rfem["n"], ref, cols, output_dt)
        x2, _ = _aligned(rfem["2n"], ref, cols, output_dt)
        e_ref = REFERENCE_ORDER_MARGIN * max(
            reference.mesh_change.get(c, 0.0) + reference.step_change.get(c, 0.0) for c in cols)
        predicted = RICHARDSON_ORDER2 * float(np.abs(x - x2).max()) if x.size else 0.0
        physics = (f"RFEM's error at n predicted from n and 2n (order 2, x{ORDER_MARGIN:g} "
                   f"for an observed order down to 0.8): {predicted:.3g}; the continuum's "
                   f"mesh and step error, 3 x its last changes: {e_ref:.3g}")
        if group in stated:
            o = stated[group]
            tol = Tolerance(o.abs, o.rel, f"model file: {o.reason} (instead of the physics "
                            f"gate {ORDER_MARGIN * predicted + e_ref:.3g}: {physics})")
        elif group in GATED:
            tol = Tolerance(ORDER_MARGIN * predicted + e_ref, 0.0, physics)
        elif group == "axial":
            tol = Tolerance(np.inf, 0.0, "information: RFEM's rigid segments do not stretch; the "
                            "row compares with the inextensible continuum (RFEM n to 2n: "
                            f"{predicted:.3g} m); the stretch itself is in the physical-continuum row")
        else:
            tol = Tolerance(np.inf, 0.0, "information: the multipliers carry the beams' higher "
                            "torsion and axial modes, which RFEM at any n and the continuum "
                            f"represent differently (RFEM n to 2n: {predicted:.3g})")
        rows.append(_row(model, QUANTITY[group], case, x, y, cols, tol))
    if physical is None:
        return Validity(reference, rfem, groups, rows, horizon, output_dt)
    phys = physical.copy()
    phys["t"] = np.round(phys["t"] / output_dt) * output_dt
    for group, cols in groups.items():
        if group == "lambda":
            continue
        x, y = _aligned(phys, ref, cols, output_dt)
        rows.append(_row(model, f"{QUANTITY[group]}: shear and axial compliance", case, x, y,
                         cols, Tolerance(np.inf, 0.0, "information: the physical continuum (the "
                                         "section's own E A and k G A) against its inextensible, "
                                         "shear-rigid limit: what RFEM leaves out")))
    return Validity(reference, rfem, groups, rows, horizon, output_dt)


def _row(model, quantity, case, x, y, cols, tol) -> dict:
    row = compare(ENGINE, model.name, quantity, case, x.T.ravel(), y.T.ravel(), tol,
                  [f"{c} sample {i}" for c in cols for i in range(len(x))])
    row["section"] = SECTION
    return row
