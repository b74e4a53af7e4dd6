"""Mutation testing of the physics modules of gpme_core with cosmic-ray (docs/mutation.md).

    python -m mutation.run --sample 300 --seed 20260511     # seeded random sample
    python -m mutation.run --all --modules kinematics dynamics   # every mutant of modules
    python -m mutation.run --rerun-survivors OUT             # after new tests: survivors only
    python -m mutation.run --report OUT                      # summary of a finished run

One cosmic-ray session (sqlite) per module under OUT (default mutation/out); one worker
process (cosmic-ray's local distributor runs the mutants one after another); run it with
``nice -n 10``.  Modules other than fast.py are tested with GPME_NO_JIT=1 (the numpy
reference path); fast.py and the ``if fast.ENABLED:`` dispatch blocks with numba on (the
kernels are recompiled for every fast.py mutant); see mutation/killsuite.py.
"""
import argparse
import json
import os
import random
import re
import sqlite3
import subprocess
import sys
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PY = sys.executable
MODULES = ("kinematics", "dynamics", "rfem", "inertia", "constraints", "gpme", "integrate",
           "fast")

# Operators left out: replacing an arithmetic operator by //, %, <<, >>, |, &, ^ and a
# comparison by is / is not, a unary minus by ~ / not: on floats and float arrays these
# raise TypeError or turn a number into a bool at once, so every test run kills them; they
# inflate the score without saying anything about the tests.
EXCLUDED_OPERATORS = re.compile(
    r"ReplaceBinaryOperator_\w+_(FloorDiv|Mod|RShift|LShift|BitOr|BitAnd|BitXor)$"
    r"|ReplaceComparisonOperator_\w+_(Is|IsNot)$"
    r"|ReplaceUnaryOperator_\w+_(Invert|Not)$")

# The kill suite: the core tests minus the slow end-to-end ones (each > 0.5 s; they run
# whole simulations) plus the dedicated tests/test_mutation_kills_*.py.
CORE = ["tests/test_kinematics.py", "tests/test_dynamics.py", "tests/test_gpme.py",
        "tests/test_rfem.py", "tests/test_fast.py", "tests/test_integrators.py",
        "tests/test_energy.py", "tests/test_statics.py", "tests/test_validation.py"]
SLOW = ["tests/test_integrators.py::test_scipy_methods_match_rk4",
        "tests/test_integrators.py::test_simulate_command_writes_csv_and_figures",
        "tests/test_integrators.py::test_simulate_command_static_arm_starts_in_the_sag",
        "tests/test_energy.py::test_energy_balance_with_dampers_drive_and_programmed_constraints",
        "tests/test_energy.py::test_energy_is_conserved_to_fourth_order_without_dissipation",
        "tests/test_gpme.py::test_on_manifold_start_stays_on_manifold",
        "tests/test_gpme.py::test_baumgarte_pulls_off_manifold_start_onto_the_constraints"]
# per-module selection: the tests that exercise the module run first (-x stops at the
# first failure, so a mutant is usually killed within its own module's tests)
FIRST = {"kinematics": ["tests/test_kinematics.py"], "dynamics": ["tests/test_dynamics.py"],
         "rfem": ["tests/test_rfem.py", "tests/test_statics.py"], "inertia": [],
         "constraints": ["tests/test_gpme.py"], "gpme": ["tests/test_gpme.py"],
         "integrate": ["tests/test_integrators.py"], "fast": ["tests/test_fast.py"]}
TIMEOUT = 60.0


def kill_tests(module, with_new=True):
    new = sorted(str(p.relative_to(ROOT)) for p in (ROOT / "tests").glob("test_mutation_kills_*.py"))
    own = [f"tests/test_mutation_kills_{module}.py"] if f"tests/test_mutation_kills_{module}.py" in new else []
    files = own + FIRST[module] + CORE + (new if with_new else [])
    files = list(dict.fromkeys(files))
    if not with_new:
        files = [f for f in files if "mutation_kills" not in f]
    return files


def test_command(module, with_new=True):
    # mutation/killsuite.py picks the computation path from where the mutant sits
    return (f"env PYTHONPATH={ROOT} {PY} -m mutation.killsuite {module}"
            + ("" if with_new else " --baseline"))


def write_config(out, module, with_new=True):
    cfg = out / f"{module}.toml"
    cfg.write_text(
        "[cosmic-ray]\n"
        f'module-path = "gpme_core/{module}.py"\n'
        f"timeout = {TIMEOUT}\n"
        "excluded-modules = []\n"
        f"test-command = {json.dumps(test_command(module, with_new))}\n\n"
        "[cosmic-ray.distributor]\nname = \"local\"\n")
    return cfg


def cr(*args):
    subprocess.run([str(Path(PY).parent / "cosmic-ray"), *args], cwd=ROOT, check=True)


def spec_key(row):
    # deterministic order of mutants (job ids are random uuids)
    return (row["module_path"], row["start_pos_row"], row["start_pos_col"], row["operator_name"],
            row["occurrence"])


def specs(db):
    con = sqlite3.connect(db)
    con.row_factory = sqlite3.Row
    rows = [dict(r) for r in con.execute("select * from mutation_specs")]
    con.close()
    return rows


def delete_jobs(db, job_ids):
    con = sqlite3.connect(db)
    for j in job_ids:
        for table in ("work_results", "mutation_specs", "work_items"):
            con.execute(f"delete from {table} where job_id = ?", (j,))
    con.commit()
    con.close()


def init(out, modules, sample, seed, with_new):
    out.mkdir(parents=True, exist_ok=True)
    population = []
    for m in modules:
        db = out / f"{m}.sqlite"
        if db.exists():
            db.unlink()
        cr("init", str(write_config(out, m, with_new)), str(db))
        rows = specs(db)
        delete_jobs(db, [r["job_id"] for r in rows if EXCLUDED_OPERATORS.search(r["operator_name"])])
        population += [(m, r) for r in specs(db)]
    population.sort(key=lambda mr: spec_key(mr[1]))
    chosen = population
    if sample:
        chosen = random.Random(seed).sample(population, min(sample, len(population)))
    keep = {r["job_id"] for _, r in chosen}
    for m in modules:
        db = out / f"{m}.sqlite"
        delete_jobs(db, [r["job_id"] for r in specs(db) if r["job_id"] not in keep])
    meta = {"seed": seed, "sample": sample, "population": len(population),
            "population_by_module": dict(Counter(m for m, _ in population)),
            "chosen": len(chosen), "chosen_by_module": dict(Counter(m for m, _ in chosen)),
            "modules": list(modules), "with_new_tests": with_new}
    (out / "meta.json").write_text(json.dumps(meta, indent=1))
    print(json.dumps(meta, indent=1))


def exec_all(out, modules):
    for m in modules:
        db = out / f"{m}.sqlite"
        if db.exists():
            print(f"== {m}", flush=True)
            cr("exec", str(out / f"{m}.toml"), str(db))


def rerun_survivors(out, modules):
    """Forget the results of the surviving mutants and run them again with the current
    kill suite (tests added since); killed mutants stay killed (tests were only added)."""
    for m in modules:
        db = out / f"{m}.sqlite"
        if not db.exists():
            continue
        write_config(out, m, True)
        con = sqlite3.connect(db)
        con.execute("delete from work_results where lower(test_outcome) = 'survived'")
        con.commit()
        con.close()
    exec_all(out, modules)


def results(out, modules):
    rows = []
    for m in modules:
        db = out / f"{m}.sqlite"
        if not db.exists():
            continue
        con = sqlite3.connect(db)
        con.row_factory = sqlite3.Row
        rows += [dict(r, module=m) for r in con.execute(
            "select s.*, r.worker_outcome, r.test_outcome, r.diff from mutation_specs s "
            "left join work_results r on s.job_id = r.job_id")]
        con.close()
    return rows


def report(out, modules):
    rows = results(out, modules)
    by = {}
    for r in rows:
        outcome = (r["test_outcome"] or "pending").lower()
        if (r["worker_outcome"] or "").lower() == "timeout":
            outcome = "timeout"
        by.setdefault(r["module"], Counter())[outcome] += 1
    total = Counter()
    for m, c in by.items():
        total += c
        print(m, dict(c))
    print("all", dict(total))
    surv = sorted((r for r in rows if (r["test_outcome"] or "").lower() == "survived"), key=spec_key)
    (out / "survivors.txt").write_text("".join(
        f"{r['module_path']}:{r['start_pos_row']}:{r['start_pos_col']} {r['definition_name']} "
        f"{r['operator_name']} #{r['occurrence']} {r['job_id']}\n"
        + "".join("    " + ln + "\n" for ln in (r["diff"] or "").splitlines()
                  if ln.startswith(("+", "-")) and not ln.startswith(("+++", "---")))
        for r in surv))
    (out / "summary.json").write_text(json.dumps({m: dict(c) for m, c in by.items()}, indent=1))
    print(f"{len(surv)} survivors listed in {out / 'survivors.txt'}")


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", default="mutation/out")
    p.add_argument("--modules", nargs="+", default=list(MODULES), choices=MODULES)
    p.add_argument("--sample", type=int, default=0, help="random sample size (0: all)")
    p.add_argument("--all", action="store_true", help="every mutant of --modules")
    p.add_argument("--seed", type=int, default=20260511)
    p.add_argument("--baseline-suite", action="store_true",
                   help="kill suite without tests/test_mutation_kills_*.py (the 'before' score)")
    p.add_argument("--rerun-survivors", action="store_true")
    p.add_argument("--report", action="store_true", help="only summarise --out")
    p.add_argument("--init-only", action="store_true")
    a = p.parse_args(argv)
    out = (ROOT / a.out).resolve()
    if a.report:
        return report(out, a.modules)
    if a.rerun_survivors:
        rerun_survivors(out, a.modules)
        return report(out, a.modules)
    init(out, a.modules, 0 if a.all else a.sample, a.seed, not a.baseline_suite)
    if a.init_only:
        return None
    exec_all(out, a.modules)
    report(out, a.modules)
    subprocess.run(["git", "diff", "--exit-code", "--stat", "gpme_core"], cwd=ROOT, check=True)


if __name__ == "__main__":
    main()
