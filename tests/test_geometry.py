"""Models people can see (issue 28): the written URDFs and MJCFs carry geometry (RFEM
elements as their section, the crane's rigid links from their sizes, a user's shapes and
meshes kept), they load with it in Pinocchio, MuJoCo and PyBullet, and geometry never
adds mass."""
import re
import shutil
import subprocess
import sysconfig
import warnings
from pathlib import Path

import numpy as np
import pytest

from crosscheck.mujoco.mjcf import mjcf_text
from gpme_core.geometry import Shape
from gpme_core.model import Model
from gpme_examples.crane import CraneParameters, build_crane
from gpme_io.urdf_read.shapes import resolve_mesh
from gpme_io.urdf_reader import load_urdf
from gpme_io.urdf_writer import urdf_documents, write_urdf

# example-robot-data installed as data (the test extra; cmeel layout), as test_urdf_reader
ROBOTS = (Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix" / "share"
          / "example-robot-data" / "robots")
UR5 = ROBOTS / "ur_description" / "urdf" / "ur5_robot.urdf"


def _without_geometry(model):
    return Model(model.joints, model.links, model.frames, model.drives, model.gravity,
                 model.flexible_links, model.name)


def _stripped(text):
    return re.sub(r"<(visual|collision)>.*?</\1>", "", text, flags=re.S)


def _pybullet_visuals(urdf):
    """How many visual shapes PyBullet loads from ``urdf`` (a third reader)."""
    pybullet = pytest.importorskip("pybullet")
    client = pybullet.connect(pybullet.DIRECT)
    try:
        body = pybullet.loadURDF(str(urdf), physicsClientId=client)
        return len(pybullet.getVisualShapeData(body, physicsClientId=client))
    finally:
        pybullet.disconnect(client)


@pytest.fixture(scope="module")
def crane_urdf(tmp_path_factory):
    path = tmp_path_factory.mktemp("urdf") / "crane_flexible_n3.urdf"
    write_urdf(build_crane(3), path)
    return path


def test_the_crane_is_drawn_from_its_sizes():
    """Base box, column drum (solid, its outer radius), one cylinder per RFEM element of the
    arm's outer radius and length (L/2n, L/n, L/n, L/2n), the slider rod: 7 shapes; only
    base and column collide (the elements touch each other, the rod reaches the column)."""
    p = CraneParameters()
    model = build_crane(3)
    kinds = [(model.links[s.link_index].name, s.kind, s.size, s.role) for s in model.geometry]
    dl = p.arm_length / 3
    r = p.arm_diameter / 2
    assert kinds[:2] == [("base", "box", p.base_size, "both"),
                         ("column", "cylinder", (p.column_radius, p.column_height), "both")]
    assert np.allclose([k[2] for k in kinds[2:6]],
                       [(r, dl / 2), (r, dl), (r, dl), (r, dl / 2)], rtol=1e-15, atol=0)
    assert {k[3] for k in kinds[2:]} == {"visual"}
    assert kinds[6][:3] == ("slider", "cylinder", (p.slider_radius, p.slider_length))
    # an element's cylinder lies along its link's x axis from the element's start
    first = model.geometry[2].origin_array
    assert first[:3, 2] == pytest.approx([1, 0, 0]) and first[0, 3] == pytest.approx(dl / 4)


def test_the_written_urdf_loads_with_its_geometry_everywhere(crane_urdf):
    """check_urdf, Pinocchio's visual and collision models, PyBullet's visual shapes and
    MuJoCo's geoms all see the 7 visuals and 2 collision shapes."""
    pin = pytest.importorskip("pinocchio")
    if shutil.which("check_urdf"):
        subprocess.run(["check_urdf", str(crane_urdf)], check=True, capture_output=True)
    model = pin.buildModelFromUrdf(str(crane_urdf))
    assert pin.buildGeomFromUrdf(model, str(crane_urdf), pin.GeometryType.VISUAL).ngeoms == 7
    assert pin.buildGeomFromUrdf(model, str(crane_urdf),
                                 pin.GeometryType.COLLISION).ngeoms == 2
    assert _pybullet_visuals(crane_urdf) == 7
    mujoco = pytest.importorskip("mujoco")
    with_shapes = mujoco.MjModel.from_xml_path(str(crane_urdf))
    assert with_shapes.ngeom == 9                     # MuJoCo keeps visuals (group 1) too


def test_geometry_never_adds_mass(crane_urdf):
    """The same bodies with and without shapes: gpme's pseudo-inertias read back, MuJoCo's
    masses and inertias from the URDF and from the MJCF, bit for bit."""
    mujoco = pytest.importorskip("mujoco")
    text = crane_urdf.read_text()
    bare = crane_urdf.with_name("bare.urdf")
    bare.write_text(_stripped(text))
    shutil.copy(crane_urdf.with_suffix("").with_suffix(".gpme.json"),
                bare.with_suffix("").with_suffix(".gpme.json"))
    a, b = load_urdf(crane_urdf).model, load_urdf(bare).model
    assert len(a.geometry) == 7 and len(b.geometry) == 0
    assert np.array_equal(a.pseudo_inertias, b.pseudo_inertias)
    m_a, m_b = (mujoco.MjModel.from_xml_path(str(p)) for p in (crane_urdf, bare))
    assert np.array_equal(m_a.body_mass, m_b.body_mass)
    assert np.array_equal(m_a.body_inertia, m_b.body_inertia)
    crane = build_crane(3)
    x_a, x_b = (mujoco.MjModel.from_xml_string(mjcf_text(m)) for m in
                (crane, _without_geometry(crane)))
    assert x_a.ngeom == x_b.ngeom + 7
    assert np.array_equal(x_a.body_mass, x_b.body_mass)
    assert np.array_equal(x_a.body_inertia, x_b.body_inertia)
    shape_geoms = [k for k in range(x_a.ngeom) if x_a.geom_group[k] == 1 and
                   x_a.geom_type[k] != mujoco.mjtGeom.mjGEOM_SPHERE]
    assert len(shape_geoms) == 7 and not x_a.geom_contype.any()


def test_the_shapes_read_back_as_written(crane_urdf):
    built = build_crane(3).geometry
    read = load_urdf(crane_urdf).model.geometry
    assert [(s.link_index, s.kind, s.role, s.rgba) for s in read] == \
        [(s.link_index, s.kind, s.role, s.rgba) for s in built]
    for r, b in zip(read, built):
        assert r.size == pytest.approx(b.size, rel=1e-15)
        assert np.allclose(r.origin_array, b.origin_array, rtol=0, atol=1e-15)


def test_a_users_meshes_are_kept_with_their_paths_resolved(tmp_path):
    """UR5 (example-robot-data): its package:// meshes resolved to files that exist, kept
    through a read and a write, and Pinocchio and PyBullet load the written file's 6
    visuals (MuJoCo cannot read the .dae meshes of this robot at all)."""
    if not UR5.exists():
        pytest.skip("example-robot-data not installed")
    pin = pytest.importorskip("pinocchio")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = load_urdf(UR5, side_file=None)
    meshes = [s for s in res.model.geometry if s.kind == "mesh"]
    assert len(res.model.geometry) == 13 and len(meshes) == 12   # and ee_link's box
    assert all(Path(s.mesh).is_file() for s in meshes)
    assert any("world" in n and "base_link" in n for n in res.notes)   # world-fixed left out
    path, _ = write_urdf(res.model, tmp_path / "ur5.urdf")
    model = pin.buildModelFromUrdf(str(path))
    assert pin.buildGeomFromUrdf(model, str(path), pin.GeometryType.VISUAL).ngeoms == 6
    assert _pybullet_visuals(path) == 6


def test_package_and_relative_mesh_paths_resolve_as_the_engines_do(tmp_path, monkeypatch):
    pkg = tmp_path / "robots" / "my_pkg"
    (pkg / "meshes").mkdir(parents=True)
    (pkg / "urdf").mkdir()
    mesh = pkg / "meshes" / "arm.stl"
    mesh.write_bytes(b"solid x\nendsolid x\n")
    urdf = pkg / "urdf" / "arm.urdf"
    urdf.write_text("<robot/>")
    assert resolve_mesh("package://my_pkg/meshes/arm.stl", urdf) == str(mesh.resolve())
    assert resolve_mesh("../meshes/arm.stl", urdf) == str(mesh.resolve())
    assert resolve_mesh("file://" + str(mesh), urdf) == str(mesh)
    elsewhere = tmp_path / "elsewhere" / "arm.urdf"
    elsewhere.parent.mkdir()
    elsewhere.write_text("<robot/>")
    assert resolve_mesh("package://my_pkg/meshes/arm.stl", elsewhere) == \
        "package://my_pkg/meshes/arm.stl"                       # not found: kept as written
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(tmp_path / "robots"))
    assert resolve_mesh("package://my_pkg/meshes/arm.stl", elsewhere) == str(mesh.resolve())


def test_a_bad_shape_is_refused_by_the_builder_and_left_out_by_the_reader(tmp_path):
    from gpme_core.errors import ModelError
    from gpme_core.model import REVOLUTE, ChainBuilder
    b = ChainBuilder("s")
    b.add_joint("q", REVOLUTE, (0, 0, 1))
    with pytest.raises(ModelError, match=r"a cylinder needs 2 positive finite sizes .* got "
                                         r"\[-0\.1, 1\.0\]"):
        b.add_shape("cylinder", (-0.1, 1.0))
    assert Shape(0, "mesh", (-1, 1, 1), mesh="m.stl").problems("x") == []   # mirrored
    text, side = urdf_documents(build_crane(0))
    text = text.replace('<box size="0.4 0.4 0.1" />', '<box size="0.4 abc 0.1" />', 1)
    path = tmp_path / "crane_rigid.urdf"
    path.write_text(text)
    res = load_urdf(path, side_file=None)
    base = [s for s in res.model.geometry if s.link_index == 0]
    assert [s.role for s in base] == ["collision"]      # its visual left out, not the model
    assert any("cannot be read left out" in n and "base <visual>" in n for n in res.notes)
