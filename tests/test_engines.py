"""crosscheck.engines and verify's handling of the optional engines (Drake, Exudyn) when
they are not installed: one clear sentence, an information row, never an ImportError."""
import builtins
import json

import pytest

from crosscheck import engines, verify, verify_steps
from gpme import cli


@pytest.fixture
def without(monkeypatch):
    """without(module): make ``import module`` (and its submodules) fail like a missing
    package."""
    real_import = builtins.__import__

    def hide(name):
        def fake(mod, *args, **kwargs):
            if mod == name or mod.startswith(name + "."):
                raise ModuleNotFoundError(f"No module named {mod!r}")
            return real_import(mod, *args, **kwargs)
        monkeypatch.setattr(builtins, "__import__", fake)
        import importlib

        real_import_module = importlib.import_module

        def fake_module(mod, *args, **kwargs):
            if mod == name or mod.startswith(name + "."):
                raise ModuleNotFoundError(f"No module named {mod!r}")
            return real_import_module(mod, *args, **kwargs)
        monkeypatch.setattr(engines, "import_module", fake_module)
    return hide


def test_every_engine_step_is_registered():
    assert set(engines.ENGINES) == set(verify_steps.STEPS) - {"gpme"}
    assert set(verify_steps.OPTIONAL_STEPS) == {e.name for e in engines.ENGINES.values() if e.extra}


@pytest.mark.parametrize("name,module,extra", [("drake", "pydrake", "drake"),
                                               ("exudyn", "exudyn", "exudyn")])
def test_missing_optional_engine_message_says_what_to_install(without, name, module, extra):
    without(module)
    message = engines.missing_message(name)
    assert message is not None
    assert f"pip install 'gpme[{extra}]'" in message and repr(module) in message
    assert not engines.is_installed(name)


def test_required_engines_are_installed():
    for name in ("pinocchio", "mujoco"):
        assert engines.missing_message(name) is None
        assert engines.version(name) != "not installed"


def test_verify_only_a_missing_engine_is_a_usage_error(without, tmp_path, capsys):
    without("pydrake")
    status = cli.main(["verify", "--quick", "--no-progress", "--only", "drake", "--out",
                       str(tmp_path)])
    err = capsys.readouterr().err
    assert status == 2
    assert "--only drake" in err and "pip install 'gpme[drake]'" in err
    assert "Traceback" not in err


def test_crosscheck_of_a_missing_engine_is_a_usage_error(without, tmp_path, capsys):
    without("exudyn")
    status = cli.main(["crosscheck", "exudyn", "--quick", "--out", str(tmp_path / "x")])
    assert status == 2
    assert "pip install 'gpme[exudyn]'" in capsys.readouterr().err


def test_a_missing_engine_step_is_one_information_row(without, tmp_path):
    without("pydrake")
    run_dir, summary, rows = verify.run_verify(tmp_path, quick=True, only="drake",
                                               progress=False, run_id="no-drake")
    assert list(summary["engine"]) == ["drake"]
    assert list(summary["status"]) == ["info"]
    assert "pip install 'gpme[drake]'" in summary["reason"].iloc[0]
    document = json.loads((run_dir / "summary.json").read_text())
    assert document["passed"] is True
    index = (run_dir / "index.html").read_text()
    assert "not installed" in index and "gpme[drake]" in index
