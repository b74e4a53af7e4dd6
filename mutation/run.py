"""Mutation testing of the physics modules of gpme_core with cosmic-ray (docs/mutation.md).

    python -m mutation.run --sample 300 --seed 20260511     # seeded random sample
    python -m mutation.run --all --modules kinematics dynamics   # every mutant of modules
    python -m mutation.run --rerun-survivors OUT             # after new tests: survivors only
    python -m mutation.run --report OUT                      # summary of a finished run
    python -m mutation.run --modules kernels --sample 100 --seed 20260511 --out OUT
                                                             # kernels.py, its own sample

One cosmic-ray session (sqlite) per module under OUT (default mutation/out); one worker
process (cosmic-ray's local distributor runs the mutants one after another); run it with
``nice -n 10``.  Modules other than fast.py and kernels.py are tested with GPME_NO_JIT=1
(the numpy reference path); fast.py, kernels.py and the ``if fast.ENABLED:`` dispatch
blocks with numba on (the kernels are recompiled for every fast.py or kernels.py mutant);
see mutation/killsuite.py.
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
# the physics modules of the joint seeded sample (docs/mutation.md: its population of 3284)
MODULES = ("kinematics", "dynamics", "rfem", "inertia", "constraints", "gpme", "integrate",
           "fast")
# modules sampled from their own population only (the same --sample and --seed, drawn from
# that module's mutants alone), so that adding one leaves the joint sample of MODULES as it
# was: gpme_core/kernels.py (the fused compiled right-hand side and the RK4 / Radau IIA
# loops every compiled run goes through; issue 25)
OWN_SAMPLE = ("kernels",)
ALL_MODULES = MODULES + OWN_SAMPLE
# modules tested with numba on as a whole (mutation/killsuite.py), each mutant recompiling
# what it touches (gpme_core/jit_cache.py stamps every cached kernel with its sources)
JIT_MODULES = ("fast", "kernels")

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
         "integrate": ["tests/test_integrators.py"], "fast": ["tests/test_fast.py", "tests/test_chain_solve.py"],
         # the compiled evaluation against the numpy reference (tests/test_compiled.py), the
         # compiled RK4 / Radau IIA loops against the Python loop and their order
         # (tests/test_compiled_runs.py), the compiled reduced solve (tests/test_fast.py);
         # CORE then runs solve() and every simulation through the kernels too
         "kernels": ["tests/test_compiled.py", "tests/test_compiled_runs.py",
                     "tests/test_fast.py"]}
TIMEOUT = 60.0
# a kernels.py mutant recompiles the fused evaluation, the RK4 and Radau IIA loops and the
# module generated for the SymPy parts (the whole suite ~60 s cold on the shared machine,
# against ~36 s warm): a longer limit, so that a slow compile is not counted as a kill
TIMEOUTS = {"kernels": 180.0}


def kill_tests(module, with_new=True, leave_out=()):
    """The kill suite's test files for ``module``; leave_out: files (paths from the
    repository root) left out, e.g. a kill file added after the run it is compared with."""
    new = sorted(str(p.relative_to(ROOT)) for p in (ROOT / "tests").glob("test_mutation_kills_*.py"))
    own = [f"tests/test_mutation_kills_{module}.py"] if f"tests/test_mutation_kills_{module}.py" in new else []
    files = own + FIRST[module] + CORE + (new if with_new else [])
    files = [f for f in dict.fromkeys(files) if f not in set(leave_out)]
    if not with_new:
        files = [f for f in files if "mutation_kills" not in f]
    return files


def test_command(module, with_new=True, leave_out=()):
    # mutation/killsuite.py picks the computation path from where the mutant sits
    return (f"env PYTHONPATH={ROOT} {PY} -m mutation.killsuite {module}"
            + ("" if with_new else " --baseline")
            + "".join(f" --leave-out {f}" for f in leave_out))


def write_config(out, module, with_new=True, leave_out=()):
    cfg = out / f"{module}.toml"
    cfg.write_text(
        "[cosmic-ray]\n"
        f'module-path = "gpme_core/{module}.py"\n'
        f"timeout = {TIMEOUTS.get(module, TIMEOUT)}\n"
        "excluded-modules = []\n"
        f"test-command = {json.dumps(test_command(module, with_new, leave_out))}\n\n"
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


def clean_population(tmp, modules=MODULES):
    """Every mutant of ``modules``, made from gpme_core as committed (git HEAD, exported
    to ``tmp``: independent of a mutant that may be applied in the work tree)."""
    archive = subprocess.run(["git", "archive", "HEAD", "gpme_core"], cwd=ROOT, check=True,
                             capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(tmp)], input=archive, check=True)
    dbs = {}
    for m in modules:
        db = tmp / f"{m}.sqlite"
        cfg = write_config(tmp, m)
        subprocess.run([str(Path(PY).parent / "cosmic-ray"), "init", str(cfg), str(db)],
                       cwd=tmp, check=True)
        delete_jobs(db, [r["job_id"] for r in specs(db) if EXCLUDED_OPERATORS.search(r["operator_name"])])
        dbs[m] = db
    return dbs


def copy_rows(src, dst, job_ids):
    con = sqlite3.connect(dst)
    con.execute("attach database ? as src", (str(src),))
    for j in job_ids:
        con.execute("insert into work_items select * from src.work_items where job_id = ?", (j,))
        con.execute("insert into mutation_specs select * from src.mutation_specs where job_id = ?", (j,))
    con.commit()
    con.close()


def init(out, modules, sample, seed, with_new, extend=False, sample_fast=0, leave_out=()):
    """Sessions for ``modules`` holding the seeded sample (drawn from the population of ALL
    physics modules of MODULES, so it does not depend on --modules; random.sample's first k
    draws are the sample of size k; a module of OWN_SAMPLE has its own sample of the same
    size and seed from its own mutants).  extend: add the missing sampled mutants to
    existing sessions, keeping their results."""
    import shutil
    import tempfile
    out.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix="gpme_mut_"))
    joint = any(m in MODULES for m in modules)
    own = [m for m in modules if m in OWN_SAMPLE]
    try:
        dbs = clean_population(tmp, (MODULES if joint else ()) + tuple(own))
        population, chosen = [], []
        if joint:
            population = sorted(((m, r) for m in MODULES for r in specs(dbs[m])),
                                key=lambda mr: spec_key(mr[1]))
            chosen = population
            if sample:
                chosen = random.Random(seed).sample(population, min(sample, len(population)))
        if sample and sample_fast and joint:
            # fast.py mutants cost a numba compile each (~35 s on the shared machine): keep
            # only those among the first sample_fast draws (a smaller random sample of fast.py)
            first = {spec_key(r) for _, r in random.Random(seed).sample(population, min(sample_fast, len(population)))}
            chosen = [(m, r) for m, r in chosen if m != "fast" or spec_key(r) in first]
        for m in own:
            pop = sorted(((m, r) for r in specs(dbs[m])), key=lambda mr: spec_key(mr[1]))
            population += pop
            chosen += random.Random(seed).sample(pop, min(sample, len(pop))) if sample else pop
        keys = {spec_key(r) for _, r in chosen}
        for m in modules:
            db = out / f"{m}.sqlite"
            write_config(out, m, with_new, leave_out)
            if extend and db.exists():
                have = {spec_key(r) for r in specs(db)}
                copy_rows(dbs[m], db, [r["job_id"] for r in specs(dbs[m])
                                       if spec_key(r) in keys and spec_key(r) not in have])
            else:
                shutil.copy(dbs[m], db)
                delete_jobs(db, [r["job_id"] for r in specs(db) if spec_key(r) not in keys])
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    meta = {"seed": seed, "sample": sample, "population": len(population),
            "population_by_module": dict(Counter(m for m, _ in population)),
            "chosen": len(chosen), "chosen_by_module": dict(Counter(m for m, _ in chosen)),
            "sample_fast": sample_fast, "modules": list(modules), "with_new_tests": with_new}
    if leave_out:
        meta["left_out"] = list(leave_out)
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
            "select s.*, r.worker_outcome, r.test_outcome, r.diff, r.output from mutation_specs s "
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


def _key_text(r):
    return f"{r['module_path']}:{r['start_pos_row']}:{r['start_pos_col']} {r['operator_name'].split('/')[-1]} #{r['occurrence']}"


def _change(r):
    lines = [ln[1:].strip() for ln in (r["diff"] or "").splitlines()
             if ln.startswith(("+", "-")) and not ln.startswith(("+++", "---"))]
    old = [ln for ln in lines[:len(lines) // 2]]
    new = [ln for ln in lines[len(lines) // 2:]]
    return " / ".join(old), " / ".join(new)


def _killer(output):
    m = re.search(r"FAILED (\S+)", output or "")
    if m:
        return m.group(1).split(" ")[0]
    m = re.search(r"ERROR (\S+)", output or "")
    return ("error in " + m.group(1)) if m else "test run failed"


def table(before, after, modules):
    """Markdown rows for every mutant that survived the baseline kill suite: its status
    after the new tests (the killing test from the pytest output) or, for survivors, the
    reason recorded in mutation/equivalent.json."""
    verdicts = json.loads((ROOT / "mutation" / "equivalent.json").read_text())
    after_rows = {spec_key(r): r for r in results(after, modules)}
    lines = ["| # | mutant (file:line:col operator #occurrence) | original -> mutated | after the new tests |",
             "|---|---|---|---|"]
    counts = Counter()
    surv = sorted((r for r in results(before, modules) if (r["test_outcome"] or "").lower() == "survived"),
                  key=spec_key)
    for k, r in enumerate(surv, 1):
        a = after_rows.get(spec_key(r), {})
        old, new = _change(r)
        outcome = (a.get("test_outcome") or "pending").lower()
        key = _key_text(r)
        if (a.get("worker_outcome") or "").lower() == "timeout":
            verdict = "killed (timeout)"
            counts["killed"] += 1
        elif outcome == "killed":
            cmd = "GPME_NO_JIT=1" if "GPME_NO_JIT" not in (a.get("output") or "") else ""
            verdict = f"killed by `{_killer(a.get('output'))}`"
            counts["killed"] += 1
        elif key in verdicts:
            verdict = "**equivalent**: " + verdicts[key]
            counts["equivalent"] += 1
        else:
            verdict = f"**survives** ({outcome})"
            counts["survived"] += 1
        esc = lambda t: t.replace("|", "\\|").replace("`", "'")
        lines.append(f"| {k} | `{key}` | `{esc(old)}` -> `{esc(new)}` | {verdict} |")
    return "\n".join(lines), counts


def wilson(k, n, z=1.96):
    """95 % Wilson score interval of a proportion k / n."""
    if n == 0:
        return (float("nan"), float("nan"))
    p = k / n
    c = (p + z * z / (2 * n)) / (1 + z * z / n)
    h = z * (p * (1 - p) / n + z * z / (4 * n * n)) ** 0.5 / (1 + z * z / n)
    return c - h, c + h


def scores(before, after, modules):
    """Markdown table: per module, mutants run, killed before (timeouts included),
    equivalent, killed after, and the scores killed / (total - equivalent)."""
    verdicts = json.loads((ROOT / "mutation" / "equivalent.json").read_text())
    after_rows = {spec_key(r): r for r in results(after, modules)}

    def dead(r):
        return (r.get("test_outcome") or "").lower() == "killed" or \
            (r.get("worker_outcome") or "").lower() == "timeout"
    lines = ["| module | mutants | killed before | timeouts | survived before | equivalent | killed after | "
             "score before | score after |", "|---|---|---|---|---|---|---|---|---|"]
    tot = Counter()
    meta = json.loads((before / "meta.json").read_text())
    weights = meta["population_by_module"]
    strata = []
    for m in list(modules) + ["all"]:
        if m == "all":
            c = tot
        else:
            c = Counter()
            for r in results(before, [m]):
                a = after_rows.get(spec_key(r), r)
                c["n"] += 1
                c["kb"] += dead(r)
                c["to"] += (r.get("worker_outcome") or "").lower() == "timeout"
                eq = (not dead(r)) and (not dead(a)) and _key_text(r) in verdicts
                c["eq"] += eq
                c["ka"] += dead(r) or dead(a)
                c["pending"] += r.get("test_outcome") is None and r.get("worker_outcome") is None
            tot += c
        if not c["n"]:
            continue
        nn = c["n"] - c["eq"]
        if m != "all":
            strata.append((weights[m], c["kb"] / nn, c["ka"] / nn, nn))
        lo_b, hi_b = wilson(c["kb"], nn)
        lo_a, hi_a = wilson(c["ka"], nn)
        lines.append(f"| {m} | {c['n']} | {c['kb']} | {c['to']} | {c['n'] - c['kb']} | {c['eq']} | {c['ka']} | "
                     f"{100 * c['kb'] / nn:.1f} % ({100 * lo_b:.0f}-{100 * hi_b:.0f}) | "
                     f"{100 * c['ka'] / nn:.1f} % ({100 * lo_a:.0f}-{100 * hi_a:.0f}) |"
                     + (f" {c['pending']} pending" if c["pending"] else ""))
    w_all = sum(w for w, *_ in strata)
    cells = []
    for k in (1, 2):
        est = sum(w * st[k - 1] for w, *st in strata) / w_all
        var = sum((w / w_all) ** 2 * st[k - 1] * (1 - st[k - 1]) / st[2] for w, *st in strata)
        cells.append(f"{100 * est:.1f} % (+-{196 * var ** 0.5:.0f})")
    lines.append(f"| all, weighted by population | {meta['population']} | | | | | | {cells[0]} | {cells[1]} |")
    return "\n".join(lines)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", default="mutation/out")
    p.add_argument("--modules", nargs="+", choices=ALL_MODULES,
                   help=f"default: {' '.join(MODULES)} (the joint sample); --report, "
                        "--rerun-survivors and --table: every module with a session in --out")
    p.add_argument("--sample", type=int, default=0, help="random sample size (0: all)")
    p.add_argument("--all", action="store_true", help="every mutant of --modules")
    p.add_argument("--seed", type=int, default=20260511)
    p.add_argument("--sample-fast", type=int, default=0,
                   help="for fast.py keep only the mutants among the first N draws of the sample")
    p.add_argument("--baseline-suite", action="store_true",
                   help="kill suite without tests/test_mutation_kills_*.py (the 'before' score)")
    p.add_argument("--leave-out", nargs="+", default=[], metavar="TEST_FILE",
                   help="kill-suite files left out of the run (e.g. a kill file added "
                        "after it: the score before that file)")
    p.add_argument("--rerun-survivors", action="store_true")
    p.add_argument("--report", action="store_true", help="only summarise --out")
    p.add_argument("--table", metavar="BEFORE",
                   help="markdown table of BEFORE's survivors with their status in --out")
    p.add_argument("--init-only", action="store_true")
    p.add_argument("--extend", action="store_true",
                   help="add the sampled mutants missing from existing sessions (keeps results)")
    a = p.parse_args(argv)
    out = (ROOT / a.out).resolve()
    if a.modules is None:
        a.modules = list(MODULES) if not (a.report or a.rerun_survivors or a.table) \
            else list(ALL_MODULES)
    if a.report:
        return report(out, a.modules)
    if a.table:
        text, counts = table((ROOT / a.table).resolve(), out, a.modules)
        print(scores((ROOT / a.table).resolve(), out, a.modules))
        print()
        print(text)
        print(dict(counts), file=sys.stderr)
        return None
    if a.rerun_survivors:
        rerun_survivors(out, a.modules)
        return report(out, a.modules)
    init(out, a.modules, 0 if a.all else a.sample, a.seed, not a.baseline_suite, a.extend,
         a.sample_fast, a.leave_out)
    if a.init_only:
        return None
    exec_all(out, a.modules)
    report(out, a.modules)
    subprocess.run(["git", "diff", "--exit-code", "--stat", "gpme_core"], cwd=ROOT, check=True)


if __name__ == "__main__":
    main()
