"""Names never become paths (issue 24): every name that reaches a file or folder name goes
through gpme_io.file_names.file_stem, and a path to be written is checked to lie inside
the output root.

The names are those a hostile model file can carry: parent references, absolute paths,
URL-special characters, Windows device names, a 300-character name, names that differ
only in case, control characters and lone surrogates.
"""
import dataclasses
import re
from pathlib import Path

import pytest

from crosscheck.mujoco.report import plot_name
from crosscheck.reports.rows import check_id, slice_path
from gpme_io.file_names import MAX_READABLE, UnsafePathError, file_stem, inside, named_path

HOSTILE = ["../x", "../../../../c2esc", "/abs", "/etc/passwd", "a#b", "../../esc#ape", "CON",
           "con.txt", "Lpt1", "nul", "x" * 300, "Arm", "arm", "ARM", "a b?c%d", ".hidden",
           "-dash", "..", ".", "", "a/b\\c", "tab\there", "nul\x00byte", "\ud800lone",
           "ünïcode", "a:b*c|d<e>f\"g"]
SAFE_STEM = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.-]*")
DEVICES = re.compile(r"(con|prn|aux|nul|com[0-9]|lpt[0-9])", re.IGNORECASE)


@pytest.mark.parametrize("name", HOSTILE)
def test_stem_is_one_safe_component(name):
    stem = file_stem(name)
    assert SAFE_STEM.fullmatch(stem), stem
    assert DEVICES.fullmatch(stem.split(".")[0]) is None
    assert len(stem) <= MAX_READABLE + 9          # readable part, '-', 8 hex digits
    assert stem not in (".", "..")


def test_stems_are_unique_even_without_case():
    """Names that differ (also only in case) never share a stem on a case-insensitive
    file system."""
    stems = [file_stem(n) for n in HOSTILE]
    assert len({s.lower() for s in stems}) == len(HOSTILE)


def test_plain_names_are_kept():
    for name in ("crane_flexible_n3", "ur5", "my_arm", "panda.v2", "a-b"):
        assert file_stem(name) == name


@pytest.mark.parametrize("name", HOSTILE)
def test_named_path_stays_inside(tmp_path, name):
    path = named_path(tmp_path, name, ".png", prefix="mujoco_exact_")
    assert path.parent == tmp_path
    path.write_bytes(b"x")                       # the file system accepts the name
    assert path.is_file()


def test_inside_refuses_escapes(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    for bad in (out / ".." / "x", Path("/tmp/elsewhere"), out / "a" / ".." / ".." / "y"):
        with pytest.raises(UnsafePathError, match="outside the output directory"):
            inside(out, bad)
    # a symbolic link planted in the output root that points out is refused too
    (out / "link").symlink_to(tmp_path)
    with pytest.raises(UnsafePathError):
        inside(out, out / "link" / "z")
    assert inside(out, out / "sub" / "f.csv") == (out / "sub" / "f.csv").resolve()


@pytest.mark.parametrize("name", HOSTILE)
def test_report_names_are_url_safe(name):
    """Plot names and check slices are single, URL-safe path components (no '#', '?',
    '%', '/', spaces): the page can load them without escaping."""
    for rel in (plot_name("exact", name), str(slice_path(f"mujoco/runs/{name}/q1")),
                check_id(name) + ".csv.gz"):
        assert re.fullmatch(r"[A-Za-z0-9_./-]+", rel), rel
        assert ".." not in Path(rel).parts
    assert "/" not in plot_name("exact", name)


def test_run_outputs_of_hostile_names_stay_inside(tmp_path):
    """gpme_io.runs.write_run_outputs (simulate's and verify's gpme step) writes every file of
    a run whose model is named '../../../../c2esc' (or '/abs/x', 'a#b', 'CON') inside the
    output folder."""
    from gpme_io.runs import simulate_scenario, write_run_outputs
    from gpme_io.scenario import crane_scenario
    base = crane_scenario(0)
    df = simulate_scenario(base, t_end=0.02, quick=True)
    out = tmp_path / "deep" / "out"
    out.mkdir(parents=True)
    for name in ("../../../../c2esc", "/abs/x", "a#b", "CON"):
        paths = write_run_outputs(dataclasses.replace(base, name=name), df, out,
                                  compressed=True)
        assert len(paths) >= 4
        for p in paths.values():
            assert Path(p).resolve().parent == out.resolve()
    assert {p.parent for p in tmp_path.rglob("*") if p.is_file()} == {out}


@pytest.mark.parametrize("name", ["../../../../c2esc", "../../esc#ape"])
def test_verify_of_a_hostile_model_name_writes_only_inside_out(tmp_path, name):
    """The issue's cases through `gpme verify --quick --only mujoco`: every file lands
    under --out, and every plot the pages link exists (no '#' cut off a src)."""
    import subprocess
    import sys
    root = Path(__file__).resolve().parents[1]
    deep = tmp_path / "a" / "b" / "c" / "d"
    deep.mkdir(parents=True)
    text = (root / "examples" / "my_arm" / "my_arm.toml").read_text()
    (deep / "m.toml").write_text(text.replace('name = "my_arm"', f'name = "{name}"', 1))
    (deep / "my_arm.urdf").write_text((root / "examples" / "my_arm" / "my_arm.urdf").read_text())
    before = {p for p in tmp_path.rglob("*")}
    out = deep / "out"
    proc = subprocess.run([sys.executable, "-m", "gpme.cli", "verify", "--quick", "--only",
                           "mujoco", "--model", str(deep / "m.toml"), "--out", str(out),
                           "--no-progress"], cwd=root, capture_output=True, text=True,
                          timeout=900)
    assert proc.returncode == 0, proc.stderr[-2000:]
    new = {p for p in tmp_path.rglob("*")} - before
    assert new and all(out in p.parents or p == out for p in new), sorted(new - {out})
    run_dir = (out / "latest").resolve()
    for page in run_dir.glob("*.html"):
        for src in re.findall(r'src="([^"]+)"', page.read_text()):
            if not src.startswith("data:"):
                assert (run_dir / src).is_file(), (page.name, src)
