"""Peak element angles and bending stress of RFEM links (gpme_core.elastic_loads).

The physics check: a horizontal steel cantilever sagging under its own weight.  In static
equilibrium each spring-damping element (sde) carries the bending moment of the beam
beyond it, M(x) = rho A g (L - x)^2 / 2 at x = (r - 1/2) dl (statics of the rigid
elements outboard of the sde, exact up to the geometric non-linearity: the lever arms
shorten by cos(slope), a relative change below slope^2 with slope <= the sum of the sde
angles, ~2e-6 here), and the corner stress of a rectangle is sigma = |M| c_z / I_y.
"""
import numpy as np
import pandas as pd
import pytest

from gpme_core.elastic_loads import SMALL_ANGLE_LIMIT, STRESS_SAFETY_FACTOR, elastic_peaks
from gpme_core.errors import ModelError
from gpme_core.inertia import cuboid
from gpme_core.model import PRISMATIC, ChainBuilder
from gpme_core.rfem import BeamProperties, BeamSection, sde_coordinate_name
from gpme_core.statics import static_equilibrium

E, G, RHO, GRAV = 210e9, 81e9, 7850.0, 9.81
LENGTH, WIDTH_Y, HEIGHT_Z = 0.6, 0.03, 0.012
N_SEGMENTS = 6


def cantilever():
    """Beam along world x on a carrier (prismatic along z, held), gravity -z: it bends
    about its y axis (theta coordinates)."""
    beam = BeamProperties.from_section(LENGTH, BeamSection.rectangle(WIDTH_Y, HEIGHT_Z), E, G,
                                       RHO)
    b = ChainBuilder("cantilever", gravity=(0.0, 0.0, -GRAV))
    b.add_joint("carrier", PRISMATIC, (0, 0, 1))
    b.add_body(cuboid(1.0, (0.1, 0.1, 0.1)))
    b.add_beam("beam", beam, N_SEGMENTS)
    return b.build()


def static_history(model):
    """(history with the static sag at t = 0 and twice it at t = 1 s, sag q)."""
    flex = [n for n in model.coordinate_names if n != "carrier"]
    q = static_equilibrium(model, np.zeros(model.n_coordinates), flex)
    rows = [dict(zip(model.coordinate_names, q), t=0.0),
            dict(zip(model.coordinate_names, 2.0 * q), t=1.0)]
    return pd.DataFrame(rows), q


def test_sag_stress_equals_the_beam_moment_over_the_section_modulus():
    model = cantilever()
    hist, q = static_history(model)
    dl = LENGTH / N_SEGMENTS
    area, i_y = WIDTH_Y * HEIGHT_Z, WIDTH_Y * HEIGHT_Z ** 3 / 12.0
    x_sde = (np.arange(1, N_SEGMENTS + 1) - 0.5) * dl
    moment = RHO * area * GRAV * (LENGTH - x_sde) ** 2 / 2.0           # N m
    expected = moment * (HEIGHT_Z / 2.0) / i_y                          # Pa
    theta = np.array([q[model.index(sde_coordinate_name("beam", r, "theta"))]
                      for r in range(1, N_SEGMENTS + 1)])
    psi = np.array([q[model.index(sde_coordinate_name("beam", r, "psi"))]
                    for r in range(1, N_SEGMENTS + 1)])
    assert np.abs(psi).max() < 1e-12 * np.abs(theta).max()   # gravity bends about y only
    stress = model.flexible_links[0].beam.bending_stress(psi, theta, N_SEGMENTS)
    # linear beam theory vs the RFEM statics on the sagged geometry: lever arms shortened
    # by cos(slope) with slope <= sum |theta| (statics solved to 1e-10 N m on ~1 N m)
    slope = np.abs(theta).sum()
    np.testing.assert_allclose(stress, expected, rtol=slope ** 2)
    assert np.abs(stress / expected - 1).max() > 0.01 * slope ** 2   # the bound is not slack
    peak, = elastic_peaks(model, hist, {"beam": 355e6})
    # the root sde at the later (doubled) sample
    assert (peak.stress_sde, peak.stress_time) == (1, 1.0)
    assert peak.bending_stress == pytest.approx(2.0 * stress[0], rel=1e-12)
    assert peak.bending_angle == pytest.approx(2.0 * abs(theta[0]), rel=1e-12)
    assert peak.bending_sde == 1 and peak.torsion_angle < 1e-12
    assert peak.warnings() == []


def test_warnings_name_the_exceeded_limit():
    model = cantilever()
    hist, q = static_history(model)
    peak, = elastic_peaks(model, hist, {"beam": 355e6})
    # a yield strength just below 1.5 x the peak stress: the elastic limit is exceeded
    low_yield = 0.99 * STRESS_SAFETY_FACTOR * peak.bending_stress
    weak, = elastic_peaks(model, hist, {"beam": low_yield})
    assert len(weak.warnings()) == 1 and "would not stay elastic" in weak.warnings()[0]
    assert "sde 1" in weak.warnings()[0]
    # angles scaled past the small-angle limit
    big = hist.copy()
    cols = [c for c in model.coordinate_names if c != "carrier"]
    big[cols] *= 1.01 * SMALL_ANGLE_LIMIT / peak.bending_angle
    bent, = elastic_peaks(model, big)
    assert any("small-angle limit" in w for w in bent.warnings())
    assert bent.allowed_stress is None        # no yield strength given: no stress verdict


def test_bad_yield_strengths_and_missing_columns_are_clear_errors():
    model = cantilever()
    hist, _ = static_history(model)
    with pytest.raises(ModelError, match="not a flexible link"):
        elastic_peaks(model, hist, {"arm": 355e6})
    with pytest.raises(ModelError, match="positive finite number of Pa"):
        elastic_peaks(model, hist, {"beam": -1.0})
    with pytest.raises(ModelError, match="history lacks the RFEM coordinates"):
        elastic_peaks(model, hist.drop(columns=[sde_coordinate_name("beam", 2, "phi")]))


def _model_file_with(tmp_path, extra):
    """tests/data/runs/flexible_free_arm.toml with ``extra`` lines in its [[flexible]]."""
    from pathlib import Path
    src = Path(__file__).parent / "data" / "runs" / "flexible_free_arm.toml"
    text = src.read_text().replace('urdf = "../../../examples/',
                                   f'urdf = "{(src.parent / "../../../examples").resolve()}/')
    path = tmp_path / "arm.toml"
    path.write_text(text.replace("bending_viscosity = 1e6", "bending_viscosity = 1e6\n" + extra))
    return path


@pytest.mark.parametrize("yield_line, warned", [("", False), ("yield_strength = 270e6", False),
                                                ("yield_strength = 1.0", True)])
def test_run_rows_report_peaks_and_warn_past_the_yield_limit(tmp_path, yield_line, warned):
    """The verify/simulate run rows of a model file: the peaks are information rows; a
    yield strength from [[flexible]] gives the stress verdict (1 Pa: surely exceeded;
    aluminium 6061-T6's 270 MPa: not, for this lightly loaded arm)."""
    from crosscheck.run_checks import WARNING, run_rows, run_warnings
    from gpme_io.runs import simulate_scenario
    from gpme_io.modelfile import load_model_file
    scenario = load_model_file(_model_file_with(tmp_path, yield_line))
    assert dict(scenario.yield_strengths) == (
        {"upper_arm": float(yield_line.split("=")[1])} if yield_line else {})
    df = simulate_scenario(scenario, t_end=0.05)
    rows = {r["quantity"]: r for r in run_rows(scenario, df)}
    stress = rows["peak bending stress (upper_arm)"]
    assert stress["status"] == "info" and stress["gpme_value"] > 0
    assert stress["reason"].startswith(WARNING) == warned
    assert ("no yield strength" in stress["reason"]) == (not yield_line)
    assert len(run_warnings(list(rows.values()))) == int(warned)


def test_the_crane_scenario_judges_its_arm_against_s355():
    from gpme_io.scenario import crane_scenario
    assert dict(crane_scenario(1).yield_strengths) == {"arm": 355e6}
