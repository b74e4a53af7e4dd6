"""One "did you mean" for every message (gpme_core.echo.closest / did_you_mean, issue 25):
model files, side files, sweep files and expressions suggest names the same way."""
from gpme_core.echo import closest, did_you_mean


def test_a_typo_and_a_case_difference_are_found():
    assert closest("elbwo", ["shoulder", "elbow", "wrist"]) == ["elbow"]
    assert closest("ELBOW", ["shoulder", "elbow"]) == ["elbow"]      # case only
    assert did_you_mean("yaww", ["yaw", "pitch"]) == " (did you mean 'yaw'?)"


def test_nothing_close_says_nothing_and_n_bounds_the_list():
    assert closest("zzz", ["shoulder", "elbow"]) == [] and did_you_mean("zzz", ["a"]) == ""
    three = closest("joint_1", [f"joint_{k}" for k in range(10)], n=3)
    assert len(three) == 3 and "joint_1" in three


def test_a_hostile_choice_is_echoed_bounded():
    long = "x" * 1000
    assert len(did_you_mean("x" * 999, [long])) < 300
