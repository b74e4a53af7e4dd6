"""crosscheck.term_coverage (issue 23): every term of the equations is exercised by some
shipped example, and the tool does see a term that is zero.

The shipped examples run for their first RUN_S seconds on the Python reference path (no
numba compilation of the examples' SymPy kernels, so the cost is known: ~20 s on two
cores); which terms are non-zero does not depend on the path, and every term the examples
exercise is non-zero from the start (docs/coverage.md).
"""
from pathlib import Path

import numpy as np
import pytest

from crosscheck import term_coverage as tc
from gpme_core import constraints as gc
from gpme_core.kinematics import point_kinematics
from gpme_core.rfem import BeamProperties, BeamSection
from gpme_core.time_functions import Cosine
from gpme_io.modelfile import load_model_file

REPO = Path(__file__).resolve().parent.parent
MY_ARM = REPO / "examples" / "my_arm" / "my_arm.toml"
SCARA_URDF = REPO / "examples" / "scara" / "scara.urdf"
RUN_S = 0.2


@pytest.fixture(scope="module")
def shipped():
    return tc.shipped_examples()


@pytest.fixture(scope="module")
def shipped_coverage(shipped):
    return [tc.example_coverage(ex, t_end=RUN_S, compiled=False) for ex in shipped]


def test_every_required_term_is_exercised_by_a_shipped_example(shipped_coverage):
    missing = tc.uncovered_terms(shipped_coverage)
    assert missing == [], (
        "terms of the equations no shipped example exercises (above "
        f"{tc.WEAK_RELATIVE:g} of their scale), so a fault in them would pass every check: "
        f"{missing}; add an example that makes them non-zero (docs/coverage.md)\n"
        + tc.markdown_table(shipped_coverage))


def test_the_shipped_examples_are_the_crane_cases_and_the_model_files(shipped):
    origins = " ".join(e.origin for e in shipped)
    names = [e.name for e in shipped]
    assert {"crane_rigid", "crane_flexible_n3"} <= set(names)
    assert len(set(names)) == len(names)
    for path in ("models/crane_rigid.toml", "models/ur5_flexible_forearm.toml",
                 "models/panda_gripper.toml", "models/scara_tilting_plane.toml",
                 "examples/my_arm/my_arm.toml"):
        assert path in origins
    assert "zoo" not in origins


def _coverage(path, t_end=0.1):
    return tc.example_coverage(tc.example_from_file(path), t_end=t_end, compiled=False)


def test_a_model_without_prismatic_joints_or_moving_gradients_reports_them():
    """my_arm: three revolute joints, a circle and a plane fixed in time, a programmed yaw."""
    cov = _coverage(MY_ARM)
    assert cov.status("joint prismatic") == tc.ABSENT
    assert cov.status("joint revolute") == tc.EXERCISED
    key = tc.constraint_term_key
    assert cov.status(key(tc.EXPRESSION, tc.GRAD_T)) == tc.ZERO
    assert cov.status(key(tc.EXPRESSION, tc.PHI_TT)) == tc.ZERO
    assert cov.status(key(tc.EXPRESSION, tc.HESS)) == tc.EXERCISED
    assert cov.status(key(tc.JOINT_PROGRAMME, tc.PHI_TT)) == tc.EXERCISED
    missing = tc.uncovered_terms([cov])
    for expected in ("joint prismatic", key(tc.EXPRESSION, tc.GRAD_T), "drive",
                     "rfem spring tube", key(tc.ELLIPSE, tc.HESS)):
        assert expected in missing
    assert "joint revolute" not in missing and "M" not in missing


def _write_scara_file(tmp_path, body):
    path = tmp_path / "model.toml"
    path.write_text(f'[model]\nname = "scara_variant"\nurdf = "{SCARA_URDF.as_posix()}"\n'
                    'gravity = [0.0, 0.0, -9.81]\n[chain]\nroot = "base"\ntip = "tool"\n'
                    + body + "\n[run]\nt_end = 0.1\nquick_t_end = 0.1\ndt = 1e-3\n")
    return path


def test_a_prismatic_joint_held_still_is_zero(tmp_path):
    """The SCARA's quill held at a constant height by its programme: present, not moving."""
    path = _write_scara_file(tmp_path, """
[[programme]]
joint = "quill"
q = "-0.1 + 0*t"
[[programme]]
joint = "shoulder"
q = "0.5*sin(pi*t)"
[initial]
q = { quill = -0.1, elbow = 1.0 }
on_constraints = true
""")
    cov = _coverage(path)
    assert cov.values["joint prismatic"].largest == 0.0
    assert cov.status("joint prismatic") == tc.ZERO
    assert "joint prismatic" in tc.uncovered_terms([cov])


def test_uniform_rotation_does_not_exercise_the_moving_gradient(tmp_path):
    """Issue 23's blind spot: a constraint turning uniformly, y cos(w t) - x sin(w t), with
    the point on a circle about the axis: grad(phi_t) is radial, p_dot tangential, so
    2 grad(phi_t).p_dot vanishes on the motion, and so does phi_tt = -w^2 phi; the tool
    must count neither, although their factors are not small."""
    text = MY_ARM.read_text()
    head = text[:text.index("[[constraint]]")]
    path = tmp_path / "rotating.toml"
    urdf = (MY_ARM.parent / "my_arm.urdf").as_posix()
    path.write_text(head.replace('urdf = "my_arm.urdf"', f'urdf = "{urdf}"') + """
[[constraint]]
name = "circle"
frame = "tool"
phi = "x**2 + y**2 - 0.45**2"
[[constraint]]
name = "height"
frame = "tool"
phi = "z - 0.3"
[[constraint]]
name = "angle"
frame = "tool"
phi = "y*cos(pi*t) - x*sin(pi*t)"
[initial]
q = { yaw = 0.0, shoulder = -0.3, elbow = 1.2 }
on_constraints = true
[run]
t_end = 0.1
quick_t_end = 0.1
""")
    cov = _coverage(path)
    for piece in (tc.GRAD_T, tc.PHI_TT):
        key = tc.constraint_term_key(tc.EXPRESSION, piece)
        assert cov.status(key) in (tc.ZERO, tc.WEAK), piece
        assert key in tc.uncovered_terms([cov])
    for piece in (tc.PHI_T, tc.DRIFT, tc.HESS):
        assert cov.status(tc.constraint_term_key(tc.EXPRESSION, piece)) == tc.EXERCISED


def _local_pieces(spec, p, t):
    phi, grad, hess, phi_t, grad_t, phi_tt = spec.local_terms(p, t)
    return {tc.PHI: phi, tc.ROW: grad, tc.PHI_T: phi_t, tc.DRIFT: grad, tc.HESS: hess,
            tc.GRAD_T: grad_t, tc.PHI_TT: phi_tt}


@pytest.mark.parametrize("kind, spec", [
    (tc.ELLIPSE, gc.EllipseConstraint(0.3, 0.5, center=(0.1, -0.2))),
    (tc.COORDINATE, gc.CoordinateProgramme(Cosine(0.2, 0.1, 1.5), axis=1)),
    (tc.EXPRESSION, gc.SympyPointConstraint("z - 0.1*x*sin(2*t) + x**2*y - t**2*z")),
], ids=["ellipse", "coordinate", "expression"])
def test_structurally_zero_pieces_are_those_local_terms_never_gives(kind, spec, rng):
    """STRUCTURALLY_ZERO (the pieces that are not rows of the table) against each kind's
    local_terms at random points and times: exactly zero there, every other piece
    non-zero somewhere."""
    assert tc.constraint_kind(spec) == kind
    samples = [_local_pieces(spec, rng.uniform(-1, 1, 3), rng.uniform(0, 3)) for _ in range(20)]
    for piece in tc.PIECES:
        largest = max(float(np.max(np.abs(s[piece]))) for s in samples)
        if piece in tc.STRUCTURALLY_ZERO[kind]:
            assert largest == 0.0, (kind, piece)
        else:
            assert largest > 0.0, (kind, piece)


@pytest.mark.parametrize("kind, section", [
    ("circle", BeamSection.solid_circle(0.02)),
    ("tube", BeamSection.tube(0.06, 0.003)),
    ("tube", BeamSection.tube(0.1, 0.0002)),
    ("rectangle", BeamSection.rectangle(0.05, 0.025)),
    ("rectangle", BeamSection.rectangle(0.03, 0.03)),
    ("hollow_rectangle", BeamSection.hollow_rectangle(0.08, 0.05, 0.004)),
    ("hollow_rectangle", BeamSection.hollow_rectangle(0.04, 0.04, 0.002)),
    (tc.OTHER_SECTION, BeamSection(1e-4, 1e-9, 2e-9, 1e-9, "made up", 0.01, 0.02)),
], ids=["circle", "tube", "thin_tube", "rectangle", "square", "box", "square_box", "other"])
def test_section_kind_recognises_each_constructor(kind, section):
    beam = BeamProperties.from_section(0.5, section, 70e9, 26e9, 2700.0)
    assert tc.section_kind(beam) == kind


def test_the_pieces_must_reproduce_the_engine(monkeypatch):
    """Issue 23's fault planted in the engine's kappa (Python path): 1.9 grad(phi_t).p_dot
    instead of 2; the pieces, taken from local_terms and point_kinematics, no longer add up
    to it and the tool stops."""
    scenario = load_model_file(REPO / "models" / "scara_tilting_plane.toml")
    df = tc.run_example(scenario, t_end=0.01, compiled=False)
    tc.evaluate_terms(scenario, df)
    original = gc._BoundPointConstraint.evaluate

    def faulty(self, t, kin, q_dot, point=None):
        phi, row, phi_dot, kappa = original(self, t, kin, q_dot, point)
        pk = point_kinematics(self.model, kin, q_dot, self.link, self.r_local)
        grad_t = self.spec.local_terms(pk.position, t)[4]
        return phi, row, phi_dot, kappa - 0.1 * float(grad_t @ pk.velocity)
    monkeypatch.setattr(gc._BoundPointConstraint, "evaluate", faulty)
    with pytest.raises(tc.TermCoverageError, match="kappa differing from the engine's"):
        tc.evaluate_terms(scenario, df)


def test_command_exits_1_when_a_term_is_missing_and_writes_the_page(tmp_path, capsys):
    page = tmp_path / "coverage.md"
    status = tc.main(["--model", str(MY_ARM), "--t-end", "0.02", "--python-path",
                      "--write", str(page)])
    assert status == 1
    out = capsys.readouterr().out
    assert "prismatic joints: max abs(q_dot)" in out
    text = page.read_text()
    assert "| term | unit | my_arm |" in text and "**0**" in text


def test_the_page_shows_every_shipped_example_and_term(shipped):
    """docs/coverage.md is generated; a new example or term means regenerating it."""
    text = (REPO / "docs" / "coverage.md").read_text()
    header = next(line for line in text.splitlines() if line.startswith("| term | unit |"))
    columns = [c.strip() for c in header.strip("|").split("|")]
    assert columns[2:-1] == [e.name for e in shipped]
    for term in tc.TERMS:
        assert f"| {term.label}" in text, term.label
    assert f"{tc.ZERO_RELATIVE:g}" in text and f"{tc.WEAK_RELATIVE:g}" in text
    assert "python -m crosscheck.term_coverage --write docs/coverage.md" in text
