"""Bad URDF files and side files: one ModelFileError listing every problem of one read.

Each case writes a broken copy of examples/my_arm (URDF + side file) and checks the error
type, the file or record the message names, the value and what would be valid.  The
staged cases check that problems from different stages (side file and URDF, a bad
inertial and a mesh-only link, two drive records, the XML tree and an inertial) come in
ONE message.  A seeded fuzz over the repository's URDFs and side files checks that any
malformed file either loads or raises ModelFileError (never another exception, never the
reader's last-resort message for an exception its checks missed), and two cases go
through ``python -m gpme.cli simulate --model``: exit status 2, no traceback.
"""
import copy
import json
import subprocess
import sys
import warnings
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from gpme_core.errors import ModelFileError
from gpme_io.side_file import check_side_file, side_file_path
from gpme_io.urdf_reader import load_urdf, parse_urdf

ROOT = Path(__file__).resolve().parents[1]
ARM = ROOT / "examples" / "my_arm" / "my_arm.urdf"
ARM_TEXT = ARM.read_text()
# the forearm's <inertial> as my_arm.urdf writes it
FOREARM_INERTIAL = """<inertial><origin xyz="0.15 0 0"/><mass value="1.0"/>
      <inertia ixx="0.0005" ixy="0" ixz="0" iyy="0.008" iyz="0" izz="0.008"/></inertial>"""
ZERO_INERTIAL = ('<inertial><mass value="0"/><inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" '
                 'izz="0"/></inertial>')
MESH = '<visual><geometry><mesh filename="forearm.stl"/></geometry></visual>'
CHAIN = "['yaw', 'shoulder', 'elbow']"
GOOD_BEAM = {"length": 0.35, "youngs_modulus": 7e10, "shear_modulus": 2.6e10,
             "density": 2700.0, "area": 1e-4, "second_moment_y": 1e-9,
             "second_moment_z": 1e-9, "torsion_constant": 2e-9}


def side(**changes):
    """A valid side file for my_arm with ``changes`` (None deletes a key)."""
    doc = {"format": "gpme-urdf-side-file", "version": 1, "model": "my_arm",
           "gravity": [0.0, 0.0, -9.81],
           "joints": {"shoulder": {"stiffness": 1.0, "spring_reference": 0.0}},
           "massless_links": [], "flexible_links": [],
           "drives": [{"joint": "elbow", "function": "QuinticRamp",
                       "parameters": {"level": 1.0, "ramp_time": 0.5}}]}
    for key, value in changes.items():
        if value is None:
            doc.pop(key, None)
        else:
            doc[key] = value
    return doc


def arm(*replacements):
    """my_arm.urdf with each (old, new) replaced once (old must be in the file)."""
    text = ARM_TEXT
    for old, new in replacements:
        assert old in text, old
        text = text.replace(old, new, 1)
    return text


def drive(joint, function, **parameters):
    return {"joint": joint, "function": function, "parameters": parameters}


def flexible(name, links, joints, **beam):
    return {"name": name, "n_segments": 0, "beam": {**GOOD_BEAM, **beam}, "joints": joints,
            "links": links}


def write_case(tmp_path, urdf, side_doc):
    """Write the URDF (str or bytes) and its side file (dict, raw str, or None) beside it."""
    path = tmp_path / "robot.urdf"
    if isinstance(urdf, bytes):
        path.write_bytes(urdf)
    else:
        path.write_text(urdf)
    if side_doc is not None:
        side_file_path(path).write_text(side_doc if isinstance(side_doc, str)
                                        else json.dumps(side_doc))
    return path


def problems_of(path, **kwargs):
    with pytest.raises(ModelFileError) as info:
        load_urdf(path, **kwargs)
    return info.value


# (id, URDF text or bytes, side file, words every one of which the message holds)
CASES = [
    # ---------------------------------------------------------------- XML
    ("xml-not-well-formed", '<robot name="r">\n  <link name="a">\n</robot>\n', None,
     ["robot.urdf: not well-formed XML at line 3", "mismatched tag",
      "nothing else in the URDF could be checked"]),
    ("xml-empty-file", "", None,
     ["not well-formed XML at line 1, column 1 (no element found)"]),
    ("xml-binary-junk", bytes(range(256)) * 3, None,
     ["not well-formed XML at line 1", "invalid token"]),
    ("xml-wrong-root-tag", arm(("<robot name", "<robots name"), ("</robot>", "</robots>")),
     None, ["the root element must be <robot>, got <robots>"]),
    # ---------------------------------------------------------------- inertials
    ("mass-not-a-number", arm(('<mass value="2.0"/>', '<mass value="abc"/>')), None,
     ["link 'column' <inertial> <mass value>: expected 1 finite number, got 'abc'"]),
    ("mass-nan", arm(('<mass value="2.0"/>', '<mass value="nan"/>')), None,
     ["link 'column' <inertial> <mass value>: expected 1 finite number, got 'nan'"]),
    ("mass-negative", arm(('<mass value="1.5"/>', '<mass value="-1.5"/>')), None,
     ["link 'upper_arm' <inertial>: mass must be positive and finite, got -1.5 kg",
      "or exactly 0 kg for a massless body"]),
    ("inertia-negative-moment", arm(('ixx="0.02" ixy="0"', 'ixx="-0.02" ixy="0"')), None,
     ["link 'column' <inertial>: inertia tensor must be positive definite or semi-definite",
      "principal moments [-0.02,"]),
    ("inertia-attribute-missing", arm(('ixx="0.0005" ixy="0" ixz="0"', 'ixx="0.0005" ixz="0"')),
     None, ["link 'forearm' <inertial>: <inertia> without ixy (kg m^2; URDF needs all six: "
            "ixx, ixy, ixz, iyy, iyz, izz)"]),
    ("mesh-only-moving-link", arm((FOREARM_INERTIAL, MESH)), None,
     ["link 'forearm' has <visual>/<collision> geometry but no <inertial>, and it moves "
      "(with joint 'elbow')", "give it an <inertial>", "explicit zero <inertial>"]),
    ("inertia-too-large", arm(('<mass value="1.0"/>', '<mass value="1e300"/>')), None,
     ["link 'forearm' <inertial>: mass 1e+300 kg", "too large to compute with",
      "check the units (kg, m, kg m^2)"]),
    # ---------------------------------------------------------------- joints
    ("joint-type-unsupported", arm(('name="elbow" type="revolute"',
                                    'name="elbow" type="spherical"')), None,
     ["joint 'elbow': unknown type 'spherical'; URDF types: revolute, continuous, prismatic, "
      "fixed, floating, planar"]),
    ("joint-type-missing", arm(('name="elbow" type="revolute"', 'name="elbow"')), None,
     ["joint 'elbow': missing type=...; URDF types: revolute, continuous, prismatic"]),
    ("axis-zero", arm(('<axis xyz="0 1 0"/>', '<axis xyz="0 0 0"/>')), None,
     ["joint 'shoulder': <axis xyz> must not be zero, got '0 0 0'", "e.g. '0 0 1'"]),
    ("axis-not-finite", arm(('<axis xyz="0 1 0"/>', '<axis xyz="nan 1 0"/>')), None,
     ["joint 'shoulder' <axis xyz>: expected 3 finite numbers, got 'nan 1 0'"]),
    ("limits-reversed", arm(('lower="-2.0" upper="2.0"', 'lower="2.0" upper="-2.0"')), None,
     ["joint 'shoulder': <limit lower=2.0 upper=-2.0> must have lower <= upper"]),
    ("origin-rpy-not-numbers", arm(('<origin xyz="0.4 0 0" rpy="0 0 0"/>',
                                    '<origin xyz="0.4 0 0" rpy="0 abc"/>')), None,
     ["joint 'elbow' <origin rpy>: expected 3 finite numbers, got '0 abc'",
      "3 decimal numbers separated by spaces"]),
    ("origin-far-beyond-any-robot", arm(('<origin xyz="0.4 0 0" rpy="0 0 0"/>',
                                         '<origin xyz="1e300 0 0" rpy="0 0 0"/>')), None,
     ["joint 'elbow', 1e+300 m", "too large to compute with",
      "check the units of <origin xyz> (m)"]),
    ("damping-negative", arm(('<dynamics damping="0.3"/>', '<dynamics damping="-0.3"/>')), None,
     ["joint 'elbow': <dynamics damping> must be >= 0 (N m s/rad or N s/m), got -0.3"]),
    # ---------------------------------------------------------------- tree
    ("parent-missing", arm(('<parent link="upper_arm"/>', '')), None,
     ["joint 'elbow': missing <parent link=...>",
      "exactly one root link (a link that is no joint's child), found ['base', 'forearm']",
      "not checked because of it: the chain"]),
    ("child-not-a-link", arm(('<child link="forearm"/>', '<child link="fore_arm"/>')), None,
     ["joint 'elbow': child link 'fore_arm' is not a <link> of the file"]),
    ("joints-form-a-loop", arm(('<joint name="yaw"', '<joint name="back" type="fixed"><parent '
                                'link="tool"/><child link="base"/></joint>\n  <joint name="yaw"')),
     None, ["found []; every link is some joint's child, so the joints form a loop"]),
    ("link-names-repeat", arm(('<link name="tool">', '<link name="column">')), None,
     ["link names repeat: ['column']"]),
    ("joint-without-name", arm(('<joint name="tool_mount" type="fixed">',
                                '<joint type="fixed">')), None,
     ["a <joint> without a name attribute (type 'fixed', child link 'tool')"]),
    # ---------------------------------------------------------------- side file alone
    ("side-not-json", ARM_TEXT, '{"format": "gpme-urdf-side-file",\n "version": 1,,}',
     ["robot.gpme.json': not valid JSON at line 2, column 15",
      "nothing in it was checked"]),
    ("side-not-an-object", ARM_TEXT, "[1, 2]",
     ["expected a JSON object {\"format\": 'gpme-urdf-side-file', \"version\": 1, ...}, got a "
      "JSON array"]),
    ("side-wrong-format", ARM_TEXT, side(format="other", version=3),
     ["expected format 'gpme-urdf-side-file' version 1, got 'other' version 3"]),
    ("side-unknown-key", ARM_TEXT, side(gravty=[0, 0, -9.81]),
     ["unknown key 'gravty' (did you mean 'gravity'?); the keys are format, version, model, "
      "gravity, joints, massless_links, flexible_links, drives"]),
    ("side-gravity-not-numbers", ARM_TEXT, side(gravity=[0, 0, "down"]),
     ["gravity must be 3 finite numbers (m/s^2, world frame), got [0, 0, 'down']"]),
    ("side-stiffness-negative", ARM_TEXT,
     side(joints={"shoulder": {"stiffness": -5.0, "spring_reference": 0.0}}),
     ["joint 'shoulder' stiffness must be a finite number >= 0 (N m/rad or N/m), got -5.0"]),
    ("side-spring-record-unknown-key", ARM_TEXT,
     side(joints={"shoulder": {"stifness": 5.0}}),
     ["joint 'shoulder': unknown key 'stifness' (did you mean 'stiffness'?); the keys are "
      "stiffness, spring_reference"]),
    ("side-springs-for-unknown-joint", ARM_TEXT,
     side(joints={"wrist": {"stiffness": 5.0, "spring_reference": 0.0}}),
     [f"the side file gives springs for joints ['wrist'] that are not moving joints of the "
      f"chain {CHAIN}"]),
    ("side-drive-wrong-parameter", ARM_TEXT,
     side(drives=[drive("shoulder", "QuinticRamp", levle=1.0, ramp_time=0.5)]),
     ["drive record on 'shoulder' (drives #1, QuinticRamp): unknown parameter 'levle' (did "
      "you mean 'level'?); missing parameter level; QuinticRamp takes level, ramp_time"]),
    ("side-drive-unknown-function", ARM_TEXT,
     side(drives=[drive("shoulder", "Ramp", level=1.0)]),
     ["drive record on 'shoulder' (drives #1): function must be one of Constant, Cosine, "
      "QuinticRamp, Sine", "got 'Ramp'"]),
    ("side-drive-bad-value", ARM_TEXT,
     side(drives=[drive("shoulder", "QuinticRamp", level=1.0, ramp_time=-0.5)]),
     ["drive record on 'shoulder' (drives #1, QuinticRamp): QuinticRamp: ramp_time must be a "
      "finite number > 0 (s), got -0.5"]),
    ("side-drive-on-unknown-joint", ARM_TEXT,
     side(drives=[drive("wrist", "Constant", level=1.0)]),
     [f"the side file's drive record on 'wrist' (Constant): not a moving joint of the chain "
      f"{CHAIN}"]),
    ("side-flexible-names-missing-link", ARM_TEXT,
     side(flexible_links=[flexible("forearm", ["forearm", "hand"], ["elbow"])]),
     ["the side file's flexible link record 'forearm' names link 'hand', not in the chain"]),
    ("side-flexible-beam-property", ARM_TEXT,
     side(flexible_links=[flexible("forearm", ["forearm"], ["elbow"], youngs_modulus=-7e10,
                                   density="heavy")]),
     ["flexible link record 'forearm' (flexible_links #1) beam: density must be a finite "
      "number, got 'heavy'"]),
    ("side-flexible-record-incomplete", ARM_TEXT,
     side(flexible_links=[{"name": "forearm", "n_segments": -1}]),
     ["flexible link record 'forearm' (flexible_links #1): missing beam, joints, links",
      "n_segments must be an integer from 0 to 1000, got -1"]),
    ("side-key-given-twice", ARM_TEXT,
     '{"format": "gpme-urdf-side-file", "version": 1, "joints": {"shoulder": '
     '{"stiffness": 1.0, "stiffness": -1.0}}}',
     ["keys given twice in one object: ['stiffness'] (JSON keeps only the last; give each "
      "once)"]),
    ("side-massless-link-unknown", ARM_TEXT, side(massless_links=["wrist"]),
     ["the side file's massless_links ['wrist'] are not links of the URDF"]),
]


@pytest.mark.parametrize("urdf, side_doc, words", [c[1:] for c in CASES],
                         ids=[c[0] for c in CASES])
def test_bad_input_is_one_model_file_error_naming_the_place(tmp_path, urdf, side_doc, words):
    path = write_case(tmp_path, urdf, side_doc)
    msg = str(problems_of(path))
    for word in words:
        assert word in msg, f"{word!r} not in:\n{msg}"
    assert str(tmp_path) in msg                     # the file is named
    assert "unexpected" not in msg                  # found by a check, not by the net


# ------------------------------------------------------------------ several stages at once
# (id, URDF, side file, words: each from a different stage, all in the one message)
STAGED = [
    ("bad-side-file-and-urdf-problem",
     arm(('<axis xyz="0 1 0"/>', '<axis xyz="0 0 0"/>')), side(format="other"),
     ["robot.gpme.json': expected format 'gpme-urdf-side-file' version 1, got 'other'",
      "robot.urdf: joint 'shoulder': <axis xyz> must not be zero"]),
    ("invalid-json-and-urdf-problem",
     arm(('lower="-2.0" upper="2.0"', 'lower="2.0" upper="-2.0"')), "{oops",
     ["not valid JSON at line 1, column 2",
      "joint 'shoulder': <limit lower=2.0 upper=-2.0> must have lower <= upper"]),
    ("negative-inertia-and-mesh-only-link",
     arm(('<mass value="1.5"/>', '<mass value="-1.5"/>'), (FOREARM_INERTIAL, MESH)), None,
     ["link 'upper_arm' <inertial>: mass must be positive and finite, got -1.5 kg",
      "link 'forearm' has <visual>/<collision> geometry but no <inertial>"]),
    ("two-drives-wrong",
     ARM_TEXT, side(drives=[drive("shoulder", "QuinticRamp", levle=1.0, ramp_time=0.5),
                            drive("elbow", "Cosine", offset=0.0, amplitude=1.0)]),
     ["drive record on 'shoulder' (drives #1, QuinticRamp): unknown parameter 'levle'",
      "drive record on 'elbow' (drives #2, Cosine): missing parameter period; Cosine takes "
      "offset, amplitude, period"]),
    ("bad-drive-and-side-file-against-urdf",
     ARM_TEXT, side(drives=[drive("shoulder", "Sine", offset=0.0)],
                    joints={"wrist": {"stiffness": 1.0}}),
     ["drive record on 'shoulder' (drives #1, Sine): missing parameters amplitude, period",
      "the side file gives springs for joints ['wrist']"]),
    ("side-file-and-inertial-and-joint-and-mass-matrix",
     # the forearm and the tool massless: nothing resists the elbow (the built model)
     arm(('<mass value="2.0"/>', '<mass value="abc"/>'),
         ('<dynamics damping="0.3"/>', '<dynamics damping="-1"/>'),
         (FOREARM_INERTIAL, ZERO_INERTIAL), ('<mass value="0.2"/>', '<mass value="0"/>')),
     side(gravity="down"),
     ["gravity must be 3 finite numbers", "link 'column' <inertial> <mass value>: expected 1 "
      "finite number, got 'abc'", "joint 'elbow': <dynamics damping> must be >= 0",
      "no mass or inertia resists a motion of elbow"]),
    ("broken-tree-and-inertial",
     arm(('<parent link="upper_arm"/>', ''), ('ixx="0.02" ixy="0"', 'ixx="-0.02" ixy="0"')),
     side(drives=[drive("elbow", "Constant", lvl=1.0)]),
     ["drive record on 'elbow' (drives #1, Constant): unknown parameter 'lvl'",
      "link 'column' <inertial>: inertia tensor must be positive definite",
      "joint 'elbow': missing <parent link=...>",
      "not checked because of it: the chain, frozen joints, the side file against the URDF"]),
]


@pytest.mark.parametrize("urdf, side_doc, words", [c[1:] for c in STAGED],
                         ids=[c[0] for c in STAGED])
def test_problems_of_every_stage_come_in_one_error(tmp_path, urdf, side_doc, words):
    path = write_case(tmp_path, urdf, side_doc)
    err = problems_of(path)
    msg = str(err)
    assert len(err.problems) >= len(words) and msg.startswith(f"{len(err.problems)} problems")
    for word in words:
        assert word in msg, f"{word!r} not in:\n{msg}"


def test_missing_file_and_directory_are_named(tmp_path):
    msg = str(problems_of(tmp_path / "nowhere.urdf"))
    assert "nowhere.urdf: cannot read the URDF: it does not exist" in msg
    assert "<robot name=...>" in msg
    msg = str(problems_of(tmp_path))
    assert "cannot read the URDF: it is a directory, not a regular file" in msg
    side_dir = tmp_path / "side"
    side_dir.mkdir()
    path = write_case(tmp_path, ARM_TEXT, None)
    msg = str(problems_of(path, side_file=side_dir))
    assert f"side file {str(side_dir)!r}: cannot read it" in msg


def test_chain_choice_failure_says_what_was_not_checked(tmp_path):
    path = write_case(tmp_path, ARM_TEXT, side(joints={"wrist": {"stiffness": 1.0}}))
    msg = str(problems_of(path, chain=("base", "nowhere")))
    assert "chain tip 'nowhere': not a link of the file" in msg
    assert "not checked because of it: frozen joints, the side file against the URDF" in msg


def test_text_and_side_dict_api_reports_both(tmp_path):
    bad_side = side(drives=[drive("elbow", "QuinticRamp", level="1", ramp_time=0.5)])
    with pytest.raises(ModelFileError) as info:
        parse_urdf(arm(('<mass value="2.0"/>', '<mass value="-2"/>')), side=bad_side,
                   source="arm.urdf")
    msg = str(info.value)
    assert "QuinticRamp: level must be a finite number, got '1'" in msg
    assert "arm.urdf: link 'column' <inertial>: mass must be positive" in msg


def test_the_valid_side_file_loads_and_keeps_its_records(tmp_path):
    """The reference the cases break: the same files load, drive and spring applied."""
    path = write_case(tmp_path, ARM_TEXT, side())
    res = load_urdf(path)
    assert res.model.coordinate_names == ("yaw", "shoulder", "elbow")
    assert res.model.joints[1].stiffness == 1.0
    assert [d.joint for d in res.model.drives] == ["elbow"]
    clean, problems = check_side_file(side(drives=[drive("elbow", "Constant", level=1.0),
                                                   drive("yaw", "Constant", lvl=1.0)]))
    assert [d["joint"] for d in clean["drives"]] == ["elbow"] and len(problems) == 1


def test_non_unit_axis_infinite_limit_and_unnamed_robot_are_accepted_and_noted(tmp_path):
    path = write_case(tmp_path, arm(('<axis xyz="0 1 0"/>', '<axis xyz="0 2 0"/>'),
                                    ('<robot name="my_arm">', '<robot>'),
                                    ('lower="-2.6" upper="2.6"', 'lower="-inf" upper="inf"')),
                      None)
    res = load_urdf(path)
    assert res.model.joints[2].limits == (-np.inf, np.inf)
    assert np.allclose(res.model.joints[1].axis, (0.0, 1.0, 0.0), rtol=0, atol=1e-15)
    assert any("<axis xyz> not of unit length on 1 joint, normalised" in n and "shoulder" in n
               for n in res.notes)
    assert "<robot> without a name: the model is named 'urdf'" in res.notes


# ------------------------------------------------------------------ fuzz
# The repository's URDFs (with the chain a tree needs) and their side files.
FUZZ_SOURCES = [
    ("examples/my_arm/my_arm.urdf", {}),
    ("models/urdf/crane_rigid.urdf", {}),
    ("models/urdf/crane_flexible_n1.urdf", {}),
    ("tests/data/modelfiles/arm3.urdf", {}),
    ("tests/data/pinocchio/branch_arm.urdf", {"chain": ("base", "tool")}),
    ("tests/data/urdf/beam_along_z.urdf", {}),
    ("tests/data/urdf/extensions.urdf", {}),
    ("tests/data/urdf/tree.urdf", {"chain": ("base", "c"), "frozen": {"jb": 0.4}}),
]
BAD_TEXT = ["abc", "nan", "-1", "", "1 2", "inf", "-inf", "1e308", "-1e308", "0", "1e-320",
            "1 2 3 4", "  "]
BAD_NAMES = ["", " ", "world", "base", "tool", "x" * 200]
BAD_JSON = [None, "abc", float("nan"), -1, [], {}, "", [1, 2], 10 ** 400, True, {"x": 1}]


def _mutate_urdf(text, rng):
    """1 to 3 random edits of the XML tree: delete or corrupt an attribute, delete or
    duplicate an element, rename the root, change a joint's type or ends."""
    root = ET.fromstring(text)
    for _ in range(int(rng.integers(1, 4))):
        els = list(root.iter())
        el = els[int(rng.integers(len(els)))]
        keys = sorted(el.attrib)
        op = int(rng.integers(8))
        if op == 0 and keys:
            del el.attrib[keys[int(rng.integers(len(keys)))]]
        elif op in (1, 2) and keys:
            key = keys[int(rng.integers(len(keys)))]
            pool = BAD_NAMES if key in ("name", "link") and rng.random() < 0.5 else BAD_TEXT
            el.set(key, pool[int(rng.integers(len(pool)))])
        elif op == 3 and el is not root:
            parent = next(p for p in root.iter() if el in list(p))
            parent.remove(el)
        elif op == 4:
            elements = root.findall("link") + root.findall("joint")
            if elements:
                root.append(copy.deepcopy(elements[int(rng.integers(len(elements)))]))
        elif op == 5:
            root.tag = ["robots", "sdf", "Robot"][int(rng.integers(3))]
        elif op == 6 and el.tag == "joint":
            el.set("type", ["ball", "", "fixed", "floating", "planar", "continuous",
                            "prismatic"][int(rng.integers(7))])
        elif op == 7 and el.tag == "joint":
            links = [lk.get("name") for lk in root.findall("link") if lk.get("name")]
            end = el.find(["parent", "child"][int(rng.integers(2))])
            if end is not None and links:
                end.set("link", links[int(rng.integers(len(links)))])
    return ET.tostring(root, encoding="unicode")


def _mutate_side(doc, rng):
    """1 to 3 random edits anywhere in the side file: delete or rename a key, or put a
    wrong value (wrong type, NaN, an int too large for a float, ...)."""
    doc = copy.deepcopy(doc)
    for _ in range(int(rng.integers(1, 4))):
        node = doc
        for _ in range(int(rng.integers(0, 4))):
            keys = list(node) if isinstance(node, dict) else list(range(len(node)))
            if not keys:
                break
            child = node[keys[int(rng.integers(len(keys)))]]
            if not isinstance(child, (dict, list)) or not child:
                break
            node = child
        keys = list(node) if isinstance(node, dict) else list(range(len(node)))
        if not keys:
            continue
        key = keys[int(rng.integers(len(keys)))]
        r = rng.random()
        if r < 0.3 and isinstance(node, dict):
            del node[key]
        elif r < 0.45 and isinstance(node, dict):
            node[f"{key}x"] = node.pop(key)
        else:
            node[key] = copy.deepcopy(BAD_JSON[int(rng.integers(len(BAD_JSON)))])
    return doc


def _variant(tmp_path, k, rng):
    """(path, load_urdf kwargs) of fuzz variant ``k``."""
    rel, kwargs = FUZZ_SOURCES[int(rng.integers(len(FUZZ_SOURCES)))]
    src = ROOT / rel
    text = src.read_text()
    path = tmp_path / f"v{k}.urdf"
    r = rng.random()
    if r < 0.04:
        path.write_bytes(rng.integers(0, 256, int(rng.integers(0, 300)), dtype=np.uint8)
                         .tobytes())
    elif r < 0.08:
        path.write_text(text[:int(rng.integers(0, len(text)))])
    elif r < 0.75:
        path.write_text(_mutate_urdf(text, rng))
    else:
        path.write_text(text)                         # the side file carries the fault
    side_src = side_file_path(src)
    if side_src.exists():
        doc = json.loads(side_src.read_text())
        if r >= 0.75 or rng.random() < 0.3:
            doc = _mutate_side(doc, rng)
        side_file_path(path).write_text(json.dumps(doc))
    return path, kwargs


def test_fuzz_every_malformed_file_loads_or_raises_model_file_error(tmp_path):
    rng = np.random.default_rng(20240612)
    outcomes = {"loaded": 0, "refused": 0}
    paths = [(tmp_path / "nowhere.urdf", {}), (tmp_path, {})]
    paths += [_variant(tmp_path, k, rng) for k in range(200)]
    for path, kwargs in paths:
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")       # SectionWarning of a mutated beam
                load_urdf(path, **kwargs)
            outcomes["loaded"] += 1
        except ModelFileError as exc:
            outcomes["refused"] += 1
            msg = str(exc)
            assert "reading stopped at an unexpected" not in msg, (path, msg)
            assert msg.strip()
    # the mutations are mostly harmful: most variants are refused, some still load
    assert outcomes["refused"] > 100 and outcomes["loaded"] > 10, outcomes


# ------------------------------------------------------------------ through the CLI
MODEL_TOML = """[model]
name = "my_arm"
urdf = "robot.urdf"
gravity = [0.0, 0.0, -9.81]

[[programme]]
joint = "yaw"
q = "0.8*sin(pi*t)"

[initial]
q = { yaw = 0.0, shoulder = -0.3, elbow = 1.2 }

[run]
t_end = 0.05
quick_t_end = 0.05
"""

CLI = [
    ("negative-mass-and-bad-drive",
     arm(('<mass value="1.5"/>', '<mass value="-1.5"/>')),
     side(drives=[drive("shoulder", "QuinticRamp", levle=1.0, ramp_time=0.5)]),
     ["model.urdf (robot.urdf)", "link 'upper_arm' <inertial>: mass must be positive and "
      "finite, got -1.5 kg", "drive record on 'shoulder' (drives #1, QuinticRamp): unknown "
      "parameter 'levle' (did you mean 'level'?)"]),
    ("binary-urdf", bytes(range(200)), None,
     ["model.urdf (robot.urdf)", "not well-formed XML at line 1"]),
]


@pytest.mark.parametrize("urdf, side_doc, words", [c[1:] for c in CLI],
                         ids=[c[0] for c in CLI])
def test_cli_simulate_exits_2_without_a_traceback(tmp_path, urdf, side_doc, words):
    write_case(tmp_path, urdf, side_doc)
    model = tmp_path / "robot.toml"
    model.write_text(MODEL_TOML)
    run = subprocess.run([sys.executable, "-m", "gpme.cli", "simulate", "--model", str(model),
                          "--out", str(tmp_path / "out")],
                         capture_output=True, text=True, cwd=ROOT, timeout=300)
    assert run.returncode == 2, run.stderr
    assert "Traceback" not in run.stderr
    assert run.stderr.startswith("error: ")
    for word in words:
        assert word in run.stderr, f"{word!r} not in:\n{run.stderr}"
