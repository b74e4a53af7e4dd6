"""Run the kill suite for the mutant currently applied to gpme_core/<module>.py.

    python -m mutation.killsuite MODULE [--baseline]

Which computation path the tests must use follows from where the mutant sits: the file is
compared with git HEAD, and a mutant inside fast.py or inside an ``if fast.ENABLED:``
block (the dispatch to the compiled kernels in dynamics.py, kinematics.py, gpme.py) is
tested with numba on; every other mutant with GPME_NO_JIT=1 (the numpy reference).
--baseline leaves out tests/test_mutation_kills_*.py and numba's bounds checking (the
score before them); without it, numba-on runs set NUMBA_BOUNDSCHECK=1.
"""
import ast
import difflib
import os
import subprocess
import sys

from mutation.run import ROOT, SLOW, kill_tests


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
    if module == "fast":
        return True
    head, changed = mutated_lines(f"gpme_core/{module}.py")
    return bool(changed & jit_lines(head))


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    module = argv[0]
    baseline = "--baseline" in argv
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
           *kill_tests(module, not baseline)]
    for s in SLOW:
        cmd += ["--deselect", s]
    os.chdir(ROOT)
    os.execve(sys.executable, cmd, env)


if __name__ == "__main__":
    main()
