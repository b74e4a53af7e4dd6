"""A model file's [[reference]]: published values of the motion, read, checked against the
model's names, and compared with the run (crosscheck.reference_values)."""
from pathlib import Path

import numpy as np
import pytest

from crosscheck.reference_values import reference_rows
from gpme_core.errors import ModelFileError
from gpme_core.integrate import simulate
from gpme_io.modelfile import load_model_file

REPO = Path(__file__).resolve().parents[1]
FIVE_BAR = (REPO / "tests" / "data" / "modelfiles" / "five_bar_rigid.toml").read_text()
FIVE_BAR = FIVE_BAR.replace('urdf = "../../../examples/', f'urdf = "{REPO.as_posix()}/examples/')


def _scenario(tmp_path, reference):
    path = tmp_path / "model.toml"
    path.write_text(FIVE_BAR + reference, encoding="utf-8")
    return load_model_file(path)


def _entry(q, q_dot, rel=1e-6, t=0.2):
    q_text = ", ".join(f"{k} = {v!r}" for k, v in q.items())
    v_text = ", ".join(f"{k} = {v!r}" for k, v in q_dot.items())
    return (f"\n[[reference]]\nt = {t}\nq = {{ {q_text} }}\nq_dot = {{ {v_text} }}\n"
            f"abs = 0.0\nrel = {rel}\nsource = \"this test's own run\"\n"
            "reason = \"the run reproduces itself to round-off\"\n")


def test_values_at_a_sample_pass_and_a_planted_error_fails(tmp_path):
    sc = _scenario(tmp_path, "")
    df = simulate(sc.system, 0.2, sc.q0, sc.q_dot0, dt=sc.dt, output_dt=0.01)
    last = df.iloc[-1]
    q = {c: float(last[c]) for c in ("motor_a", "elbow_b")}
    q_dot = {"motor_a": float(last["motor_a_dot"])}
    sc = _scenario(tmp_path, _entry(q, q_dot))
    rows = reference_rows(sc, df)
    assert [r["status"] for r in rows] == ["pass", "pass"]
    assert rows[0]["quantity"] == "published coordinates at t = 0.2 s"
    wrong = dict(q, elbow_b=q["elbow_b"] * (1 + 1e-4))
    sc = _scenario(tmp_path, _entry(wrong, q_dot))
    rows = reference_rows(sc, df)
    assert [r["status"] for r in rows] == ["fail", "pass"]
    assert "elbow_b" in rows[0]["entry"]
    # a run that ends before the published time: information, not a failure
    short = df[df["t"] <= 0.1]
    assert {r["status"] for r in reference_rows(sc, short)} == {"info"}


@pytest.mark.parametrize("entry, message", [
    (_entry({"motor_z": 1.0}, {}), r"reference\[0\]\.q\.motor_z: no coordinate 'motor_z'"),
    (_entry({"motor_a": 1.0}, {"elbow_q": 0.0}),
     r"reference\[0\]\.q_dot\.elbow_q: no coordinate 'elbow_q'"),
    (_entry({"motor_a": 1.0}, {}, t=5.0), r"reference\[0\]\.t: 5 s is after the run's end"),
    (_entry({"motor_a": 1.0}, {}, rel=-1.0), r"reference\[0\]\.rel: must be >= 0"),
    ("\n[[reference]]\nt = 0.1\nabs = 0.0\nrel = 0.0\nsource = \"s\"\nreason = \"r\"\n",
     r"give the published values"),
])
def test_bad_references_name_the_key(tmp_path, entry, message):
    with pytest.raises(ModelFileError, match=message):
        _scenario(tmp_path, entry)
