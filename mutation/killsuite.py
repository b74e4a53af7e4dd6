"""Run the kill suite for the mutant currently applied to gpme_core/<module>.py.

    python -m mutation.killsuite MODULE [--baseline] [--leave-out TEST_FILE ...]

Which computation path the tests must use follows from where the mutant sits: the file is
compared with git HEAD, and a mutant inside fast.py or kernels.py (JIT_MODULES) or inside
an ``if fast.ENABLED:`` block (the dispatch to the compiled kernels in dynamics.py,
kinematics.py, gpme.py) is tested with numba on; every other mutant with GPME_NO_JIT=1
(the numpy reference).  --baseline leaves out tests/test_mutation_kills_*.py and numba's
bounds checking (the score before them); without it, numba-on runs set NUMBA_BOUNDSCHECK=1.
--leave-out drops one test file of the suite (repeatable; mutation.run --leave-out).

A fast.py or kernels.py mutant never meets a stale compiled kernel: gpme_core/jit_cache.py
stamps every cached kernel with the contents of its own file and of the gpme_core modules
it imports, so a mutated kernels.py (or fast.py, which kernels.py imports) recompiles its
kernels.  The modules generated for SymPy parts (gpme_core.compiled) are copies of
kernels.py written under GPME_KERNEL_CACHE; for these two modules it points to a fresh
temporary directory, removed after the run, so that no mutant's generated module (or its
numba cache) is left in the user's ~/.cache/gpme/kernels.
"""
import ast
import difflib
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from mutation.run import JIT_MODULES, ROOT, SLOW, kill_tests


def jit_lines(source):
    """Line numbers (1-based) of the bodies of ``if fast.ENABLED:`` blocks."""
    lines = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.If) and ast.unparse(node.test) == "fast.ENABLED":
            for stmt in node.body:
                lines.update(range(stmt.lineno, stmt.end_lineno + 1))
    return lines


def mutated_lines(path):
    head = subprocess.run(["git", "show", f"HEAD:{path}"], cwd=ROOT, capture_output=True,
                          text=True, check=True).stdout
    now = (ROOT / path).read_text()
    changed = set()
    sm = difflib.SequenceMatcher(None, head.splitlines(), now.splitlines(), autojunk=False)
    for tag, i1, i2, _, _ in sm.get_opcodes():
        if tag != "equal":
            changed.update(range(i1 + 1, max(i2, i1 + 1) + 1))
    return head, changed


def use_jit(module):
    if module in JIT_MODULES:
        return True
    head, changed = mutated_lines(f"gpme_core/{module}.py")
    return bool(changed & jit_lines(head))


CACHE_PREFIX = "gpme_mut_kernel_cache_"


def _remove_orphaned_caches():
    """Remove the kernel caches of earlier runs whose process is gone (cosmic-ray kills a
    timed-out run's process group, so its ``finally`` never ran)."""
    for path in Path(tempfile.gettempdir()).glob(f"{CACHE_PREFIX}*_*"):
        try:
            os.kill(int(path.name[len(CACHE_PREFIX):].split("_")[0]), 0)
        except ProcessLookupError:
            shutil.rmtree(path, ignore_errors=True)
        except (ValueError, PermissionError):
            pass


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    module = argv[0]
    baseline = "--baseline" in argv
    leave_out = [argv[i + 1] for i, arg in enumerate(argv[:-1]) if arg == "--leave-out"]
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    env.pop("GPME_NO_JIT", None)
    if not use_jit(module):
        env["GPME_NO_JIT"] = "1"
    elif not baseline:
        # numba does not check array bounds: a mutated buffer shape or loop bound in a kernel
        # writes past an array without any error.  With bounds checking such a write raises
        # IndexError (the kernels compile ~20 % slower; results are unchanged).
        env["NUMBA_BOUNDSCHECK"] = "1"
    cmd = [sys.executable, "-m", "pytest", "-x", "-q", "--no-header", "-p", "no:cacheprovider",
           *kill_tests(module, not baseline, leave_out)]
    for s in SLOW:
        cmd += ["--deselect", s]
    os.chdir(ROOT)
    if module not in JIT_MODULES:
        os.execve(sys.executable, cmd, env)
    _remove_orphaned_caches()
    cache = tempfile.mkdtemp(prefix=f"{CACHE_PREFIX}{os.getpid()}_")
    env["GPME_KERNEL_CACHE"] = cache
    try:
        return subprocess.run(cmd, env=env).returncode
    finally:
        shutil.rmtree(cache, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
