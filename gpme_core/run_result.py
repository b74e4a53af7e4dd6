"""A run's settings and its result as values: :class:`RunSettings` (how to integrate) in,
:class:`RunResult` (the recorded histories as read-only arrays, the run's metadata as
fields) out.  gpme_core.integrate.run takes and returns them; simulate is run(...).to_frame()
with the settings as keyword arguments.

Units: SI (s, m, rad, N, N m, J) throughout; the columns are those of
gpme_core.integrate.simulate's docstring.
"""
from dataclasses import dataclass, field, fields, replace
from types import MappingProxyType
from typing import Mapping, Optional

import numpy as np
import pandas as pd

from .gpme import SWITCH_RCOND


@dataclass(frozen=True)
class RunSettings:
    """How a run is integrated (gpme_core.integrate.simulate documents each field).

    dt          : s, RK4/RadauIIA step, or an adaptive method's largest step; None: the
                  method's default (RK4: gpme_core.stability.rk4_step at the start)
    method      : one of gpme_core.methods.METHODS
    output_dt   : s, spacing of the recorded rows
    rtol, atol  : the solve_ivp methods' tolerances (1, and the state's units)
    on_manifold : start on the constraints (dependent q, q_dot solved at t = 0)
    switch_rcond: re-choose the dependent coordinates below this partition_rcond (None: never)
    check_step  : RK4: refuse a dt above the stability limit at the start
    max_wall_s  : s, stop the run after this long (None: no limit)
    compiled    : run RK4 and RadauIIA in the compiled loops when the system compiles
    """

    dt: Optional[float] = None
    method: str = "RK4"
    output_dt: float = 1e-3
    rtol: float = 1e-8
    atol: float = 1e-10
    on_manifold: bool = False
    switch_rcond: Optional[float] = SWITCH_RCOND
    check_step: bool = True
    max_wall_s: Optional[float] = None
    compiled: bool = True

    @classmethod
    def names(cls) -> tuple:
        """The settings' names, in order (simulate's keyword arguments)."""
        return tuple(f.name for f in fields(cls))

    def with_changes(self, **changes) -> "RunSettings":
        """A copy with ``changes``; an unknown name is a TypeError naming the known ones."""
        unknown = sorted(set(changes) - set(self.names()))
        if unknown:
            raise TypeError(f"unknown run settings {unknown}; the settings are "
                            f"{list(self.names())}")
        return replace(self, **changes)


def _read_only(values) -> np.ndarray:
    a = np.array(values, dtype=float)
    a.setflags(write=False)
    return a


@dataclass(frozen=True)
class RunResult:
    """The recorded run: ``columns`` {name: (k,) read-only array} in the history's column
    order (t first; gpme_core.integrate.simulate lists them) and the metadata of the run.

    model          : the model's name
    method, dt, rtol, switch_rcond, baumgarte, on_manifold : the run's settings as used
                     (dt after fitting whole steps into output_dt; rtol None for the
                     fixed-step methods; baumgarte (alpha 1/s, beta 1/s))
    wall_time_s    : s, the integration's wall time (compilation and history excluded)
    compiled       : whether the compiled loop ran; compiled_reason why not ("" if it did)
    rhs_evaluations: right-hand-side evaluations (None when not counted)
    dependent, dependent_final : the dependent coordinates at t = 0 and at the end
    events         : one mapping per switch of the dependent coordinates, in order
                     (keys of gpme_core.integrate.RunPartition's records)
    """

    columns: Mapping[str, np.ndarray]
    model: str
    method: str
    dt: Optional[float]
    rtol: Optional[float]
    wall_time_s: float
    compiled: bool
    compiled_reason: str
    rhs_evaluations: Optional[int]
    dependent: tuple
    dependent_final: tuple
    events: tuple
    switch_rcond: Optional[float]
    baumgarte: tuple
    on_manifold: bool
    metadata_names: tuple = field(init=False, repr=False, default=())

    def __post_init__(self):
        object.__setattr__(self, "columns", MappingProxyType(
            {name: _read_only(v) for name, v in self.columns.items()}))
        for name in ("dependent", "dependent_final", "baumgarte"):
            object.__setattr__(self, name, tuple(getattr(self, name)))
        object.__setattr__(self, "events", tuple(MappingProxyType(dict(e))
                                                 for e in self.events))
        object.__setattr__(self, "metadata_names", tuple(
            f.name for f in fields(self) if f.name not in ("columns", "metadata_names")))

    @property
    def t(self) -> np.ndarray:
        """(k,) s, the recorded times."""
        return self.columns["t"]

    def __getitem__(self, name: str) -> np.ndarray:
        """The history column ``name`` ((k,) read-only array)."""
        return self.columns[name]

    def metadata(self) -> dict:
        """The run's metadata as plain values ({field: value}, lists for sequences): what
        :meth:`to_frame` puts in ``DataFrame.attrs``."""
        out = {}
        for name in self.metadata_names:
            value = getattr(self, name)
            if name in ("dependent", "dependent_final"):
                value = list(value)
            elif name == "events":
                value = [dict(e) for e in value]
            out[name] = value
        return out

    def to_frame(self) -> pd.DataFrame:
        """The history as a DataFrame (a copy: one row per recorded time, the columns in
        order) with the metadata in ``df.attrs``."""
        df = pd.DataFrame({name: np.array(v) for name, v in self.columns.items()})
        df.attrs.update(self.metadata())
        return df

