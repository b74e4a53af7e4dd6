"""Run a scenario with gpme and write its history and figures (used by `gpme simulate` and
the gpme step of `gpme verify`)."""
import json
from pathlib import Path

from gpme_io.atomic import (HISTORY_DIGITS, atomic_save_figure, atomic_write_csv,
                              atomic_write_text)
from gpme_core.errors import ModelError
from gpme_core.integrate import estimate_simulation, run
from gpme_core.stability import rk4_step
from gpme_core.methods import METHODS, RADAU_IIA, RK4
from gpme_core.run_result import RunSettings
from gpme_io.file_names import named_path
from gpme_io.progress import progress_callback

from . import animation, figures


def resolved_step(scenario, dt=None):
    """s, the RK4 step of a run: ``dt`` if given, else the scenario's, else
    gpme_core.stability.rk4_step at the scenario's initial state (half the stability limit
    of its stiffest mode, at most its output spacing)."""
    step = dt if dt is not None else scenario.dt
    if step is None:
        step = rk4_step(scenario.system, scenario.q0, cap=scenario.output_dt)
    if not (step > 0 and step < float("inf")):
        raise ModelError(f"RK4 step must be positive and finite (s), got {step!r}")
    return float(step)


def _run_settings(scenario, t_end, dt, method, quick, output_dt, max_wall_s=None):
    """(t_end s, gpme_core.run_result.RunSettings) of one run of ``scenario``."""
    method = method or scenario.integrator
    if method not in METHODS:
        raise ModelError(f"integrator must be one of {METHODS}, got {method!r}")
    t_end = scenario.t_run(quick) if t_end is None else float(t_end)
    out_dt = output_dt or scenario.output_dt
    if method == RK4:
        step = resolved_step(scenario, dt)
        if dt is None:
            step = min(step, t_end)     # the scenario's step, not one the caller gave
    elif dt is None and method == RADAU_IIA == scenario.integrator:
        step = scenario.dt           # the model file's RadauIIA step (None: its default)
    else:
        step = dt
    return t_end, RunSettings(dt=step, method=method, output_dt=out_dt, max_wall_s=max_wall_s)


def simulate_scenario(scenario, t_end=None, dt=None, method=None, quick=False, progress=False,
                      output_dt=None, before_run=None, max_wall_s=None):
    """History DataFrame of ``scenario`` from its initial state.

    t_end  : s, default scenario.t_run(quick)
    dt     : s, RK4 step, default :func:`resolved_step`; RadauIIA's step, default the model
             file's when it chose RadauIIA, else gpme_core.integrate.RADAU_IIA_STEP
    method : one of gpme_core.methods.METHODS, default the scenario's integrator; with an
             adaptive method a given dt is its largest step
    progress : True (a bar on a terminal, a few lines in a log: gpme_io.progress), False
             (silent) or a callable given the run's events (gpme_core.progress)
    before_run, max_wall_s : as gpme_core.integrate.simulate
    """
    t_end, settings = _run_settings(scenario, t_end, dt, method, quick, output_dt, max_wall_s)
    df = run(scenario.system, t_end, scenario.q0, scenario.q_dot0, settings,
             progress_callback(progress), before_run).to_frame()
    df.attrs["scenario"] = scenario.name
    return df


def estimate_scenario(scenario, t_end=None, dt=None, method=None, quick=False,
                      output_dt=None):
    """gpme_core.run_cost.RunCost of :func:`simulate_scenario` with the same arguments,
    without running it (gpme_core.integrate.estimate_simulation)."""
    t_end, settings = _run_settings(scenario, t_end, dt, method, quick, output_dt)
    return estimate_simulation(scenario.system, t_end, scenario.q0, scenario.q_dot0, settings)


def events_json(df):
    """The run's events as JSON text: {"dependent": [names at t = 0], "dependent_final":
    [...], "events": df.attrs["events"]} (see gpme_core.integrate.simulate; times in s)."""
    return json.dumps({"dependent": list(df.attrs.get("dependent", [])),
                       "dependent_final": list(df.attrs.get("dependent_final", [])),
                       "events": list(df.attrs.get("events", []))}, indent=2) + "\n"


def write_run_outputs(scenario, df, out_dir, compressed=False):
    """<out_dir>/<name>.csv and <name>_<figure>.png for one run, <name>_motion.html (the
    motion in 3D, gpme_io.animation; a stick figure for a model without shapes), and <name>_events.json
    when the run switched its dependent coordinates; returns {label: path}.  With
    ``compressed`` (verify's report) the history is <name>.csv.gz with
    gpme_io.atomic.HISTORY_DIGITS significant digits instead of full precision."""
    out = Path(out_dir)
    history = named_path(out, scenario.name, ".csv.gz" if compressed else ".csv")
    paths = {history.name: history}
    atomic_write_csv(df, history, HISTORY_DIGITS if compressed else None)
    if df.attrs.get("events"):
        events = named_path(out, scenario.name, "_events.json")
        paths[events.name] = events
        atomic_write_text(events, events_json(df))
    for name, make in figures.FIGURES.items():
        path = named_path(out, scenario.name, f"_{name}")
        atomic_save_figure(make(scenario, df), path)
        paths[path.name] = path
    if scenario.model.n_coordinates:
        path = named_path(out, scenario.name, "_motion.html")
        frames = [f for f in dict.fromkeys(getattr(c, "frame", None)
                                           for c in scenario.constraints) if f]
        title = f"{df.attrs.get('method', 'RK4')}, {float(df['t'].iloc[-1]):g} s"
        written = animation.write_motion(scenario.model, df, path, title, constrained=frames)
        if written is not None:           # None: over the page's size budget, said
            paths[path.name] = written
    return paths
