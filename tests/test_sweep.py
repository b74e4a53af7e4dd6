"""gpme sweep (gpme_study): spec parsing and validation, metric helpers, one point with its
failures recorded, the Dask runner with resume, the table against direct single runs, the
plots and the command line.  Runs are short (t_end 1 s, n_rfe <= 1) to keep this file fast.
"""
import json
import re
import signal
import subprocess
import sys
import time

import numpy as np
import pandas as pd
import pytest

from gpme.cli import main as gpme_main
from gpme_examples.crane import CraneParameters, crane_system, initial_state
from gpme_core.integrate import simulate
from gpme_core.stability import suggest_rk4_step
from gpme_io.file_names import file_stem
from gpme_study import metrics as mx
from gpme_study.plots import safe_mask, write_plots
from gpme_study.point import point_key, run_point
from gpme_study.runner import run_sweep
from gpme_study.spec import RunSettings
from gpme_study.spec_points import SweepSpecError
from gpme_study.sweep_spec import load_spec, spec_from_dict
from gpme_study.store import ResultStore

SHORT = {"t_end": 1.0, "transient": 0.3}
# an ellipse with a 1.5 m semi-axis along x puts E out of the crane's reach at t = 0
UNREACHABLE = {"a": 1.5}


# ------------------------------------------------------------------ spec
def test_grid_is_the_cartesian_product_with_defaults_for_n_rfe():
    spec = spec_from_dict({"parameters": {"A": [0.2, 0.3], "T": "1:3:3"}, "run": SHORT})
    assert len(spec.points) == 6
    assert spec.points[0] == {"amplitude": 0.2, "period": 1.0, "n_rfe": 1}
    assert {p["period"] for p in spec.points} == {1.0, 2.0, 3.0}
    assert spec.swept == ("amplitude", "period")
    assert (spec.plot_x, spec.plot_y) == ("amplitude", "period")


def test_lhs_puts_one_sample_in_each_stratum_and_is_reproducible():
    data = {"mode": "lhs", "samples": 8, "seed": 3,
            "parameters": {"A": [0.1, 0.5], "T": "1:3", "n_rfe": [0, 1]}}
    spec = spec_from_dict(data)
    a = np.array([p["amplitude"] for p in spec.points])
    strata = np.floor((a - 0.1) / 0.4 * 8).astype(int)
    assert sorted(strata) == list(range(8))
    assert {p["n_rfe"] for p in spec.points} == {0, 1}
    assert spec_from_dict(data).points == spec.points


def test_toml_and_yaml_files_give_the_same_spec(tmp_path):
    toml = tmp_path / "s.toml"
    toml.write_text('mode = "list"\npoints = [{A = 0.3, T = 2.0}, {A = 0.4, n_rfe = 0}]\n'
                    '[run]\nt_end = 2.0\n[limits]\nvib_peak_m = 1e-4\n')
    yaml = tmp_path / "s.yaml"
    yaml.write_text("mode: list\npoints:\n  - {A: 0.3, T: 2.0}\n  - {A: 0.4, n_rfe: 0}\n"
                    "run: {t_end: 2.0}\nlimits: {vib_peak_m: 1.0e-4}\n")
    a, b = load_spec(toml), load_spec(yaml)
    assert a == b
    # the second point does not set T: it runs (and its row shows) the default period
    assert a.points[1] == {"amplitude": 0.4, "period": CraneParameters().period, "n_rfe": 0}
    assert a.limits == {"vib_peak_m": 1e-4}


def test_invalid_spec_lists_every_problem():
    with pytest.raises(SweepSpecError) as info:
        spec_from_dict({"mode": "grid", "parameters": {"A": [0.2], "Q": [1], "T": [-1.0]},
                        "run": {"t_end": 0.5, "transient": 2.0}, "limits": {"nope": 1},
                        "extra": 1})
    msg = str(info.value)
    for part in ("unknown parameter 'Q'", "period must be finite and > 0 s, got -1.0",
                 "run.transient (2 s) must be shorter than run.t_end", "limits.nope",
                 "unknown key 'extra'"):
        assert part in msg
    assert "5 problems" in msg


def test_spec_file_that_does_not_parse_names_the_file(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("mode = \n")
    with pytest.raises(SweepSpecError, match="bad.toml.*cannot be parsed"):
        load_spec(bad)


# ------------------------------------------------------------------ metrics
def test_dominant_frequency_finds_a_sine_between_bins():
    fs, f0 = 500.0, 7.3
    t = np.arange(0, 4.0, 1 / fs)
    x = np.column_stack([np.sin(2 * np.pi * f0 * t) + 0.5 * t,     # trend is removed
                         0.1 * np.sin(2 * np.pi * 1.0 * t)])       # below the 2 Hz band
    # tolerance: the Hann-window parabola interpolation is good to ~0.1 bin (bin 0.25 Hz)
    assert mx.dominant_frequency(x, fs, 2.0) == pytest.approx(f0, abs=0.03)


def test_highpass_keeps_vibration_and_removes_the_slow_part():
    fs = 500.0
    t = np.arange(0, 4.0, 1 / fs)[:, None]
    slow, fast = 0.01 * np.cos(2 * np.pi * 0.4 * t), 1e-4 * np.sin(2 * np.pi * 15 * t)
    dev = mx.deviation_metrics(np.hstack([slow + fast, 0 * t, 0 * t]), fs, 2.0, 1.0)
    # tolerance: 4th-order filtfilt at 2 Hz passes 15 Hz within 0.01 % and leaves
    # 0.01 * (0.4/2)^8 ~ 3e-8 m of the 0.4 Hz part; the edge transients of the slow part
    # (5.6e-5 m at t = 0) measured below 1e-6 m inside the window [1 s, 3 s]: 1 %
    assert dev["vib_peak_m"] == pytest.approx(1e-4, rel=0.01)
    whole = mx.deviation_metrics(np.hstack([slow + fast, 0 * t, 0 * t]), fs, 2.0, 0.0)
    assert whole["vib_peak_m"] > 1.3e-4   # without the window the edge effect shows
    assert dev["dev_peak_m"] == pytest.approx(0.01 + 1e-4, rel=1e-3)


# ------------------------------------------------------------------ one point
def test_unreachable_point_is_a_recorded_outcome():
    spec = spec_from_dict({"mode": "list", "points": [UNREACHABLE], "run": SHORT})
    row = run_point(spec.points[0], spec.run)
    assert row["status"] == "infeasible"
    assert row["failed_run"] == "rigid"
    assert "ConstraintError" in row["error"] and "out of reach" in row["error"]
    assert row["constraints_met"] is False
    assert np.isnan(row["dev_peak_m"]) and row["wall_time_s"] > 0


def test_rigid_point_has_no_flexibility_metrics_but_drive_peaks():
    row = run_point({"amplitude": 0.3, "n_rfe": 0}, RunSettings(**{**SHORT, "n_rfe": 0}))
    assert row["status"] == "ok" and row["constraints_met"]
    assert np.isnan(row["vib_peak_m"]) and np.isnan(row["flex_peak_rad"])
    assert row["drive_psi3_peak_Nm"] == row["rigid_drive_psi3_peak_Nm"] > 0


def test_point_key_depends_on_parameters_and_settings_only():
    s = RunSettings(**SHORT)
    assert point_key({"amplitude": 0.5, "n_rfe": 1}, s) == point_key({"n_rfe": 1}, s)  # default
    assert point_key({"amplitude": 0.3, "n_rfe": 1}, s) != point_key({"n_rfe": 1}, s)
    assert point_key({"n_rfe": 1}, s) != point_key({"n_rfe": 1}, RunSettings(t_end=2.0))


# ------------------------------------------------------------------ runner on Dask
@pytest.fixture(scope="module")
def cluster():
    from dask.distributed import LocalCluster
    import logging
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=":0", silence_logs=logging.ERROR) as c:
        yield c


@pytest.fixture(scope="module")
def tiny_sweep(cluster, tmp_path_factory):
    out = tmp_path_factory.mktemp("sweep")
    spec = spec_from_dict({"mode": "list", "run": SHORT,
                           "points": [{"A": 0.3, "T": 1.5}, {"A": 0.5, "T": 2.5},
                                      UNREACHABLE]})
    table = run_sweep(spec, out, scheduler=cluster.scheduler_address, report=None)
    return spec, out, table


def _direct(point, settings, steps):
    """The metrics recomputed from direct gpme_core runs, independently of gpme_study, with
    the RK4 steps (rigid, flexible) the sweep chose (checked separately)."""
    params = CraneParameters().with_changes(**{k: v for k, v in point.items() if k != "n_rfe"})
    runs = {}
    for n, dt in zip((0, 1), steps):
        system = crane_system(n, params)
        q0, qd0 = initial_state(system.model, params)
        df = simulate(system, settings.t_end, q0, qd0, dt=dt, on_manifold=True,
                      output_dt=settings.output_dt)
        names = list(system.model.coordinate_names)
        f_r = np.array([system.solve(t, q, qd).reaction_forces for t, q, qd in zip(
            df.t, df[names].to_numpy(), df[[f"{c}_dot" for c in names]].to_numpy())])
        runs[n] = (df, f_r, names)
    flex, f_r, names = runs[1]
    rigid = runs[0][0]
    dr = flex[["x_E", "y_E", "z_E"]].to_numpy() - rigid[["x_E", "y_E", "z_E"]].to_numpy()
    late = flex[flex.t >= settings.transient]
    return {"dev_peak_m": np.linalg.norm(dr, axis=1).max(),
            "z4_dev_peak_m": np.abs(flex.z4 - rigid.z4).max(),
            "flex_peak_rad": flex[["psi_arm_1", "theta_arm_1", "phi_arm_1"]].abs().max().max(),
            "drive_psi3_peak_Nm": np.abs(f_r[:, names.index("psi3")]).max(),
            "drive_z4_peak_N": np.abs(f_r[:, names.index("z4")]).max(),
            "phi2_max_abs_m": late.Phi_2.abs().max(),
            # one sde (n = 1, dl = L): M = E I angle / L on a round tube, sigma = M (d/2) / I
            "stress_peak_Pa": params.steel_youngs_modulus * 0.5 * params.arm_diameter
            * np.hypot(flex.psi_arm_1, flex.theta_arm_1).max() / params.arm_length}


def test_table_matches_direct_single_runs(tiny_sweep):
    spec, out, table = tiny_sweep
    assert list(table.status) == ["ok", "ok", "infeasible"]
    assert table.constraints_met.tolist() == [True, True, False]
    ok = table.iloc[0]
    # the steps: stable (below suggest_rk4_step's limit at the start, 2x the suggestion)
    # and a whole number per output step, the rigid one at the 1e-3 s cap
    params = CraneParameters().with_changes(
        **{k: v for k, v in spec.points[0].items() if k != "n_rfe"})
    for n, dt in ((0, ok.rigid_dt_s), (1, ok.flexible_dt_s)):
        system = crane_system(n, params)
        limit = 2.0 * suggest_rk4_step(system.model, initial_state(system.model, params)[0])
        per_output = spec.run.output_dt / dt
        assert 0 < dt < limit and per_output == pytest.approx(round(per_output), abs=1e-9)
    assert ok.rigid_dt_s == pytest.approx(1e-3, rel=1e-12)
    direct = _direct(spec.points[0], spec.run, (ok.rigid_dt_s, ok.flexible_dt_s))
    for name, value in direct.items():
        # tolerance: identical computations in another process; 1e-9 relative allows
        # only for a different BLAS summation order, and 1e-15 absolute for Phi ~ 1e-13
        assert ok[name] == pytest.approx(value, rel=1e-9, abs=1e-15), name
    assert 0 < ok.vib_peak_m <= ok.dev_peak_m
    assert ok.vib_freq_hz > spec.run.min_frequency_hz


def test_table_files_and_point_store(tiny_sweep):
    spec, out, table = tiny_sweep
    csv = pd.read_csv(out / "results.csv")
    parquet = pd.read_parquet(out / "results.parquet")
    assert len(csv) == len(parquet) == 3
    assert list(parquet.columns) == list(table.columns)
    # tolerance: CSV prints floats with 17 significant digits: exact round trip
    np.testing.assert_allclose(csv.dev_peak_m, table.dev_peak_m, rtol=0, atol=0)
    stored = ResultStore(out).keys()
    assert stored == set(table.key)
    assert json.loads((out / "points" / f"{table.key[2]}.json").read_text())["status"] == \
        "infeasible"


def test_resume_recomputes_only_missing_points(tiny_sweep, cluster):
    spec, out, table = tiny_sweep
    again = run_sweep(spec, out, scheduler=cluster.scheduler_address, report=None)
    assert again.attrs["computed"] == 0 and again.attrs["cached"] == 3
    pd.testing.assert_frame_equal(again, table)
    (out / "points" / f"{table.key[2]}.json").unlink()
    third = run_sweep(spec, out, scheduler=cluster.scheduler_address, report=None)
    assert third.attrs["computed"] == 1
    assert third.status.tolist() == table.status.tolist()


# ------------------------------------------------------------------ plots
def _synthetic_table():
    rows = []
    for a in (0.1, 0.2, 0.3):
        for t in (1.0, 2.0):
            rows.append({"amplitude": a, "period": t, "status": "ok", "constraints_met": True,
                         "vib_peak_m": a / t, "drive_psi3_peak_Nm": 10 * a})
    rows[-1].update(status="infeasible", constraints_met=False, vib_peak_m=np.nan,
                    drive_psi3_peak_Nm=np.nan)
    return pd.DataFrame(rows)


def test_safe_mask_applies_every_limit_and_excludes_infeasible():
    table = _synthetic_table()
    safe = safe_mask(table, {"vib_peak_m": 0.12, "drive_psi3_peak_Nm": 2.5})
    expected = [(r.vib_peak_m <= 0.12) and (r.drive_psi3_peak_Nm <= 2.5)
                and r.status == "ok" for r in table.itertuples()]
    assert safe.tolist() == expected == [True, True, False, True, False, False]


def test_plots_mark_the_infeasible_cell(tmp_path):
    from gpme_study.plots import heat_map
    table = _synthetic_table()
    fig = heat_map(table, "amplitude", "period", "vib_peak_m", {"vib_peak_m": 0.12})
    hatched = [p for p in fig.axes[0].patches if p.get_hatch() == "xx"]
    assert len(hatched) == 1 and hatched[0].get_x() == pytest.approx(0.25)
    paths = write_plots(table, tmp_path, "amplitude", "period", {"vib_peak_m": 0.12},
                        metrics=("vib_peak_m", "drive_psi3_peak_Nm"))
    # a metric name with upper case gets a digest (gpme_io.file_names: two names that
    # differ only in case must not meet on a case-insensitive file system)
    assert sorted(paths) == sorted([f"heatmap_{file_stem('drive_psi3_peak_Nm')}.png",
                                    "heatmap_vib_peak_m.png", "safe_region.png"])
    assert file_stem("drive_psi3_peak_Nm").startswith("drive_psi3_peak_Nm-")
    assert all(p.stat().st_size > 1000 for p in paths.values())


def test_a_point_without_a_value_is_marked_not_left_blank():
    """issue 28: a point that ran and met its constraints but has no value of the metric
    (NaN: a rigid point's vibration frequency) is hatched "no value" on the grid and a
    hollow marker on a scatter, apart from the infeasible ones."""
    from gpme_study.plots import heat_map
    table = _synthetic_table()
    table.loc[0, "vib_peak_m"] = np.nan                 # ok, constraints met, no value
    fig = heat_map(table, "amplitude", "period", "vib_peak_m")
    ax = fig.axes[0]
    marked = {p.get_hatch(): p for p in ax.patches}
    assert set(marked) == {"xx", "//"}
    assert (marked["//"].get_x(), marked["//"].get_y()) == (pytest.approx(0.05),
                                                            pytest.approx(0.5))
    assert {t.get_text() for t in ax.get_legend().get_texts()} == {"infeasible", "no value"}
    scatter = table.drop(index=[1])                     # not a full grid: a scatter plot
    ax = heat_map(scatter, "amplitude", "period", "vib_peak_m").axes[0]
    assert {t.get_text() for t in ax.get_legend().get_texts()} == {"infeasible", "no value"}


# ------------------------------------------------------------------ command line
def test_cli_sweep_on_the_default_local_cluster(tmp_path, capsys):
    out = tmp_path / "cli"
    code = gpme_main(["sweep", "--param", "A=0.3,0.4", "--param", "T=2", "--n-rfe", "0",
                      "--t-end", "1", "--transient", "0.3", "--workers", "1", "--out",
                      str(out), "--limit", "drive_psi3_peak_Nm=100", "--quiet"])
    assert code == 0
    table = pd.read_csv(out / "results.csv")
    assert table.amplitude.tolist() == [0.3, 0.4] and (table.status == "ok").all()
    assert (out / "plots" / "safe_region.png").is_file()
    assert "2 points: {'ok': 2}" in capsys.readouterr().out


def test_cli_invalid_sweep_exits_2_with_every_problem(tmp_path, capsys):
    code = gpme_main(["sweep", "--param", "A", "--limit", "x=1", "--t-end", "-1",
                      "--out", str(tmp_path)])
    assert code == 2
    err = capsys.readouterr().err
    for part in ("problems in the sweep description", "--param 'A': expected NAME=VALUE",
                 "limits.x: not a metric", "run.t_end (--t-end) must be finite and > 0, got -1.0",
                 "mode 'grid' needs at least one parameter"):
        assert part in err


# ------------------------------------------------------------------ interruptions
# 8 points of the rigid crane, 0.3 s each: a few seconds in one process
FAULT_ARGS = ["sweep", "--param", "A=0.2:0.5:8", "--n-rfe", "0", "--t-end", "0.3",
              "--transient", "0.1", "--in-process"]
WALL_KEYS = ("wall_time_s", "rigid_sim_wall_s", "flexible_sim_wall_s")


def _stored(out):
    """{key: the point file's values without wall times, as JSON text}; every file in
    points/ is either a complete point file or a hidden temporary file of an interrupted
    atomic write (never a partial *.json)."""
    points = out / "points"
    stored = {}
    for f in sorted(points.iterdir()) if points.is_dir() else []:
        if f.name.startswith("."):
            assert f.suffix == ".tmp", f.name
            continue
        assert f.suffix == ".json", f.name
        row = json.loads(f.read_text())            # complete and loadable
        assert row["key"] == f.stem and row["status"] == "ok"
        stored[f.stem] = json.dumps({k: v for k, v in row.items() if k not in WALL_KEYS},
                                    sort_keys=True)
    return stored


def _temporary_files(out):
    return [p for p in out.rglob(".*.tmp")]


def _sweep_process(out):
    return subprocess.Popen([sys.executable, "-m", "gpme.cli", *FAULT_ARGS, "--out", str(out)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            cwd=out.parent)


def test_interrupted_point_write_leaves_the_stored_point_whole(tmp_path, monkeypatch):
    store = ResultStore(tmp_path)
    store.save({"key": "k", "status": "ok", "x": 1.0})
    good = store.path("k").read_text()

    def interrupted(fd):
        raise KeyboardInterrupt       # Ctrl-C (or gpme.cli.Terminated) inside the write
    monkeypatch.setattr("os.fsync", interrupted)
    with pytest.raises(KeyboardInterrupt):
        store.save({"key": "k", "status": "ok", "x": 2.0})
    assert store.path("k").read_text() == good and store.load("k")["x"] == 1.0
    assert sorted(p.name for p in store.directory.iterdir()) == ["k.json"]


def test_killed_sweep_keeps_whole_points_and_resumes_to_the_same_values(tmp_path):
    """The fault test: the command in a subprocess, killed (SIGTERM, SIGKILL) at seeded
    random moments while points are being computed; every point file left is complete and
    has the values of an uninterrupted sweep, and a rerun computes only the rest."""
    start = time.perf_counter()
    ref = tmp_path / "reference"
    done = subprocess.run([sys.executable, "-m", "gpme.cli", *FAULT_ARGS, "--out", str(ref)],
                          capture_output=True, text=True, cwd=tmp_path, timeout=120)
    assert done.returncode == 0, done.stderr
    reference = _stored(ref)
    assert len(reference) == 8
    sweep_s = float(re.search(r"computed 8 in ([\d.]+) s", done.stdout).group(1))
    out = tmp_path / "killed"
    rng = np.random.default_rng(20261122)
    for sig in (signal.SIGTERM, signal.SIGKILL, signal.SIGTERM, signal.SIGKILL):
        proc = _sweep_process(out)
        for line in proc.stdout:           # kill while the points are being computed
            if "to run" in line:
                break
        left = 1.0 - len(_stored(out)) / 8.0      # a moment while points are left to run
        time.sleep(rng.uniform(0.0, 0.9 * left * sweep_s))
        proc.send_signal(sig)
        _, err = proc.communicate(timeout=60)
        assert "Traceback" not in err
        if sig == signal.SIGTERM and proc.returncode == 143:
            # gpme.cli: one line; every atomic write in flight removed its temporary file
            assert err.strip().splitlines()[-1].startswith("terminated (SIGTERM)")
            assert _temporary_files(out) == []
        else:
            assert proc.returncode in (0, -sig), (sig, proc.returncode, err)
        stored = _stored(out)
        assert {k: reference[k] for k in stored} == stored
        if (out / "results.csv").exists():     # written whole at the end of a finished run
            assert len(pd.read_csv(out / "results.csv")) == 8
    before = _stored(out)
    final = subprocess.run([sys.executable, "-m", "gpme.cli", *FAULT_ARGS, "--out", str(out)],
                           capture_output=True, text=True, cwd=tmp_path, timeout=120)
    assert final.returncode == 0, final.stderr
    assert f"{len(before)} already done, {8 - len(before)} to run" in final.stdout
    assert _stored(out) == reference
    table = pd.read_csv(out / "results.csv")
    assert len(table) == 8 and (table.status == "ok").all()
    assert time.perf_counter() - start < 90


# ------------------------------------------------------------------ cost, progress, lists
TINY = ["--n-rfe", "0", "--t-end", "0.3", "--transient", "0.1", "--in-process"]


def test_list_points_setting_different_parameters_run_at_the_defaults(tmp_path, capsys):
    out = tmp_path / "list"
    code = gpme_main(["sweep", "--point", "A=0.3", "--point", "T=2", *TINY, "--out", str(out)])
    assert code == 0
    table = pd.read_csv(out / "results.csv")
    defaults = CraneParameters()
    assert table.amplitude.tolist() == [0.3, defaults.amplitude]
    assert table.period.tolist() == [defaults.period, 2.0]
    assert (table.status == "ok").all()
    # each point is the crane with what it sets: the same key as the full point
    settings = RunSettings(t_end=0.3, transient=0.1, n_rfe=0)
    assert table.key[0] == point_key({"amplitude": 0.3, "n_rfe": 0}, settings)
    # the two points are not a grid: scatter maps over (amplitude, period)
    assert (out / "plots" / f"heatmap_{file_stem('drive_psi3_peak_Nm')}.png").stat().st_size > 1000


def test_estimate_is_printed_before_the_run_and_force_runs_above_the_limit(
        tmp_path, capsys, monkeypatch):
    monkeypatch.setattr("gpme_study.cost.MAX_WALL_S", 1e-3)
    argv = ["sweep", "--param", "A=0.2,0.3", *TINY, "--out", str(tmp_path / "s")]
    assert gpme_main(argv) == 2
    captured = capsys.readouterr()
    assert "estimate: 2 points x" in captured.out
    assert "above the limit of 1 ms" in captured.err and "--force" in captured.err
    assert not (tmp_path / "s").exists()
    assert gpme_main(argv + ["--force"]) == 0
    lines = capsys.readouterr().out.splitlines()
    first = next(k for k, line in enumerate(lines) if line.startswith("estimate: "))
    assert lines[first + 1].startswith("--force given, running although the sweep is "
                                       "estimated at")
    assert lines[first + 2] == "2 points (2 distinct): 0 already done, 2 to run"


def test_estimate_of_a_run_follows_its_steps():
    from gpme_study.point_cost import ROW_PASSES, Sampler, crane_point_plans
    sampler = Sampler(lambda line: None)
    point = {"amplitude": 0.3, "n_rfe": 0}
    short, long_ = (crane_point_plans(point, RunSettings(t_end=t, n_rfe=0, transient=0.1,
                                                         dt=1e-3), sampler)[0]
                    for t in (0.5, 5.0))
    assert (short.steps, long_.steps) == (500, 5000)
    assert (short.rows, long_.rows) == (251, 2501)
    # one measurement (the first run's) prices both: per step, per row (history and
    # metrics), once per run
    assert list(sampler.costs) == [("crane", 0)]
    c = sampler.costs[("crane", 0)]
    assert c.step_s > 0 and c.row_s > 0 and c.fixed_s >= 0
    for plan in (short, long_):
        assert plan.seconds == pytest.approx(
            c.fixed_s + plan.steps * c.step_s + plan.rows * ROW_PASSES * c.row_s, rel=1e-12)


def test_progress_in_a_log_is_a_few_lines_with_the_counts():
    from gpme_study.runner import MAX_LOG_LINES, PointProgress
    lines = []
    progress = PointProgress(lines.append, 500, terminal=False)
    for k in range(500):
        progress.point(f"k{k}", {"status": "ok" if k % 10 else "infeasible"})
    assert len(lines) <= MAX_LOG_LINES + 1
    assert lines[-1].startswith("[500/500] 50 infeasible, 450 ok; ")
    on_terminal = []
    progress = PointProgress(on_terminal.append, 3, terminal=True)
    for k in range(3):
        progress.point(f"k{k}", {"status": "ok", "wall_time_s": 1.0})
    assert [line.split(";")[0] for line in on_terminal] == ["[1/3] k0 ok 1.0 s",
                                                             "[2/3] k1 ok 1.0 s",
                                                             "[3/3] k2 ok 1.0 s"]
