"""A scenario: everything one model file describes, ready for the engine and the crosschecks.

A :class:`Scenario` is what ``gpme simulate|crosscheck|verify|sweep --model FILE`` work on:
the validated gpme model, its programmed constraints (already bound in a
:class:`gpme_core.gpme.ProgrammedMotion` with the dependent coordinates fixed), the initial
state, how to integrate it, where the model came from (URDF, chain, frozen joints) and
what the reader left out (``notes``), and the tolerance overrides the file asks for.

Scenarios are built by gpme_io.modelfile (from a TOML file) or, for the paper's crane
without a file, by :func:`crane_scenario`.  Immutable: arrays are read-only and the
mappings are read-only views.
"""
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Mapping, Optional

import numpy as np
from numpy.typing import NDArray

from gpme_core.gpme import ProgrammedMotion
from gpme_core.methods import METHODS
from gpme_core.model import Model
from gpme_core.stability import rk4_step
from gpme_examples import crane, paper

INTEGRATORS = METHODS            # gpme_core.methods


@dataclass(frozen=True)
class ToleranceOverride:
    """A tolerance a model file sets for one check, with its reason.

    check  : "<engine>/<quantity>", e.g. "pinocchio/M" or "mujoco/exact run psi2"
    abs    : in the quantity's unit
    rel    : normwise, relative to the largest entry of the reference value
    reason : why this tolerance holds for this model (shown in every report row it gates)
    """

    check: str
    abs: float
    rel: float
    reason: str


@dataclass(frozen=True)
class EngineStep:
    """The first (coarsest) step a model file sets for an engine with its own integrator,
    with its reason; the harness still halves it as long as the engine's runs are not in
    their asymptotic regime (crosscheck.convergence), at most ``max_halvings`` times.

    engine : "drake" or "exudyn" (Pinocchio's and MuJoCo's runs use gpme's RK4 step)
    dt     : s, > 0
    reason : why this step (shown in the report's case text and in every row's case)
    max_halvings : halvings allowed beyond the first three runs (None: the harness's)
    """

    engine: str
    dt: float
    reason: str
    max_halvings: Optional[int] = None


@dataclass(frozen=True)
class ReferenceValues:
    """Published values of the motion at one time, which a run must reproduce (a model
    file's [[reference]]; crosscheck.reference_values makes the report rows).

    key    : the entry's key path in the file ("reference[0]")
    t      : s, the time of the values (a sample time of the run)
    values : {column: value}: coordinates (rad or m) by name, velocities as <name>_dot
    abs    : allowed |run - value| in each group's unit (coordinates, velocities), plus
    rel    : times the group's largest |value| (normwise, as every tolerance here)
    source : where the values are published (shown in the rows)
    reason : why this tolerance holds (the source's stated or demonstrated precision)
    """

    key: str
    t: float
    values: Mapping[str, float]
    abs: float
    rel: float
    source: str
    reason: str

    def __post_init__(self):
        object.__setattr__(self, "values", MappingProxyType(dict(self.values)))


@dataclass(frozen=True)
class Scenario:
    """One model and task, ready to run and to compare.

    name        : the scenario's name (report label)
    model       : gpme_core.model.Model (validated, immutable)
    constraints : tuple of constraint specs (gpme_core.constraints), as given
    system      : ProgrammedMotion of model and constraints, dependent coordinates fixed
    q0, q_dot0  : (n,) initial state, ordered as model.coordinate_names (rad, m; rad/s, m/s)
    t_end       : s, length of the full run
    quick_t_end : s, length of the CI-sized run (``--quick``)
    integrator  : one of INTEGRATORS
    dt          : s, RK4 step (None: gpme_core.stability.rk4_step at q0, gpme_io.runs.resolved_step)
    output_dt   : s, spacing of the recorded samples
    source      : the model file (None when built in code)
    urdf        : the user's URDF (None for models built in code, e.g. the crane)
    chain       : (root link, tip link) used from the URDF tree, or None
    frozen      : {URDF joint name: value (rad or m)} joints held fixed off the chain
    notes       : what the reader accepted but left out of M, h, g (friction, limits, ...)
                  and what it replaced (a link's inertial by its RFEM beam), one line each
    tolerances  : {check: ToleranceOverride}
    engine_steps: {engine: EngineStep}, the model file's first steps of drake and exudyn
    on_constraints: whether q0, q_dot0 were placed on the constraints
    yield_strengths: {flexible link name: Pa}, the links whose elasticity can be judged
                  (gpme_core.elastic_loads)
    example     : the built-in example the scenario is a run of (gpme_examples.paper.EXAMPLE
                  for the paper's crane runs: their figures are added by
                  gpme_io.example_outputs), None for a model file's
    references  : ReferenceValues, published values the runs are checked against
    """

    name: str
    model: Model
    constraints: tuple
    system: ProgrammedMotion
    q0: NDArray[np.float64]
    q_dot0: NDArray[np.float64]
    t_end: float
    quick_t_end: float
    integrator: str = "RK4"
    dt: Optional[float] = None
    output_dt: float = 1e-3
    source: Optional[Path] = None
    urdf: Optional[Path] = None
    chain: Optional[tuple] = None
    frozen: Mapping[str, float] = field(default_factory=dict)
    notes: tuple = ()
    tolerances: Mapping[str, ToleranceOverride] = field(default_factory=dict)
    on_constraints: bool = False
    yield_strengths: Mapping[str, float] = field(default_factory=dict)
    engine_steps: Mapping[str, EngineStep] = field(default_factory=dict)
    example: Optional[str] = None
    references: tuple = ()

    def __post_init__(self):
        for name in ("q0", "q_dot0"):
            a = np.array(getattr(self, name), dtype=float)
            a.setflags(write=False)
            object.__setattr__(self, name, a)
        object.__setattr__(self, "frozen", MappingProxyType(dict(self.frozen)))
        object.__setattr__(self, "tolerances", MappingProxyType(dict(self.tolerances)))
        object.__setattr__(self, "engine_steps", MappingProxyType(dict(self.engine_steps)))
        object.__setattr__(self, "yield_strengths",
                           MappingProxyType(dict(self.yield_strengths)))
        object.__setattr__(self, "constraints", tuple(self.constraints))
        object.__setattr__(self, "notes", tuple(self.notes))
        object.__setattr__(self, "references", tuple(self.references))

    @property
    def flexible_coordinates(self):
        """Names of the RFEM coordinates (psi, theta, phi of every sde), in model order."""
        return self.model.flexible_coordinates

    def t_run(self, quick):
        """s, run length for a full or a quick (CI) run."""
        return self.quick_t_end if quick else self.t_end

    def tolerance(self, engine, quantity):
        """The ToleranceOverride of "<engine>/<quantity>", or None."""
        return self.tolerances.get(f"{engine}/{quantity}")


def crane_scenario(n_rfe=0, on_constraints=False, static_arm=False):
    """The paper's crane as a Scenario (rigid for n_rfe = 0, else n_rfe RFEM segments),
    with the paper's off-manifold start unless ``on_constraints``.  The model files
    models/crane_rigid.toml and models/crane_flexible.toml describe the same."""
    params = crane.CraneParameters()
    system = crane.crane_system(n_rfe, params)
    q0, qd0 = crane.initial_state(system.model, params, static_arm=static_arm and n_rfe > 0)
    if on_constraints:
        q0, qd0 = system.consistent_state(0.0, q0, qd0)
    case = "rigid" if n_rfe == 0 else "flexible"
    dt = crane.DEFAULT_DT[case]
    if n_rfe > crane.DEFAULT_N_RFE:
        # the paper's step is set for n_rfe = 3; finer arms have stiffer torsion modes
        dt = rk4_step(system, q0, cap=dt)
    return Scenario(name=system.model.name, model=system.model,
                    constraints=tuple(crane.crane_constraints(params)), system=system,
                    q0=q0, q_dot0=qd0, t_end=crane.T_END, quick_t_end=crane.QUICK_T_END,
                    integrator="RK4",
                    dt=dt, output_dt=1e-3, on_constraints=on_constraints,
                    example=paper.EXAMPLE,
                    yield_strengths={f.name: params.arm_yield_strength
                                     for f in system.model.flexible_links})
