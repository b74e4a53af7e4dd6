"""One direction of dependence between gpme's packages (issue 25, docs/architecture.md).

The contract is pyproject.toml's [tool.importlinter]: gpme (command line) > gpme_study >
crosscheck > gpme_io > gpme_examples > gpme_core; a package imports only packages below
it, imports inside functions included.  import-linter checks it here; a planted contract
that puts the engine above the model io must be reported broken (the check can fail), and
tools/import_graph.py (the printed graph) must agree that no two packages import each other.
"""
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
LINT = shutil.which("lint-imports", path=str(Path(sys.executable).parent))


def _lint(*args):
    if LINT is None:
        pytest.fail("lint-imports is not installed (pip install -e '.[test]')")
    return subprocess.run([LINT, "--no-cache", *args], cwd=ROOT, capture_output=True,
                          text=True, timeout=300)


def test_the_layers_contract_is_kept():
    done = _lint()
    assert done.returncode == 0, done.stdout[-4000:] + done.stderr[-2000:]
    assert "1 kept, 0 broken" in done.stdout


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


def test_the_printed_graph_has_no_package_cycle():
    sys.path.insert(0, str(ROOT / "tools"))
    try:
        import import_graph
    finally:
        sys.path.pop(0)
    assert import_graph.cycles(import_graph.edges()) == []
