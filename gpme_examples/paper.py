"""The paper's two simulations (section 3): the crane with rigid links and flexible support,
and with the flexible arm and flexible support, 10 s of programmed motion.  Their histories
and the paper's figures are written by gpme_io.paper_outputs (examples return data)."""
# the runs' settings (DEFAULT_N_RFE, T_END, QUICK_T_END, DEFAULT_DT) live in crane.py with
# every other number of the example; they are read here too, as paper.T_END etc.
from .crane import (DEFAULT_DT, DEFAULT_N_RFE, QUICK_T_END, T_END, CraneParameters, build_crane,
                    crane_system, initial_state)
from gpme_core.elastic_loads import elastic_peaks
from gpme_core.integrate import estimate_simulation, simulate


def _case_run(case, n_rfe, t_end, dt, method, params, static_arm):
    """(system, q0, qd0, dt, n) of one of the paper's runs."""
    n = 0 if case == "rigid" else n_rfe
    system = crane_system(n, params)
    q0, qd0 = initial_state(system.model, params, static_arm=static_arm and n > 0)
    if dt is None and method == "RK4" and n <= DEFAULT_N_RFE:
        dt = min(DEFAULT_DT[case], t_end) if t_end > 0 else DEFAULT_DT[case]
    return system, q0, qd0, dt, n


def run_case(case, n_rfe=DEFAULT_N_RFE, t_end=T_END, dt=None, method="RK4", on_manifold=False,
             params=CraneParameters(), progress=None, output_dt=1e-3, static_arm=False,
             before_run=None, max_wall_s=None):
    """One run of the paper: case 'rigid' or 'flexible'; returns the history DataFrame.
    static_arm: start the flexible arm in its gravity sag instead of straight.
    dt: s, RK4 step (default DEFAULT_DT up to DEFAULT_N_RFE segments, else half the
    stability limit, gpme_core.stability); with an adaptive method its largest step.
    progress, before_run, max_wall_s: as gpme_core.integrate.simulate
    (progress: None or a callable given the run's events; gpme_io.progress draws them)."""
    system, q0, qd0, dt, n = _case_run(case, n_rfe, t_end, dt, method, params, static_arm)
    df = simulate(system, t_end, q0, qd0, dt=dt, method=method, on_manifold=on_manifold,
                  progress=progress, output_dt=output_dt, before_run=before_run,
                  max_wall_s=max_wall_s)
    df.attrs["case"] = case
    df.attrs["n_rfe"] = n
    return df


def estimate_case(case, n_rfe=DEFAULT_N_RFE, t_end=T_END, dt=None, method="RK4",
                  on_manifold=False, params=CraneParameters(), output_dt=1e-3,
                  static_arm=False):
    """gpme_core.run_cost.RunCost of :func:`run_case` with the same arguments, without
    running it (gpme_core.integrate.estimate_simulation)."""
    system, q0, qd0, dt, _ = _case_run(case, n_rfe, t_end, dt, method, params, static_arm)
    return estimate_simulation(system, t_end, q0, qd0, dt=dt, method=method,
                               on_manifold=on_manifold, output_dt=output_dt)


def summary(df, transient=2.0, params=CraneParameters()):
    """Largest |Phi_1|, |Phi_2| after ``transient`` s, the wall time and step count, and
    the arm's peak sde angles and bending stress (gpme_core.elastic_loads; flexible runs)."""
    late = df[df.t >= transient]
    n = df.attrs.get("n_rfe", 0)
    peaks = elastic_peaks(build_crane(n, params), df, {"arm": params.arm_yield_strength}) \
        if n else []
    return {"case": df.attrs.get("case"), "n_rfe": df.attrs.get("n_rfe"),
            "max_abs_Phi_1_after_transient": float(late.Phi_1.abs().max()),
            "max_abs_Phi_2_after_transient": float(late.Phi_2.abs().max()),
            "wall_time_s": df.attrs.get("wall_time_s"), "dt": df.attrs.get("dt"),
            "method": df.attrs.get("method"),
            "elastic_peaks": [p.as_record() for p in peaks]}
