"""Free-motion runs of a scenario in Drake, with Drake's own Simulator and integrator, gated
by both engines' errors measured by step halving (crosscheck.halving_gates).

The model runs without its constraints, drives on (crosscheck.mujoco.cases.free_variant:
the crane gets the holding springs that keep its free arm in the slider's stroke, the same
in both engines).  Drake: the continuous MultibodyPlant of the URDF gpme wrote
(crosscheck.drake.model.for_model), the drives t(t) fed to its applied generalized force
input port by Drake's own sources where it has the function (crosscheck.drake.drives),
integrated by ``Simulator`` with Drake's ``runge_kutta5`` (Dormand-Prince 5(4), FSAL, 7
stages) in fixed-step mode at h, h/2 and h/4, advanced to each output time k output_dt in
turn (``AdvanceTo``) and the state recorded there.  Drake's
clock adds h at every step, so within an interval it drifts from k h by a few roundings;
at each output time the simulator ends exactly on the requested time (with a step of the
drift's size where needed), so the samples are at gpme's output times, not ~N eps t
(times |q_dot|, up to 1e-14 m here) away from them.  gpme: classical RK4 at h, h/2, h/4
(crosscheck.run_gates.refined_gpme_runs, which may halve h until gpme's own order is
observed; Drake then runs at that h).

Why fixed steps: an error-controlled run has no step to halve, so its error could only be
bounded by its own tolerance, which is a local, not a global, error.  With fixed steps
Drake's global error at h/4 is estimated from its own three runs, (x_h/2 - x_h/4) /
(2^(p-1) - 1) at the lowest order the order row accepts (p - 1 = 4), as gpme's is
(p - 1 = 3); the two finest runs must agree within the sum of both estimates plus round-off
floors.  No gpme kinematics, dynamics or integration code runs on Drake's side.
"""
import tempfile
import time
from typing import Optional

import numpy as np
import pandas as pd
from pydrake.systems.analysis import ResetIntegratorFromFlags, Simulator
from pydrake.systems.framework import DiagramBuilder

from gpme_core.errors import ConstraintError, SimulationError

from .. import halving_gates, run_gates
from ..engine_steps import engine_first_step
from ..compare import Tolerance, compare
from ..sampling import COMPARED_DT, compared_output_dt
from ..convergence import FINEST, RefinementBudget, refine
from ..mujoco.cases import free_variant
from ..pinocchio.runs import run_step, run_t_end
from .drives import drive_output
from .model import DrakeSystem, for_model

ENGINE = "drake"
FREE = "free run"
OUTPUT_DT = COMPARED_DT     # s, spacing of the compared samples (shorter runs:
#                             crosscheck.sampling.compared_output_dt)
SCHEME = "runge_kutta5"     # pydrake.systems.analysis.GetIntegrationSchemes()
SCHEME_TEXT = "Runge-Kutta 5 (Dormand-Prince), fixed step"
SCHEME_ORDER = 5.0
MIN_FREE_T_END = 0.05       # s, shortest free run compared (5 output samples)
# Drake's step halvings beyond its first three runs, to reach the asymptotic regime at every
# compared time (crosscheck.convergence); a run projected above 120 s is not started
REFINEMENT = RefinementBudget(max_halvings=3, max_run_wall_s=120.0)


def drake_free_run(scenario, t_end: float, dt: float, output_dt: float, urdf_dir,
                   drake_system: Optional[DrakeSystem] = None) -> pd.DataFrame:
    """The scenario's model (run as it is: no constraints) from (q0, q_dot0), integrated by
    Drake's Simulator with runge_kutta5 at the fixed step dt (s) to t_end (s).

    output_dt : s, a whole number of steps dt
    urdf_dir  : where the URDF Drake reads is written (for_model)
    drake_system : a fresh, not yet used DrakeSystem to run instead (tests perturb it)
    Returns columns t (s), every coordinate (rad, m) and <name>_dot; attrs: engine, dt,
    steps, derivative_evaluations, wall_time_s.
    """
    model = scenario.model
    ds = drake_system or for_model(model, urdf_dir, scenario.name)
    builder = DiagramBuilder()
    plant = builder.AddSystem(ds.plant)
    port = plant.get_applied_generalized_force_input_port()
    drives = drive_output(builder, model, ds)
    if drives is not None:
        builder.Connect(drives, port)
    else:
        builder.ExportInput(port, "applied")
    diagram = builder.Build()
    simulator = Simulator(diagram)
    root = simulator.get_mutable_context()
    if not model.drives:
        diagram.get_input_port(0).FixValue(root, np.zeros(plant.num_velocities()))
    context = plant.GetMyMutableContextFromRoot(root)
    plant.SetPositions(context, ds.q_drake(scenario.q0))
    plant.SetVelocities(context, ds.to_drake(scenario.q_dot0))
    integrator = ResetIntegratorFromFlags(simulator, SCHEME, dt)
    integrator.set_fixed_step_mode(True)
    n_out = int(round(t_end / output_dt))
    names = list(model.coordinate_names)
    samples = np.full((n_out + 1, 1 + 2 * len(names)), np.nan)

    def record(k):
        samples[k] = [root.get_time(), *ds.to_gpme(plant.GetPositions(context)),
                      *ds.to_gpme(plant.GetVelocities(context))]

    start = time.perf_counter()
    try:
        simulator.Initialize()
        record(0)
        for k in range(1, n_out + 1):
            simulator.AdvanceTo(k * output_dt)
            record(k)
    except RuntimeError as exc:
        raise SimulationError(f"Drake's run of {scenario.name} stopped at t = "
                              f"{root.get_time():.6g} s (dt = {dt:g} s): {exc}") from None
    if not np.all(np.isfinite(samples)):
        bad = int(np.argmax(~np.all(np.isfinite(samples), axis=1)))
        raise SimulationError(f"Drake's run of {scenario.name} (dt = {dt:g} s) diverged: no "
                              f"finite state at t = {bad * output_dt:.6g} s")
    df = pd.DataFrame(samples, columns=["t", *names, *(f"{c}_dot" for c in names)])
    df.attrs.update(engine=ENGINE, dt=dt, steps=int(integrator.get_num_steps_taken()),
                    derivative_evaluations=int(integrator.get_num_derivative_evaluations()),
                    wall_time_s=time.perf_counter() - start)
    return df


def halved_drake_runs(scenario, t_end: float, dt: float, output_dt: float,
                      urdf_dir, log=None, budget: RefinementBudget = REFINEMENT
                      ) -> halving_gates.HalvedRuns:
    """Drake's runs at dt, dt/2, dt/4 (s) as crosscheck.halving_gates.HalvedRuns, dt halved
    (crosscheck.convergence.refine, within REFINEMENT budget) until Drake's runs are in
    their asymptotic regime at every compared time; ``.refinement`` records how."""
    model = scenario.model
    columns = state_columns(model)

    def run_at(h):
        return drake_free_run(scenario, t_end, h, output_dt, urdf_dir)

    def floors_of(runs):
        trial = halving_gates.HalvedRuns(ENGINE, SCHEME_TEXT, SCHEME_ORDER, runs, dt)
        return {c: trial.floor(c, model) for c in columns}

    runs, h, _, record = refine(run_at, dt, columns, floors_of, SCHEME_ORDER, FINEST,
                                budget, log)
    return halving_gates.HalvedRuns(ENGINE, SCHEME_TEXT, SCHEME_ORDER, runs, h,
                                    refinement=record)


def state_columns(model) -> list:
    names = list(model.coordinate_names)
    return names + [f"{c}_dot" for c in names]


def _gpme_free_runs(free, t_end: float, dt: float) -> tuple:
    """(RefinedRuns or None, run length s, note): gpme's runs at h, h/2, h/4 of the free
    model over t_end, or over t_end / 2, / 4, ... (whole output samples, at least
    MIN_FREE_T_END) when gpme stops the run (a free arm falls out of a joint's range, which
    gpme refuses and Drake's continuous plant would not notice); None when even the shortest
    cannot be run (the note says why)."""
    t_run, last = t_end, ""
    spacing = compared_output_dt(t_end, dt)
    while True:
        try:
            refined = run_gates.refined_gpme_runs(free.system, free.q0, free.q_dot0, t_run,
                                                  dt, spacing, compared=FINEST)
        except (SimulationError, ConstraintError) as exc:   # diverged, or left a joint range
            shorter = round(t_run / 2.0 / spacing) * spacing
            if shorter < MIN_FREE_T_END:
                return None, t_run, (f"the free motion cannot be run for {MIN_FREE_T_END:g} s: "
                                     f"{exc}")
            last = str(exc)
            t_run = shorter
            continue
        note = "" if t_run == t_end else (f" (shortened from {t_end:g} s: gpme stopped the "
                                          f"longer run: {last.split(': the mechanism')[0][:200]})")
        return refined, t_run, note


def run_section(scenario, quick: bool, log=None, urdf_dir=None) -> list:
    """Rows (crosscheck.compare dicts) of the free run of ``scenario`` in Drake against
    gpme: one per state column (the two finest runs, gated by both engines' halving errors
    and round-off floors, crosscheck.halving_gates.run_rows) and one observed-order row per
    engine; or one information row when the run is over run_gates' step budget."""
    log = log or (lambda msg: None)
    free = free_variant(scenario)
    t_end, dt = run_t_end(scenario, quick), run_step(scenario)
    skip = run_gates.over_budget(t_end, dt)
    if skip:
        log(f"{FREE} {free.name}: {skip}")
        return [compare(ENGINE, free.name, f"{FREE}: not run", f"{t_end:g} s, dt = {dt:.3g} s",
                        [0.0], [0.0], Tolerance(np.inf, 0.0, f"information: {skip}"), ["-"])]
    refined, t_run, why = _gpme_free_runs(free, t_end, dt)
    if refined is None:
        log(f"{FREE} {free.name}: {why}")
        return [compare(ENGINE, free.name, f"{FREE}: not run", f"{t_end:g} s, dt = {dt:.3g} s",
                        [0.0], [0.0], Tolerance(np.inf, 0.0, f"information: {why}"), ["-"])]
    first, note, budget = engine_first_step(scenario, ENGINE, refined.dt, REFINEMENT)
    with tempfile.TemporaryDirectory() as tmp:
        drake = halved_drake_runs(free, t_run, first, compared_output_dt(t_end, dt),
                                  urdf_dir or tmp,
                                  log=lambda m: log(f"{FREE} {free.name}: drake {m}"),
                                  budget=budget)
    case = (f"{FREE}, drive on, {t_run:g} s{why}; gpme RK4 at dt = {refined.dt:g}, dt/2, "
            f"dt/4 s, Drake {SCHEME} at dt = {drake.dt:g}, dt/2, dt/4 s{note} (compared: the "
            "finest of each)")
    rows = halving_gates.run_rows(ENGINE, free, halving_gates.from_refined(refined), drake,
                                  state_columns(free.model), FREE, case)
    gpme_s = sum(r.attrs.get("wall_time_s", 0.0) for r in refined.runs)
    drake_s = sum(r.attrs["wall_time_s"] for r in drake.runs)
    log(f"{FREE} {free.name}: {t_run:g} s, gpme x3 {gpme_s:.1f} s, drake x3 {drake_s:.1f} s")
    return rows
