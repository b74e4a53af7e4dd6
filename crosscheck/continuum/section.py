"""The continuum section data of an RFEM beam (gpme_core.rfem.BeamProperties).

Section frame: x along the beam, y and z the principal axes (I_y = int z^2 dA bends about
y, deflection along z).  Strain order of Exudyn's geometrically exact beam (checked in
tests/test_continuum.py on a cantilever against P L^3 / (3 E I)):
(axial, shear y, shear z, torsion, curvature about y, curvature about z), so

    stiffness = diag(E A, k G A, k G A, G J, E I_y, E I_z)        (N, N, N, N m^2 x3)
    damping   = diag(eta_E A, k eta_G A, k eta_G A, eta_G J, eta_E I_y, eta_E I_z)
    mass per length rho A (kg/m), rotary inertia per length rho diag(I_y + I_z, I_y, I_z)
    (kg m; about x, y, z).

RFEM keeps neither axial nor shear flexibility; the continuum keeps both, so the
comparison shows what leaving them out costs.  Shear coefficient k (Cowper, "The shear
coefficient in Timoshenko's beam theory", J. Appl. Mech. 33:335-340, 1966), Poisson's
ratio nu = E / (2 G) - 1:

* round section (extreme fibres equal, area at most a circle's of that radius): a tube of
  outer radius R = c_y and inner r with pi (R^2 - r^2) = A, m = r / R:
  k = 6 (1 + nu) (1 + m^2)^2 / ((7 + 6 nu)(1 + m^2)^2 + (20 + 12 nu) m^2)
  (m = 0 the solid circle 6 (1 + nu) / (7 + 6 nu));
* any other section with known extreme fibres (rectangles): k = 10 (1 + nu) / (12 + 11 nu);
* extreme fibres unknown: k = 5/6 (stated, not derived).

The shear term changes a bending frequency by about (r_g / L)^2 (r_g the radius of
gyration), below 1e-4 for the slender links of the examples.
"""
from dataclasses import dataclass

import numpy as np

UNKNOWN_SHAPE_SHEAR_COEFFICIENT = 5.0 / 6.0
ROUND_TOL = 1e-9      # relative: extreme fibres equal and area within a circle's


@dataclass(frozen=True)
class ContinuumSection:
    """Section data of a geometrically exact beam (units in the module docstring).

    stiffness (6,) : diagonal of the section stiffness, strain order above
    damping   (6,) : diagonal of the Kelvin-Voigt section damping (N s ...)
    mass_per_length : rho A, kg/m
    rotary_inertia (3,) : rho (I_y + I_z), rho I_y, rho I_z, kg m
    shear_coefficient : k used for both shear directions
    shape : "round", "rectangle-like" or "unknown" (how k was chosen)
    """

    stiffness: tuple
    damping: tuple
    mass_per_length: float
    rotary_inertia: tuple
    shear_coefficient: float
    shape: str


def poisson_ratio(beam) -> float:
    """nu = E / (2 G) - 1 of an isotropic material (dimensionless)."""
    return beam.youngs_modulus / (2.0 * beam.shear_modulus) - 1.0


def shear_coefficient(beam) -> tuple:
    """(k, shape) of the beam's section (module docstring)."""
    c_y, c_z = beam.extreme_fibre_y, beam.extreme_fibre_z
    nu = poisson_ratio(beam)
    if c_y is None or c_z is None:
        return UNKNOWN_SHAPE_SHEAR_COEFFICIENT, "unknown"
    outer = np.pi * c_y * c_y
    if abs(c_y - c_z) <= ROUND_TOL * c_y and beam.area <= outer * (1.0 + ROUND_TOL):
        inner_sq = max(c_y * c_y - beam.area / np.pi, 0.0)
        m2 = inner_sq / (c_y * c_y)
        s = (1.0 + m2) ** 2
        return 6.0 * (1.0 + nu) * s / ((7.0 + 6.0 * nu) * s + (20.0 + 12.0 * nu) * m2), "round"
    return 10.0 * (1.0 + nu) / (12.0 + 11.0 * nu), "rectangle-like"


# Euler-Bernoulli limit of the rod: axial and shear stiffness raised until their
# compliance relative to the bending one, e_limit = 3 E I / (k G A L^2) + E I / (E A L^2)
# (the share of a cantilever's tip deflection under a tip load), is this small: the limit
# RFEM converges to.  Raised no further: a 1e4-fold stiffer rod made Exudyn's Newton fail
# on the spin-up beam (E A x 1e4 = 2.8e11 N at dt = 0.01 s), while its e_limit is 4e-5
EULER_BERNOULLI_RESIDUAL = 1e-6


def compliance_fraction(beam) -> float:
    """e_limit (dimensionless) of a beam: its shear and axial against bending compliance."""
    k, _ = shear_coefficient(beam)
    ei = beam.youngs_modulus * max(beam.second_moment_y, beam.second_moment_z)
    length = beam.length
    return (3.0 * ei / (k * beam.shear_modulus * beam.area * length ** 2)
            + ei / (beam.youngs_modulus * beam.area * length ** 2))


def euler_bernoulli_factor(beam) -> float:
    """The factor on E A and k G A that brings e_limit down to EULER_BERNOULLI_RESIDUAL."""
    return max(1.0, compliance_fraction(beam) / EULER_BERNOULLI_RESIDUAL)


def continuum_section(beam, euler_bernoulli: bool = False) -> ContinuumSection:
    """:class:`ContinuumSection` of a gpme_core.rfem.BeamProperties; ``euler_bernoulli``:
    axial and shear stiffness x euler_bernoulli_factor (a rod inextensible and shear-rigid
    to EULER_BERNOULLI_RESIDUAL, RFEM's limit), else the section's own (the physical
    Timoshenko-Reissner rod)."""
    e, g, rho = beam.youngs_modulus, beam.shear_modulus, beam.density
    a, i_y, i_z, j = beam.area, beam.second_moment_y, beam.second_moment_z, beam.torsion_constant
    eta_e = beam.bending_viscosity
    eta_g = beam.torsion_viscosity if beam.torsion_viscosity is not None else eta_e * g / e
    k, shape = shear_coefficient(beam)
    f = euler_bernoulli_factor(beam) if euler_bernoulli else 1.0
    stiffness = (f * e * a, f * k * g * a, f * k * g * a, g * j, e * i_y, e * i_z)
    damping = (eta_e * a, k * eta_g * a, k * eta_g * a, eta_g * j, eta_e * i_y, eta_e * i_z)
    return ContinuumSection(tuple(float(v) for v in stiffness), tuple(float(v) for v in damping),
                            float(rho * a), (float(rho * (i_y + i_z)), float(rho * i_y),
                                             float(rho * i_z)), float(k), shape)
