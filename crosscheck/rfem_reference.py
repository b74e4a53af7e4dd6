"""The RFEM discretisation of each flexible link against closed-form beam theory.

Every engine of `gpme verify` receives the same discretised model from gpme, so the
crosschecks cannot see a wrong discretisation (a section constant, an sde spring, a rigid
element's mass).  Here the discretisation is recomputed on its own side from the section's
dimensions and the material constants as the model file (or, for the paper's crane built
in code, gpme_examples.crane.CraneParameters) gives them, with the textbook formulas
written out below (gpme_core.rfem's BeamSection and BeamProperties are not called), and
compared with what the built model holds.

Section constants (m^2, m^4; y, z the section axes of the beam frame, w = width_y,
h = height_z):

* solid circle, diameter d: A = pi d^2/4, I_y = I_z = pi d^4/64, J = pi d^4/32 (exact);
* tube, outer diameter D, wall t, d = D - 2t: A = pi (D^2 - d^2)/4,
  I_y = I_z = pi (D^4 - d^4)/64, J = pi (D^4 - d^4)/32 (exact: a circular tube does not warp);
* rectangle: A = w h, I_y = w h^3/12, I_z = h w^3/12 (exact); J from Saint-Venant's series
  (Timoshenko and Goodier, *Theory of Elasticity*, 3rd ed., sec. 109), a >= b the sides:
  J = (a b^3/3) [1 - (192/pi^5)(b/a) sum_{n odd} tanh(n pi a/(2b))/n^5], summed over the
  first SERIES_TERMS odd n; the tail is below (192/pi^5)/(8 (2N)^4) / 0.37 < 2e-18 of J
  (0.37 bounds the bracket from below).  gpme uses Roark's approximation (Young and Budynas,
  7th ed., table 10.7 case 4), documented to within 0.5 % of the series for every aspect
  ratio, so J of a rectangle, and the torsion spring and damper built from it, are gated
  at ROARK_ACCURACY;
* hollow rectangle, outer w x h, wall t: A = w h - (w-2t)(h-2t), I_y = (w h^3 - (w-2t)(h-2t)^3)/12,
  I_z likewise (exact); J by Bredt's thin-walled formula as docs/rfem.md states it,
  J = 4 A_m^2 t / p_m, A_m = (w-t)(h-t), p_m = 2 (w+h-2t) (the model's definition of J for
  this shape, so compared at round-off).

Discretisation (docs/rfem.md): dl = L/n; sde r (r = 1..n) in the middle of segment r with
springs psi: E I_z/dl, theta: E I_y/dl, phi: G J/dl and dampers eta_E I_z/dl,
eta_E I_y/dl, eta_G J/dl (eta_G = eta_E G/E when the file gives none); rfe 0 and rfe n of
length dl/2, the others dl; an rfe of length l: m = rho A l, centre (l/2, 0, 0) in the
beam frame, I_xx = rho (I_y + I_z) l, I_yy = rho I_y l + m l^2/12, I_zz = rho I_z l + m l^2/12
about its centre.

What the model holds: model.stiffness and model.damping of the coordinates named
psi_<link>_<r>, theta_<link>_<r>, phi_<link>_<r>; the inertia of link <link>_rfe<r> (its
frame is the beam frame at sde r) and, for rfe 0, of the carrying link (the link of the
joint before psi_<link>_1), expressed in the beam frame B = origin(psi_<link>_1) moved back
by dl/2.  An end rfe (0 or n) shares its link with whatever the model attaches there (a
URDF's tool, a motor); such a link is recognised by its centre of mass, which is not that of
one beam piece of its mass (on the beam axis at m/(2 rho A)), and gets an information row.
A rigid link (n = 0) has its section constants compared only.

Rows: engine "gpme", section "rfem", quantities QUANTITIES, one case per link and
constant, rotation or rfe.
"""
from dataclasses import dataclass
from typing import Mapping, Optional

import numpy as np
import pandas as pd

from gpme_core.errors import ModelFileError
from gpme_examples.crane import CraneParameters
from gpme_io.modelfile import read_model_file
from gpme_io.modelfile.schema import CraneSource

from .compare import COLUMNS, Tolerance, compare

SECTION = "rfem"
SECTION_QUANTITY = "section constants vs beam theory"
STIFFNESS_QUANTITY = "RFEM sde stiffness vs beam theory"
DAMPING_QUANTITY = "RFEM sde damping vs beam theory"
MASS_QUANTITY = "RFEM rfe mass vs beam theory"
CENTRE_QUANTITY = "RFEM rfe centre vs beam theory"
INERTIA_QUANTITY = "RFEM rfe inertia vs beam theory"
QUANTITIES = (SECTION_QUANTITY, STIFFNESS_QUANTITY, DAMPING_QUANTITY, MASS_QUANTITY,
              CENTRE_QUANTITY, INERTIA_QUANTITY)

EPS = float(np.finfo(float).eps)
# odd terms of Saint-Venant's series for a rectangle's J (truncation < 2e-18 relative)
SERIES_TERMS = 10_000
# Roark's rectangle J against the series: documented below 0.5 % for every aspect ratio
# (largest 0.49 % near a/b = 1.14, 0.18 % for a square; gpme_core/rfem.py)
ROARK_ACCURACY = 5e-3
# relative: a constant from the same closed form in double precision, each side a product
# of at most ~10 roundings (<= eps/2 each) and, for a tube or hollow rectangle, one
# difference of fourth powers that amplifies the round-off of d = D - 2t by about D/(2t)
# (within 64 eps down to walls of D/100; the shipped tubes have D/t <= 20)
ROUND_OFF_REL = 64 * EPS
# a link "holds one beam piece" when its centre lies on the beam axis at m/(2 rho A) to
# this relative accuracy (round-off is ~1e-15; a merged body moves it by its mass share)
PIECE_MATCH = 1e-9

ROUND_OFF = Tolerance(
    0.0, ROUND_OFF_REL,
    "round-off: the same closed-form beam formula on both sides in double precision, "
    "each a product of ~10 roundings: 64 eps relative")
ROARK = Tolerance(
    0.0, ROARK_ACCURACY,
    "gpme's rectangle J is Roark's approximation (Young and Budynas, table 10.7 case 4), "
    "documented within 0.5 % of Saint-Venant's series for every aspect ratio (0.49 % near "
    "a/b = 1.14); the reference sums 10000 odd terms of the series (truncation < 2e-18)")


@dataclass(frozen=True)
class BeamReference:
    """What the model file (or the crane's parameters) says about one flexible link.

    shape, dimensions : the section (gpme_io.modelfile.schema.SECTION_SHAPES), m
    youngs_modulus, shear_modulus : Pa;  density : kg/m^3
    bending_viscosity, torsion_viscosity : Pa s (torsion None: eta_E G / E)
    length : m, or None when the file leaves it to the geometry (the model's own is used)
    """

    shape: str
    dimensions: Mapping[str, float]
    youngs_modulus: float
    shear_modulus: float
    density: float
    bending_viscosity: float
    torsion_viscosity: Optional[float]
    length: Optional[float]

    @property
    def eta_g(self) -> float:
        """Pa s, the torsion viscosity."""
        if self.torsion_viscosity is not None:
            return self.torsion_viscosity
        return self.bending_viscosity * self.shear_modulus / self.youngs_modulus


# ------------------------------------------------------------------ section constants
def saint_venant_rectangle_j(width: float, height: float, terms: int = SERIES_TERMS) -> float:
    """m^4, torsion constant of a solid width x height rectangle (m) by Saint-Venant's
    series (Timoshenko and Goodier sec. 109), ``terms`` odd terms."""
    a, b = max(width, height), min(width, height)
    n = 2.0 * np.arange(terms) + 1.0
    series = np.sum(np.tanh(n * np.pi * a / (2.0 * b)) / n ** 5)
    return a * b ** 3 / 3.0 * (1.0 - 192.0 / np.pi ** 5 * (b / a) * series)


def section_constants(shape: str, dims: Mapping[str, float]) -> dict:
    """{"A": m^2, "I_y": m^4, "I_z": m^4, "J": m^4} of a section and whether J is exact
    (False: the rectangle, whose J gpme takes from Roark's approximation)."""
    if shape == "circle":
        d = dims["diameter"]
        i = np.pi * d ** 4 / 64.0
        return {"A": np.pi * d ** 2 / 4.0, "I_y": i, "I_z": i, "J": np.pi * d ** 4 / 32.0}
    if shape == "tube":
        d_o = dims["outer_diameter"]
        d_i = d_o - 2.0 * dims["wall_thickness"]
        i = np.pi * (d_o ** 4 - d_i ** 4) / 64.0
        return {"A": np.pi * (d_o ** 2 - d_i ** 2) / 4.0, "I_y": i, "I_z": i,
                "J": np.pi * (d_o ** 4 - d_i ** 4) / 32.0}
    if shape == "rectangle":
        w, h = dims["width_y"], dims["height_z"]
        return {"A": w * h, "I_y": w * h ** 3 / 12.0, "I_z": h * w ** 3 / 12.0,
                "J": saint_venant_rectangle_j(w, h)}
    if shape == "hollow_rectangle":
        w, h, t = dims["width_y"], dims["height_z"], dims["wall_thickness"]
        wi, hi = w - 2.0 * t, h - 2.0 * t
        a_m, p_m = (w - t) * (h - t), 2.0 * (w + h - 2.0 * t)
        return {"A": w * h - wi * hi, "I_y": (w * h ** 3 - wi * hi ** 3) / 12.0,
                "I_z": (h * w ** 3 - hi * wi ** 3) / 12.0, "J": 4.0 * a_m ** 2 * t / p_m}
    raise ValueError(f"unknown section shape {shape!r}")


def _torsion_tolerance(shape: str) -> Tolerance:
    return ROARK if shape == "rectangle" else ROUND_OFF


# ------------------------------------------------------------------ where the numbers are
def beam_references(scenario) -> tuple:
    """({flexible link name: BeamReference}, why) for a scenario; ``why`` says where the
    numbers came from, or why there are none (then the mapping is empty)."""
    if scenario.source is None:
        if str(scenario.model.name).startswith("crane_"):
            return _crane_references(CraneParameters()), \
                "the paper's crane built in code: gpme_examples.crane.CraneParameters()"
        return {}, "built in code without a model file: no section dimensions to read"
    try:
        spec = read_model_file(scenario.source)
    except (ModelFileError, OSError, ValueError) as exc:
        return {}, f"the model file {scenario.source} could not be read again: {exc}"
    if isinstance(spec.model.source, CraneSource):
        return _crane_references(CraneParameters(**dict(spec.model.source.overrides))), \
            f"{scenario.source}: the builtin crane's parameters"
    refs = {f.link: BeamReference(f.section.shape, dict(f.section.dimensions), f.youngs_modulus,
                                  f.shear_modulus, f.density, f.bending_viscosity,
                                  f.torsion_viscosity, f.length)
            for f in spec.flexible}
    return refs, f"{scenario.source}: [[flexible]] tables"


def _crane_references(p) -> dict:
    if p.arm_wall_thickness == 0.0:
        shape, dims = "circle", {"diameter": p.arm_diameter}
    else:
        shape, dims = "tube", {"outer_diameter": p.arm_diameter,
                               "wall_thickness": p.arm_wall_thickness}
    return {"arm": BeamReference(shape, dims, p.steel_youngs_modulus, p.steel_shear_modulus,
                                 p.steel_density, p.arm_viscosity, None, p.arm_length)}


# ------------------------------------------------------------------ rows
def _row(model_name, quantity, case, gpme_value, reference, tol, **kw) -> dict:
    return compare("gpme", model_name, quantity, case, gpme_value, reference, tol, **kw) \
        | {"section": SECTION}


def _info_row(model_name, quantity, case, entry, reason) -> dict:
    # values 0, 0: a number here would count as the check's worst error in the summary
    return _row(model_name, quantity, case, [0.0], [0.0],
                Tolerance(np.inf, 0.0, f"information: {reason}")) | {"entry": entry}


def rfem_rows(scenario) -> list:
    """Rows (dicts of crosscheck.compare.COLUMNS plus section "rfem") comparing every
    flexible link of ``scenario.model`` with closed-form beam theory; [] without flexible
    links."""
    model = scenario.model
    if not model.flexible_links:
        return []
    refs, why = beam_references(scenario)
    rows = []
    for fl in model.flexible_links:
        ref = refs.get(fl.name)
        if ref is None:
            rows.append(_info_row(model.name, SECTION_QUANTITY, fl.name, "no dimensions",
                                  f"not checked: the section dimensions of flexible link "
                                  f"{fl.name!r} were not found ({why})"))
            continue
        rows += _link_rows(model, fl, ref)
    return rows


def _link_rows(model, fl, ref: BeamReference) -> list:
    name, n = fl.name, int(fl.n_segments)
    sec = section_constants(ref.shape, ref.dimensions)
    gpme_sec = {"A": fl.beam.area, "I_y": fl.beam.second_moment_y,
                "I_z": fl.beam.second_moment_z, "J": fl.beam.torsion_constant}
    rows = [_row(model.name, SECTION_QUANTITY, f"{name}: {key} ({ref.shape})", gpme_sec[key],
                 sec[key], _torsion_tolerance(ref.shape) if key == "J" else ROUND_OFF,
                 labels=[key]) for key in ("A", "I_y", "I_z", "J")]
    if n == 0:
        return rows
    length = ref.length if ref.length is not None else float(fl.beam.length)
    dl = length / n
    e, g = ref.youngs_modulus, ref.shear_modulus
    springs = {"psi": e * sec["I_z"] / dl, "theta": e * sec["I_y"] / dl, "phi": g * sec["J"] / dl}
    dampers = {"psi": ref.bending_viscosity * sec["I_z"] / dl,
               "theta": ref.bending_viscosity * sec["I_y"] / dl,
               "phi": ref.eta_g * sec["J"] / dl}
    index = {nm: k for k, nm in enumerate(model.coordinate_names)}
    for quantity, values, held in ((STIFFNESS_QUANTITY, springs, model.stiffness),
                                   (DAMPING_QUANTITY, dampers, model.damping)):
        for rot, value in values.items():
            names = [f"{rot}_{name}_{r}" for r in range(1, n + 1)]
            got = [held[index[c]] if c in index else np.nan for c in names]
            tol = _torsion_tolerance(ref.shape) if rot == "phi" else ROUND_OFF
            rows.append(_row(model.name, quantity, f"{name} {rot}", got, [value] * n, tol,
                             labels=names))
    rows += _rfe_rows(model, name, n, dl, ref, sec, index)
    return rows


def _piece(rho, sec, length):
    """(m kg, centre (3,) m, I (3, 3) kg m^2 about the centre) of a beam piece of
    ``length`` m from the beam frame's origin along +x."""
    m = rho * sec["A"] * length
    inertia = np.diag([rho * (sec["I_y"] + sec["I_z"]) * length,
                       rho * sec["I_y"] * length + m * length ** 2 / 12.0,
                       rho * sec["I_z"] * length + m * length ** 2 / 12.0])
    return m, np.array([0.5 * length, 0.0, 0.0]), inertia


def _rfe_rows(model, name, n, dl, ref, sec, index) -> list:
    links = {lk.name: k for k, lk in enumerate(model.links)}
    first = index.get(f"psi_{name}_1")
    gated, rows = [], []
    for r in range(n + 1):
        length = 0.5 * dl if r in (0, n) else dl
        label = f"{name}_rfe{r}"
        if r == 0:
            k = None if first is None else first - 1
            # beam frame B in the carrying link: psi_1's origin moved back by dl/2 along x
            t_link_b = None if first is None else \
                model.origins[first] @ _translation_x(-0.5 * dl)
        else:
            k = links.get(label)
            t_link_b = np.eye(4)
        held = None if k is None else model.links[k].inertia
        m_ref, c_ref, i_ref = _piece(ref.density, sec, length)
        if held is None:
            gated.append((label, length, (np.nan, np.full(3, np.nan), np.full((3, 3), np.nan)),
                          (m_ref, c_ref, i_ref), 0.0))
            continue
        rot, p = t_link_b[:3, :3], t_link_b[:3, 3]
        m = float(held.mass)
        c = rot.T @ (np.asarray(held.com, dtype=float) - p)
        inertia = rot.T @ np.asarray(held.inertia, dtype=float) @ rot
        one_piece = m > 0 and np.all(np.abs(c[1:]) <= PIECE_MATCH * length) and \
            abs(c[0] - 0.5 * m / (ref.density * sec["A"])) <= PIECE_MATCH * length
        if r in (0, n) and not one_piece:
            rows.append(_info_row(
                model.name, INERTIA_QUANTITY, f"{name} {label}", label,
                f"not compared: the link holding {label} also carries other bodies (its "
                f"{m:.6g} kg have their centre at {np.round(c, 6).tolist()} m in the beam "
                f"frame, not that of one beam piece; the rfe alone: {m_ref:.6g} kg at "
                f"{0.5 * length:.6g} m on the axis)"))
            continue
        gated.append((label, length, (m, c, inertia), (m_ref, c_ref, i_ref),
                      float(np.linalg.norm(p))))
    if not gated:
        return rows
    labels = [g[0] for g in gated]
    rows.append(_row(model.name, MASS_QUANTITY, name, [g[2][0] for g in gated],
                     [g[3][0] for g in gated], ROUND_OFF, labels=labels))
    offset = max(g[4] for g in gated)
    centre_tol = Tolerance(
        8 * EPS * offset, ROUND_OFF_REL,
        f"round-off: 64 eps relative, plus 8 eps x {offset:.3g} m (the offset of the beam "
        "frame in the link of rfe 0, subtracted from the link's centre)")
    rows.append(_row(model.name, CENTRE_QUANTITY, name, np.array([g[2][1] for g in gated]),
                     np.array([g[3][1] for g in gated]), centre_tol,
                     labels=(labels, ["x", "y", "z"])))
    for label, length, (m, _, inertia), (m_ref, _, i_ref), offset in gated:
        tol = Tolerance(
            16 * EPS * m_ref * (offset + length) ** 2, ROUND_OFF_REL,
            f"round-off: 64 eps relative, plus 16 eps m (|p| + l)^2 = the cancellation of "
            f"the m c c^T terms when the link's pseudo-inertia, summed about the link origin "
            f"(offset |p| = {offset:.3g} m), is taken back to the centre")
        rows.append(_row(model.name, INERTIA_QUANTITY, f"{name} {label}", inertia, i_ref, tol,
                         labels=(["x", "y", "z"], ["x", "y", "z"])))
    return rows


def _translation_x(x: float) -> np.ndarray:
    t = np.eye(4)
    t[0, 3] = x
    return t


def rows_frame(rows) -> pd.DataFrame:
    """DataFrame of rfem rows (section "rfem"), with the compare columns when empty."""
    return pd.DataFrame(rows, columns=[*COLUMNS, "section"])
