"""Bad inputs of `gpme sweep`: each is refused before any work with exit status 2, one
message listing every problem (the value, the option or key, what would be valid), no
traceback, and nothing written where the output would go.  In-process through gpme.cli.main
(a subprocess costs seconds of imports per case); two cases also through `python -m
gpme.cli` to see the real command's stderr.
"""
import os
import subprocess
import sys
from pathlib import Path

import pytest

from gpme.cli import main as gpme_main

ROOT = Path(__file__).resolve().parents[1]
ARM = ROOT / "tests" / "data" / "sweep" / "sweep_arm2.toml"
# a valid small crane sweep the cases below spoil one input of
OK = ["--param", "A=0.2,0.3", "--n-rfe", "0", "--t-end", "0.3", "--transient", "0.1",
      "--in-process"]
MODEL = ["--model", str(ARM), "--param", "joint.shoulder.stiffness=10,20", "--in-process"]


def _files(tmp):
    """Files the case needs, made in ``tmp``: {name: path as text}."""
    (tmp / "a_file").write_text("not a directory\n")
    (tmp / "bad.toml").write_text("mode = \n")
    (tmp / "bad.yaml").write_text("mode: [grid\n  x: : :\n")
    (tmp / "sweep.json").write_text("{}\n")
    return {"file": str(tmp / "a_file"), "bad_toml": str(tmp / "bad.toml"),
            "bad_yaml": str(tmp / "bad.yaml"), "json": str(tmp / "sweep.json"),
            "missing": str(tmp / "missing.toml")}


# id: (arguments (with {placeholders} from _files), --out or None for tmp/out, key words)
CASES = {
    "out-is-a-file": (OK, "{file}", ["--out", "a_file'", "exists and is not a directory"]),
    "out-under-a-file": (OK, "{file}/sub", ["cannot be created", "on its way is a file"]),
    "out-empty": (OK, "", ["--out is empty", "give a directory (e.g. --out reports/sweep)"]),
    "config-missing": (["--config", "{missing}"], None, ["sweep file", "missing.toml",
                                                          "does not exist"]),
    "config-bad-toml": (["--config", "{bad_toml}"], None, ["bad.toml", "cannot be parsed",
                                                           "line 1"]),
    "config-bad-yaml": (["--config", "{bad_yaml}"], None, ["bad.yaml", "cannot be parsed",
                                                           "line 2"]),
    "config-suffix": (["--config", "{json}"], None, ["sweep.json", "expected a .toml, .yaml "
                                                     "or .yml file", "'.json'"]),
    "t-end-negative": (OK + ["--t-end", "-1"], None,
                       ["run.t_end (--t-end) must be finite and > 0, got -1.0"]),
    "t-end-nan": (OK + ["--t-end", "nan"], None,
                  ["run.t_end (--t-end) must be finite and > 0, got nan"]),
    "output-dt-below-dt": (OK + ["--dt", "1e-3", "--output-dt", "1e-4"], None,
                           ["run.dt (--dt, 0.001 s) must not exceed run.output_dt "
                            "(--output-dt, 0.0001 s)", "output_dt >= dt"]),
    "transient-after-t-end": (OK + ["--transient", "0.5"], None,
                              ["run.transient (--transient, 0.5 s) must be shorter than "
                               "run.t_end (--t-end, 0.3 s)"]),
    "n-rfe-too-large": (OK + ["--n-rfe", "1000"], None,
                        ["run.n_rfe (--n-rfe) must be an integer from 0 to 100", "got 1000"]),
    "workers-zero": (OK[:-1] + ["--workers", "0"], None, ["--workers must be >= 1, got 0"]),
    "workers-too-many": (OK[:-1] + ["--workers", "100000"], None,
                         ["--workers 100000: at most 4 x the", "--scheduler"]),
    "scheduler-malformed": (OK[:-1] + ["--scheduler", "nonsense"], None,
                            ["--scheduler 'nonsense' cannot be reached", "tcp://host:8786"]),
    "lhs-samples-zero": (["--mode", "lhs", "--samples", "0", "--param", "A=0.2:0.3"], None,
                         ["samples = an integer from 1 to 100000, got 0"]),
    "lhs-low-equals-high": (["--mode", "lhs", "--samples", "2", "--param", "A=0.3:0.3"], None,
                            ["parameters.A: low must be < high", "[0.3, 0.3]"]),
    "grid-num-zero": (["--param", "A=0.2:0.5:0"], None,
                      ["parameters.A: num must be a positive integer, got '0'"]),
    "grid-too-large": (["--param", "A=0.1:1:1000", "--param", "T=1:3:1000"], None,
                       ["1000 x 1000 = 1000000 points; at most 100000"]),
    "value-not-finite": (["--param", "A=nan,0.3"], None,
                         ["parameters.A: amplitude must be finite and >= 0 m, got nan"]),
    "value-out-of-range": (["--param", "T=-1,2"], None,
                           ["parameters.T: period must be finite and > 0 s, got -1.0"]),
    "unknown-parameter": (["--param", "amplitud=0.2,0.3"], None,
                          ["unknown parameter 'amplitud' (did you mean 'amplitude'?)",
                           "valid: ['amplitude'"]),
    "plot-x-not-swept": (OK + ["--plot-x", "z0"], None,
                         ["plot.x (--plot-x) = 'z0' is not swept; swept: ['amplitude']"]),
    "plot-y-unknown": (OK + ["--plot-y", "Q"], None,
                       ["plot.y (--plot-y): unknown parameter 'Q'"]),
    "limit-unknown-metric": (OK + ["--limit", "vib_peek_m=1"], None,
                             ["limits.vib_peek_m: not a metric that can be bounded",
                              "'vib_peak_m'"]),
    "limit-not-a-number": (OK + ["--limit", "vib_peak_m=abc"], None,
                           ["limits.vib_peak_m: expected a number, got 'abc'"]),
    "param-without-value": (["--param", "A"], None, ["--param 'A': expected NAME=VALUE"]),
    "t-end-absurd": (OK + ["--t-end", "1e12"], None,
                     ["estimated at", "years wall time", "above the limit of 2.0 h",
                      "a smaller --t-end", "--force", "in memory"]),
    "dt-absurd": (OK + ["--dt", "1e-12", "--output-dt", "1e-3"], None,
                  ["estimated at", "RK4 steps", "above the limit of 2.0 h", "a larger --dt",
                   "--force"]),
    "model-missing": (["--model", "{missing}", "--param", "run.t_end=0.1"], None,
                      ["model file", "missing.toml", "cannot be read"]),
    "model-unknown-path": (MODEL + ["--param", "joint.shoulder.stifness=1,2"], None,
                           ["unknown parameter path 'joint.shoulder.stifness' (did you mean "
                            "'joint.shoulder.stiffness'", "valid paths in sweep_arm2.toml"]),
    "model-value-refused": (MODEL + ["--param", "flexible.forearm.youngs_modulus=-1,70e9"],
                            None, ["parameters.flexible.forearm.youngs_modulus = -1.0: "
                                   "flexible[0].youngs_modulus: must be > 0 (Pa), got -1.0"]),
    "model-dt-above-output-dt": (MODEL + ["--dt", "0.01", "--output-dt", "0.001"], None,
                                 ["run.dt (--dt, 0.01 s) must not exceed run.output_dt "
                                  "(--output-dt, 0.001 s)"]),
    "model-segments-not-integer": (MODEL + ["--param", "flexible.forearm.segments=1.5"], None,
                                   ["parameters.flexible.forearm.segments: segments is an "
                                    "integer, got 1.5"]),
    "model-setting-of-the-crane": (MODEL + ["--min-frequency", "3"], None,
                                   ["run.min_frequency_hz (--min-frequency): not a setting of "
                                    "a model-file sweep"]),
}


def _argv(args, out, files, tmp):
    out = str(tmp / "out") if out is None else out.format(**files)
    return ["sweep", *[a.format(**files) for a in args], "--out", out], out


@pytest.mark.parametrize("case", list(CASES), ids=list(CASES))
def test_bad_input_exits_2_before_any_work(case, tmp_path, capsys):
    args, out, words = CASES[case]
    files = _files(tmp_path)
    argv, out = _argv(args, out, files, tmp_path)
    code = gpme_main(argv)
    captured = capsys.readouterr()
    assert code == 2, captured
    assert captured.err.startswith("error: ")
    for word in words:
        assert word in captured.err, (word, captured.err)
    assert "Traceback" not in captured.err
    assert not (tmp_path / "out").exists()        # nothing written before the refusal


def test_every_problem_is_listed_at_once(tmp_path, capsys):
    files = _files(tmp_path)
    code = gpme_main(["sweep", "--param", "Q=1", "--param", "T=1,-2", "--t-end", "-1",
                      "--workers", "0", "--limit", "nope=1", "--out", files["file"]])
    err = capsys.readouterr().err
    assert code == 2
    assert err.startswith("error: 6 problems in the sweep description:\n")
    for word in ("--out", "exists and is not a directory", "unknown parameter 'Q'",
                 "period must be finite and > 0 s, got -2.0", "run.t_end (--t-end) must be",
                 "--workers must be >= 1", "limits.nope"):
        assert word in err, word


@pytest.mark.skipif(not Path("/proc").is_dir(), reason="needs /proc (Linux)")
def test_unwritable_out_is_refused(tmp_path, capsys):
    # root writes anywhere its permissions say; /proc takes no new files even for root
    code = gpme_main(["sweep", *OK, "--out", "/proc/gpme_sweep_test"])
    err = capsys.readouterr().err
    assert code == 2
    assert "--out '/proc/gpme_sweep_test' cannot be created in '/proc'" in err
    assert "give a directory you can write" in err


@pytest.mark.parametrize("case", ["out-is-a-file", "t-end-absurd"])
def test_the_command_itself_prints_one_error_and_no_traceback(case, tmp_path):
    args, out, words = CASES[case]
    files = _files(tmp_path)
    argv, _ = _argv(args, out, files, tmp_path)
    done = subprocess.run([sys.executable, "-m", "gpme.cli", *argv], capture_output=True,
                          text=True, cwd=tmp_path, timeout=120,
                          env={**os.environ, "PYTHONWARNINGS": "ignore"})
    assert done.returncode == 2
    assert "Traceback" not in done.stderr
    assert done.stderr.startswith("error: ")
    for word in words:
        assert word in done.stderr
    assert not (tmp_path / "out").exists()


def test_model_lhs_range_end_the_loader_refuses_is_named(tmp_path, capsys):
    code = gpme_main(["sweep", "--model", str(ARM), "--mode", "lhs", "--samples", "3",
                      "--param", "joint.shoulder.stiffness=-10:20", "--param",
                      "flexible.forearm.segments=1:1000", "--in-process",
                      "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2 and "Traceback" not in err
    assert "parameters.joint.shoulder.stiffness = -10.0: joint[0].stiffness: must be >= 0" in err
    assert "parameters.flexible.forearm.segments: at most 100 RFEM segments in a sweep, got " \
           "1000" in err
    assert not (tmp_path / "out").exists()


def test_unreadable_config_does_not_hide_the_other_problems(tmp_path, capsys):
    files = _files(tmp_path)
    code = gpme_main(["sweep", "--config", files["bad_toml"], "--workers", "0",
                      "--out", files["file"]])
    err = capsys.readouterr().err
    assert code == 2 and "Traceback" not in err
    assert err.startswith("error: 3 problems in the sweep description:\n")
    for word in ("exists and is not a directory", "bad.toml' cannot be parsed",
                 "--workers must be >= 1, got 0"):
        assert word in err, word


def test_sweep_refused_while_another_writes_the_same_out(tmp_path, capsys):
    """Two sweeps on one --out would interleave their point files: the second is refused,
    naming the first (gpme_io.out_lock)."""
    from gpme.cli import main
    from gpme_io.out_lock import exclusive_output
    out = tmp_path / "sweep"
    with exclusive_output(out):
        code = main(["sweep", *OK, "--out", str(out), "--in-process", "--quiet"])
    err = capsys.readouterr().err
    assert code == 2 and "is being written by another gpme run (pid" in err
    assert "Traceback" not in err and not list(out.glob("points/*"))
