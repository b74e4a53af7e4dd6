"""A check is counted for the engine whose numbers it judges: gpme's observed RK4 order,
measured inside the Pinocchio, MuJoCo, Drake and Exudyn steps, is a gpme check, written
once with gpme's rows (crosscheck.verify._merge_prerequisites)."""
import numpy as np
import pandas as pd

from crosscheck.compare import Tolerance, compare, not_judged
from crosscheck.reports.rows import normalise, other_rows, own_rows, read_rows, write_rows
from crosscheck.verify import _merge_prerequisites

ORDER = Tolerance(1.0, 0.0, "RK4 is order 4")


def _row(engine, quantity, value, case="case"):
    return {**compare(engine, "arm", quantity, case, [value], [4.0], ORDER, ["q1"]),
            "section": "runs"}


def test_gpme_rows_of_two_engine_steps_are_written_once_with_gpmes(tmp_path):
    gpme_step = pd.DataFrame([_row("gpme", "energy balance", 4.0)])
    write_rows(normalise(gpme_step), tmp_path, "gpme")
    order = _row("gpme", "exact programmed run: observed RK4 order of gpme", 1.14)
    pin = pd.DataFrame([_row("pinocchio", "exact programmed run q1", 4.0), order])
    mj = pd.DataFrame([_row("mujoco", "exact programmed run q1", 4.0), order])
    tables = {"gpme": gpme_step, "pinocchio": own_rows(pin, "pinocchio"),
              "mujoco": own_rows(mj, "mujoco")}
    _merge_prerequisites(tmp_path, tables, [other_rows(pin, "pinocchio"),
                                            other_rows(mj, "mujoco")])
    assert list(tables["pinocchio"]["engine"]) == ["pinocchio"]
    gpme = tables["gpme"]
    assert len(gpme) == 2 and (gpme["status"] == "fail").sum() == 1     # counted once
    back = read_rows(tmp_path, "gpme")
    assert sorted(back["quantity"]) == sorted(gpme["quantity"])


def test_not_judged_is_information_and_keeps_the_gate_in_its_reason():
    row = compare("mujoco", "arm", "exact programmed run q1", "case", [1.0], [1.1],
                  Tolerance(1e-3, 0.0, "RK4 error"), ["t=0.1"])
    assert row["status"] == "fail"
    info = not_judged(row, "gpme's runs did not converge")
    assert info["status"] == "info" and info["passed"]
    assert "not judged, because gpme's runs did not converge" in info["reason"]
    assert "0.001" in info["reason"] and "RK4 error" in info["reason"]
    # a NaN stays a failure whatever its prerequisites
    nan = compare("mujoco", "arm", "q1", "case", [np.nan], [1.0], Tolerance(1e-3, 0.0, "r"))
    assert not_judged(nan, "x")["status"] == "fail"
