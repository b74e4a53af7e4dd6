"""The README's "your own robot" section runs as written: its model file is the one in
examples/, and `gpme verify --quick --model` on it passes (exit status 0)."""
import re
from pathlib import Path

import pytest

from gpme import cli

REPO = Path(__file__).resolve().parent.parent
EXAMPLE = REPO / "examples" / "my_arm" / "my_arm.toml"


def _without_leading_comments(text):
    lines = text.splitlines()
    while lines and lines[0].startswith("#"):
        lines.pop(0)
    return "\n".join(lines).strip()


def test_readme_shows_the_example_model_file():
    readme = (REPO / "README.md").read_text()
    section = readme[readme.index("## Your own robot"):]
    block = re.search(r"```toml\n(.*?)```", section, re.S).group(1).strip()
    assert block == _without_leading_comments(EXAMPLE.read_text())
    assert "gpme verify --quick --model examples/my_arm/my_arm.toml" in section
    assert len(block.splitlines()) <= 30


def test_readme_command_passes(tmp_path, monkeypatch):
    monkeypatch.chdir(REPO)
    status = cli.main(["verify", "--quick", "--no-progress", "--out", str(tmp_path),
                       "--model", "examples/my_arm/my_arm.toml"])
    assert status == 0
    run = tmp_path / "latest"
    for name in ("index.html", "summary.json", "checks/index.csv", "tolerances.csv.gz",
                 "checks/gpme/columns.csv", "checks/pinocchio/columns.csv",
                 "checks/mujoco/columns.csv", "runs/my_arm.csv.gz"):
        assert (run / name).is_file(), name


def test_bad_model_file_exits_2_with_the_key(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text(EXAMPLE.read_text().replace('urdf = "my_arm.urdf"', 'urdf = "missing.urdf"')
                   .replace("[run]", "[run]\nt_ned = 3.0"))
    assert cli.main(["simulate", "--no-progress", "--model", str(bad), "--out",
                     str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "missing.urdf" in err and "t_ned" in err


def test_point_masses_export_to_mujoco_and_match_its_terms():
    """Point masses (zero inertia) are valid when M stays positive definite; MuJoCo needs a
    positive-definite body inertia, so the MJCF raises it by INERTIA_BOUND, which keeps the
    term comparison at round-off."""
    import mujoco

    from crosscheck.mujoco.mjcf import INERTIA_BOUND, mjcf_text
    from crosscheck.mujoco.terms import sample_states, term_rows
    from gpme_io.modelfile import load_model_file
    scenario = load_model_file(REPO / "tests" / "data" / "runs" / "point_pendulum.toml")
    text = mjcf_text(scenario.model, 1e-3)
    assert f"raised by {INERTIA_BOUND!r}" in text
    mj = mujoco.MjModel.from_xml_string(text)
    rows = term_rows(scenario.model, mj, sample_states(scenario.model, 4, 7))
    assert all(r["status"] == "pass" for r in rows), [r for r in rows if r["status"] != "pass"]


@pytest.mark.parametrize("command", [["simulate"], ["verify"], ["crosscheck", "mujoco"]],
                         ids=["simulate", "verify", "crosscheck"])
def test_unusable_output_directory_is_refused_before_any_work(tmp_path, capsys, command):
    a_file = tmp_path / "a_file"
    a_file.write_text("x")
    for out, why in ((a_file, "is not a directory"), (a_file / "sub", "cannot be created")):
        assert cli.main(command + ["--out", str(out), "--model", str(EXAMPLE)]) == 2
        assert why in capsys.readouterr().err
