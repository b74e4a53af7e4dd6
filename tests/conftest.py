"""Shared fixtures: small models built from the public API."""
import zlib

import numpy as np
import pytest

from gpme_core import fast
from gpme_core import transforms as tf
from gpme_examples.crane import build_crane
from gpme_core.inertia import cuboid
from gpme_core.model import PRISMATIC, REVOLUTE, WORLD, ChainBuilder


COMPUTATION_PATHS = ("compiled", "numpy")


def pytest_generate_tests(metafunc):
    """Tests marked ``both_computation_paths`` run once per path of gpme_core: the numba
    kernels (gpme_core.fast) and the readable numpy reference they replace, so that CI
    exercises both (a fault in either fails a test)."""
    if metafunc.definition.get_closest_marker("both_computation_paths"):
        metafunc.parametrize("computation_path", COMPUTATION_PATHS, indirect=True)


@pytest.fixture(autouse=True)
def computation_path(request, monkeypatch):
    """The path gpme_core computes with in this test: "compiled" or "numpy".

    Unparametrised tests use whatever the environment gives (numba unless GPME_NO_JIT=1).
    The dispatch sites read ``fast.ENABLED`` at call time, so patching it switches path."""
    path = getattr(request, "param", None)
    if path is None:
        return "compiled" if fast.ENABLED else "numpy"
    if path == "compiled" and not fast.ENABLED:
        pytest.skip("GPME_NO_JIT=1 or numba missing: the compiled path is not available")
    if path == "numpy":
        monkeypatch.setattr(fast, "ENABLED", False)
    return path


@pytest.fixture
def rng(request):
    """A generator of the test's own: seeded from the test's name, so its draws do not
    depend on which tests ran before it (a session-wide generator did)."""
    return np.random.default_rng([20261122, zlib.crc32(request.node.name.encode())])


def spatial_arm():
    """A 5-joint arm mixing revolute and prismatic joints with skewed axes and offsets."""
    b = ChainBuilder("spatial_arm")
    b.add_joint("q0", REVOLUTE, (0, 0, 1), stiffness=3.0, spring_reference=0.2, damping=0.1)
    b.add_body(cuboid(2.0, (0.2, 0.3, 0.4), com=(0.05, -0.02, 0.1)))
    b.add_joint("q1", PRISMATIC, np.array([1, 1, 0]) / np.sqrt(2), origin=tf.translation(0.1, 0, 0.3))
    b.add_body(cuboid(1.0, (0.1, 0.5, 0.2), com=(0.0, 0.1, 0.0)))
    b.add_joint("q2", REVOLUTE, np.array([0, 1, 1]) / np.sqrt(2),
                origin=tf.translation(0, 0.2, 0.1) @ tf.rot_x(0.3) @ tf.rot_z(-0.4), damping=0.05)
    b.add_body(cuboid(0.7, (0.6, 0.1, 0.1), com=(0.3, 0.0, 0.02)))
    b.add_joint("q3", REVOLUTE, (1, 0, 0), origin=tf.translation(0.6, 0, 0) @ tf.rot_y(0.5))
    b.add_body(cuboid(0.4, (0.3, 0.1, 0.05), com=(0.1, 0.05, 0.0)))
    b.add_joint("q4", PRISMATIC, (0, 0, 1), origin=tf.translation(0.2, 0.1, 0), stiffness=50.0)
    b.add_body(cuboid(0.3, (0.05, 0.05, 0.3), com=(0.0, 0.0, -0.1)))
    b.add_frame("E", tf.translation(0.01, 0.02, 0.05))
    return b.build()


@pytest.fixture(scope="session")
def arm():
    return spatial_arm()


def spatial_tree():
    """A 7-joint kinematic tree: a base q0 carrying two branches (q1-q2 and q3-q4), a
    second root q5 on the world with a child q6; skewed axes, offsets, both joint kinds.
    Links are listed parents first, branches interleaved with the chain order."""
    b = ChainBuilder("spatial_tree")
    b.add_joint("q0", REVOLUTE, (0, 0, 1), damping=0.1)
    b.add_body(cuboid(2.0, (0.3, 0.3, 0.4), com=(0.05, -0.02, 0.1)))
    b.add_joint("q1", REVOLUTE, np.array([0, 1, 1]) / np.sqrt(2),
                origin=tf.translation(0.2, 0, 0.3) @ tf.rot_x(0.3))
    b.add_body(cuboid(1.0, (0.5, 0.1, 0.2), com=(0.25, 0.01, 0.0)))
    b.add_joint("q2", PRISMATIC, (1, 0, 0), origin=tf.translation(0.5, 0, 0), stiffness=40.0)
    b.add_body(cuboid(0.5, (0.2, 0.1, 0.1), com=(0.05, 0.0, 0.02)))
    b.add_frame("E", tf.translation(0.1, 0.02, 0.0))
    b.add_joint("q3", REVOLUTE, (1, 0, 0), origin=tf.translation(-0.2, 0.1, 0.3) @ tf.rot_z(0.7),
                parent="q0")
    b.add_body(cuboid(0.8, (0.1, 0.4, 0.1), com=(0.0, 0.2, 0.03)))
    b.add_joint("q4", REVOLUTE, (0, 0, 1), origin=tf.translation(0, 0.4, 0) @ tf.rot_y(-0.4),
                stiffness=5.0, spring_reference=0.1)
    b.add_body(cuboid(0.3, (0.3, 0.05, 0.05), com=(0.15, 0.0, 0.0)))
    b.add_frame("F", tf.translation(0.3, 0.0, 0.01))
    b.add_joint("q5", REVOLUTE, (0, 1, 0), origin=tf.translation(1.0, 0.0, 0.5), parent=WORLD)
    b.add_body(cuboid(0.6, (0.4, 0.1, 0.1), com=(0.2, 0.0, 0.0)))
    b.add_joint("q6", PRISMATIC, np.array([1, 0, 1]) / np.sqrt(2),
                origin=tf.translation(0.4, 0, 0), damping=0.2)
    b.add_body(cuboid(0.2, (0.1, 0.1, 0.1), com=(0.0, 0.0, 0.0)))
    return b.build()


@pytest.fixture(scope="session")
def tree():
    return spatial_tree()


@pytest.fixture(scope="session", params=[0, 2], ids=["crane_rigid", "crane_n2"])
def crane(request):
    return build_crane(request.param)
