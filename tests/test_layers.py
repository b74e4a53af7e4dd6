"""One direction of dependence between gpme's packages (issue 25, docs/architecture.md).

The contracts are pyproject.toml's [tool.importlinter]: gpme (command line) > gpme_study >
crosscheck > gpme_io > gpme_examples > gpme_core, a package importing only packages below
it, imports inside functions included; and the engine (gpme_core) imports no tqdm, PIL or
matplotlib (it returns data: bars and figures are gpme_io's).  import-linter checks them
here; planted contracts that the code breaks (the engine placed above the model io, gpme_io
forbidden the engine or the plotting packages) must be reported broken (the check can
fail), and tools/import_graph.py (the printed graph) must agree that no two packages import
each other.
"""
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
LINT = shutil.which("lint-imports", path=str(Path(sys.executable).parent))


def _lint(*args):
    if LINT is None:
        pytest.fail("lint-imports is not installed (pip install -e '.[test]')")
    return subprocess.run([LINT, "--no-cache", *args], cwd=ROOT, capture_output=True,
                          text=True, timeout=300)


def _contracts():
    with open(ROOT / "pyproject.toml", "rb") as fh:
        return tomllib.load(fh)["tool"]["importlinter"]["contracts"]


def test_every_contract_is_kept():
    """The layers and the engine's forbidden packages, both checked and both kept."""
    contracts = _contracts()
    assert sorted(c["type"] for c in contracts) == ["forbidden", "layers"]
    forbidden = next(c for c in contracts if c["type"] == "forbidden")
    assert forbidden["source_modules"] == ["gpme_core"]
    assert {"tqdm", "PIL", "matplotlib"} <= set(forbidden["forbidden_modules"])
    done = _lint()
    assert done.returncode == 0, done.stdout[-4000:] + done.stderr[-2000:]
    assert f"Contracts: {len(contracts)} kept, 0 broken." in done.stdout


def test_a_planted_upward_dependence_is_reported(tmp_path):
    """The same tool on a contract the code breaks (the engine placed above gpme_io, which
    imports it everywhere): broken, naming an import."""
    config = tmp_path / "planted.toml"
    config.write_text('[tool.importlinter]\nroot_packages = ["gpme_io", "gpme_core"]\n\n'
                      '[[tool.importlinter.contracts]]\nname = "planted"\ntype = "layers"\n'
                      'layers = ["gpme_core", "gpme_io"]\n')
    done = _lint("--config", str(config))
    assert done.returncode != 0
    assert "BROKEN" in done.stdout and "gpme_io." in done.stdout and "-> gpme_core." in done.stdout


@pytest.mark.parametrize("forbidden, imported", [
    (["gpme_core"], "-> gpme_core."),                     # a project package
    (["tqdm", "PIL", "matplotlib"], "-> matplotlib"),     # packages outside the project
], ids=["engine", "plotting"])
def test_a_planted_forbidden_import_is_reported(tmp_path, forbidden, imported):
    """The forbidden contract's form on imports the code has (gpme_io imports the engine,
    and draws figures and bars): broken, naming an import."""
    config = tmp_path / "planted.toml"
    config.write_text('[tool.importlinter]\nroot_packages = ["gpme_io", "gpme_core"]\n'
                      'include_external_packages = true\n\n'
                      '[[tool.importlinter.contracts]]\nname = "planted"\ntype = "forbidden"\n'
                      'source_modules = ["gpme_io"]\n'
                      f'forbidden_modules = {forbidden!r}\n'.replace("'", '"'))
    done = _lint("--config", str(config))
    assert done.returncode != 0
    assert "BROKEN" in done.stdout and "gpme_io." in done.stdout and imported in done.stdout


def test_the_printed_graph_has_no_package_cycle():
    sys.path.insert(0, str(ROOT / "tools"))
    try:
        import import_graph
    finally:
        sys.path.pop(0)
    assert import_graph.cycles(import_graph.edges()) == []
