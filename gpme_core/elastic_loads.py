"""Peak elastic deformation and bending stress of the RFEM links along a run, with the limits
of the model's validity.

The RFEM spring-damping elements (sde) are linear springs on the three Euler angles
(psi about z, theta about y, phi about x; gpme_core.rfem) of a linear-elastic beam.  Two
assumptions can fail during a run, and this module measures both:

* **small angles**: the sde rotation R = Rz(psi) Ry(theta) Rx(phi) is treated as a vector
  of independent angles; the neglected coupling between them is of second order, a
  relative error ~ angle.  SMALL_ANGLE_LIMIT = 0.05 rad keeps it below 5 % of the spring
  moment (and sin(angle) = angle to 0.04 %).
* **elasticity**: the peak bending stress of an sde (BeamProperties.bending_stress, from the
  spring moments) must stay below the material's yield strength divided by
  STRESS_SAFETY_FACTOR = 1.5 (the usual design margin on the yield strength of steel
  structures against combined load and material uncertainty).  Only where the yield
  strength of the link is known (``yield_strengths``) can this be judged; the peak stress is
  reported always.

Axial, shear and torsional stresses are not included in the stress (torsion appears as the
peak torsion angle).
"""
from dataclasses import dataclass
from typing import Mapping, Optional

import numpy as np

from .errors import ModelError
from .rfem import sde_coordinate_name

SMALL_ANGLE_LIMIT = 0.05        # rad, see the module docstring
STRESS_SAFETY_FACTOR = 1.5      # yield strength / allowed stress


@dataclass(frozen=True)
class ElasticPeak:
    """Peaks of one RFEM link over a run.

    link                 : name of the flexible link (Model.flexible_links[..].name)
    n_segments           : its number of RFEM segments
    bending_angle        : rad, max over sdes and time of sqrt(psi^2 + theta^2)
    bending_sde, bending_time : sde number (1..n) and time (s) of that peak
    torsion_angle        : rad, max |phi|
    torsion_sde, torsion_time
    bending_stress       : Pa, max peak bending stress (nan: the section's extreme fibres
                           are unknown)
    stress_sde, stress_time
    yield_strength       : Pa or None (unknown: no elasticity verdict)
    """

    link: str
    n_segments: int
    bending_angle: float
    bending_sde: int
    bending_time: float
    torsion_angle: float
    torsion_sde: int
    torsion_time: float
    bending_stress: float
    stress_sde: int
    stress_time: float
    yield_strength: Optional[float] = None

    @property
    def allowed_stress(self):
        """Pa, yield_strength / STRESS_SAFETY_FACTOR (None when the yield strength is unknown)."""
        if self.yield_strength is None:
            return None
        return self.yield_strength / STRESS_SAFETY_FACTOR

    def warnings(self):
        """Sentences, one per limit exceeded (empty when the run stayed in the valid regime)."""
        out = []
        for label, angle, sde, t in (("bending", self.bending_angle, self.bending_sde,
                                      self.bending_time),
                                     ("torsion", self.torsion_angle, self.torsion_sde,
                                      self.torsion_time)):
            if angle > SMALL_ANGLE_LIMIT:
                out.append(f"{self.link}: peak {label} angle {angle:.3g} rad at sde {sde}, "
                           f"t = {t:.3g} s exceeds the small-angle limit {SMALL_ANGLE_LIMIT} "
                           "rad of the linear RFEM springs on Euler angles")
        allowed = self.allowed_stress
        if allowed is not None and self.bending_stress > allowed:
            out.append(f"{self.link}: peak bending stress {self.bending_stress / 1e6:.4g} MPa "
                       f"at sde {self.stress_sde}, t = {self.stress_time:.3g} s exceeds yield "
                       f"{self.yield_strength / 1e6:.4g} MPa / {STRESS_SAFETY_FACTOR} = "
                       f"{allowed / 1e6:.4g} MPa: the beam would not stay elastic")
        return out

    def as_record(self):
        """Flat dict for JSON/CSV (angles rad, stresses Pa, times s)."""
        rec = {k: getattr(self, k) for k in self.__dataclass_fields__}
        rec["allowed_stress"] = self.allowed_stress
        rec["warnings"] = self.warnings()
        return rec


def _argmax_2d(values):
    """(value, row, column) of the largest entry of a (rows, cols) array."""
    flat = int(np.argmax(values))
    row, col = np.unravel_index(flat, values.shape)
    return float(values[row, col]), int(row), int(col)


def elastic_peaks(model, history, yield_strengths: Optional[Mapping[str, float]] = None):
    """[ElasticPeak] of every flexible link of ``model`` over ``history``.

    history         : DataFrame with a column ``t`` (s) and one per coordinate name (rad)
    yield_strengths : {link name: Pa}, optional, links without an entry get no stress verdict
    """
    yield_strengths = dict(yield_strengths or {})
    unknown = sorted(set(yield_strengths) - {f.name for f in model.flexible_links})
    bad = [f"yield strength given for {name!r}, which is not a flexible link of "
           f"{model.name!r} (flexible: {[f.name for f in model.flexible_links]})"
           for name in unknown]
    bad += [f"yield strength of {name!r} must be a positive finite number of Pa, got {v!r}"
            for name, v in yield_strengths.items()
            if not (isinstance(v, (int, float)) and np.isfinite(v) and v > 0)]
    if bad:
        raise ModelError(bad)
    t = history["t"].to_numpy()
    peaks = []
    for flex in model.flexible_links:
        n = flex.n_segments
        if n < 1:
            continue

        def angles(rotation):
            cols = [sde_coordinate_name(flex.name, r, rotation) for r in range(1, n + 1)]
            missing = [c for c in cols if c not in history.columns]
            if missing:
                raise ModelError([f"history lacks the RFEM coordinates {missing} of link "
                                  f"{flex.name!r}"])
            return history[cols].to_numpy()          # (samples, n) rad

        psi, theta, phi = angles("psi"), angles("theta"), angles("phi")
        bend, i_b, r_b = _argmax_2d(np.hypot(psi, theta))
        tors, i_t, r_t = _argmax_2d(np.abs(phi))
        beam = flex.beam
        if beam.extreme_fibre_y is None or beam.extreme_fibre_z is None:
            stress, i_s, r_s = float("nan"), 0, -1
        else:
            stress, i_s, r_s = _argmax_2d(beam.bending_stress(psi, theta, n))
        peaks.append(ElasticPeak(flex.name, n, bend, r_b + 1, float(t[i_b]), tors, r_t + 1,
                                 float(t[i_t]), stress, r_s + 1, float(t[i_s]),
                                 yield_strengths.get(flex.name)))
    return peaks
