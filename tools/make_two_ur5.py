"""Write examples/two_ur5/two_ur5.urdf: two UR5s (example-robot-data's ur5_robot.urdf,
names prefixed a_ and b_) facing each other 1.0 m apart, and a light aluminium bar
fixed to a's flange whose far end (frame bar_end) sits on b's flange at the start
posture (the model file welds it there).  Run once; the URDF is committed.

    python tools/make_two_ur5.py
"""
import copy
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from gpme_core import transforms as tf
from gpme_core.kinematics import link_transforms
from gpme_io.modelfile.load import resolve_urdf
from gpme_io.urdf_reader import load_urdf

REPO = Path(__file__).resolve().parents[1]
OUT = REPO / "examples" / "two_ur5" / "two_ur5.urdf"
SOURCE = "example-robot-data:ur_description/urdf/ur5_robot.urdf"
# the start posture of both arms (rad): the flange in front, pointing along -z
START = {"shoulder_pan_joint": 0.0, "shoulder_lift_joint": -1.2, "elbow_joint": 1.6,
         "wrist_1_joint": -1.97, "wrist_2_joint": -1.5708, "wrist_3_joint": 0.0}
B_BASE = (1.0, 0.0, 0.0, np.pi)       # b's base: x, y, z (m) and yaw (rad) in the world
BAR_MASS = 0.8                        # kg, an aluminium tube of about 0.5 m


def _arm(robot, prefix):
    """The UR5's links and joints renamed with ``prefix`` (world and extension tags out)."""
    out = []
    for el in robot:
        if el.tag not in ("link", "joint") or el.get("name") == "world":
            continue
        el = copy.deepcopy(el)
        el.set("name", prefix + el.get("name"))
        for end in ("parent", "child"):
            sub = el.find(end)
            if sub is not None:
                sub.set("link", prefix + sub.get("link"))
        out.append(el)
    return [e for e in out if not (e.tag == "joint" and e.find("parent").get("link")
                                   == prefix + "world")]


def _fixed(name, parent, child, xyz, rpy=(0.0, 0.0, 0.0)):
    j = ET.Element("joint", name=name, type="fixed")
    ET.SubElement(j, "parent", link=parent)
    ET.SubElement(j, "child", link=child)
    ET.SubElement(j, "origin", xyz=" ".join(repr(float(v)) for v in xyz),
                  rpy=" ".join(repr(float(v)) for v in rpy))
    return j


def _link(name, mass=None, com=None, inertia=None):
    link = ET.Element("link", name=name)
    if mass is not None:
        inertial = ET.SubElement(link, "inertial")
        ET.SubElement(inertial, "origin", xyz=" ".join(repr(float(v)) for v in com),
                      rpy="0 0 0")
        ET.SubElement(inertial, "mass", value=repr(float(mass)))
        names = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
        idx = ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2))
        ET.SubElement(inertial, "inertia", {n: repr(float(inertia[i])) for n, i in zip(names, idx)})
    return link


def write(bar_end=np.eye(4)):
    robot = ET.parse(resolve_urdf(SOURCE, REPO / "models" / "x.toml")).getroot()
    out = ET.Element("robot", name="two_ur5")
    out.append(ET.Comment(" Two UR5s (example-robot-data's ur5_robot.urdf, names prefixed a_ "
                          "and b_) holding a bar; written by tools/make_two_ur5.py "))
    out.append(ET.Element("link", name="world"))
    for prefix, (x, y, z, yaw) in (("a_", (0.0, 0.0, 0.0, 0.0)), ("b_", B_BASE)):
        for el in _arm(robot, prefix):
            out.append(el)
        out.append(_fixed(prefix + "mount", "world", prefix + "base_link", (x, y, z),
                          (0.0, 0.0, yaw)))
    # the bar: a thin rod from a's flange origin to bar_end's origin, in a_tool0's frame
    end = bar_end[:3, 3]
    length = float(np.linalg.norm(end))
    u = end / length if length > 0 else np.array([1.0, 0.0, 0.0])
    inertia = BAR_MASS * length ** 2 / 12.0 * (np.eye(3) - np.outer(u, u)) + 1e-5 * np.eye(3)
    out.append(_link("bar", BAR_MASS, 0.5 * end, inertia))
    out.append(_fixed("bar_mount", "a_tool0", "bar", (0.0, 0.0, 0.0)))
    rpy = tf.rotation_to_rpy(bar_end[:3, :3])
    out.append(_link("bar_end"))
    out.append(_fixed("bar_end_fixed", "bar", "bar_end", end, rpy))
    out.append(_link("bar_center"))
    out.append(_fixed("bar_center_fixed", "bar", "bar_center", 0.5 * end))
    ET.indent(out, space="  ")
    OUT.write_text('<?xml version="1.0"?>\n' + ET.tostring(out, encoding="unicode") + "\n",
                   encoding="utf-8")


def main():
    write()                                       # bar_end at a's flange: find b's flange
    res = load_urdf(OUT, side_file=None, whole_tree=True)
    model = res.model
    q = np.zeros(model.n_coordinates)
    for prefix in ("a_", "b_"):
        for name, v in START.items():
            q[model.index(prefix + name)] = v
    t = link_transforms(model, q)
    pose = {}
    for f in ("a_tool0", "b_tool0"):
        fr = model.frame(f)
        pose[f] = t[fr.link_index] @ fr.transform
    bar_end = tf.inverse(pose["a_tool0"]) @ pose["b_tool0"]
    write(bar_end)
    print(f"wrote {OUT}: bar from a_tool0 to b_tool0, {np.linalg.norm(bar_end[:3, 3]):.4f} m; "
          f"a_tool0 at {np.round(pose['a_tool0'][:3, 3], 4).tolist()}, b_tool0 at "
          f"{np.round(pose['b_tool0'][:3, 3], 4).tolist()}")


if __name__ == "__main__":
    main()
