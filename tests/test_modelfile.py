"""Model files (gpme_io.modelfile): the crane files agree with the code's crane scenario,
a URDF robot with a SymPy task loads and runs, and every kind of bad key or value gives
one ModelFileError naming the key path, the value and what is valid."""
import importlib.metadata
import math
import re
import textwrap
from pathlib import Path

import numpy as np
import pytest

from gpme_core.dynamics import dynamics_terms
from gpme_core.errors import ConstraintError, ModelFileError
from gpme_core.integrate import simulate
from gpme_core.time_functions import Sine, SympyTimeFunction, Tabulated
from gpme_io.modelfile import load_model_file, read_model_file
from gpme_io.modelfile import load as mf_load
from gpme_io.scenario import crane_scenario

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(__file__).resolve().parent / "data" / "modelfiles"


# ============================================================ the crane files vs the code
@pytest.mark.parametrize("file, n_rfe", [("crane_rigid.toml", 0), ("crane_flexible.toml", 3)],
                         ids=["rigid", "flexible-n3"])
def test_crane_files_match_crane_scenario(file, n_rfe):
    rng = np.random.default_rng(100 + n_rfe)
    mine = load_model_file(ROOT / "models" / file)
    ref = crane_scenario(n_rfe)
    assert mine.name == ref.name
    assert mine.model.coordinate_names == ref.model.coordinate_names
    np.testing.assert_array_equal(mine.q0, ref.q0)
    np.testing.assert_array_equal(mine.q_dot0, ref.q_dot0)
    assert (mine.dt, mine.t_end, mine.quick_t_end, mine.integrator, mine.output_dt) == \
        (ref.dt, ref.t_end, ref.quick_t_end, ref.integrator, ref.output_dt)
    assert mine.system.dependent == ref.system.dependent == ("psi3", "z4")
    assert (mine.system.alpha, mine.system.beta) == (ref.system.alpha, ref.system.beta)
    assert mine.system.constraint_names == ref.system.constraint_names
    assert mine.on_constraints is ref.on_constraints is False
    np.testing.assert_array_equal(mine.model.gravity, ref.model.gravity)
    n = ref.model.n_coordinates
    for _ in range(5):
        t = rng.uniform(0.0, 10.0)
        q = ref.q0 + rng.normal(scale=0.3, size=n)
        qd = rng.normal(scale=0.5, size=n)
        a, b = dynamics_terms(mine.model, t, q, qd), dynamics_terms(ref.model, t, q, qd)
        np.testing.assert_array_equal(a.M, b.M)
        np.testing.assert_array_equal(a.rhs, b.rhs)     # h + Q: springs, dampers, drive at t
        for u, v in zip(mine.system.constraints(t, q, qd), ref.system.constraints(t, q, qd)):
            np.testing.assert_array_equal(u, v)


def test_crane_file_without_optional_sections_uses_stated_defaults(tmp_path):
    s = load_model_file(write(tmp_path, crane_text(solver=None, initial=None,
                                                   run="[run]\nt_end = 3.0\n")))
    assert s.quick_t_end == 1.0 and s.output_dt == 1e-3 and s.integrator == "RK4"
    assert (s.system.alpha, s.system.beta) == (20.0, 20.0)
    assert s.system.dependent is not None and len(s.system.dependent) == 2
    assert any("chosen by pivoting" in n for n in s.notes)
    assert any("RK4 step dt" in n for n in s.notes)
    assert 0 < s.dt <= s.output_dt
    np.testing.assert_array_equal(s.q0, s.model.spring_reference)


# ============================================================ a URDF robot with a SymPy task
def test_urdf_model_file_with_sympy_constraint_and_programme_runs():
    s = load_model_file(DATA / "arm3.toml")
    assert s.urdf == (DATA / "arm3.urdf").resolve()
    assert s.source == DATA / "arm3.toml"
    assert s.chain == ("base_link", "tool")
    assert s.model.coordinate_names == ("yaw", "shoulder", "elbow")
    shoulder = s.model.joints[s.model.index("shoulder")]
    assert (shoulder.damping, shoulder.stiffness, shoulder.spring_reference) == (0.5, 2.0, 0.0)
    assert s.model.joints[s.model.index("yaw")].damping == 0.1      # the URDF's, kept
    assert s.model.drives[0].joint == "elbow" and s.model.drives[0].function == Sine(0.0, 0.3, 0.5)
    assert any("friction" in n for n in s.notes)                     # the reader's notes kept
    assert s.system.constraint_names == ("tool_height", "Phi_yaw")
    # placed on the constraints at t = 0
    phi, phi_dot, _, _ = s.system.constraints(0.0, s.q0, s.q_dot0)
    assert np.max(np.abs(phi)) < 1e-12 and np.max(np.abs(phi_dot)) < 1e-12
    df = simulate(s.system, s.t_end, s.q0, s.q_dot0, dt=s.dt, output_dt=s.output_dt)
    assert df.t.iloc[-1] == pytest.approx(0.05)
    # a wrong kappa of 1 % would leave |Phi| ~ 1e-2 |z_ddot| / beta^2 ~ 5e-5 m; RK4 at
    # dt = 1e-3 s leaves ~dt^4 |q^(5)| t ~ 1e-11 (measured 4.5e-12)
    assert df.tool_height.abs().max() < 1e-9
    np.testing.assert_allclose(df.z_tool, 0.2 - 0.05 * np.sin(2 * np.pi * df.t), atol=1e-9)
    np.testing.assert_allclose(df.yaw, 0.2 * np.sin(3 * df.t), atol=1e-9)


def test_flexible_urdf_link_follows_the_geometry(tmp_path):
    text = (DATA / "arm3.toml").read_text().replace('urdf = "arm3.urdf"',
                                                    f'urdf = "{DATA / "arm3.urdf"}"')
    text += textwrap.dedent("""
        [[flexible]]
        link = "upper_arm"
        section = { shape = "tube", outer_diameter = 0.04, wall_thickness = 0.003 }
        youngs_modulus = 70e9
        shear_modulus = 26e9
        density = 2700.0
        segments = 2
        bending_viscosity = 1e5
        """)
    s = load_model_file(write(tmp_path, text))
    names = s.model.coordinate_names
    assert names == ("yaw", "shoulder", "psi_upper_arm_1", "theta_upper_arm_1",
                     "phi_upper_arm_1", "psi_upper_arm_2", "theta_upper_arm_2",
                     "phi_upper_arm_2", "elbow")
    assert s.flexible_coordinates == names[2:8]
    # the beam runs from the shoulder to the elbow origin: 0.4 m along the link x axis
    area = math.pi / 4 * (0.04 ** 2 - 0.034 ** 2)
    beam_mass = 2700.0 * area * 0.4
    assert s.model.total_mass == pytest.approx(4.2 - 1.2 + beam_mass, rel=1e-12)
    # at zero deflection the tool is where the rigid arm has it
    rigid = load_model_file(DATA / "arm3.toml")
    from gpme_core.kinematics import chain_kinematics
    q_rigid = np.array([0.1, 0.3, -0.6])
    q_flex = np.zeros(len(names))
    q_flex[[0, 1, 8]] = q_rigid
    p = [(chain_kinematics(sc.model, q).T[sc.model.frames["tool"].link_index]
          @ sc.model.frames["tool"].transform[:, 3])[:3] for sc, q in ((rigid, q_rigid),
                                                                       (s, q_flex))]
    np.testing.assert_allclose(p[0], p[1], atol=1e-15)


def test_example_robot_data_urdf_resolves_and_loads(tmp_path):
    try:
        importlib.metadata.distribution("example-robot-data")
    except importlib.metadata.PackageNotFoundError:
        pytest.skip("example-robot-data not installed (the robots extra)")
    text = textwrap.dedent("""
        [model]
        name = "ur5"
        urdf = "example-robot-data:ur_description/urdf/ur5_robot.urdf"
        gravity = [0, 0, -9.81]
        [chain]
        root = "world"
        tip = "tool0"
        [[programme]]
        joint = "shoulder_pan_joint"
        q = "0.5*(1 - cos(t))"
        [run]
        t_end = 1.0
        """)
    s = load_model_file(write(tmp_path, text))
    assert s.urdf.name == "ur5_robot.urdf" and s.urdf.is_file()
    assert s.model.n_coordinates == 6
    assert s.system.dependent == ("shoulder_pan_joint",)


def test_missing_example_robot_data_says_how_to_install(tmp_path, monkeypatch):
    def missing(name):
        raise importlib.metadata.PackageNotFoundError(name)
    monkeypatch.setattr(mf_load.importlib.metadata, "distribution", missing)
    text = crane_text(model='[model]\nname = "r"\ngravity = [0, 0, -9.81]\n'
                            'urdf = "example-robot-data:ur_description/urdf/ur5_robot.urdf"\n',
                      constraints=None, solver=None, initial=None)
    with pytest.raises(ModelFileError, match=re.escape(
            "model.urdf: 'example-robot-data:ur_description/urdf/ur5_robot.urdf' needs the "
            "package example-robot-data, which is not installed; install the optional extra: "
            "pip install -e '.[robots]'")):
        load_model_file(write(tmp_path, text))


def test_unknown_example_robot_data_path_lists_close_matches(tmp_path):
    text = crane_text(model='[model]\nname = "r"\ngravity = [0, 0, -9.81]\n'
                            'urdf = "example-robot-data:ur_description/urdf/ur5_robt.urdf"\n',
                      constraints=None, solver=None, initial=None)
    with pytest.raises(ModelFileError, match=r"model\.urdf: example-robot-data \S+ has no "
                       r"'ur_description/urdf/ur5_robt\.urdf' under robots/; close matches: "
                       r"\[.*'ur_description/urdf/ur5_robot\.urdf'"):
        load_model_file(write(tmp_path, text))


# ============================================================ bad files: one error, every key
def crane_text(**sections):
    """A valid crane model file; each section can be replaced (a string) or dropped (None)."""
    parts = {
        "model": '[model]\nname = "crane"\nbuiltin = "crane"\ngravity = [0, 0, -9.81]\n',
        "crane": "",
        "drives": '[[drive]]\njoint = "psi2"\ntype = "quintic"\nlevel = 1.0\nramp_time = 5.0\n',
        "constraints": ('[[constraint]]\nname = "Phi_1"\nframe = "E"\nkind = "ellipse"\n'
                        'a = 0.375\nb = 0.75\n'
                        '[[constraint]]\nname = "Phi_2"\nframe = "E"\nkind = "coordinate"\n'
                        'axis = "z"\nfunction = { type = "cosine", offset = 1.0, '
                        'amplitude = 0.5, period = 2.5 }\n'),
        "programmes": "",
        "solver": '[solver]\ndependent = ["psi3", "z4"]\nbaumgarte = [20.0, 20.0]\n',
        "initial": '[initial]\nq = { psi3 = 0.785, z4 = 0.2 }\n',
        "run": '[run]\nt_end = 1.0\ndt = 1e-3\n',
        "extra": "",
    }
    for key, value in sections.items():
        assert key in parts, key
        parts[key] = value
    return "\n".join(v for v in parts.values() if v)


def write(tmp_path, text, name="model.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_the_valid_base_file_loads(tmp_path):
    s = load_model_file(write(tmp_path, crane_text()))
    assert s.model.n_coordinates == 4 and s.system.constraint_names == ("Phi_1", "Phi_2")


BAD = [
    # ---- structure and unknown keys
    ("toml-syntax", dict(extra="[run\n"), r"not valid TOML"),
    ("unknown-top-level", dict(extra="[solvr]\nx = 1\n"),
     r"solvr: unknown key; did you mean 'solver'\?"),
    ("unknown-model-key", dict(model='[model]\nname = "c"\nbuiltin = "crane"\n'
                               'gravity = [0, 0, -9.81]\ngravty = 1\n'),
     r"model\.gravty: unknown key; did you mean 'gravity'\?"),
    ("unknown-run-key", dict(run="[run]\nt_end = 1.0\ntend = 2.0\n"),
     r"run\.tend: unknown key; did you mean 't_end'\?"),
    ("drive-not-array", dict(drives='[drive]\njoint = "psi2"\n'),
     r"drive: must be an array of tables, written \[\[drive\]\]"),
    # ---- [model]
    ("no-model", dict(model=None), r"model: missing table"),
    ("no-source", dict(model='[model]\nname = "c"\ngravity = [0, 0, -9.81]\n'),
     r"model: give exactly one source"),
    ("two-sources", dict(model='[model]\nname = "c"\nbuiltin = "crane"\nurdf = "a.urdf"\n'
                         'gravity = [0, 0, -9.81]\n'), r"model: give exactly one source.*not both"),
    ("unknown-builtin", dict(model='[model]\nname = "c"\nbuiltin = "crain"\n'
                             'gravity = [0, 0, -9.81]\n'),
     r"model\.builtin: 'crain' is not one of 'crane'; did you mean 'crane'\?"),
    ("gravity-missing", dict(model='[model]\nname = "c"\nbuiltin = "crane"\n'),
     r"model\.gravity: missing; 3 numbers \(m/s\^2"),
    ("gravity-short", dict(model='[model]\nname = "c"\nbuiltin = "crane"\ngravity = [0, -9.81]\n'),
     r"model\.gravity: must be an array of 3 numbers"),
    ("gravity-nan", dict(model='[model]\nname = "c"\nbuiltin = "crane"\ngravity = [0, 0, nan]\n'),
     r"model\.gravity\[2\]: must be a finite number \(m/s\^2.*got nan"),
    ("urdf-missing-file", dict(model='[model]\nname = "c"\nurdf = "nowhere.urdf"\n'
                               'gravity = [0, 0, -9.81]\n', constraints=None, solver=None),
     r"model\.urdf: no file at '.*nowhere\.urdf' \(paths are relative to the model file's folder"),
    ("crane-negative-mass", dict(crane="[model.crane]\nslider_mass = -1.0\n"),
     r"model\.crane\.slider_mass: must be > 0 \(kg\), got -1\.0"),
    ("crane-n-rfe-float", dict(crane="[model.crane]\nn_rfe = 2.0\n"),
     r"model\.crane\.n_rfe: must be an integer"),
    ("crane-task-field", dict(crane="[model.crane]\nellipse_a = 0.5\n"),
     r"model\.crane\.ellipse_a: a task parameter of the crane; set it in \[\[constraint\]\]"),
    ("crane-unknown-field", dict(crane="[model.crane]\narm_lenght = 0.5\n"),
     r"model\.crane\.arm_lenght: unknown key; did you mean 'arm_length'\?"),
    ("crane-range", dict(crane="[model.crane]\nslider_stroke = [0.5, -0.3]\n"),
     r"model\.crane\.slider_stroke: must be \[lower, upper\] with lower < upper \(m\)"),
    ("chain-on-builtin", dict(extra='[chain]\ntip = "E"\n'), r"chain: only for urdf models"),
    ("flexible-on-builtin", dict(extra='[[flexible]]\nlink = "arm"\n'),
     r"flexible\[0\]: a builtin model sets its flexible links itself"),
    # ---- [[joint]]
    ("joint-negative-stiffness", dict(extra='[[joint]]\nname = "z1"\nstiffness = -5.0\n'),
     r"joint\[0\]\.stiffness: must be >= 0 \(N m/rad or N/m\), got -5\.0"),
    ("joint-sets-nothing", dict(extra='[[joint]]\nname = "z1"\n'),
     r"joint\[0\]: sets nothing; give stiffness, spring_reference and/or damping"),
    ("joint-twice", dict(extra='[[joint]]\nname = "z1"\ndamping = 1.0\n'
                               '[[joint]]\nname = "z1"\ndamping = 2.0\n'),
     r"joint\[1\]\.name: joint 'z1' is already given in joint\[0\]"),
    ("joint-unknown", dict(extra='[[joint]]\nname = "z11"\ndamping = 1.0\n'),
     r"joint\[0\]\.name: no joint 'z11'; did you mean 'z1'\? the model has: z1, psi2, psi3, z4"),
    # ---- [[drive]]
    ("drive-unknown-type", dict(drives='[[drive]]\njoint = "psi2"\ntype = "quintik"\n'),
     r"drive\[0\]\.type: 'quintik' is not one of .*; did you mean 'quintic'\?"),
    ("drive-wrong-parameter", dict(drives='[[drive]]\njoint = "psi2"\ntype = "quintic"\n'
                                          'level = 1.0\nramp = 5.0\n'),
     r"drive\[0\]\.ramp: unknown key.*\(type 'quintic' takes level, ramp_time\)"),
    ("drive-missing-parameter", dict(drives='[[drive]]\njoint = "psi2"\ntype = "sine"\n'
                                            'offset = 0.0\namplitude = 1.0\n'),
     r"drive\[0\]\.period: missing; a number \(s\)"),
    ("drive-period-zero", dict(drives='[[drive]]\njoint = "psi2"\ntype = "cosine"\n'
                                      'offset = 0.0\namplitude = 1.0\nperiod = 0\n'),
     r"drive\[0\]\.period: must be > 0 \(s\), got 0"),
    ("drive-level-string", dict(drives='[[drive]]\njoint = "psi2"\ntype = "constant"\n'
                                       'level = "1 N m"\n'),
     r"drive\[0\]\.level: must be a number \(N or N m\), got a string '1 N m'"),
    ("drive-table-not-increasing", dict(drives='[[drive]]\njoint = "psi2"\ntype = "table"\n'
                                               'times = [0, 2, 1]\nvalues = [0, 1, 0]\n'),
     r"drive\[0\]: Tabulated: times must be strictly increasing"),
    ("drive-expression-symbol", dict(drives='[[drive]]\njoint = "psi2"\ntype = "expression"\n'
                                            'f = "sin(w*t)"\n'),
     r"drive\[0\]\.f: 'sin\(w\*t\)': unknown symbol 'w'; allowed t \(s\)"),
    ("drive-expression-blows-up", dict(drives='[[drive]]\njoint = "psi2"\n'
                                              'type = "expression"\nf = "1/(t - 0.5)"\n'),
     r"drive\[0\]\.f: not finite at t = 0\.5 s .*division: where t - 0\.5 = 0"),
    ("drive-unknown-joint", dict(drives='[[drive]]\njoint = "psi_2"\ntype = "constant"\n'
                                        'level = 1.0\n'),
     r"drive\[0\]\.joint: no coordinate 'psi_2'; did you mean 'psi2'\?"),
    # ---- [[constraint]]
    ("constraint-unknown-kind", dict(constraints='[[constraint]]\nframe = "E"\nkind = "circle"\n'),
     r"constraint\[0\]\.kind: 'circle' is not one of 'expression', 'ellipse', 'coordinate'"),
    ("constraint-key-of-other-kind", dict(constraints='[[constraint]]\nframe = "E"\n'
                                                      'kind = "ellipse"\na = 1.0\nb = 1.0\n'
                                                      'phi = "x"\n'),
     r"constraint\[0\]\.phi: unknown key;.*\(kind 'ellipse' takes a, b, center\)"),
    ("constraint-negative-semi-axis", dict(constraints='[[constraint]]\nframe = "E"\n'
                                                       'kind = "ellipse"\na = -1.0\nb = 1.0\n'),
     r"constraint\[0\]\.a: must be > 0 \(m, semi-axis along world x\), got -1\.0"),
    ("constraint-axis", dict(constraints='[[constraint]]\nframe = "E"\nkind = "coordinate"\n'
                                         'axis = "w"\nfunction = { type = "constant", '
                                         'level = 1.0 }\n'),
     r"constraint\[0\]\.axis: 'w' is not one of 'x', 'y', 'z'"),
    ("constraint-function-parameter", dict(constraints='[[constraint]]\nframe = "E"\n'
                                                       'kind = "coordinate"\naxis = "z"\n'
                                                       'function = { type = "cosine", '
                                                       'offset = 1.0, amplitude = 0.5 }\n'),
     r"constraint\[0\]\.function\.period: missing; a number \(s\)"),
    ("constraint-phi-symbol", dict(constraints='[[constraint]]\nframe = "E"\n'
                                               'phi = "x + w"\n'),
     r"constraint\[0\]\.phi: 'x \+ w': unknown symbol 'w'; allowed x, y, z \(m\) and t \(s\)"),
    ("constraint-phi-missing", dict(constraints='[[constraint]]\nframe = "E"\n'),
     r"constraint\[0\]\.phi: missing; phi\(x, y, z, t\) = 0"),
    ("constraint-phi-time-only", dict(constraints='[[constraint]]\nframe = "E"\n'
                                                  'phi = "t - 1"\n'),
     r"constraint\[0\]\.phi: 't - 1' depends on t only"),
    ("constraint-unknown-frame", dict(constraints='[[constraint]]\nframe = "EE"\n'
                                                  'phi = "x - 0.3"\n', solver=None),
     r"constraint\[0\]\.frame: no frame or link 'EE'; did you mean 'E'\?"),
    ("constraint-names-repeat", dict(programmes='[[programme]]\njoint = "psi2"\nq = "0"\n'
                                                'name = "Phi_1"\n', solver=None),
     r"programme\[0\]\.name: constraint 'Phi_1' is already given in constraint\[0\]"),
    # ---- [[programme]]
    ("programme-symbol", dict(programmes='[[programme]]\njoint = "psi2"\nq = "sin(x)"\n',
                              solver=None),
     r"programme\[0\]\.q: 'sin\(x\)': unknown symbol 'x'; allowed t \(s\)"),
    ("programme-not-smooth", dict(programmes='[[programme]]\njoint = "psi2"\nq = "abs(t - 1)"\n',
                                  solver=None),
     r"programme\[0\]\.q: 'abs\(t - 1\)': abs\(\) is not smooth.*second derivative"),
    ("programme-unknown-joint", dict(programmes='[[programme]]\njoint = "q7"\nq = "t"\n',
                                     solver=None),
     r"programme\[0\]\.joint: no coordinate 'q7'"),
    ("too-many-constraints", dict(programmes="".join(
        f'[[programme]]\njoint = "{j}"\nq = "0.1"\n' for j in ("z1", "psi2", "psi3")),
        solver=None), r"constraint: 5 constraints \(\[\[constraint\]\] \+ \[\[programme\]\]\) "
                      r"on 4 coordinates"),
    # ---- [solver]
    ("dependent-wrong-length", dict(solver='[solver]\ndependent = ["psi3"]\n'),
     r"solver\.dependent: gives 1 coordinates \['psi3'\] for 2 constraints"),
    ("dependent-repeat", dict(solver='[solver]\ndependent = ["psi3", "psi3"]\n'),
     r"solver\.dependent: names repeat: \['psi3'\]"),
    ("dependent-unknown", dict(solver='[solver]\ndependent = ["psi3", "z5"]\n'),
     r"solver\.dependent: no coordinate 'z5'; did you mean 'z4'\?"),
    ("baumgarte-negative", dict(solver='[solver]\nbaumgarte = [20.0, -1.0]\n'),
     r"solver\.baumgarte: alpha and beta must be >= 0 \(1/s\), got \[20\.0, -1\.0\]"),
    # ---- [initial]
    ("initial-unknown-coordinate", dict(initial='[initial]\nq = { psi33 = 0.5 }\n'),
     r"initial\.q\.psi33: no coordinate 'psi33'; did you mean 'psi3'\?"),
    ("initial-value-string", dict(initial='[initial]\nq = { psi3 = "pi/4" }\n'),
     r"initial\.q\.psi3: must be a number \(rad or m\), got a string 'pi/4'"),
    ("initial-bool", dict(initial='[initial]\non_constraints = "yes"\n'),
     r"initial\.on_constraints: must be true or false, got a string 'yes'"),
    ("static-flexible-rigid", dict(initial='[initial]\nstatic_flexible = true\n'),
     r"initial\.static_flexible: the model has no flexible links"),
    # ---- [run]
    ("no-run", dict(run=None), r"run: missing table"),
    ("t-end-negative", dict(run="[run]\nt_end = -1.0\n"), r"run\.t_end: must be > 0 \(s"),
    ("t-end-inf", dict(run="[run]\nt_end = inf\n"),
     r"run\.t_end: must be a finite number \(s, length of the full run\), got inf"),
    ("quick-longer", dict(run="[run]\nt_end = 1.0\nquick_t_end = 2.0\n"),
     r"run\.quick_t_end: must be <= t_end = 1\.0 s, got 2\.0"),
    ("integrator-unknown", dict(run='[run]\nt_end = 1.0\nintegrator = "rk4"\n'),
     r"run\.integrator: 'rk4' is not one of 'RK4', 'RadauIIA', 'RK45', 'DOP853', 'Radau'; did you mean "
     r"'RK4'\?"),
    ("dt-with-radau", dict(run='[run]\nt_end = 1.0\nintegrator = "Radau"\ndt = 1e-3\n'),
     r"run\.dt: is the RK4 or RadauIIA step; integrator 'Radau' chooses its own steps"),
    # ---- [[tolerance]]
    ("tolerance-no-reason", dict(extra='[[tolerance]]\ncheck = "pinocchio/M"\nabs = 1e-12\n'
                                       'rel = 1e-10\nreason = ""\n'),
     r"tolerance\[0\]\.reason: must be a non-empty string \(why this tolerance holds"),
    ("tolerance-engine", dict(extra='[[tolerance]]\ncheck = "bullet/M"\nabs = 1e-12\n'
                                    'rel = 1e-10\nreason = "r"\n'),
     r"tolerance\[0\]\.check: 'bullet/M' must be \"<engine>/<quantity>\" with engine one of "
     r"gpme, pinocchio, mujoco, drake, exudyn"),
    ("engine-step-engine", dict(extra='[[engine_step]]\nengine = "mujoco"\ndt = 1e-4\n'
                                      'reason = "r"\n'),
     r"engine_step\[0\]\.engine: 'mujoco' is not one of 'drake', 'exudyn'"),
    ("engine-step-dt", dict(extra='[[engine_step]]\nengine = "exudyn"\ndt = -1e-4\n'
                                  'reason = "r"\n'),
     r"engine_step\[0\]\.dt: must be > 0"),
    ("engine-step-reason", dict(extra='[[engine_step]]\nengine = "exudyn"\ndt = 1e-4\n'),
     r"engine_step\[0\]\.reason: missing"),
    ("engine-step-halvings", dict(extra='[[engine_step]]\nengine = "drake"\ndt = 1e-4\n'
                                        'max_halvings = 20\nreason = "r"\n'),
     r"engine_step\[0\]\.max_halvings: must be a whole number from 0 to 8"),
    ("engine-step-twice", dict(extra=('[[engine_step]]\nengine = "drake"\ndt = 1e-4\n'
                                      'reason = "r"\n') * 2),
     r"engine_step\[1\]\.engine: engine_step 'drake' is already given in engine_step\[0\]"),
    ("tolerance-negative", dict(extra='[[tolerance]]\ncheck = "mujoco/E_kin"\nabs = -1.0\n'
                                      'rel = 0.0\nreason = "r"\n'),
     r"tolerance\[0\]\.abs: must be >= 0"),
]


@pytest.mark.parametrize("sections, message", [b[1:] for b in BAD], ids=[b[0] for b in BAD])
def test_bad_file_names_the_key(tmp_path, sections, message):
    path = write(tmp_path, crane_text(**sections))
    with pytest.raises(ModelFileError, match=message) as info:
        load_model_file(path)
    # every line names the file
    text = str(info.value)
    lines = [ln.strip()[2:] for ln in text.splitlines()[1:]] if "problems in" in text else [text]
    assert all(ln.startswith(f"{path}: ") for ln in lines), text


def test_every_problem_is_listed_at_once_with_model_names(tmp_path):
    text = crane_text(
        drives='[[drive]]\njoint = "psi_2"\ntype = "constant"\nlevel = 1.0\n',   # name: model
        run="[run]\nt_end = -2.0\n",                                               # file
        initial='[initial]\nq = { z44 = 0.1 }\n',                                  # name: model
        extra='[[joint]]\nname = "z1"\nstiffness = -1.0\n')                        # file
    with pytest.raises(ModelFileError) as info:
        load_model_file(write(tmp_path, text))
    msg = str(info.value)
    assert msg.startswith("4 problems in the model file:"), msg
    for key in ("run.t_end: must be > 0", "joint[0].stiffness: must be >= 0",
                "drive[0].joint: no coordinate 'psi_2'", "initial.q.z44: no coordinate"):
        assert key in msg, msg
    assert len(info.value.problems) == 4


def test_read_model_file_checks_the_file_only(tmp_path):
    spec = read_model_file(write(tmp_path, crane_text(
        drives='[[drive]]\njoint = "no_such_joint"\ntype = "constant"\nlevel = 1.0\n')))
    assert spec.drives[0].joint == "no_such_joint"      # names are checked on building


def test_missing_file_is_named(tmp_path):
    with pytest.raises(ModelFileError, match=r"nothing\.toml: cannot read the model file"):
        load_model_file(tmp_path / "nothing.toml")


# ============================================================ expressions and the initial state
EXPRESSIONS = [
    ("attribute", "x.__class__", r"attribute access \('\.__class__'\) is not allowed"),
    ("import", "__import__('os')", r"unknown function '__import__'"),
    ("xor-power", "x^2 - 1", r"'\^' is not a power here: write a\*\*b"),
    ("modulo", "x % 1", r"operator '%' is not smooth"),
    ("comparison", "x < 1", r"comparisons and conditions make a function piecewise"),
    ("conditional", "x if t else y", r"comparisons and conditions make a function piecewise"),
    ("heaviside", "Heaviside(x)", r"Heaviside\(\) is not smooth: it jumps at 0"),
    ("max", "Max(x, y)", r"Max\(\) is not smooth: it has a kink where its arguments are equal"),
    ("floor", "floor(x)", r"floor\(\) is not smooth: it jumps at every integer"),
    ("sign", "sign(x)*x", r"sign\(\) is not smooth"),
    ("piecewise", "Piecewise((x, t < 1), (y, True))", r"Piecewise\(\) is not smooth"),
    ("unknown-function", "sinn(x)", r"unknown function 'sinn' \(did you mean 'sin'\?\)"),
    ("arity", "atan2(y)", r"atan2\(\) takes 2 arguments, got 1"),
    ("keyword", "sin(x=1)", r"sin\(\) takes plain arguments only"),
    ("string", "'x'", r"'x' is not a number"),
    ("complex", "x + 2j", r"2j is not a number"),
    ("subscript", "x[0]", r"Subscript is not allowed"),
    ("lambda", "(lambda: 1)()", r"only the named functions"),
    ("syntax", "x +* 2", r"is not an expression"),
    ("empty", "  ", r"is empty"),
    ("not-a-string", 3.0, r"must be a string holding an expression"),
    ("division-by-zero", "x/0", r"is infinite or undefined"),
    ("imaginary", "x + sqrt(-1)", r"is complex"),
    ("function-as-symbol", "x + sin", r"'sin' is a function: call it"),
]


@pytest.mark.parametrize("phi, message", [e[1:] for e in EXPRESSIONS],
                         ids=[e[0] for e in EXPRESSIONS])
def test_bad_constraint_expression_is_refused(tmp_path, phi, message):
    # TOML: a literal string '...' unless the text holds a quote; a number as is
    value = repr(phi) if not isinstance(phi, str) else \
        (f'"{phi}"' if "'" in phi else f"'{phi}'")
    text = crane_text(constraints=f'[[constraint]]\nframe = "E"\nphi = {value}\n', solver=None)
    with pytest.raises(ModelFileError, match=r"constraint\[0\]\.phi: .*" + message):
        load_model_file(write(tmp_path, text))


def test_good_expression_gives_the_same_constraint_as_the_ellipse(tmp_path):
    """phi written as a formula = the builtin EllipseConstraint, value and derivatives."""
    rng = np.random.default_rng(7)
    formula = crane_text(constraints=(
        '[[constraint]]\nname = "Phi_1"\nframe = "E"\nphi = "(x/0.375)**2 + (y/0.75)**2 - 1"\n'
        '[[constraint]]\nname = "Phi_2"\nframe = "E"\nphi = "z - (1.0 + 0.5*cos(2*pi*t/2.5))"\n'))
    a = load_model_file(write(tmp_path, formula, "a.toml"))
    b = load_model_file(write(tmp_path, crane_text(), "b.toml"))
    for _ in range(5):
        t = rng.uniform(0, 5)
        q = b.q0 + rng.normal(scale=0.3, size=4)
        qd = rng.normal(size=4)
        for u, v in zip(a.system.constraints(t, q, qd), b.system.constraints(t, q, qd)):
            np.testing.assert_allclose(u, v, rtol=1e-13, atol=1e-13)


def test_expression_not_finite_at_the_initial_state_names_where(tmp_path):
    # E starts at x = 0.5 cos(pi/4) + ... < 5 m: sqrt(x - 5) is not real there
    text = crane_text(constraints='[[constraint]]\nname = "reach"\nframe = "E"\n'
                                  'phi = "sqrt(x - 5) - 0.1"\n', solver=None)
    with pytest.raises(ModelFileError, match=r"constraint\[0\]\.phi: constraint 'reach' = "
                       r"'sqrt\(x - 5\) - 0\.1' or its first or second derivatives are not "
                       r"finite at the initial state \(t = 0 s, frame 'E' at x, y, z = .* m\)"
                       r".*not smooth sqrt: where x - 5 <= 0"):
        load_model_file(write(tmp_path, text))


def test_unreachable_initial_state_names_the_constraint_values(tmp_path):
    # an ellipse 10 m wide cannot be reached by a 1.3 m crane
    text = crane_text(constraints='[[constraint]]\nname = "far"\nframe = "E"\n'
                                  'kind = "ellipse"\na = 10.0\nb = 10.0\n',
                      solver='[solver]\ndependent = ["z4"]\n',
                      initial='[initial]\non_constraints = true\n')
    with pytest.raises(ConstraintError, match=r"initial\.on_constraints = true: cannot place "
                       r"the model on the constraints.*At the given q0 the constraints are "
                       r"far = -0\.99"):
        load_model_file(write(tmp_path, text))


# ============================================================ what else reaches the Scenario
def test_tolerances_drives_tables_and_notes_reach_the_scenario(tmp_path):
    text = crane_text(
        drives='[[drive]]\njoint = "psi2"\ntype = "table"\ntimes = [0, 1, 2]\n'
               'values = [0, 1, 0.5]\n'
               '[[drive]]\njoint = "z1"\ntype = "expression"\nf = "0.1*sin(t)"\n',
        extra='[[tolerance]]\ncheck = "pinocchio/M"\nabs = 1e-12\nrel = 1e-10\n'
              'reason = "heavy gripper"\n')
    s = load_model_file(write(tmp_path, text))
    assert s.tolerance("pinocchio", "M").reason == "heavy gripper"
    assert s.tolerance("pinocchio", "M").abs == 1e-12
    assert isinstance(s.model.drives[0].function, Tabulated)
    assert isinstance(s.model.drives[1].function, SympyTimeFunction)
    assert s.model.drive_forces(1.0)[1] == pytest.approx(1.0)
    assert s.model.drive_forces(0.5)[0] == pytest.approx(0.1 * math.sin(0.5), rel=1e-15)
    assert any("drives of the source replaced" in n for n in s.notes)
    assert any("table held constant outside [0, 2] s" in n for n in s.notes)


def test_static_flexible_puts_the_arm_in_its_sag(tmp_path):
    text = crane_text(crane="[model.crane]\nn_rfe = 2\n",
                      initial='[initial]\nq = { psi3 = 0.7853981633974483, z4 = 0.2 }\n'
                              'static_flexible = true\n')
    s = load_model_file(write(tmp_path, text))
    ref = crane_scenario(2, static_arm=True)
    np.testing.assert_allclose(s.q0, ref.q0, rtol=0, atol=1e-12)
    assert np.any(s.q0[[s.model.index(c) for c in s.flexible_coordinates]] != 0.0)


def test_the_example_of_docs_models_md_loads_and_runs(tmp_path):
    """The complete example on docs/models.md is a working file (so the page stays right)."""
    try:
        importlib.metadata.distribution("example-robot-data")
    except importlib.metadata.PackageNotFoundError:
        pytest.skip("example-robot-data not installed (the robots extra)")
    page = (ROOT / "docs" / "models.md").read_text()
    block = re.search(r"```toml\n(.*?)```", page, re.S).group(1)
    s = load_model_file(write(tmp_path, block))
    assert s.model.n_coordinates == 12 and len(s.flexible_coordinates) == 6
    assert s.tolerance("pinocchio", "M").rel == 1e-11
    assert any("replaced by the RFEM beam" in n for n in s.notes)
    phi, phi_dot, _, _ = s.system.constraints(0.0, s.q0, s.q_dot0)
    assert np.max(np.abs(phi)) < 1e-12 and np.max(np.abs(phi_dot)) < 1e-12
    df = simulate(s.system, 0.02, s.q0, s.q_dot0, dt=s.dt, output_dt=0.01)
    # started on the constraints; RK4 at the suggested step keeps them to round-off level
    # (measured 2e-11 m after 0.05 s); a wrong kappa would show as ~1e-5
    assert df[["height", "circle"]].abs().max().max() < 1e-9


def test_urdf_names_are_checked_by_the_reader_and_a_chain_link_can_be_a_frame(tmp_path):
    base = (DATA / "arm3.toml").read_text().replace('urdf = "arm3.urdf"',
                                                    f'urdf = "{DATA / "arm3.urdf"}"')
    bad = base + ('\n[[flexible]]\nlink = "fore_arm"\nsection = { shape = "circle", '
                  'diameter = 0.02 }\nyoungs_modulus = 1e9\nshear_modulus = 4e8\n'
                  'density = 1000.0\nsegments = 1\nbending_viscosity = 0.0\n')
    with pytest.raises(ModelFileError, match=r"model\.urdf \(.*arm3\.urdf\): .*fore_arm"):
        load_model_file(write(tmp_path, bad, "bad.toml"))
    # the elbow's link 'forearm' is no fixed frame of the URDF: its joint frame is used
    good = base.replace('frame = "tool"', 'frame = "forearm"')
    s = load_model_file(write(tmp_path, good, "good.toml"))
    assert s.model.frames["forearm"].link_index == s.model.index("elbow")
    assert any("frame 'forearm' is the frame of link 'forearm'" in n for n in s.notes)


def test_engine_steps_and_engine_tolerances_reach_the_scenario(tmp_path):
    from crosscheck.convergence import RefinementBudget
    from crosscheck.engine_steps import engine_first_step
    text = crane_text(extra=(
        '[[engine_step]]\nengine = "exudyn"\ndt = 2.5e-4\nmax_halvings = 2\n'
        'reason = "start transient"\n'
        '[[tolerance]]\ncheck = "drake/free run q1"\nabs = 1e-9\nrel = 0.0\n'
        'reason = "measured"\n'))
    s = load_model_file(write(tmp_path, text))
    assert s.tolerance("drake", "free run q1").abs == 1e-9
    dt, note, budget = engine_first_step(s, "exudyn", 1e-3, RefinementBudget(4, 60.0))
    assert dt == 2.5e-4 and "start transient" in note and budget.max_halvings == 2
    assert budget.max_run_wall_s == 60.0
    dt, note, budget = engine_first_step(s, "drake", 1e-3, RefinementBudget(4, 60.0))
    assert (dt, note, budget.max_halvings) == (1e-3, "", 4)
