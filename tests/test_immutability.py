"""Immutable means immutable: a built Model cannot be changed through any attribute, the
builder's arrays are not frozen under it, and simulate() leaves the system it is given as
it was (docs: STYLE.md, "Immutable means immutable")."""
import copy
import pickle
from types import MappingProxyType

import numpy as np
import pytest

from gpme_core import transforms as tf
from gpme_core.constraints import CoordinateProgramme
from gpme_core.gpme import ProgrammedMotion
from gpme_core.inertia import cuboid
from gpme_core.integrate import simulate
from gpme_core.model import PRISMATIC, REVOLUTE, ChainBuilder, Frame, Joint
from gpme_core.time_functions import Constant
from gpme_examples.crane import crane_system, initial_state


def _array_attributes(obj):
    return {k: v for k, v in vars(obj).items() if isinstance(v, np.ndarray)}


@pytest.fixture(scope="module")
def model():
    return crane_system(1).model


def test_every_model_array_is_read_only(model):
    arrays = _array_attributes(model)
    # the arrays the engine reads (a new one added to Model is covered automatically)
    assert {"origins", "axes", "is_revolute", "generators", "pseudo_inertias", "gravity",
            "gamma", "stiffness", "spring_reference", "damping", "lower_limits",
            "upper_limits"} <= set(arrays)
    for name, arr in arrays.items():
        assert not arr.flags.writeable, name
        with pytest.raises(ValueError, match="read-only"):
            arr[...] = 0
        with pytest.raises(ValueError, match="read-only"):
            arr += 0 if arr.dtype != bool else False
    for j in model.joints:
        assert not j.origin.flags.writeable, j.name
    for fr in model.frames.values():
        assert not fr.transform.flags.writeable, fr.name
        with pytest.raises(ValueError, match="read-only"):
            fr.transform[0, 3] = 1.0


def test_model_mappings_sequences_and_attributes_cannot_change(model):
    assert isinstance(model.frames, MappingProxyType)
    with pytest.raises(TypeError):
        model.frames["new"] = Frame("new", 0, np.eye(4))
    with pytest.raises(AttributeError):
        model.frames.update({})
    for seq in (model.joints, model.links, model.drives, model.flexible_links,
                model.coordinate_names):
        assert isinstance(seq, tuple)
    with pytest.raises(AttributeError, match="Model is immutable"):
        model.gravity = np.zeros(3)
    with pytest.raises(AttributeError, match="Model is immutable"):
        model.name = "other"
    with pytest.raises(AttributeError, match="Model is immutable"):
        del model.joints
    with pytest.raises(AttributeError):       # frozen dataclasses
        model.joints[0].origin = np.eye(4)
    with pytest.raises(AttributeError):
        model.flexible_links[0].n_segments = 3
    assert all(isinstance(f.joint_indices, tuple) for f in model.flexible_links)


def test_builder_arrays_are_copied_not_frozen():
    origin = tf.translation(0.3)
    frame = tf.translation(0.1, 0.2)
    gravity = np.array([0.0, 0.0, -9.81])
    b = ChainBuilder("copy", gravity=gravity)
    b.add_joint("z", PRISMATIC, np.array([0.0, 0.0, 1.0]), origin=origin)
    b.add_body(cuboid(2.0, (0.1, 0.1, 0.1)))
    b.add_frame("tip", frame)
    m = b.build()
    for arr in (origin, frame, gravity):
        assert arr.flags.writeable
    origin[0, 3] = 99.0        # the caller changes its arrays: the model does not move
    frame[0, 3] = 99.0
    gravity[2] = 0.0
    assert m.joints[0].origin[0, 3] == 0.3 and m.origins[0, 0, 3] == 0.3
    assert m.frames["tip"].transform[0, 3] == 0.1
    assert m.gravity[2] == -9.81 and m.gamma[2] == -9.81
    j = Joint("k", REVOLUTE, (0, 0, 1), origin)
    assert j.origin is not origin and not j.origin.flags.writeable


def test_with_changes_and_pickling_give_equal_read_only_models(model):
    changed = model.with_changes(joint_changes={"z1": {"damping": 3.0}})
    assert changed.damping[model.index("z1")] == 3.0
    assert model.damping[model.index("z1")] != 3.0       # the original is unchanged
    for other in (changed, pickle.loads(pickle.dumps(model)), copy.deepcopy(model)):
        assert isinstance(other.frames, MappingProxyType)
        assert all(not a.flags.writeable for a in _array_attributes(other).values())
        np.testing.assert_array_equal(other.pseudo_inertias, model.pseudo_inertias)
        assert other.coordinate_names == model.coordinate_names


def _observable(system):
    """Everything a caller can see on a ProgrammedMotion, arrays as lists (comparable)."""
    return {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in vars(system).items()}


@pytest.mark.parametrize("dependent", [None, ("psi3", "z4")], ids=["chosen-by-run", "given"])
@pytest.mark.parametrize("on_manifold", [False, True], ids=["as-given", "on-manifold"])
def test_simulate_leaves_the_system_unchanged(dependent, on_manifold):
    paper = crane_system(0)
    system = ProgrammedMotion(paper.model, paper.constraint_specs, dependent=dependent)
    before = _observable(system)
    q, qd = initial_state(system.model)
    q_given, qd_given = q.copy(), qd.copy()
    df = simulate(system, 0.05, q, qd, dt=1e-3, on_manifold=on_manifold)
    assert _observable(system) == before
    assert system.dependent == dependent
    np.testing.assert_array_equal(q, q_given)          # the initial state is not touched
    np.testing.assert_array_equal(qd, qd_given)
    assert len(df.attrs["dependent"]) == 2


def test_simulate_keeps_the_given_partition_when_the_run_switches():
    # a one-joint pendulum-on-a-slider whose run starts on a singular partition: the run
    # switches (tests/test_dependent_switch.py has the physics); here only the system counts
    b = ChainBuilder("slider_pendulum", gravity=(0.0, -9.81, 0.0))
    b.add_joint("x", PRISMATIC, (1, 0, 0))
    b.add_body(cuboid(1.0, (0.1, 0.1, 0.1)))
    b.add_joint("a", REVOLUTE, (0, 0, 1))
    b.add_body(cuboid(1.0, (0.1, 0.1, 0.1), com=(0.5, 0.0, 0.0)))
    b.add_frame("E", tf.translation(1.0))
    m = b.build()
    # x_E = x + cos(a) = 1: at a = 0 the column of a (-sin a) is zero
    system = ProgrammedMotion(m, [CoordinateProgramme(Constant(1.0), axis=0, name="Phi_x")],
                              dependent=("a",))
    before = _observable(system)
    df = simulate(system, 0.05, np.zeros(2), np.zeros(2), dt=1e-3)
    assert df.attrs["events"] and df.attrs["dependent_final"] == ["x"]
    assert _observable(system) == before and system.dependent == ("a",)


def test_programmed_motion_is_immutable_like_model():
    """A built ProgrammedMotion cannot be changed (issue 25): another partition is a new
    object, and pickling or copying gives an equally immutable one."""
    system = crane_system(0)
    for name, value in (("dependent", ("psi2", "z4")), ("alpha", 1.0), ("model", None),
                        ("new_attribute", 1)):
        with pytest.raises(AttributeError, match="immutable"):
            setattr(system, name, value)
    q0, qd0 = initial_state(system.model)
    other = system.with_dependent(("psi2", "z4"))
    assert system.dependent == ("psi3", "z4") and other.dependent == ("psi2", "z4")
    pivoted = system.with_pivoted_dependent(0.0, q0, qd0)
    assert system.dependent == ("psi3", "z4") and len(pivoted.dependent) == 2
    for twin in (copy.copy(system), pickle.loads(pickle.dumps(system))):
        with pytest.raises(AttributeError, match="immutable"):
            twin.alpha = 2.0


def test_the_pinocchio_check_leaves_the_scenarios_system_alone():
    """crosscheck.states.scenario_states (the Pinocchio check's, before) used to choose the
    partition on the scenario's own system; it works on a copy now."""
    from crosscheck.states import QUICK, scenario_states
    from gpme_io.scenario import Scenario
    system = ProgrammedMotion(crane_system(0).model, crane_system(0).constraint_specs)
    model = system.model
    q0, qd0 = initial_state(model)
    scenario = Scenario(name="crane_no_partition", model=model,
                        constraints=system.constraint_specs, system=system, q0=q0,
                        q_dot0=qd0, t_end=0.1, quick_t_end=0.05)
    assert len(scenario_states(scenario, QUICK)) > 0
    assert scenario.system.dependent is None
