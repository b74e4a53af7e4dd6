"""The parsed, validated content of a model file: typed, frozen dataclasses.

gpme_io.modelfile.load fills them from the TOML text (every value checked, units SI);
gpme_io.modelfile.build turns them into a gpme_io.scenario.Scenario.  Nothing here
reads files or builds models.  ``key`` fields hold the entry's key path in the file
(e.g. ``"constraint[1]"``, counted from 0 in file order) for messages.
docs/models.md describes every key.
"""
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Mapping, Optional, Union

import sympy as sp

from gpme_core.time_functions import TimeFunction
from gpme_io.scenario import EngineStep, ToleranceOverride

BUILTIN_MODELS = ("crane",)
SECTION_SHAPES = {"circle": ("diameter",), "tube": ("outer_diameter", "wall_thickness"),
                  "rectangle": ("width_y", "height_z"),
                  "hollow_rectangle": ("width_y", "height_z", "wall_thickness")}
CONSTRAINT_KINDS = ("expression", "ellipse", "coordinate", "relative", "distance",
                    "coincident", "aligned", "weld")
# kinds between two frames (gpme_core.pair_constraints), with the rows each makes
PAIR_KINDS = ("relative", "distance", "coincident", "aligned", "weld")
AXES = {"x": 0, "y": 1, "z": 2}
# units of the symbols of each kind of expression
POINT_SYMBOLS = {"x": "m", "y": "m", "z": "m", "t": "s"}
TIME_SYMBOLS = {"t": "s"}
PAIR_SYMBOLS = {"x_a": "m", "y_a": "m", "z_a": "m", "x_b": "m", "y_b": "m", "z_b": "m",
                "t": "s"}


def _frozen_map(obj, name):
    object.__setattr__(obj, name, MappingProxyType(dict(getattr(obj, name))))


@dataclass(frozen=True)
class CraneSource:
    """``builtin = "crane"``: gpme_examples.crane with CraneParameters ``overrides``
    (mechanism fields only) and ``n_rfe`` RFEM segments of the arm (0 = rigid)."""

    overrides: Mapping[str, object] = field(default_factory=dict)
    n_rfe: int = 0

    def __post_init__(self):
        _frozen_map(self, "overrides")


@dataclass(frozen=True)
class UrdfSource:
    """``urdf = "..."``: ``path`` resolved (relative to the model file, or inside the
    example-robot-data package), ``written`` as in the file, optional side file."""

    path: Path
    written: str
    side_file: Optional[Path] = None


@dataclass(frozen=True)
class ModelSection:
    """[model]: name, source, gravity (3,) m/s^2 in the world frame."""

    name: str
    source: Union[CraneSource, UrdfSource]
    gravity: tuple


@dataclass(frozen=True)
class ChainSection:
    """[chain]: the serial chain from link ``root`` to link ``tip`` of the URDF tree (None:
    the reader's default), joints off the chain held at ``frozen`` {joint: rad or m}."""

    root: Optional[str] = None
    tip: Optional[str] = None
    frozen: Mapping[str, float] = field(default_factory=dict)

    def __post_init__(self):
        _frozen_map(self, "frozen")


@dataclass(frozen=True)
class TreeSection:
    """[tree]: every moving joint of the URDF below link ``root`` (None: the URDF root) is a
    coordinate (a tree whose branches all move), except the joints held at ``frozen``
    {joint: rad or m}."""

    root: Optional[str] = None
    frozen: Mapping[str, float] = field(default_factory=dict)

    def __post_init__(self):
        _frozen_map(self, "frozen")


@dataclass(frozen=True)
class SectionSpec:
    """A beam cross-section: ``shape`` in SECTION_SHAPES with its ``dimensions`` (m)."""

    shape: str
    dimensions: Mapping[str, float]

    def __post_init__(self):
        _frozen_map(self, "dimensions")


@dataclass(frozen=True)
class FlexibleSpec:
    """[[flexible]]: URDF link ``link`` as an RFEM beam.

    youngs_modulus, shear_modulus : Pa;  density : kg/m^3;  segments : RFEM segments (>= 0)
    bending_viscosity, torsion_viscosity : Pa s (Kelvin-Voigt; torsion None: eta_E G / E)
    axis (3,), section_y_axis (3,) : in the link frame (None: from the geometry)
    length : m (None: from the geometry)
    yield_strength : Pa, optional; enables the elasticity warning of gpme_core.elastic_loads
    """

    key: str
    link: str
    section: SectionSpec
    youngs_modulus: float
    shear_modulus: float
    density: float
    segments: int
    bending_viscosity: float
    torsion_viscosity: Optional[float] = None
    axis: Optional[tuple] = None
    length: Optional[float] = None
    section_y_axis: Optional[tuple] = None
    yield_strength: Optional[float] = None


@dataclass(frozen=True)
class JointSpec:
    """[[joint]]: spring and damper of chain joint ``name`` (None: keep the source's).

    stiffness : N m/rad or N/m;  spring_reference : rad or m;  damping : N m s/rad or N s/m
    """

    key: str
    name: str
    stiffness: Optional[float] = None
    spring_reference: Optional[float] = None
    damping: Optional[float] = None


@dataclass(frozen=True)
class DriveSpec:
    """[[drive]]: a generalized force (N or N m) ``function`` of time on coordinate ``joint``."""

    key: str
    joint: str
    function: TimeFunction


@dataclass(frozen=True)
class PointSpringSpec:
    """[[point_spring]]: a spring-damper from the origin of frame ``frame`` to ``anchor``
    (a world point (3,) m, or another frame's name); stiffness N/m, free_length m,
    damping N s/m (gpme_core.point_springs)."""

    key: str
    name: str
    frame: str
    anchor: Union[str, tuple]
    stiffness: float
    free_length: float
    damping: float = 0.0


@dataclass(frozen=True)
class ExpressionConstraintSpec:
    """[[constraint]] phi(x, y, z, t) = 0 on the world position (m) of frame ``frame``."""

    key: str
    name: str
    frame: str
    phi: sp.Expr
    text: str


@dataclass(frozen=True)
class EllipseConstraintSpec:
    """[[constraint]] kind = "ellipse": ((x - xc)/a)^2 + ((y - yc)/b)^2 - 1 = 0 (m)."""

    key: str
    name: str
    frame: str
    a: float
    b: float
    center: tuple


@dataclass(frozen=True)
class CoordinateConstraintSpec:
    """[[constraint]] kind = "coordinate": world coordinate ``axis`` (0 x, 1 y, 2 z) of the
    frame's origin follows ``function`` (m) of time."""

    key: str
    name: str
    frame: str
    axis: int
    function: TimeFunction


@dataclass(frozen=True)
class PairConstraintSpec:
    """[[constraint]] between two frames ``frames`` = (a, b) (gpme_core.pair_constraints):

    kind "relative"  : world coordinate ``axis`` (0 x, 1 y, 2 z) of b's origin relative to
                       a's follows ``function`` (m)
    kind "distance"  : |p_b - p_a| follows ``function`` (m)
    kind "coincident": the origins coincide along ``axes`` (a string of x, y, z)
    kind "aligned"   : b has a's orientation (3 rows)
    kind "weld"      : coincident and aligned (6 rows)
    kind "expression": phi(x_a, y_a, z_a, x_b, y_b, z_b, t) = ``phi`` (m and s)
    """

    key: str
    name: str
    kind: str
    frames: tuple
    axis: Optional[int] = None
    axes: str = "xyz"
    function: Optional[TimeFunction] = None
    phi: Optional[sp.Expr] = None
    text: Optional[str] = None

    @property
    def row_names(self) -> tuple:
        """The names of the constraint rows this entry makes (output columns)."""
        if self.kind == "coincident":
            return tuple(f"{self.name}_{a}" for a in self.axes)
        rotations = tuple(f"{self.name}_r{a}" for a in "xyz")
        if self.kind == "aligned":
            return rotations
        if self.kind == "weld":
            return tuple(f"{self.name}_{a}" for a in "xyz") + rotations
        return (self.name,)


ConstraintSpec = Union[ExpressionConstraintSpec, EllipseConstraintSpec, CoordinateConstraintSpec,
                       PairConstraintSpec]


def constraint_frames(c) -> tuple:
    """The frames a [[constraint]] entry names: (frame,) or (a, b)."""
    return tuple(c.frames) if isinstance(c, PairConstraintSpec) else (c.frame,)


def constraint_rows(c) -> tuple:
    """The row names of a [[constraint]] entry (one for a point constraint)."""
    return c.row_names if isinstance(c, PairConstraintSpec) else (c.name,)


@dataclass(frozen=True)
class ProgrammeSpec:
    """[[programme]]: coordinate ``joint`` follows q(t) = ``expression`` (rad or m)."""

    key: str
    joint: str
    expression: sp.Expr
    text: str
    name: Optional[str] = None


@dataclass(frozen=True)
class SolverSpec:
    """[solver]: dependent coordinates (None: chosen by pivoting at q0) and Baumgarte
    (alpha, beta) in 1/s."""

    dependent: Optional[tuple] = None
    baumgarte: tuple = (20.0, 20.0)


@dataclass(frozen=True)
class InitialSpec:
    """[initial]: q {coordinate: rad or m} (others: their spring reference), q_dot
    {coordinate: rad/s or m/s} (others 0), on_constraints, static_flexible."""

    q: Mapping[str, float] = field(default_factory=dict)
    q_dot: Mapping[str, float] = field(default_factory=dict)
    on_constraints: bool = False
    static_flexible: bool = False

    def __post_init__(self):
        _frozen_map(self, "q")
        _frozen_map(self, "q_dot")


@dataclass(frozen=True)
class RunSpec:
    """[run]: t_end, quick_t_end, dt (RK4 step, None: suggested), output_dt, all in s."""

    t_end: float
    quick_t_end: float
    integrator: str = "RK4"
    dt: Optional[float] = None
    output_dt: float = 1e-3


@dataclass(frozen=True)
class ModelFile:
    """Everything a model file says, validated (entries that failed are left out, so a
    ModelFile with problems is only used to find more problems, never built)."""

    path: Path
    model: Optional[ModelSection]
    chain: Optional[ChainSection] = None
    tree: Optional[TreeSection] = None
    flexible: tuple = ()
    joints: tuple = ()
    drives: tuple = ()
    point_springs: tuple = ()   # PointSpringSpec, in file order
    constraints: tuple = ()
    programmes: tuple = ()
    solver: SolverSpec = SolverSpec()
    initial: InitialSpec = InitialSpec()
    run: Optional[RunSpec] = None
    tolerances: tuple = ()      # ToleranceOverride, in file order
    references: tuple = ()      # gpme_io.scenario.ReferenceValues, in file order
    engine_steps: tuple = ()    # EngineStep, in file order

    @property
    def n_constraints(self) -> int:
        """Constraint rows: a [[constraint]] between two frames may make several."""
        return sum(len(constraint_rows(c)) for c in self.constraints) + len(self.programmes)

    def tolerance_map(self) -> Mapping[str, ToleranceOverride]:
        return {t.check: t for t in self.tolerances}

    def engine_step_map(self) -> Mapping[str, EngineStep]:
        return {s.engine: s for s in self.engine_steps}
