"""The paper's crane cases and run lengths are defined once (issue 25): every engine's
default scenarios and `gpme verify`'s come from crosscheck.crane_cases, every run length
from gpme_examples.paper."""
import pytest

from crosscheck import crane_cases, verify
from crosscheck.drake import check as drake_check
from crosscheck.mujoco import check as mujoco_check
from crosscheck.pinocchio import check as pinocchio_check
from gpme_examples import paper
from gpme_io.scenario import crane_scenario


def _cases(scenarios):
    return [(s.name, s.on_constraints) for s in scenarios]


@pytest.mark.parametrize("quick", [False, True], ids=["full", "quick"])
def test_verify_and_the_engines_use_one_case_list(quick):
    for engine, module in (("pinocchio", pinocchio_check), ("drake", drake_check),
                           ("mujoco", mujoco_check)):
        assert _cases(verify.default_scenarios(engine, quick)) == \
            _cases(module.default_scenarios(quick)) == \
            _cases(crane_cases.crane_cases(engine, quick))


def test_the_quick_term_checks_take_rigid_and_the_papers_arm():
    names = [s.name for s in pinocchio_check.default_scenarios(True)]
    assert names == ["crane_rigid", f"crane_flexible_n{paper.DEFAULT_N_RFE}"]


def test_one_run_length():
    s = crane_scenario(3)
    assert (s.t_end, s.quick_t_end) == (paper.T_END, paper.QUICK_T_END)
