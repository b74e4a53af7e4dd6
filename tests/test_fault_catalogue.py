"""The fault catalogue of faults/ (issue 23) against the current sources: every anchor is
there exactly once, the catalogue spans every term of the equations, and the tool refuses
an anchor that is missing or repeated.  No verify run here (faults.run does those)."""
import sys
from dataclasses import replace
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:           # faults/ is a tool beside the installed packages
    sys.path.insert(0, str(ROOT))

from faults import catalogue as cat  # noqa: E402
from faults.run import invocations, model_files  # noqa: E402

# modules of the numpy reference path only: a fault there would not reach the runs
NUMPY_REFERENCE_ONLY = {"gpme_core/dynamics.py", "gpme_core/kinematics.py",
                        "gpme_core/constraints.py", "gpme_core/gpme.py"}


@pytest.mark.parametrize("fault", cat.CATALOGUE, ids=lambda f: f.id)
def test_anchor_occurs_exactly_once_in_the_current_sources(fault):
    assert cat.anchor_problem(fault, ROOT) is None


def test_catalogue_spans_every_term_of_the_equations():
    terms = {f.term for f in cat.CATALOGUE}
    assert not set(cat.REQUIRED_TERMS) - terms
    assert len(cat.CATALOGUE) >= 25


@pytest.mark.parametrize("fault", cat.CATALOGUE, ids=lambda f: f.id)
def test_fault_is_subtle_and_on_the_run_path(fault):
    assert 0 < fault.size <= cat.MAX_SIZE
    assert fault.replacement != fault.anchor
    assert fault.file.startswith("gpme_core/") and fault.file not in NUMPY_REFERENCE_ONLY
    assert fault.term and fault.what


def test_ids_are_unique():
    ids = [f.id for f in cat.CATALOGUE + cat.CONTROLS]
    assert len(ids) == len(set(ids)) == len(cat.BY_ID)


def _one_file_copy(tmp_path, fault):
    dest = tmp_path / fault.file
    dest.parent.mkdir(parents=True)
    dest.write_text((ROOT / fault.file).read_text(encoding="utf-8"), encoding="utf-8")
    return dest


def test_apply_replaces_the_anchor_once(tmp_path):
    fault = cat.BY_ID["kappa-grad-t"]
    path = _one_file_copy(tmp_path, fault)
    before = path.read_text(encoding="utf-8")
    cat.apply(fault, tmp_path)
    after = path.read_text(encoding="utf-8")
    assert after == before.replace(fault.anchor, fault.replacement)
    assert fault.anchor not in after and after.count(fault.replacement) == 1


def test_missing_or_repeated_anchor_is_refused(tmp_path):
    fault = cat.BY_ID["g-scale"]
    path = _one_file_copy(tmp_path, fault)
    missing = replace(fault, anchor="no such text in fast.py")
    with pytest.raises(cat.AnchorError, match="'g-scale'.*is missing from gpme_core/fast.py"):
        cat.apply(missing, tmp_path)
    path.write_text(path.read_text(encoding="utf-8") + f"\n# {fault.anchor}\n",
                    encoding="utf-8")
    with pytest.raises(cat.AnchorError, match="occurs 2 times in gpme_core/fast.py"):
        cat.check_anchors([fault], tmp_path)
    with pytest.raises(cat.AnchorError, match="does not exist"):
        cat.apply(replace(fault, file="gpme_core/nowhere.py"), tmp_path)


def test_examples_exclude_the_zoo_and_start_with_the_cheap_checks():
    models = model_files(ROOT)
    assert models and not any("zoo" in m for m in models)
    invs = invocations(models)
    assert (invs[0].group, invs[0].step) == ("crane", "pinocchio")
    assert all(inv.models == models for inv in invs if inv.group == "models")


def test_a_model_is_left_out_of_one_step_or_of_all():
    models = ("models/a.toml", "examples/b/b.toml")
    by_step = {inv.step: inv.models for inv in invocations(models, ["exudyn:examples/b/*"])
               if inv.group == "models"}
    assert by_step["exudyn"] == ("models/a.toml",) and by_step["drake"] == models
    left = invocations(models, ["models/*", "examples/*/*.toml"])
    assert all(inv.group == "crane" for inv in left)


@pytest.mark.parametrize("control", cat.CONTROLS, ids=lambda f: f.id)
def test_controls_change_a_description_not_an_equation(control):
    assert cat.anchor_problem(control, ROOT) is None
    assert control.term == cat.CONTROL and not control.file.startswith("gpme_core/")
    assert 0 < control.size <= cat.MAX_SIZE and control.id in cat.BY_ID
