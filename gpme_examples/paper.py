"""The paper's two simulations (section 3): the crane with rigid links and flexible support,
and with the flexible arm and flexible support, 10 s of programmed motion.

They are run like every model (gpme_io.scenario.crane_scenario, the scenario that
models/crane_rigid.toml and models/crane_flexible.toml describe, through
gpme_io.runs.simulate_scenario); what is special about them is said here, once, and used as
a hook by the writers (gpme_io.example_outputs): which runs are the paper's (a scenario whose
``example`` is :data:`EXAMPLE`) and how they are named in the paper's figures.  The figures
themselves are drawn by gpme_io.paper_figures (examples return data, never files).
"""
# the runs' settings (DEFAULT_N_RFE, T_END, QUICK_T_END, DEFAULT_DT) live in crane.py with
# every other number of the example; they are read here too, as paper.T_END etc.
from .crane import (DEFAULT_DT, DEFAULT_N_RFE, QUICK_T_END, T_END, CraneParameters,
                    build_crane)
from gpme_core.elastic_loads import elastic_peaks

__all__ = ["CASES", "DEFAULT_DT", "DEFAULT_N_RFE", "EXAMPLE", "QUICK_T_END", "T_END",
           "arm_segments", "case_name", "figure_runs", "step_name", "summary"]

# Scenario.example of the paper's crane runs (gpme_io.scenario.crane_scenario)
EXAMPLE = "crane"
# the paper's two runs: case name -> RFEM segments of the arm (0 = rigid)
CASES = {"rigid": 0, "flexible": DEFAULT_N_RFE}


def case_name(n_rfe: int) -> str:
    """The paper's name of a crane run with ``n_rfe`` arm segments: "rigid" (0) or
    "flexible"."""
    return "rigid" if n_rfe == 0 else "flexible"


def arm_segments(scenario) -> int:
    """RFEM segments of the crane's arm in ``scenario`` (a gpme_io.scenario.Scenario of the
    crane; 0 for the rigid arm)."""
    return sum(link.n_segments for link in scenario.model.flexible_links)


def step_name(scenario):
    """"the paper's step" when ``scenario`` is a crane run at one of the paper's RK4 steps
    (DEFAULT_DT), else None (the caller names the step otherwise)."""
    if getattr(scenario, "example", None) == EXAMPLE and scenario.dt in DEFAULT_DT.values():
        return "the paper's step"
    return None


def figure_runs(runs) -> dict:
    """{case name: history DataFrame} of the paper's figures (gpme_io.paper_figures), from
    ``runs``, a sequence of (scenario, history) pairs; only the crane's runs (scenario.example
    == EXAMPLE) are taken, the rigid one first, and empty when there are none.  A case run
    twice (two flexible arms) is named by its segments: "flexible (n_rfe=5)"."""
    crane_runs = sorted(((arm_segments(s), df) for s, df in runs
                         if getattr(s, "example", None) == EXAMPLE), key=lambda pair: pair[0])
    names = [case_name(n) for n, _ in crane_runs]
    return {(name if names.count(name) == 1 else f"{name} (n_rfe={n})"): df
            for name, (n, df) in zip(names, crane_runs)}


def summary(df, n_rfe, transient=2.0, params=CraneParameters()):
    """Largest |Phi_1|, |Phi_2| after ``transient`` s, the wall time and step count, and
    the arm's peak sde angles and bending stress (gpme_core.elastic_loads; flexible runs)
    of a crane run with ``n_rfe`` arm segments."""
    late = df[df.t >= transient]
    peaks = elastic_peaks(build_crane(n_rfe, params), df, {"arm": params.arm_yield_strength}) \
        if n_rfe else []
    return {"case": case_name(n_rfe), "n_rfe": n_rfe,
            "max_abs_Phi_1_after_transient": float(late.Phi_1.abs().max()),
            "max_abs_Phi_2_after_transient": float(late.Phi_2.abs().max()),
            "wall_time_s": df.attrs.get("wall_time_s"), "dt": df.attrs.get("dt"),
            "method": df.attrs.get("method"),
            "elastic_peaks": [p.as_record() for p in peaks]}
