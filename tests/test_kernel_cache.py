"""numba's disk cache of the kernels is never stale (gpme_core.jit_cache, issue 23).

numba keys a cached function on its own source file only, while kernels.evaluate carries
the code of fast.py's functions compiled in: with a fault planted in fast.py and the caches
kept, kernels.evaluate returned the old accelerations.  The end-to-end test here runs one
compiled evaluation in fresh processes on a copy of gpme_core (PYTHONPATH at the copy, its
own in-tree numba cache):

1. the copy as it is (numba's cache files of this checkout are copied along: the stamp
   holds contents, not paths, so a warm cache is reused and this run takes seconds; a cold
   one compiles, ~35 s on this 2-core machine);
2. again, unchanged: numba loads evaluate from the cache (cache hits, no miss, numba's
   counters of the dispatcher) and the index file holds the stamp the process computes;
3. with a factor planted in fast.terms_into (the gravity forces; called by kernels.evaluate,
   another file), no cache cleared: evaluate is compiled again (a miss, a new stamp in the
   index) and its accelerations change.

Runtime: ~40 s when this checkout's cache is warm (test_compiled.py warms it in a full run:
one compile, for step 3), ~90 s cold (two compiles; ~37 s of CPU on two shared cores).

The other tests check, without compiling, which files a stamp covers, that the cache stays
where numba would put it (NUMBA_CACHE_DIR, in-tree, user-wide when the source directory is
not writable), that other numba code in the process keeps numba's own cache, and that every
compiled function of gpme_core goes through gpme_core.jit_cache.
"""
import importlib.util
import json
import os
import pickle
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import numba
import numpy as np
import pytest
from numba.core import caching, config

from gpme_core import fast, jit_cache, kernels

pytestmark = pytest.mark.skipif(not fast.ENABLED, reason="GPME_NO_JIT=1: no compiled path")

PACKAGE_DIR = Path(jit_cache.__file__).resolve().parent

# one compiled evaluation on a two-joint arm under gravity (a pendulum about y carrying a
# slider); prints what the test checks as one JSON line
EVALUATION = textwrap.dedent('''
    import json
    import numpy as np
    import gpme_core
    from gpme_core import compiled, jit_cache, kernels
    from gpme_core import transforms as tf
    from gpme_core.gpme import ProgrammedMotion
    from gpme_core.inertia import cuboid
    from gpme_core.model import PRISMATIC, REVOLUTE, ChainBuilder

    b = ChainBuilder("cache_probe")
    b.add_joint("q0", REVOLUTE, (0, 1, 0), stiffness=3.0, damping=0.1)
    b.add_body(cuboid(2.0, (0.2, 0.3, 0.4), com=(0.3, -0.02, 0.1)))
    b.add_joint("q1", PRISMATIC, (1, 0, 0), origin=tf.translation(0.1, 0, 0.3))
    b.add_body(cuboid(1.0, (0.1, 0.5, 0.2), com=(0.0, 0.1, 0.0)))
    cs, reason = compiled.for_system(ProgrammedMotion(b.build()))
    assert cs is not None, reason
    status, q_ddot, _, _ = cs.evaluate(0.1, np.array([0.3, 0.2]), np.array([0.5, -0.4]),
                                       np.arange(2), np.arange(0))
    stats = kernels.evaluate.stats
    print(json.dumps({"package": gpme_core.__file__, "status": int(status),
                      "q_ddot": q_ddot.tolist(), "cache_path": stats.cache_path,
                      "hits": sum(stats.cache_hits.values()),
                      "misses": sum(stats.cache_misses.values()),
                      "stamp": jit_cache.source_stamp(kernels.__file__),
                      "index": kernels.evaluate._cache._cache_file._index_path}))
''')
# the planted fault: gravity forces 1.5 times too large in fast.terms_into
FAULT = ("        g[j] = -gj\n", "        g[j] = -1.5 * gj\n")


def _run_evaluation(root):
    """The JSON record of EVALUATION run in a fresh process on the gpme_core under root."""
    env = {k: v for k, v in os.environ.items()
           if k not in ("NUMBA_CACHE_DIR", "NUMBA_CACHE_LOCATOR_CLASSES", "NUMBA_DISABLE_JIT",
                        "GPME_NO_JIT")}
    env.update(PYTHONPATH=str(root), PYTHONDONTWRITEBYTECODE="1")
    script = root / "evaluation.py"            # its directory comes first on sys.path
    script.write_text(EVALUATION, encoding="utf-8")
    done = subprocess.run([sys.executable, str(script)], cwd=root, env=env,
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    record = json.loads(done.stdout.strip().splitlines()[-1])
    assert Path(record["package"]).resolve().parent == (root / "gpme_core").resolve()
    assert record["status"] == kernels.OK
    return record


def _index_stamp(index_path):
    """Our part of the source stamp saved in a numba index file (.nbi)."""
    with open(index_path, "rb") as f:
        assert pickle.load(f) == numba.__version__
        stamp, _ = pickle.loads(f.read())
    return stamp[1]


def test_a_change_in_a_called_file_recompiles_the_kernel(tmp_path):
    copy = tmp_path / "gpme_core"
    shutil.copytree(PACKAGE_DIR, copy, ignore=shutil.ignore_patterns("*.pyc", "*.tmp.*"))

    first = _run_evaluation(tmp_path)
    cache_dir = Path(first["cache_path"]).resolve()
    assert cache_dir == (copy / "__pycache__").resolve()     # the copy's own cache

    second = _run_evaluation(tmp_path)
    assert second["q_ddot"] == first["q_ddot"]
    assert (second["hits"], second["misses"]) == (1, 0), "an unchanged run must load the cache"
    index = Path(second["index"])
    assert index.parent.resolve() == cache_dir and index.name.startswith("kernels.evaluate-")
    assert _index_stamp(index) == second["stamp"]

    fast_py = copy / "fast.py"
    source = fast_py.read_text(encoding="utf-8")
    assert source.count(FAULT[0]) == 1, "the planted fault's anchor is gone from fast.py"
    fast_py.write_text(source.replace(*FAULT), encoding="utf-8")

    faulted = _run_evaluation(tmp_path)
    assert faulted["stamp"] != second["stamp"]
    assert (faulted["hits"], faulted["misses"]) == (0, 1), "a changed callee must recompile"
    assert _index_stamp(index) == faulted["stamp"]
    assert not np.allclose(faulted["q_ddot"], first["q_ddot"], rtol=1e-3, atol=0), \
        "the fault planted in fast.py did not reach kernels.evaluate: stale compiled code"


# ---------------------------------------------------------------- without compiling
def test_the_stamp_covers_the_imported_gpme_core_modules(tmp_path):
    names = {p.relative_to(PACKAGE_DIR).as_posix()
             for p in jit_cache.source_files(kernels.__file__)}
    assert names == {"kernels.py", "fast.py", "jit_cache.py"}
    # a module generated by gpme_core.compiled lives outside the package and imports fast
    generated = tmp_path / "gpme_kernels_0123.py"
    generated.write_text("import math\nfrom gpme_core.fast import (_jit_user, chain_into)\n",
                         encoding="utf-8")
    files = jit_cache.source_files(generated)
    assert {p.name for p in files} == {"gpme_kernels_0123.py", "fast.py", "jit_cache.py"}
    stamp = jit_cache.source_stamp(generated)
    generated.write_text(generated.read_text(encoding="utf-8") + "# edited\n", encoding="utf-8")
    assert jit_cache.source_stamp(generated) != stamp


def test_numba_code_settings_name_their_own_cache_files(monkeypatch):
    """numba's index key does not hold NUMBA_BOUNDSCHECK: a cache written without bounds
    checks was loaded with them (the mutation kill suite sets it)."""
    plain = jit_cache.KernelCache(kernels.evaluate.py_func)
    monkeypatch.setattr(config, "BOUNDSCHECK", 1)
    checked = jit_cache.KernelCache(kernels.evaluate.py_func)
    names = [c._impl.filename_base for c in (plain, checked)]
    assert names[0] != names[1]
    assert all(n.startswith("kernels.evaluate-") for n in names)


def _module_function(directory):
    """A plain function defined in a module file of its own under ``directory``."""
    directory.mkdir()
    path = directory / "plain_kernel.py"
    path.write_text("def twice(x):\n    return 2.0 * x\n", encoding="utf-8")
    spec = importlib.util.spec_from_file_location("plain_kernel_for_cache_test", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.twice


def test_the_cache_stays_where_numba_puts_it(tmp_path, monkeypatch):
    py_func = _module_function(tmp_path / "src")
    assert Path(jit_cache.KernelCache(py_func).cache_path) == tmp_path / "src" / "__pycache__"

    monkeypatch.setattr(config, "CACHE_DIR", str(tmp_path / "numba_cache_dir"))
    assert Path(jit_cache.KernelCache(py_func).cache_path).parent == tmp_path / "numba_cache_dir"
    monkeypatch.setattr(config, "CACHE_DIR", "")

    # a source directory that cannot be written (simulated: the tests may run as root,
    # who can write anywhere): numba's user-wide cache directory
    def not_writable(self):
        raise PermissionError("read-only source directory")
    monkeypatch.setattr(caching.InTreeCacheLocator, "ensure_cache_path", not_writable)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "user_cache"))
    cache = jit_cache.KernelCache(py_func)
    assert Path(cache.cache_path).is_relative_to(tmp_path / "user_cache" / "numba")
    assert cache._impl.locator.get_source_stamp()[1] == jit_cache.source_stamp(
        py_func.__code__.co_filename)


def test_other_numba_code_keeps_numba_cache(tmp_path):
    dispatcher = numba.njit(cache=True)(_module_function(tmp_path / "src"))
    assert type(dispatcher._cache) is caching.FunctionCache


def test_every_compiled_function_of_gpme_core_uses_the_kernel_cache():
    dispatchers = [obj for module in (fast, kernels) for obj in vars(module).values()
                   if isinstance(obj, numba.core.registry.CPUDispatcher)]
    assert len(dispatchers) > 20
    assert all(isinstance(d._cache, jit_cache.KernelCache) for d in dispatchers)
    # no other numba cache in the engine's sources
    offenders = [p.name for p in PACKAGE_DIR.glob("*.py")
                 if p.name != "jit_cache.py" and "cache=True" in p.read_text(encoding="utf-8")]
    assert offenders == []


def test_kernel_jit_always_caches():
    with pytest.raises(TypeError, match="kernel_jit always caches on disk"):
        jit_cache.kernel_jit(cache=False)
