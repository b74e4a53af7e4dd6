"""crosscheck.reports.rows: comparison rows stored once per check (gzip CSV slices, a side
table of tolerances and reasons, an index), read back bit-exact; several engines in one
directory; ids safe for any name; the `python -m crosscheck.reports.rows` printer."""
import gzip
import io
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from pandas.testing import assert_frame_equal

from crosscheck.compare import Tolerance, compare
from crosscheck.reports import rows
from crosscheck.reports.rows import RowsError, check_id, check_name, read_rows, slice_path, \
    write_rows

REPO = Path(__file__).resolve().parent.parent
# floats that a lossy writer would change: extremes, signed zero, repr-hard values
HARD_FLOATS = [0.0, -0.0, 5e-324, -2.2250738585072014e-308, 1.7976931348623157e308,
               0.1, 1 / 3, 2 / 3 * 1e-17, 123456789.12345679, -1e-300, float("inf"),
               float("-inf"), float("nan"), 9007199254740993.0, 1.0000000000000002]


def _rows(engine, seed=0, n_states=4, reasons=("round-off", "cond(M) = 6.1e+02, n = 4")):
    """A table like an engine's: compare() rows over models, quantities and states, with
    per-row tolerances, plus random-bit floats and hard text."""
    rng = np.random.default_rng(seed)
    out = []
    for model in ("crane_rigid", "crane (URDF)", "arm/ψ₃ 角"):
        for quantity in ("M", "h", "frame jacobian", "Phi, 2"):
            for s in range(n_states):
                x = rng.normal(size=3) * 10.0 ** rng.integers(-12, 12)
                y = x + rng.normal(size=3) * 1e-15
                tol = Tolerance(float(rng.choice([1e-14, 1e-12, np.inf])),
                                float(10.0 ** -rng.integers(10, 13)),
                                str(rng.choice(reasons)) + f" ({quantity})")
                out.append(compare(engine, model, quantity, f"state {s}", x, y, tol,
                                   labels=["z1", "NA", "0"]))
    df = pd.DataFrame(out).assign(section=["terms" if i % 3 else "runs" for i in range(len(out))])
    bits = rng.integers(0, 2 ** 63, size=len(df), dtype=np.int64).view(np.float64)
    bits[~np.isfinite(bits)] = 1.5
    df["gpme_value"] = bits
    df.loc[df.index[:len(HARD_FLOATS)], "engine_value"] = HARD_FLOATS
    return df


def _as_read(df):
    """What read_rows gives for ``df``: normalised, grouped by check (in order of each
    check's first row), rows of a check in their order."""
    df = rows.normalise(df)
    groups = [g for _, g in df.groupby(list(rows.KEYS), sort=False, dropna=False)]
    return pd.concat(groups).reset_index(drop=True)


def _same(a, b):
    assert_frame_equal(a, b, check_exact=True, check_dtype=True)
    for c in a.columns:             # bit for bit: -0.0 vs 0.0, NaN payloads aside
        if a[c].dtype == float:
            x, y = a[c].to_numpy(), b[c].to_numpy()
            assert np.array_equal(np.signbit(x), np.signbit(y)), c
            assert np.array_equal(x, y, equal_nan=True), c


def test_round_trip_is_bit_exact_with_the_columns_in_order(tmp_path):
    df = _rows("pinocchio")
    written = write_rows(df, tmp_path, "pinocchio")
    back = read_rows(tmp_path, "pinocchio")
    assert list(back.columns) == list(df.columns)
    _same(back, _as_read(df))
    n_checks = df.groupby(["section", "model", "quantity"]).ngroups
    slices = sorted((tmp_path / "checks" / "pinocchio").glob("*.csv.gz"))
    assert len(slices) == n_checks and set(slices) <= set(written)
    assert (tmp_path / rows.TOLERANCES_FILE) in written


def test_columns_csv_lists_the_columns_the_files_have(tmp_path):
    """issue 28: checks/<engine>/columns.csv says which columns each slice file has (in its
    order, tol_id included) and which come from tolerances.csv.gz; an older columns.csv
    (the wide table's columns and kinds only) is still read."""
    df = _rows("mujoco")
    write_rows(df, tmp_path, "mujoco")
    schema = pd.read_csv(tmp_path / "checks" / "mujoco" / rows.COLUMNS_FILE)
    assert list(schema.columns) == ["column", "kind", "stored_in"]
    in_slice = list(schema.loc[schema["stored_in"] == "slice", "column"])
    for path in (tmp_path / "checks" / "mujoco").glob("*.csv.gz"):
        assert list(pd.read_csv(path, nrows=0).columns) == in_slice, path
    in_tolerances = set(schema.loc[schema["stored_in"] == rows.TOLERANCES_FILE, "column"])
    assert in_tolerances == {"tol_abs", "tol_rel", "reason"}
    assert in_tolerances < set(pd.read_csv(tmp_path / rows.TOLERANCES_FILE).columns)
    # the layout written before stored_in: the wide table's columns and kinds
    old = schema[schema["column"] != "tol_id"][["column", "kind"]]
    old.to_csv(tmp_path / "checks" / "mujoco" / rows.COLUMNS_FILE, index=False)
    _same(read_rows(tmp_path, "mujoco"), _as_read(df))


def test_text_columns_come_back_as_the_strings_written(tmp_path):
    df = _rows("mujoco")
    odd = ["NA", "nan", "0", "1e5", "a,b", 'say "hi"', "two\nlines", "ψ₃ 角", " x ", "True"]
    df["entry"] = [odd[i % len(odd)] for i in range(len(df))]
    df["coordinate"] = [None if i % 4 == 0 else odd[i % len(odd)] for i in range(len(df))]
    df["count"] = np.arange(len(df), dtype=np.int64) - 3
    write_rows(df, tmp_path, "mujoco")
    back = read_rows(tmp_path, "mujoco")
    expected = _as_read(df)
    assert back["entry"].tolist() == expected["entry"].tolist()
    assert back["coordinate"].isna().tolist() == expected["coordinate"].isna().tolist()
    assert back["count"].dtype == np.int64 and back["passed"].dtype == bool
    _same(back, expected)


def test_each_reason_is_stored_once(tmp_path):
    df = _rows("pinocchio", n_states=30)
    write_rows(df, tmp_path, "pinocchio")
    table = pd.read_csv(tmp_path / rows.TOLERANCES_FILE)
    assert list(table.columns) == ["tol_id", "tol_abs", "tol_rel", "reason"]
    assert len(table) == len(df[["tol_abs", "tol_rel", "reason"]].drop_duplicates())
    assert table["tol_id"].is_unique
    for path in (tmp_path / "checks" / "pinocchio").glob("*.csv.gz"):
        text = gzip.decompress(path.read_bytes()).decode()
        assert "round-off" not in text and "tol_id" in text.splitlines()[0]


def test_slices_hold_exactly_their_check_and_the_index_lists_them(tmp_path):
    df = _rows("pinocchio")
    write_rows(df, tmp_path, "pinocchio")
    index = pd.read_csv(tmp_path / "checks" / "index.csv", keep_default_na=False)
    assert list(index.columns) == list(rows.INDEX_COLUMNS)
    read = _as_read(df)
    for r in index.itertuples():
        name = check_name(r.engine, r.section, r.model, r.quantity)
        assert r.check == name and r.file == slice_path(name).as_posix()
        piece = pd.read_csv(tmp_path / r.file, keep_default_na=False)
        mine = read[(read["section"] == r.section) & (read["model"] == r.model)
                    & (read["quantity"] == r.quantity)]
        assert len(piece) == r.n_rows == len(mine)
        assert r.status == ("fail" if (mine["status"] == "fail").any() else
                            "pass" if (mine["status"] == "pass").any() else "info")


def test_two_engines_merge_and_a_rewrite_replaces_only_its_own(tmp_path):
    gpme, pin = _rows("gpme", seed=1), _rows("pinocchio", seed=2)
    write_rows(gpme, tmp_path, "gpme")
    write_rows(pin, tmp_path, "pinocchio")
    _same(read_rows(tmp_path, "gpme"), _as_read(gpme))
    _same(read_rows(tmp_path, "pinocchio"), _as_read(pin))
    both = read_rows(tmp_path)
    assert list(dict.fromkeys(both["engine"])) == ["gpme", "pinocchio"]
    table = pd.read_csv(tmp_path / rows.TOLERANCES_FILE)
    assert table["tol_id"].is_unique
    assert {t.rsplit("-", 1)[0] for t in table["tol_id"]} == {"gpme", "pinocchio"}
    # gpme again, with fewer checks: its stale slices and tolerances go, pinocchio's stay
    fewer = gpme[gpme["model"] == "crane_rigid"]
    write_rows(fewer, tmp_path, "gpme")
    _same(read_rows(tmp_path, "gpme"), _as_read(fewer))
    _same(read_rows(tmp_path, "pinocchio"), _as_read(pin))
    index = pd.read_csv(tmp_path / "checks" / "index.csv")
    assert index["check"].is_unique
    assert len(list((tmp_path / "checks" / "gpme").glob("*.csv.gz"))) == \
        (index["engine"] == "gpme").sum()
    # an engine that writes nothing leaves no rows behind
    write_rows(pd.DataFrame(), tmp_path, "gpme")
    assert not (tmp_path / "checks" / "gpme").exists()
    with pytest.raises(RowsError, match=r"no rows of engine 'gpme'.*\['pinocchio'\]"):
        read_rows(tmp_path, "gpme")


ODD = {"slash": "a/b", "space": "x y", "unicode": "ψ₃ 角 ü", "long": "q" * 500,
       "dots": "..", "dot": ".", "empty": "", "hidden": ".hidden", "dash": "-rf",
       "markup": "<b>&amp;</b>", "percent": "50%25", "newline": "a\nb"}


@pytest.mark.parametrize("name", ODD.values(), ids=ODD.keys())
def test_ids_are_safe_short_and_unique_for_odd_names(name):
    full = check_name("pinocchio", "terms", name, "M")
    ident = check_id(full)
    assert re.fullmatch(r"[A-Za-z0-9_][A-Za-z0-9._-]*", ident) and len(ident) <= 69
    path = slice_path(check_name(name, "terms", "m", "q"))
    assert ".." not in path.parts and path.parts[0] == "checks" and len(path.parts) == 3
    assert re.fullmatch(r"[A-Za-z0-9_][A-Za-z0-9._-]*", path.parts[1])
    others = [check_id(check_name("pinocchio", "terms", o, "M")) for o in ODD.values()
              if o != name]
    assert ident not in others


def test_names_differing_only_in_unsafe_characters_get_different_ids():
    names = ["a/b", "a b", "a-b", "a_b", "a\tb", "a--b", "q" * 80 + "1", "q" * 80 + "2"]
    assert len({check_id(n) for n in names}) == len(names)


def test_odd_engine_and_model_names_round_trip(tmp_path):
    frames = {engine: _rows(engine, seed=k).assign(model=lambda d, e=engine: d["model"] + e)
              for k, engine in enumerate(["a b", "..", "ψ", "-x", "engine", "index.csv"])}
    for engine, df in frames.items():
        write_rows(df, tmp_path, engine)
    for engine, df in frames.items():
        _same(read_rows(tmp_path, engine), _as_read(df))
    assert all(p.resolve().is_relative_to(tmp_path.resolve())
               for p in tmp_path.rglob("*"))
    assert len(list((tmp_path / "checks").iterdir())) == len(frames) + 1   # + index.csv


@pytest.mark.parametrize("change, message", [
    (lambda df: df.drop(columns=["reason"]), r"lack the columns \['reason'\]"),
    (lambda df: df.assign(engine=["gpme"] + ["pinocchio"] * (len(df) - 1)),
     r"rows of other engines \['gpme'\]"),
], ids=["no reason column", "another engine's row"])
def test_rows_that_do_not_belong_are_a_harness_bug(tmp_path, change, message):
    with pytest.raises(ValueError, match=message):
        write_rows(change(_rows("pinocchio")), tmp_path, "pinocchio")
    assert not (tmp_path / "checks").exists()


@pytest.mark.parametrize("engine", ["a/b", ""], ids=["slash", "empty"])
def test_an_engine_name_that_cannot_start_a_check_name_is_refused(tmp_path, engine):
    with pytest.raises(ValueError, match=f"engine name {engine!r} must be non-empty and "
                                         "without '/'"):
        write_rows(_rows(engine), tmp_path, engine)
    assert not (tmp_path / "checks").exists()


def test_a_missing_or_broken_slice_is_named(tmp_path):
    write_rows(_rows("pinocchio"), tmp_path, "pinocchio")
    slices = sorted((tmp_path / "checks" / "pinocchio").glob("*.csv.gz"))
    slices[0].unlink()
    slices[1].write_bytes(slices[1].read_bytes()[:30])
    with pytest.raises(RowsError, match="2 row files") as err:
        read_rows(tmp_path)
    assert slices[0].name in str(err.value) and slices[1].name in str(err.value)


def test_a_report_from_before_the_checks_layout_is_read(tmp_path):
    df = _rows("pinocchio")
    df.to_csv(tmp_path / "pinocchio.csv", index=False)
    pd.DataFrame({"check": ["x"]}).to_csv(tmp_path / "summary.csv", index=False)
    back = read_rows(tmp_path)
    assert len(back) == len(df) and list(back.columns) == list(df.columns)


def _module(*args):
    return subprocess.run([sys.executable, "-m", "crosscheck.reports.rows", *map(str, args)],
                          capture_output=True, text=True, cwd=REPO, timeout=120)


def test_the_module_prints_the_wide_table(tmp_path):
    gpme, pin = _rows("gpme", seed=1), _rows("pinocchio", seed=2)
    write_rows(gpme, tmp_path, "gpme")
    write_rows(pin, tmp_path, "pinocchio")
    done = _module(tmp_path, "pinocchio")
    assert done.returncode == 0, done.stderr
    printed = pd.read_csv(io.StringIO(done.stdout))
    assert list(printed.columns) == list(pin.columns) and len(printed) == len(pin)
    assert np.array_equal(printed["gpme_value"], _as_read(pin)["gpme_value"])
    out = io.StringIO()
    sys.stdout, saved = out, sys.stdout
    try:
        assert rows.main([str(tmp_path)]) == 0
    finally:
        sys.stdout = saved
    assert len(pd.read_csv(io.StringIO(out.getvalue()))) == len(gpme) + len(pin)


@pytest.mark.parametrize("setup, args, words", [
    (lambda d: None, [], ["holds no comparison rows", "checks/index.csv is missing",
                          "gpme verify"]),
    (lambda d: None, ["nowhere"], ["is not a directory", "report directory"]),
    (lambda d: write_rows(_rows("gpme"), d, "gpme"), [".", "pinochio"],
     ["no rows of engine 'pinochio'", "['gpme']"]),
    (lambda d: write_rows(pd.DataFrame(), d, "gpme"), [], ["holds no comparison rows"]),
], ids=["empty directory", "missing directory", "unknown engine", "engines wrote none"])
def test_the_module_says_why_there_is_nothing_to_print(tmp_path, setup, args, words):
    setup(tmp_path)
    target = tmp_path / args[0] if args else tmp_path
    done = _module(target, *args[1:])
    assert done.returncode == 2 and done.stdout == ""
    assert done.stderr.startswith("error: ") and "Traceback" not in done.stderr
    for word in words:
        assert word in done.stderr, (word, done.stderr)


# ---- run histories: plain CSV for `gpme simulate`, gzip CSV with HISTORY_DIGITS for verify

def _rounded(df, digits):
    """``df`` as read back from a CSV written with ``digits`` significant digits."""
    return df.apply(lambda c: c.map(lambda v: float(f"%.{digits}g" % v))
                    if c.dtype == float else c)


def _tiny_figure(*args, **kwargs):
    import matplotlib.figure
    fig = matplotlib.figure.Figure(figsize=(1, 1))
    fig.add_subplot().plot([0, 1], [1, 0])
    return fig


@pytest.mark.parametrize("compressed", [False, True], ids=["simulate-plain", "verify-gzip"])
def test_a_model_run_history_reads_back(tmp_path, monkeypatch, compressed):
    from gpme_io import figures
    from gpme_io.runs import simulate_scenario, write_run_outputs
    from gpme_io.atomic import HISTORY_DIGITS
    from gpme_io.modelfile import load_model_file
    monkeypatch.setattr(figures, "FIGURES", {"coordinates.png": _tiny_figure})
    scenario = load_model_file(REPO / "tests" / "data" / "runs" / "point_pendulum.toml")
    df = simulate_scenario(scenario, quick=True)
    paths = write_run_outputs(scenario, df, tmp_path, compressed=compressed)
    name = "point_pendulum.csv.gz" if compressed else "point_pendulum.csv"
    assert set(paths) == {name, "point_pendulum_coordinates.png", "point_pendulum_motion.html"}
    back = pd.read_csv(paths[name])
    _same(back, _rounded(df, HISTORY_DIGITS) if compressed else df)
    if compressed:
        first = paths[name].read_bytes()
        assert first[:2] == b"\x1f\x8b"
        write_run_outputs(scenario, df, tmp_path, compressed=True)
        assert paths[name].read_bytes() == first      # no time stamp: same rows, same bytes


def test_the_paper_figures_are_added_for_the_crane_runs_only(tmp_path, monkeypatch):
    """The paper's crane runs like any model (histories by write_run_outputs, above); the
    hook adds the paper's three figures when, and only when, a run is the crane's, with the
    runs named as the paper names them."""
    from gpme_io import paper_figures
    from gpme_io.example_outputs import PAPER_FIGURES, write_example_outputs
    from gpme_io.modelfile import load_model_file
    from gpme_io.runs import simulate_scenario
    from gpme_io.scenario import crane_scenario
    drawn = []

    def record(runs, *args):
        drawn.append(list(runs))
        return _tiny_figure()
    for name in ("joint_coordinates", "end_effector", "constraint_violation"):
        monkeypatch.setattr(paper_figures, name, record)
    crane = [(s, simulate_scenario(s, t_end=0.01)) for s in (crane_scenario(3),
                                                             crane_scenario(0))]
    other = load_model_file(REPO / "tests" / "data" / "runs" / "point_pendulum.toml")
    assert write_example_outputs([(other, None)], tmp_path / "none") == {}
    assert not (tmp_path / "none").exists() and not drawn
    paths = write_example_outputs(crane + [(other, None)], tmp_path)
    assert sorted(paths) == sorted(name for name, _, _ in PAPER_FIGURES)
    assert all(p.is_file() for p in paths.values())
    assert drawn == [["rigid", "flexible"]] * len(PAPER_FIGURES)


# ---- figures: a palette where it changes nothing visible, lossless elsewhere

def _pixels(data):
    from PIL import Image
    with Image.open(io.BytesIO(data)) as image:
        return image.mode, np.asarray(image.convert("RGBA")).astype(int)


def test_a_line_plot_is_stored_with_a_palette_and_looks_the_same():
    import matplotlib.figure

    from gpme_io.png import PNG_COLOURS, PNG_MAX_ERROR, figure_png
    fig = matplotlib.figure.Figure(figsize=(6, 3))
    ax = fig.add_subplot()
    t = np.linspace(0, 2, 500)
    for k in range(8):
        ax.plot(t, np.sin(3 * t + k) * np.exp(-k * t / 4), label=f"q{k}")
    ax.legend(ncols=4)
    ax.grid(alpha=0.3)
    plain = io.BytesIO()
    fig.savefig(plain, format="png", dpi=120, bbox_inches="tight")
    compact = figure_png(fig, dpi=120)
    mode, after = _pixels(compact)
    _, before = _pixels(plain.getvalue())
    assert mode == "P" and len(np.unique(after.reshape(-1, 4), axis=0)) <= PNG_COLOURS
    assert len(compact) < len(plain.getvalue()) / 2
    assert np.abs(after - before).max() <= PNG_MAX_ERROR


@pytest.mark.parametrize("mode", ["RGB", "RGBA"], ids=["many-colours", "transparent"])
def test_an_image_a_palette_cannot_hold_is_kept_exactly(mode):
    from PIL import Image

    from gpme_io.png import compact_png
    rng = np.random.default_rng(3)
    noise = rng.integers(0, 256, size=(40, 50, len(mode)), dtype=np.uint8)
    buf = io.BytesIO()
    Image.fromarray(noise, mode).save(buf, format="PNG")
    out_mode, after = _pixels(compact_png(buf.getvalue()))
    assert out_mode == mode
    assert np.array_equal(after[..., :len(mode)], noise.astype(int))
