"""The motion in 3D (issue 28, gpme_io.animation): one self-contained HTML page per run,
under 3 MB, that headless Chromium draws and plays offline; the elastic deflection
magnified by the stated factor; a model without shapes drawn as a stick figure."""
import io
import re
import time
from pathlib import Path

import numpy as np
import pytest

from gpme_io import animation
from gpme_io.modelfile import load_model_file
from gpme_io.runs import simulate_scenario, write_run_outputs
from gpme_io.scenario import crane_scenario

REPO = Path(__file__).resolve().parent.parent
SCREENSHOTS = REPO / "reports" / "screenshots"


@pytest.fixture(scope="module")
def crane_run():
    scenario = crane_scenario(3)
    return scenario, simulate_scenario(scenario, t_end=0.5)


def test_the_page_is_self_contained_and_small(crane_run, tmp_path):
    scenario, df = crane_run
    path = animation.write_motion(scenario.model, df, tmp_path / "m.html", "RK4, 0.5 s",
                                  constrained=["E"])
    text = path.read_text()
    assert path.stat().st_size <= animation.MAX_BYTES
    assert not re.search(r"""(src|href)=["']https?://""", text)     # nothing fetched
    assert "MeshCat.Viewer" in text and "elastic deflection x20" in text


def test_a_ghost_run_keeps_the_page_under_its_size_and_an_oversized_page_is_skipped(
        tmp_path, monkeypatch):
    """The UR5's meshes fill the budget: with another engine's run as a ghost (its meshes
    embedded again) the page still stays under MAX_BYTES; a page that cannot is not
    written and the caller goes on (a report step once crashed on it)."""
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scenario = load_model_file(REPO / "models" / "ur5_flexible_forearm.toml")
    df = simulate_scenario(scenario, t_end=0.2)
    page = animation.motion_page(scenario.model, df, "x", overlay=("MuJoCo", df))
    assert len(page.encode("utf-8")) <= animation.MAX_BYTES

    def too_large(*args, **kwargs):
        raise ValueError("needs 4.0 MB")
    monkeypatch.setattr(animation, "motion_page", too_large)
    assert animation.write_motion(scenario.model, df, tmp_path / "m.html", "x") is None
    assert not (tmp_path / "m.html").exists()


def test_the_deflection_is_magnified_about_the_spring_reference(crane_run):
    scenario, df = crane_run
    model = scenario.model
    q = df[list(model.coordinate_names)].to_numpy()[-1]
    shown = animation.displayed(model, q, 20.0)
    flex = [model.index(c) for c in model.flexible_coordinates]
    rigid = [k for k in range(model.n_coordinates) if k not in flex]
    assert np.array_equal(shown[rigid], q[rigid])
    ref = model.spring_reference[flex]
    assert np.allclose(shown[flex] - ref, 20.0 * (q[flex] - ref), rtol=1e-14, atol=0)
    assert np.array_equal(animation.displayed(model, q, 1.0), q)


def test_frames_are_subsampled_with_the_first_and_the_last():
    rows = animation.frame_rows(10_001, 600)
    assert len(rows) == 600 and rows[0] == 0 and rows[-1] == 10_000
    assert list(animation.frame_rows(5, 600)) == [0, 1, 2, 3, 4]


def test_a_model_without_shapes_is_a_stick_figure():
    scenario = load_model_file(REPO / "examples" / "my_arm" / "my_arm.toml")
    assert not scenario.model.geometry
    sticks = animation.stick_shapes(scenario.model)
    assert {s.kind for s in sticks} == {"sphere", "cylinder"}
    assert len([s for s in sticks if s.kind == "sphere"]) == scenario.model.n_coordinates


@pytest.mark.parametrize("which", ["crane", "ur5", "my_arm"])
def test_headless_chromium_draws_and_plays_it(which, tmp_path):
    """The canvas is drawn (a screenshot far from blank) and the animation advances (the
    mixer's time grows and a moving link's world matrix changes); screenshots are kept in
    reports/screenshots/motion_<which>.png."""
    from test_verify import _browser
    from PIL import Image
    if which == "crane":
        scenario = crane_scenario(3)
    else:
        path = {"ur5": REPO / "models" / "ur5_flexible_forearm.toml",
                "my_arm": REPO / "examples" / "my_arm" / "my_arm.toml"}[which]
        scenario = load_model_file(path)
    df = simulate_scenario(scenario, t_end=min(1.0, scenario.quick_t_end))
    paths = write_run_outputs(scenario, df, tmp_path)
    page = paths[f"{scenario.name}_motion.html"]
    assert page.stat().st_size <= animation.MAX_BYTES
    visual = [s for s in scenario.model.geometry if s.is_visual]
    link = max(s.link_index for s in (visual or animation.stick_shapes(scenario.model)))
    browser = _browser()
    try:
        browser.set_window_size(800, 600)
        browser.get(page.as_uri())
        errors = [e for e in browser.get_log("browser") if e["level"] in ("SEVERE", "ERROR")]
        assert errors == [] and browser.execute_script("return window.gpmeReady === true")
        where = f'["meshcat", "robot", "gpme", "link{link}"]'
        probe = (f"var n = viewer.scene_tree.find({where}); return [viewer.animator.mixer.time,"
                 " Array.from(n.object.matrixWorld.elements)];")
        time.sleep(0.5)
        t1, m1 = browser.execute_script(probe)
        time.sleep(1.0)
        t2, m2 = browser.execute_script(probe)
        image = Image.open(io.BytesIO(browser.get_screenshot_as_png())).convert("RGB")
        SCREENSHOTS.mkdir(parents=True, exist_ok=True)
        image.save(SCREENSHOTS / f"motion_{which}.png")
        shot = np.asarray(image.convert("L"))
    finally:
        browser.quit()
    assert t2 > t1                                          # the animation plays
    assert not np.allclose(m1, m2, rtol=0, atol=1e-9)       # and the link moves
    assert shot.std() > 20 and len(np.unique(shot)) > 50      # a drawn scene, not blank
