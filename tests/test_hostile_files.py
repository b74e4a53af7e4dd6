"""Hostile input files (issue 24): files nobody has read, as CI meets them in pull requests.

By class, each with several cases:

* special and oversized files: /dev/zero, a FIFO, a directory and a sparse file one byte
  above the limit, given as the model file, the URDF, the side file and the sweep file,
  are refused with what they are (and the size and the limit) before a byte is read; a
  symlink to a regular file is read;
* URDF trees that are not trees: a joint closing a cycle, a link that is the child of two
  joints, a self-loop, a robot that is one loop, a detached cycle and a 5 000-link cycle
  are refused in well under a second with the joints' names;
* hostile names in every XML the project writes (URDF, MJCF, JUnit, HTML): markup, "--"
  and a trailing "-" give well-formed files whose names read back (gpme's reader and
  Pinocchio for the URDF, MuJoCo for the MJCF); characters XML 1.0 cannot hold are refused
  where a name must read back (URDF, MJCF, model files) and escaped in reports;
* YAML alias bombs and recursive aliases in a sweep file are refused before any value is
  built, and a large value that does load is echoed in at most ~200 characters;
* through `python -m gpme.cli simulate --model`: exit status 2, the key words, no traceback,
  and a timeout so that a hang fails the test instead of blocking it.
"""
import os
import subprocess
import sys
import threading
import time
import xml.etree.ElementTree as ET
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest

from gpme_core import transforms as tf
from gpme_core.echo import ECHO_LIMIT, shown
from gpme_core.errors import ModelError, ModelFileError
from gpme_core.inertia import cuboid
from gpme_core.model import REVOLUTE, ChainBuilder
from gpme_io import input_files
from gpme_io.input_files import (MODEL_FILE_LIMIT, SIDE_FILE_LIMIT, SWEEP_FILE_LIMIT,
                                 URDF_LIMIT, InputFileError, read_input_file)
from gpme_io.modelfile import load_model_file, read_model_file
from gpme_io.side_file import load_side_file
from gpme_io.urdf_read.tree import _subtree_joints, _Tree
from gpme_io.urdf_reader import load_urdf, parse_urdf
from gpme_io.urdf_writer import urdf_documents
from gpme_io.xml_text import (NOT_XML_CHAR, comment_text, make_tree_safe, xml_comment,
                              xml_safe_text)
from gpme_study.bounded_yaml import YamlSizeError, load_yaml
from gpme_study.spec_points import SweepSpecError, read_spec_file

ROOT = Path(__file__).resolve().parents[1]
ARM_DIR = ROOT / "examples" / "my_arm"
ARM_TEXT = (ARM_DIR / "my_arm.urdf").read_text()
ARM_TOML = (ARM_DIR / "my_arm.toml").read_text()
# a hang guard, not a speed claim: a refusal takes milliseconds (the 5000-link cycle ~2 ms
# on an idle core) while a hang or a read of gigabytes takes far longer; 1 s failed once on
# the shared 2-core machine under four other jobs (2.0 s)
PROMPT_S = 10.0


# ============================================================================ helpers
def _within(seconds, fn, fifo=None):
    """fn() in a daemon thread; fails the test when it has not returned after ``seconds``
    (a reader blocked on ``fifo`` is then released by opening the FIFO for writing)."""
    out = {}

    def run():
        try:
            out["value"] = fn()
        except BaseException as exc:          # handed to the test below
            out["error"] = exc

    worker = threading.Thread(target=run, daemon=True)
    t0 = time.perf_counter()
    worker.start()
    worker.join(seconds)
    if worker.is_alive():
        if fifo is not None:
            os.close(os.open(fifo, os.O_WRONLY | os.O_NONBLOCK))
        pytest.fail(f"still running after {seconds} s (a hang on a special file?)")
    out["seconds"] = time.perf_counter() - t0
    return out


def _special(kind, tmp_path, limit):
    """A path of the given kind: 'dev-zero', 'fifo', 'directory' or 'too-large' (a sparse
    file of limit + 1 bytes: no disk used)."""
    if kind == "dev-zero":
        return Path("/dev/zero")
    if kind == "fifo":
        path = tmp_path / "pipe"
        os.mkfifo(path)
        return path
    if kind == "directory":
        path = tmp_path / "folder"
        path.mkdir()
        return path
    path = tmp_path / "big"
    with open(path, "wb") as f:
        f.truncate(limit + 1)
    return path


# what the message says for each kind (the too-large case: both exact sizes)
KIND_WORDS = {"dev-zero": ["is a character device, not a regular file"],
              "fifo": ["is a FIFO (named pipe), not a regular file"],
              "directory": ["is a directory, not a regular file"],
              "too-large": ["{size:,} bytes", "above the limit of {limit:,} bytes for a"]}
KINDS = list(KIND_WORDS)
if not hasattr(os, "mkfifo") or not Path("/dev/zero").exists():   # pragma: no cover
    pytest.skip("needs a POSIX system (/dev/zero, os.mkfifo)", allow_module_level=True)


def _words(kind, limit):
    return [w.format(size=limit + 1, limit=limit) for w in KIND_WORDS[kind]]


def _refused(fn, path, error=ModelError):
    """The message of the error fn() raises, checked to come within PROMPT_S."""
    out = _within(10 * PROMPT_S, fn, fifo=path if path.is_fifo() else None)
    assert "error" in out, f"accepted: {out.get('value')!r}"
    assert isinstance(out["error"], error), repr(out["error"])
    assert out["seconds"] < PROMPT_S, out["seconds"]
    return str(out["error"])


# ================================================================ special and large files
@pytest.mark.parametrize("kind", KINDS)
def test_model_file_must_be_a_regular_file_under_its_limit(kind, tmp_path):
    path = _special(kind, tmp_path, MODEL_FILE_LIMIT)
    msg = _refused(lambda: read_model_file(path), path, ModelFileError)
    assert "cannot read the model file: it " in msg and str(path) in msg
    for word in _words(kind, MODEL_FILE_LIMIT):
        assert word in msg, (word, msg)


@pytest.mark.parametrize("kind", KINDS)
def test_urdf_must_be_a_regular_file_under_its_limit(kind, tmp_path):
    path = _special(kind, tmp_path, URDF_LIMIT)
    msg = _refused(lambda: load_urdf(path, side_file=None), path, ModelFileError)
    assert "cannot read the URDF: it " in msg and str(path) in msg
    for word in _words(kind, URDF_LIMIT):
        assert word in msg, (word, msg)


@pytest.mark.parametrize("kind", KINDS)
def test_side_file_must_be_a_regular_file_under_its_limit(kind, tmp_path):
    path = _special(kind, tmp_path, SIDE_FILE_LIMIT)
    msg = _refused(lambda: load_side_file(path), path, ModelFileError)
    assert f"side file {str(path)!r}: cannot read it: it " in msg
    for word in _words(kind, SIDE_FILE_LIMIT):
        assert word in msg, (word, msg)


@pytest.mark.parametrize("kind", KINDS)
def test_sweep_file_must_be_a_regular_file_under_its_limit(kind, tmp_path):
    path = _special(kind, tmp_path, SWEEP_FILE_LIMIT)
    msg = _refused(lambda: read_spec_file(path), path, SweepSpecError)
    assert f"sweep file {str(path)!r} " in msg
    for word in _words(kind, SWEEP_FILE_LIMIT):
        assert word in msg, (word, msg)


@pytest.mark.parametrize("kind", ["fifo", "dev-zero", "too-large"])
def test_urdf_named_by_a_model_file_is_checked_before_it_is_read(kind, tmp_path):
    target = _special(kind, tmp_path, URDF_LIMIT)
    model = tmp_path / "model.toml"
    model.write_text(ARM_TOML.replace('urdf = "my_arm.urdf"', f'urdf = "{target}"'))
    msg = _refused(lambda: load_model_file(model), target, ModelFileError)
    assert "model.urdf: URDF" in msg and str(target) in msg
    for word in _words(kind, URDF_LIMIT):
        assert word in msg, (word, msg)


def test_a_symlink_to_a_regular_file_is_read_and_one_to_a_device_is_named(tmp_path):
    real = tmp_path / "real.urdf"
    real.write_text(ARM_TEXT)
    link = tmp_path / "link.urdf"
    link.symlink_to(real)
    assert load_urdf(link, side_file=None).chain == ("base", "forearm")
    dev = tmp_path / "zero.urdf"
    dev.symlink_to("/dev/zero")
    msg = _refused(lambda: load_urdf(dev, side_file=None), dev, ModelFileError)
    assert "is a character device, not a regular file (the path resolves to '/dev/zero')" in msg


def test_missing_file_and_exact_limit(tmp_path):
    with pytest.raises(InputFileError, match=r"model file '.*nowhere.toml' does not exist"):
        read_input_file(tmp_path / "nowhere.toml", "model file", MODEL_FILE_LIMIT)
    path = tmp_path / "ten"
    path.write_bytes(b"0123456789")
    assert read_input_file(path, "side file", 10) == b"0123456789"        # at the limit: read
    with pytest.raises(InputFileError, match="is 10 bytes, above the limit of 9 bytes for a "
                                             "side file"):
        read_input_file(path, "side file", 9)


def test_a_file_that_grows_after_the_check_is_still_bounded(tmp_path, monkeypatch):
    """The read takes at most limit + 1 bytes whatever the size was at the check."""
    path = tmp_path / "grows.toml"
    path.write_bytes(b"x" * 100)
    real_check = input_files.check_input_file

    def check_then_grow(p, what, limit):
        st = real_check(p, what, limit)
        with open(path, "ab") as f:
            f.write(b"y" * 1000)
        return st

    monkeypatch.setattr(input_files, "check_input_file", check_then_grow)
    with pytest.raises(InputFileError, match="grew to at least 201 bytes, above the limit of "
                                             "200 bytes for a model file"):
        read_input_file(path, "model file", 200)


def test_deeply_nested_model_file_is_a_message_not_a_recursion_error(tmp_path):
    path = tmp_path / "deep.toml"
    path.write_text("a = " + "[" * 50_000 + "]" * 50_000 + "\n")
    with pytest.raises(ModelFileError, match="nested too deeply"):
        read_model_file(path)


# ================================================================ URDF trees that are not trees
def _arm(*joints):
    """my_arm.urdf with extra joint elements before its tool mount."""
    return ARM_TEXT.replace('<joint name="tool_mount"', "\n".join(joints)
                            + '\n  <joint name="tool_mount"', 1)


def _joint(name, parent, child, kind="fixed"):
    axis = '<axis xyz="0 0 1"/>' if kind != "fixed" else ""
    return (f'<joint name="{name}" type="{kind}"><parent link="{parent}"/>'
            f'<child link="{child}"/>{axis}</joint>')


def _chain_with_loop(n):
    links = "".join(f'<link name="l{k}"/>' for k in range(n))
    joints = "".join(_joint(f"j{k}", f"l{k}", f"l{k + 1}") for k in range(n - 1))
    return f'<robot name="r">{links}{joints}{_joint("back", f"l{n - 1}", "l1")}</robot>'


TREE_CASES = {
    "joint-closes-a-cycle": (_arm(_joint("loop", "forearm", "column", "revolute")),
                             ["joint 'loop' (parent 'forearm', child 'column') closes a cycle "
                              "column -> upper_arm -> forearm -> column through joints "
                              "['shoulder', 'elbow', 'loop']",
                              "link 'column' is the child of 2 joints ['yaw', 'loop']",
                              "a URDF is a tree"]),
    "cycle-through-the-tool": (_arm(_joint("back", "tool", "upper_arm")),
                               ["joint 'back' (parent 'tool', child 'upper_arm') closes a cycle "
                                "upper_arm -> forearm -> tool -> upper_arm through joints "
                                "['elbow', 'tool_mount', 'back']"]),
    "child-of-two-joints": (_arm(_joint("extra", "base", "forearm")),
                            ["link 'forearm' is the child of 2 joints ['elbow', 'extra']",
                             "every link but the root is the child of exactly one joint"]),
    "child-of-three-joints": (_arm(_joint("x1", "base", "tool"), _joint("x2", "column", "tool")),
                              ["link 'tool' is the child of 3 joints ['x1', 'x2', "
                               "'tool_mount']"]),
    "self-loop": (_arm(_joint("me", "forearm", "forearm")),
                  ["joint 'me' (parent 'forearm', child 'forearm') closes a cycle forearm -> "
                   "forearm through joints ['me']"]),
    "robot-is-one-loop": (_arm(_joint("back", "tool", "base")),
                          ["closes a cycle", "'back'",
                           "found []; every link is some joint's child, so the joints form "
                           "a loop"]),
    "detached-cycle": (_arm('<link name="p"/><link name="q"/>', _joint("pq", "p", "q"),
                            _joint("qp", "q", "p")),
                       ["closes a cycle", "'pq'", "'qp'",
                        "links ['p', 'q'] are not connected to the root link 'base'"]),
    "5000-link-cycle": (_chain_with_loop(5000),
                        ["joint 'back' (parent 'l4999', child 'l1') closes a cycle l1 -> l2",
                         "(4988 more links)", "(4999 in all)",
                         "link 'l1' is the child of 2 joints ['j0', 'back']"]),
}


@pytest.mark.parametrize("case", list(TREE_CASES), ids=list(TREE_CASES))
def test_urdf_that_is_not_a_tree_is_refused_at_once_with_the_joints(case):
    text, words = TREE_CASES[case]
    out = _within(30.0, lambda: parse_urdf(text, source="robot.urdf"))
    assert isinstance(out.get("error"), ModelFileError), out
    msg = str(out["error"])
    assert out["seconds"] < PROMPT_S, out["seconds"]
    for word in words:
        assert word in msg, (word, msg)
    assert "not checked because of it: the chain" in msg
    assert len(msg) < 3000, len(msg)          # a long cycle is named, not printed whole


def test_traversals_are_bounded_even_on_a_graph_that_is_not_a_tree():
    """Defence in depth: the walks below a link end on a cyclic graph (the reader refuses
    one before any walk)."""
    text = _arm(_joint("loop", "forearm", "column", "revolute"))
    with pytest.raises(ModelFileError):
        parse_urdf(text)

    class J:
        def __init__(self, name, parent, child):
            self.name, self.parent, self.child = name, parent, child

    a, b = J("ab", "a", "b"), J("ba", "b", "a")
    tree = _Tree("a", {"a": [a], "b": [b]}, {"b": a, "a": b})
    assert [j.name for j in _subtree_joints(tree, "a")] == ["ab", "ba"]


# ================================================================ hostile names in XML
HOSTILE = {"model": "evil--name-", "joints": ('a"b<c>&d--e-', "-"),
           "links": ("q'<!--x-->", "l2--"), "frame": "E]]>--"}


def _model(names=HOSTILE):
    b = ChainBuilder(names["model"])
    b.add_joint(names["joints"][0], REVOLUTE, (0, 0, 1), link=names["links"][0], stiffness=2.0)
    b.add_body(cuboid(1.0, (0.1, 0.2, 0.3), com=(0.1, 0.0, 0.0)))
    b.add_joint(names["joints"][1], REVOLUTE, (0, 1, 0), origin=tf.translation(0.2, 0, 0),
                link=names["links"][1])
    b.add_body(cuboid(0.5, (0.3, 0.1, 0.1), com=(0.15, 0.0, 0.0)))
    b.add_frame(names["frame"], tf.translation(0.3, 0, 0))
    return b.build()


def _comments(text):
    parser = ET.XMLParser(target=ET.TreeBuilder(insert_comments=True))
    return [c.text for c in ET.fromstring(text, parser=parser).iter(ET.Comment)]


@pytest.mark.parametrize("text", ["--", "-", "---", "a-", "-->", "x--y-", "\x01-\ud800-"])
def test_comment_text_is_valid_for_any_text(text):
    for body in (comment_text(text), ET.tostring(xml_comment(text), encoding="unicode")):
        assert "--" not in body.removeprefix("<!--").removesuffix("-->")
    ET.fromstring(f"<r><!--{comment_text(text)}--></r>")
    ET.fromstring("<r>" + ET.tostring(xml_comment(text), encoding="unicode") + "</r>")


def test_urdf_with_hostile_names_parses_and_reads_back(tmp_path):
    model = _model()
    text, side = urdf_documents(model, urdf_name="x--y-")
    root = ET.fromstring(text)                        # the "--" comment no longer breaks it
    assert root.get("name") == "evil--name-"
    assert any("evil- -name-" in c for c in _comments(text))
    back = parse_urdf(text, side)
    assert back.name == "evil--name-"
    assert back.coordinate_names == model.coordinate_names
    assert [lk.name for lk in back.links] == [lk.name for lk in model.links]
    assert HOSTILE["frame"] in back.frames


def test_urdf_with_hostile_names_loads_in_pinocchio():
    pinocchio = pytest.importorskip("pinocchio")
    text, _ = urdf_documents(_model())
    pin = pinocchio.buildModelFromXML(text)
    assert list(pin.names)[1:] == list(HOSTILE["joints"])
    assert pin.existFrame(HOSTILE["links"][0]) and pin.existFrame(HOSTILE["frame"])


@pytest.mark.parametrize("where, name", [("model", "a\x01b"), ("joint", "j\x00"),
                                         ("link", "l\ud800"), ("frame", "f\x1f")])
def test_urdf_writer_refuses_names_xml_cannot_hold(where, name):
    names = dict(HOSTILE)
    if where in ("joint", "link"):
        names[where + "s"] = (name, names[where + "s"][1])
    else:
        names[where] = name
    with pytest.raises(ModelFileError, match=r"name .*: character U\+00|U\+D800") as exc:
        urdf_documents(_model(names))
    assert "cannot be written in XML 1.0" in str(exc.value)


def test_mjcf_with_hostile_names_parses_and_loads_in_mujoco():
    mjcf = pytest.importorskip("crosscheck.mujoco.mjcf")
    text = mjcf.mjcf_text(_model(), 1e-3)
    header, body = text.split("\n", 1)
    ET.fromstring(f"<r>{header}</r>")
    root = ET.fromstring(body)
    assert root.get("model") == "evil--name-"
    assert [j.get("name") for j in root.iter("joint")] == list(HOSTILE["joints"])
    mujoco = pytest.importorskip("mujoco")
    mujoco.MjModel.from_xml_string(text)
    with pytest.raises(ModelError, match="U\\+0001"):
        mjcf.mjcf_text(_model(dict(HOSTILE, model="m\x01")), 1e-3)


def _junit_summary(name):
    check = {"name": f"x/{name}", "engine": f"eng{name}", "section": name, "model": name,
             "quantity": name, "n_compared": 3, "n_fail": 1, "worst_abs_error": 1.0,
             "worst_rel_error": 1.0, "worst_case": name, "worst_entry": name, "tol_abs": 0.1,
             "tol_rel": 0.0, "tolerance": 0.1, "error_over_tolerance": 10.0,
             "status": "fail", "reason": name, "crashed": False}
    return {"run": {"date_utc": "2026-01-01 00:00:00", "git_commit": name,
                    "versions": {name: name}, "machine": {"node": name}},
            "checks": [check, dict(check, status="info", quantity=name + "i"),
                       dict(check, status="pass", quantity=name + "p"),
                       dict(check, crashed=True, quantity=name + "c")]}


NAMES = ['a"b<c>&d--e-', "\x01", "x\x00y\ud800z\ufffe", "]]>--><!--", "tab\tnew\nline"]


@pytest.mark.parametrize("name", NAMES)
def test_junit_is_well_formed_for_any_name(name):
    from crosscheck.reports import junit
    data = junit.junit_xml(_junit_summary(name), report_dir=f"runs/{name}")
    text = data.decode("utf-8")
    assert not NOT_XML_CHAR.search(text)
    root = ET.fromstring(data)
    assert len(root.findall(".//testcase")) == 4
    if not NOT_XML_CHAR.search(name):
        assert name.split("\n")[0] in root.find(".//failure").text


class _TagBalance(HTMLParser):
    """Start and end tags of an HTML text; records any end tag that closes nothing."""

    VOID = {"meta", "link", "br", "img", "input", "hr", "col", "wbr", "source", "area"}

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.open, self.bad, self.tags, self.data = [], [], set(), []

    def handle_starttag(self, tag, attrs):
        self.tags.add(tag)
        if tag not in self.VOID:
            self.open.append(tag)

    def handle_endtag(self, tag):
        if self.open and self.open[-1] == tag:
            self.open.pop()
        else:
            self.bad.append(tag)

    def handle_data(self, data):
        self.data.append(data)


@pytest.mark.parametrize("name", NAMES)
def test_html_engine_page_is_well_formed_for_any_name(name):
    pytest.importorskip("jinja2")
    import pandas as pd

    from crosscheck.reports import html
    text = pd.Series([name], dtype=object)   # pyarrow strings cannot hold a lone surrogate
    df = pd.DataFrame({"model": text, "quantity": text, "error": [1.0], "status": ["fail"]})
    page = html.engine_page(name, name, False, [name], [html.section(
        name, [name], table=html.table(df, left_columns=("model",)), items=[name],
        figures=[(name, name)])])
    assert not NOT_XML_CHAR.search(page)
    parser = _TagBalance()
    parser.feed(page)
    parser.close()
    assert parser.bad == [] and parser.open == [], (parser.bad, parser.open)
    assert not parser.tags & {"b", "c", "script"}
    from markupsafe import escape
    assert str(escape(xml_safe_text(name))) in page
    assert "<" not in name or name not in page


def test_make_tree_safe_escapes_text_tails_attributes_and_comments():
    root = ET.Element("r", {"a": "x\x01"})
    child = ET.SubElement(root, "c")
    child.text, child.tail = "\x02", "\x03"
    root.append(ET.Comment("--\x04-"))
    text = ET.tostring(make_tree_safe(root), encoding="unicode")
    assert '<r a="x\\x01"><c>\\x02</c>\\x03<!--- -\\x04- -->' in text
    ET.fromstring(text)


def test_model_file_refuses_a_name_xml_cannot_hold(tmp_path):
    (tmp_path / "my_arm.urdf").write_text(ARM_TEXT)
    path = tmp_path / "m.toml"
    path.write_text(ARM_TOML.replace('name = "my_arm"', 'name = "arm\\u0001"')
                    .replace('name = "circle"', 'name = "c\\u001f"'))
    with pytest.raises(ModelFileError) as exc:
        read_model_file(path)
    msg = str(exc.value)
    assert "model.name: string 'arm\\x01': character U+0001 cannot be written in XML 1.0" in msg
    assert "constraint[0].name: string 'c\\x1f': character U+001F" in msg


# ================================================================ YAML alias bombs
def _bomb(levels, width=9):
    lines = [f'a0: &a0 [{", ".join(["lol"] * width)}]']
    for k in range(1, levels):
        lines.append(f"a{k}: &a{k} [{', '.join([f'*a{k - 1}'] * width)}]")
    return "\n".join(lines) + f"\nparameters:\n  amplitude: *a{levels - 1}\n"


@pytest.mark.parametrize("levels", [6, 9, 12])
def test_yaml_alias_bomb_is_refused_before_any_value_is_built(levels, tmp_path):
    path = tmp_path / "bomb.yaml"
    path.write_text(_bomb(levels))
    t0 = time.perf_counter()
    with pytest.raises(SweepSpecError) as exc:
        read_spec_file(path)
    assert time.perf_counter() - t0 < PROMPT_S
    msg = str(exc.value)
    assert "cannot be parsed: its aliases expand it to more than 2000000" in msg
    assert "alias bomb" in msg and len(msg) < 500


def test_recursive_yaml_alias_is_refused(tmp_path):
    path = tmp_path / "loop.yaml"
    path.write_text("a: &a [1, *a]\nparameters: {amplitude: *a}\n")
    with pytest.raises(SweepSpecError, match="an alias at line 1 refers to a value that "
                                             "contains it"):
        read_spec_file(path)


def test_a_large_value_that_loads_is_echoed_in_200_characters(tmp_path, capsys):
    """Five levels (59 049 strings) are within the bound: the value reaches the checks, and
    its message shows 200 characters and the length."""
    from gpme.cli import main
    path = tmp_path / "big.yaml"
    path.write_text(_bomb(5))
    code = main(["sweep", "--config", str(path), "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2 and "Traceback" not in err
    assert "parameters.amplitude: expected a number, got [[[['lol'" in err
    assert " characters)" in err and len(err) < 3000, len(err)
    assert not (tmp_path / "out").exists()


def test_aliases_within_the_bound_still_work():
    data = load_yaml("run: &r {t_end: 1.0}\nother: *r\nlist: &l [1, 2]\nagain: *l\n")
    assert data["other"] == {"t_end": 1.0} and data["again"] == [1, 2]
    with pytest.raises(YamlSizeError):
        load_yaml("a: &a [x, x, x, x]\nb: [*a, *a, *a]\n", limit=20)


def test_echo_cuts_long_values_and_many_problems():
    assert shown("x" * 10) == repr("x" * 10)
    long = shown(list(range(10_000)))
    assert long.endswith(f"... ({len(repr(list(range(10_000))))} characters)")
    assert len(long) < ECHO_LIMIT + 40
    err = SweepSpecError([f"problem {k}" for k in range(500)])
    assert "500 problems" in str(err) and "... and 450 more problems" in str(err)
    assert len(err.problems) == 500


# ================================================================ through the command line
def _cli(tmp_path, model):
    run = subprocess.run([sys.executable, "-m", "gpme.cli", "simulate", "--model", str(model),
                          "--out", str(tmp_path / "out")],
                         capture_output=True, text=True, cwd=ROOT, timeout=120)
    assert run.returncode == 2, (run.returncode, run.stderr)
    assert "Traceback" not in run.stderr and run.stderr.startswith("error: ")
    return run.stderr


def test_cli_refuses_a_fifo_as_model_without_blocking(tmp_path):
    fifo = tmp_path / "model.toml"
    os.mkfifo(fifo)
    err = _cli(tmp_path, fifo)
    assert f"{fifo}: cannot read the model file: it is a FIFO (named pipe), not a regular " \
           "file" in err


def test_cli_refuses_dev_zero_as_model(tmp_path):
    err = _cli(tmp_path, "/dev/zero")
    assert "cannot read the model file: it is a character device, not a regular file" in err


def test_cli_names_the_joints_of_a_cyclic_urdf(tmp_path):
    (tmp_path / "my_arm.urdf").write_text(_arm(_joint("loop", "forearm", "column",
                                                      "revolute")))
    model = tmp_path / "my_arm.toml"
    model.write_text(ARM_TOML)
    err = _cli(tmp_path, model)
    for word in ("model.urdf (my_arm.urdf)", "joint 'loop' (parent 'forearm', child "
                 "'column') closes a cycle", "['shoulder', 'elbow', 'loop']",
                 "link 'column' is the child of 2 joints ['yaw', 'loop']"):
        assert word in err, (word, err)
