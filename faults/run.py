"""Plant each fault of faults.catalogue in a copy of the sources and run `gpme verify --quick`.

    python -m faults.run [--only ID ...] [--out DIR] [--work DIR] [--exclude [STEP:]GLOB ...]
                         [--resume] [--list] [--timeout S] [--keep-work]

1. **Snapshot.**  The repository's Python packages (gpme, gpme_core, gpme_io, gpme_examples,
   gpme_study, crosscheck, faults) and its model files (models/ without models/zoo, the test
   set kept out of tuning; examples/) are copied once to WORK/snapshot, numba's disk cache
   in gpme_core/__pycache__ included (valid for every file left unpatched: its stamp is
   the file's contents, gpme_core.jit_cache).  Everything below runs on copies of it, so
   edits made meanwhile in the work tree do not mix into the run.  Every anchor of the
   catalogue is checked in it first (exactly once, else refused).
2. **Which copy is imported.**  Each command runs with the copy as its working directory
   and PYTHONPATH: ``python -m`` puts the working directory first on sys.path and
   PYTHONPATH comes before site-packages, whose editable-install finder (a meta-path
   hook appended after the path finder) is consulted only for what the path does not
   hold.  The probe (faults.probe) records the files gpme_core, gpme, gpme_io and
   crosscheck were imported from; a file outside the copy stops the run.
3. **Baseline.**  The unpatched snapshot is probed twice (the runs must repeat bit for
   bit: any change a fault makes is then its own) and put through every verify
   invocation below.  If any invocation fails on the clean code, the failing checks are
   printed and nothing is scored (a false failure would count as a catch).  ``--exclude
   GLOB`` leaves a model file out of every step, ``--exclude STEP:GLOB`` out of one verify
   step only (the baseline is then run without it too); the results list what was left
   out.
4. **Each fault.**  Copy the snapshot, plant the fault (faults.catalogue.apply), run the
   probe: the crane's compiled runs first, the model files' too when the crane's did not
   change.  A fault is *reached* when a compiled run's integrated state changed.  Then
   the verify invocations, cheapest first, until one exits 1 with a failed check:

       crane --only pinocchio, models --only pinocchio, crane --only gpme,
       crane --only mujoco, models --only gpme, models --only mujoco,
       crane --only drake, crane --only exudyn, models --only drake, models --only exudyn

   ("crane": no --model, the paper's crane cases; "models": every models/*.toml and
   examples/**/*.toml of the snapshot in one invocation).  Exit status 2 (bad input), a
   crashed step (verify's "step crashed" row) or a killed process is not a catch: it is
   recorded and the next invocation runs.

Results (WORK holds the copies and reports, removed per fault unless --keep-work):
OUT/results.json (baseline, and per fault: outcome, the catching invocation, its failed
checks with error/tolerance, the probe's changes, wall times) and OUT/results.md (the
tables of docs/mutation.md).  ``--resume`` keeps the faults already in OUT/results.json
and the snapshot under WORK, and reuses its baseline (give the same --work).
``--controls`` also runs faults.catalogue.CONTROLS (correct models 1e-3 away; every
invocation, not only to the first failure): a check failing there fails on a correct
model, and results.md marks the faults caught by such checks only.
"""
import argparse
import fnmatch
import hashlib
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Optional, Sequence

import numpy as np

from .catalogue import BY_ID, CATALOGUE, CONTROLS, AnchorError, apply, check_anchors

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("gpme", "gpme_core", "gpme_io", "gpme_examples", "gpme_study", "crosscheck",
            "faults")
DATA_DIRS = ("models", "examples")
EXCLUDED_DATA = ("models/zoo",)         # the test set: kept out of tuning
STEPS_CHEAP_FIRST = (("crane", "pinocchio"), ("models", "pinocchio"), ("crane", "gpme"),
                     ("crane", "mujoco"), ("models", "gpme"), ("models", "mujoco"),
                     ("crane", "drake"), ("crane", "exudyn"), ("models", "drake"),
                     ("models", "exudyn"))
VERIFY_TIMEOUT_S = 3600.0
PROBE_TIMEOUT_S = 1800.0
CRASH_QUANTITY = "step crashed"         # crosscheck.compare.CRASH_QUANTITY
# outcomes
CAUGHT, MISSED, NOT_CAUGHT_CRASH = "caught", "missed", "crash only"
# an invocation's result
PASS, FAIL, CRASH, BAD_INPUT, TIMEOUT = "pass", "fail", "crash", "bad input", "timeout"


def _say(msg):
    print(msg, flush=True)


@dataclass(frozen=True)
class Invocation:
    """One `gpme verify --quick` command: on the crane (models empty) or on model files."""

    group: str                  # "crane" or "models"
    step: str                   # verify's --only
    models: tuple               # model files relative to the copy's root

    @property
    def name(self):
        return f"{self.group} --only {self.step}"

    @property
    def slug(self):
        return f"{self.group}-{self.step}"

    def command(self, python, out_dir):
        cmd = [str(python), "-m", "gpme.cli", "verify", "--quick", "--no-progress",
               "--only", self.step]
        for m in self.models:
            cmd += ["--model", m]
        return cmd + ["--out", str(out_dir)]


# ---------------------------------------------------------------- the copy
def _ignore(directory, names):
    skip = {n for n in names if n.endswith((".pyc", ".pyo"))}
    rel = Path(directory).resolve()
    for n in names:
        if any(rel / n == (ROOT / e).resolve() for e in EXCLUDED_DATA):
            skip.add(n)
    if rel == (ROOT / "faults").resolve():
        skip.add("out")
    return skip


def make_snapshot(dest: Path) -> Path:
    """Copy the packages and model files of the work tree to ``dest`` (file times kept:
    numba's own cache stamp includes them)."""
    dest.mkdir(parents=True)
    for name in PACKAGES + DATA_DIRS:
        shutil.copytree(ROOT / name, dest / name, ignore=_ignore, symlinks=True)
    return dest


def copy_tree(snapshot: Path, dest: Path) -> Path:
    """A copy of the snapshot to plant a fault in."""
    shutil.copytree(snapshot, dest, symlinks=True)
    return dest


def source_hash(root: Path) -> str:
    """SHA-256 over the snapshot's sources and model files (not caches)."""
    digest = hashlib.sha256()
    for path in sorted(p for p in root.rglob("*")
                       if p.is_file() and "__pycache__" not in p.parts):
        digest.update(path.relative_to(root).as_posix().encode() + b"\0" + path.read_bytes())
    return digest.hexdigest()


def model_files(root: Path) -> tuple:
    """models/*.toml and examples/**/*.toml under ``root`` (relative paths, sorted)."""
    found = sorted(p.relative_to(root).as_posix() for p in (root / "models").glob("*.toml"))
    found += sorted(p.relative_to(root).as_posix() for p in (root / "examples").glob("**/*.toml"))
    return tuple(found)


def excluded(step: str, model: str, exclude: Sequence[str]) -> bool:
    """Whether ``model`` is left out of ``step``'s invocation: an entry of ``exclude`` is
    GLOB (every step) or STEP:GLOB (that verify step only)."""
    for entry in exclude:
        only, sep, pattern = entry.partition(":")
        if not sep:
            only, pattern = None, entry
        if (only is None or only == step) and fnmatch.fnmatch(model, pattern):
            return True
    return False


def invocations(models: Sequence[str], exclude: Sequence[str] = ()) -> tuple:
    """The verify invocations, cheapest first (STEPS_CHEAP_FIRST); a "models" invocation
    takes every model file not excluded from its step, and is dropped when none is left."""
    out = []
    for group, step in STEPS_CHEAP_FIRST:
        chosen = tuple(m for m in models if not excluded(step, m, exclude))
        if group == "models" and not chosen:
            continue
        out.append(Invocation(group, step, chosen if group == "models" else ()))
    return tuple(out)


def environment(copy: Path, kernel_cache: Path) -> dict:
    """The environment of every command run on ``copy``: the copy first on the path,
    numba on, generated kernels in the run's own cache directory."""
    env = dict(os.environ)
    env["PYTHONPATH"] = str(copy)
    env["GPME_KERNEL_CACHE"] = str(kernel_cache)
    env["MPLBACKEND"] = "Agg"
    for var in ("GPME_NO_JIT", "NUMBA_DISABLE_JIT"):
        env.pop(var, None)
    return env


# ---------------------------------------------------------------- probe
def run_probe(python, copy, env, out, crane, models, log):
    """(arrays {scenario: (rows, columns)}, record) of faults.probe run in ``copy``;
    RuntimeError when it fails or imported anything from outside the copy."""
    cmd = [str(python), "-m", "faults.probe", str(out)]
    cmd += ["--crane"] if crane else []
    for m in models:
        cmd += ["--model", m]
    with open(log, "a", encoding="utf-8") as fh:
        fh.write("$ " + " ".join(cmd) + "\n")
        fh.flush()
        proc = subprocess.run(cmd, cwd=copy, env=env, stdout=fh, stderr=subprocess.STDOUT,
                              timeout=PROBE_TIMEOUT_S)
    if proc.returncode != 0:
        raise RuntimeError(f"the probe failed (exit status {proc.returncode}); see {log}")
    record = json.loads(Path(out).with_suffix(".json").read_text(encoding="utf-8"))
    outside = {k: v for k, v in record["imported"].items()
               if not Path(v).resolve().is_relative_to(Path(copy).resolve())}
    if outside:
        raise RuntimeError(f"the probe imported {outside} from outside the copy {copy}: "
                           "the patched sources are not what runs")
    with np.load(out) as data:
        arrays = {k: data[k] for k in data.files}
    not_compiled = {k: r["compiled_reason"] for k, r in record["runs"].items()
                    if not r["compiled"]}
    if not_compiled:
        raise RuntimeError(f"runs not compiled: {not_compiled}")
    return arrays, record


def probe_changes(base, base_record, arrays):
    """{scenario: {"max_rel": float, "column": str}}: the largest change of an integrated
    column relative to its largest baseline value (1 for a column that is zero)."""
    out = {}
    for key, a in arrays.items():
        b = base[key]
        if a.shape != b.shape:
            out[key] = {"max_rel": float("inf"), "column": f"shape {a.shape} != {b.shape}"}
            continue
        scale = np.abs(b).max(axis=0)
        scale[scale == 0.0] = 1.0
        with np.errstate(invalid="ignore"):
            rel = np.nan_to_num(np.abs(a - b) / scale, nan=np.inf).max(axis=0)
        j = int(np.argmax(rel))
        out[key] = {"max_rel": float(rel[j]),
                    "column": base_record["runs"][key]["columns"][j]}
    return out


# ---------------------------------------------------------------- verify
def run_invocation(python, copy, env, inv, out_dir, log, timeout):
    """Result dict of one verify invocation: status (PASS, FAIL, CRASH, BAD_INPUT, TIMEOUT),
    exit code, wall time, failed checks (name, error/tolerance) and crashed steps."""
    start = time.perf_counter()
    cmd = inv.command(python, out_dir)
    with open(log, "a", encoding="utf-8") as fh:
        fh.write("$ " + " ".join(cmd) + "\n")
        fh.flush()
        try:
            proc = subprocess.run(cmd, cwd=copy, env=env, stdout=fh, stderr=subprocess.STDOUT,
                                  timeout=timeout)
            code = proc.returncode
        except subprocess.TimeoutExpired:
            code = None
    result = {"invocation": inv.name, "exit": code,
              "wall_s": round(time.perf_counter() - start, 1), "failed": [], "crashed": []}
    if code is None:
        result["status"] = TIMEOUT
        return result
    summary = Path(out_dir) / "latest" / "summary.csv"
    if code == 2:
        result["status"] = BAD_INPUT
    elif code in (0, 1) and summary.is_file():
        import pandas as pd
        df = pd.read_csv(summary)
        failed = df[df["status"] == "fail"]
        crashed = failed[(failed["quantity"] == CRASH_QUANTITY) & (failed["model"] == "-")]
        checks = failed.drop(crashed.index)
        result["failed"] = [{"check": r.check,
                             "error_over_tolerance": _num(r.error_over_tolerance),
                             "worst_case": _text(r.worst_case)}
                            for r in checks.sort_values("error_over_tolerance",
                                                        ascending=False).itertuples()]
        result["crashed"] = [f"{r.engine}: {_text(r.reason)}" for r in crashed.itertuples()]
        result["n_checks"] = len(df)
        if code == 0:
            result["status"] = PASS
        else:
            result["status"] = FAIL if len(checks) else CRASH
    else:
        result["status"] = CRASH       # killed, a traceback out of the CLI, no report
    return result


def _num(v):
    v = float(v)
    return None if v != v else v


def _text(v):
    return None if v is None or (isinstance(v, float) and v != v) else str(v)


# ---------------------------------------------------------------- one fault, baseline
def score_fault(fault, snapshot, work, python, invs, base, base_record, noise, timeout,
                keep, control=False):
    """The record of one fault (see the module docstring); a control runs every invocation
    (its failures are the checks that fail on a correct model)."""
    start = time.perf_counter()
    fdir = work / fault.id
    if fdir.exists():
        shutil.rmtree(fdir)
    fdir.mkdir(parents=True)
    copy = copy_tree(snapshot, fdir / "src")
    apply(fault, copy)
    env = environment(copy, work / "kernel_cache")
    log = fdir / "log.txt"
    record = {"id": fault.id, "term": fault.term, "file": fault.file, "size": fault.size,
              "anchor": fault.anchor, "replacement": fault.replacement, "what": fault.what}
    # probe: the crane's runs first; the model files' when the crane did not change
    t0 = time.perf_counter()
    changes = {}
    for crane, models in ((True, ()), (False, invs_models(invs))):
        if not crane and not models:
            continue
        npz = fdir / f"probe-{'crane' if crane else 'models'}.npz"
        arrays, _ = run_probe(python, copy, env, npz, crane, models, log)
        changes.update(probe_changes(base, base_record, arrays))
        if any(c["max_rel"] > noise for c in changes.values()):
            break
    record["probe"] = changes
    record["probe_wall_s"] = round(time.perf_counter() - t0, 1)
    record["reached"] = any(c["max_rel"] > noise for c in changes.values())
    results = []
    for inv in invs:
        res = run_invocation(python, copy, env, inv, fdir / "reports" / inv.slug, log,
                             timeout)
        results.append(res)
        _say(f"    {inv.name}: {res['status']} ({res['wall_s']:.0f} s"
             + (f", {len(res['failed'])} failed checks" if res["failed"] else "")
             + (f", crashed: {res['crashed']}" if res["crashed"] else "") + ")")
        if res["status"] == FAIL and not control:
            break
    record["invocations"] = results
    record["control"] = control
    caught = [r for r in results if r["status"] == FAIL]
    if control:
        record["outcome"] = "fails verify" if caught else (
            "passes" if all(r["status"] == PASS for r in results) else NOT_CAUGHT_CRASH)
        record["failed_checks"] = [c for r in caught for c in r["failed"]]
    elif caught:
        record["outcome"] = CAUGHT
        record["caught_by"] = caught[0]["invocation"]
        record["failed_checks"] = caught[0]["failed"]
    elif any(r["status"] != PASS for r in results):
        record["outcome"] = NOT_CAUGHT_CRASH
    else:
        record["outcome"] = MISSED
    record["wall_s"] = round(time.perf_counter() - start, 1)
    for res in results:                 # the failed checks are kept once, in failed_checks
        res["n_failed"] = len(res.pop("failed"))
    if not keep:
        shutil.rmtree(fdir / "src", ignore_errors=True)
        shutil.rmtree(fdir / "reports", ignore_errors=True)
    return record


def invs_models(invs):
    """Every model file some invocation runs (the probe's), in order."""
    out = []
    for inv in invs:
        out += [m for m in inv.models if m not in out]
    return tuple(out)


def baseline(snapshot, work, python, invs, timeout):
    """(record, probe arrays, probe record, noise) of the clean snapshot."""
    start = time.perf_counter()
    bdir = work / "baseline"
    if bdir.exists():
        shutil.rmtree(bdir)
    bdir.mkdir(parents=True)
    copy = copy_tree(snapshot, bdir / "src")
    env = environment(copy, work / "kernel_cache")
    log = bdir / "log.txt"
    models = invs_models(invs)
    arrays, record = run_probe(python, copy, env, bdir / "probe.npz", True, models, log)
    again, _ = run_probe(python, copy, env, bdir / "probe-again.npz", True, models, log)
    repeat = probe_changes(arrays, record, again)
    noise = max((c["max_rel"] for c in repeat.values()), default=0.0)
    _say(f"  probe: {len(arrays)} compiled runs, imported from {record['imported']}; "
         f"repeat differs by {noise:.3g} (relative)")
    results = []
    for inv in invs:
        res = run_invocation(python, copy, env, inv, bdir / "reports" / inv.slug, log,
                             timeout)
        _say(f"    {inv.name}: {res['status']} ({res['wall_s']:.0f} s, "
             f"{res.get('n_checks', '?')} checks)")
        results.append(res)
    out = {"clean": all(r["status"] == PASS for r in results), "invocations": results,
           "probe": {k: {kk: vv for kk, vv in v.items() if kk != "columns"}
                     for k, v in record["runs"].items()},
           "imported": record["imported"], "probe_noise": noise,
           "wall_s": round(time.perf_counter() - start, 1)}
    shutil.rmtree(bdir / "reports", ignore_errors=True)
    shutil.rmtree(bdir / "src", ignore_errors=True)
    return out, arrays, record, noise


# ---------------------------------------------------------------- tables
def markdown(results) -> str:
    """The tables of docs/mutation.md from a results document."""
    faults = results["faults"]
    done = [faults[f.id] for f in CATALOGUE if f.id in faults]
    controls = [faults[f.id] for f in CONTROLS if f.id in faults]
    fragile = {c["check"] for r in controls for c in r.get("failed_checks", [])}
    caught = [r for r in done if r["outcome"] == CAUGHT]
    lines = [f"Score: **{len(caught)} of {len(done)} faults caught** "
             f"({100.0 * len(caught) / max(len(done), 1):.0f} %).", "",
             "| # | fault | term | file | size | reached: largest change of a compiled run "
             "(run: column) | outcome | caught by | checks that failed (error / tolerance) "
             "| caught down to ~ | wall |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for k, r in enumerate(done, 1):
        top = max(r["probe"].items(), key=lambda kv: kv[1]["max_rel"], default=None)
        reach = (f"{top[1]['max_rel']:.1e} ({top[0]}: {top[1]['column']})"
                 if top and r["reached"] else "no")
        checks = r.get("failed_checks", [])
        shown = ", ".join(f"`{c['check']}` ({_ratio(c['error_over_tolerance'])})"
                          + (" [fails under a control too]" if c["check"] in fragile else "")
                          for c in checks[:2])
        if len(checks) > 2:
            shown += f" and {len(checks) - 2} more"
        lines.append(f"| {k} | `{r['id']}` | {r['term']} | {Path(r['file']).name} | "
                     f"{r['size']:g} | {reach} | {r['outcome']} | "
                     f"{r.get('caught_by', '-')} | {shown or '-'} | {_down_to(r)} | "
                     f"{r['wall_s'] / 60:.1f} min |")
    doubtful = [r["id"] for r in caught
                if {c["check"] for c in r.get("failed_checks", [])} <= fragile]
    if doubtful:
        lines += ["", f"Caught only by checks that also fail under a control (a correct "
                      f"model): {', '.join(f'`{d}`' for d in doubtful)}."]
    if controls:
        lines += ["", "Controls (a correct model 1e-3 away; verify should pass):", "",
                  "| control | what | outcome | checks that failed (error / tolerance) | wall |",
                  "|---|---|---|---|---|"]
        for r in controls:
            shown = ", ".join(f"`{c['check']}` ({_ratio(c['error_over_tolerance'])})"
                              for c in r.get("failed_checks", [])) or "-"
            lines.append(f"| `{r['id']}` | {r['what']} | {r['outcome']} | {shown} | "
                         f"{r['wall_s'] / 60:.1f} min |")
    return "\n".join(lines) + "\n"


def _down_to(record) -> str:
    """The size at which the catching check would sit at its tolerance if the error grew
    linearly with the fault's size: size / (largest error / tolerance); '-' if not caught."""
    ratios = [c["error_over_tolerance"] for c in record.get("failed_checks", [])
              if c["error_over_tolerance"]]
    if not ratios:
        return "-"
    return f"{record['size'] / max(ratios):.0e}"


def _ratio(v):
    return "-" if v is None else f"{v:.3g}"


def _write(out, results):
    out.mkdir(parents=True, exist_ok=True)
    tmp = out / "results.json.tmp"
    tmp.write_text(json.dumps(results, indent=1), encoding="utf-8")
    os.replace(tmp, out / "results.json")
    (out / "results.md").write_text(markdown(results), encoding="utf-8")


# ---------------------------------------------------------------- command line
def main(argv: Optional[Sequence[str]] = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m faults.run", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--only", nargs="+", metavar="ID", help="these faults only")
    parser.add_argument("--out", type=Path, default=ROOT / "faults" / "out",
                        help="results.json and results.md (default faults/out)")
    parser.add_argument("--work", type=Path, default=None,
                        help="copies and reports (default: a new directory under /tmp)")
    parser.add_argument("--venv", type=Path, default=ROOT / ".venv",
                        help="the virtualenv whose python runs verify (default .venv)")
    parser.add_argument("--exclude", nargs="+", default=[], metavar="[STEP:]GLOB",
                        help="model files left out of every verify step, or of STEP only "
                             "(e.g. exudyn:examples/my_arm/*); recorded in the results")
    parser.add_argument("--timeout", type=float, default=VERIFY_TIMEOUT_S,
                        help="s, one verify invocation (a timeout is not a catch)")
    parser.add_argument("--resume", action="store_true",
                        help="keep the faults already in OUT/results.json")
    parser.add_argument("--keep-work", action="store_true",
                        help="keep every copy and report under WORK")
    parser.add_argument("--controls", action="store_true",
                        help="also run the controls (faults.catalogue.CONTROLS) after the "
                             "faults")
    parser.add_argument("--list", action="store_true", help="print the catalogue and stop")
    parser.add_argument("--table", action="store_true",
                        help="rewrite OUT/results.md from OUT/results.json and stop")
    args = parser.parse_args(argv)
    if args.table:
        results = json.loads((args.out / "results.json").read_text(encoding="utf-8"))
        (args.out / "results.md").write_text(markdown(results), encoding="utf-8")
        _say(str(args.out / "results.md"))
        return 0
    if args.list:
        for f in CATALOGUE + CONTROLS:
            _say(f"{f.id:28s} {f.file:22s} {f.size:<7g} {f.term}: {f.what}")
        return 0
    unknown = [i for i in args.only or () if i not in BY_ID]
    if unknown:
        print(f"error: unknown fault ids {unknown}; `python -m faults.run --list` lists them",
              file=sys.stderr)
        return 2
    python = args.venv / "bin" / "python"
    if not python.exists():
        print(f"error: no python at {python} (--venv)", file=sys.stderr)
        return 2
    chosen = [BY_ID[i] for i in args.only] if args.only else (
        list(CATALOGUE) + (list(CONTROLS) if args.controls else []))
    work = args.work or Path(tempfile.mkdtemp(prefix="gpme-faults-"))
    work.mkdir(parents=True, exist_ok=True)
    snapshot = work / "snapshot"
    if args.resume and snapshot.is_dir():
        _say(f"--resume: the sources of {snapshot} as they were")
    else:
        if snapshot.exists():
            shutil.rmtree(snapshot)
        make_snapshot(snapshot)
    try:
        check_anchors(chosen, snapshot)
    except AnchorError as exc:
        print(f"error: faults whose anchors do not match the sources:\n{exc}", file=sys.stderr)
        return 2
    digest = source_hash(snapshot)
    models = model_files(snapshot)
    invs = invocations(models, args.exclude)
    left_out = [f"{inv.step}: {m}" for inv in invocations(models) if inv.models
                for m in inv.models if excluded(inv.step, m, args.exclude)]
    _say(f"snapshot {snapshot} (sources {digest[:12]}); model files: {list(models)}"
         + (f"; left out: {left_out}" if left_out else ""))
    previous = {}
    if args.resume and (args.out / "results.json").is_file():
        previous = json.loads((args.out / "results.json").read_text(encoding="utf-8"))
    results = {"sources": digest, "models": list(models), "excluded": left_out,
               "exclude_args": list(args.exclude),
               "invocations": [i.name for i in invs], "work": str(work),
               "faults": {}}
    same = (previous.get("sources") == digest and previous.get("models") == list(models)
            and previous.get("exclude_args") == list(args.exclude))
    if same:
        results["faults"] = previous.get("faults", {})
    base_npz = work / "baseline" / "probe.npz"
    reuse = same and previous.get("baseline", {}).get("clean") and base_npz.is_file()
    if reuse:
        _say("baseline: reused from the previous run (same sources)")
        results["baseline"] = previous["baseline"]
        base_record = json.loads(base_npz.with_suffix(".json").read_text(encoding="utf-8"))
        with np.load(base_npz) as data:
            base = {k: data[k] for k in data.files}
        noise = results["baseline"]["probe_noise"]
    else:
        _say("baseline (no fault):")
        results["baseline"], base, base_record, noise = baseline(snapshot, work, python, invs,
                                                                 args.timeout)
        _write(args.out, results)
    if not results["baseline"]["clean"]:
        print("error: the clean code fails verify, so a failure under a fault would not be "
              "the fault's; not scoring.  Failing on the baseline:", file=sys.stderr)
        for r in results["baseline"]["invocations"]:
            if r["status"] != PASS:
                print(f"  {r['invocation']}: {r['status']} (exit {r['exit']}); checks "
                      f"{[c['check'] for c in r['failed']]}; crashed {r['crashed']}",
                      file=sys.stderr)
        print("(leave a model out with --exclude GLOB, or out of one step with --exclude "
              "STEP:GLOB, or fix the gates first)",
              file=sys.stderr)
        return 1
    for k, fault in enumerate(chosen, 1):
        if fault.id in results["faults"]:
            outcome = results["faults"][fault.id]["outcome"]
            _say(f"[{k}/{len(chosen)}] {fault.id}: done before ({outcome})")
            continue
        _say(f"[{k}/{len(chosen)}] {fault.id} ({fault.term}, {fault.file}, size {fault.size:g})")
        try:
            record = score_fault(fault, snapshot, work, python, invs, base, base_record,
                                 noise, args.timeout, args.keep_work,
                                 control=fault in CONTROLS)
        except (RuntimeError, subprocess.TimeoutExpired) as exc:
            record = {"id": fault.id, "term": fault.term, "file": fault.file,
                      "size": fault.size, "what": fault.what, "control": fault in CONTROLS,
                      "outcome": NOT_CAUGHT_CRASH, "error": str(exc),
                      "probe": {}, "reached": False, "wall_s": 0.0, "invocations": []}
        results["faults"][fault.id] = record
        _write(args.out, results)
        _say(f"  -> {record['outcome']}"
             + (f" by {record['caught_by']}" if record.get("caught_by") else "")
             + f", reached: {record['reached']}, {record['wall_s'] / 60:.1f} min")
    done = [results["faults"][f.id] for f in chosen if f not in CONTROLS]
    caught = sum(r["outcome"] == CAUGHT for r in done)
    _say(f"score: {caught} of {len(done)} caught; {args.out / 'results.md'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
