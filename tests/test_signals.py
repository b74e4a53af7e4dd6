"""Signals end a command at every moment (issue 24), compilation included: gpme.signals.

Before, a SIGTERM that Python handled inside numba's compiler (a callback from C through
ctypes: llvmlite's object-cache notification) was printed as "Exception ignored on calling
ctypes callback function" and lost: the run completed, exited 0 and became ``latest``.
Here the signal is sent from exactly that callback, while a fresh kernel cache compiles:
the child (``gpme simulate`` of examples/my_arm with empty GPME_KERNEL_CACHE and
NUMBA_CACHE_DIR) sends it to itself the first time numba hands over a compiled object.
The command must end with the documented status (130 SIGINT, 143 SIGTERM, 129 SIGHUP),
one line naming the signal, no traceback, nothing swallowed, and no run output written.
"""
import os
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
MY_ARM = ROOT / "examples" / "my_arm" / "my_arm.toml"
CHILD_TIMEOUT_S = 600        # a hang guard only: the child ends seconds after the signal

# the child: numba's object-compiled hook (called from C by llvmlite) sends the signal to
# the process the first time it runs, then does its normal work
DRIVER = textwrap.dedent("""
    import os, sys
    from numba.core import codegen
    library = codegen.JITCodeLibrary
    original = library._object_compiled_hook.__func__
    sent = []

    def hook(cls, ll_module, buf):
        if not sent:
            sent.append(True)
            print("signal sent from the compiler's callback", flush=True)
            os.kill(os.getpid(), int(sys.argv[1]))
        return original(cls, ll_module, buf)

    library._object_compiled_hook = classmethod(hook)
    from gpme.cli import main
    sys.exit(main(sys.argv[2:], ignore_late_signals=True))
""")


def _run_child(tmp_path, signum, argv):
    driver = tmp_path / "driver.py"
    driver.write_text(DRIVER)
    env = {**os.environ, "PYTHONUNBUFFERED": "1",
           "GPME_KERNEL_CACHE": str(tmp_path / "kernels"),
           "NUMBA_CACHE_DIR": str(tmp_path / "numba")}
    return subprocess.run([sys.executable, str(driver), str(int(signum)), *argv], cwd=ROOT,
                          env=env, capture_output=True, text=True, timeout=CHILD_TIMEOUT_S)


@pytest.mark.parametrize("signum,status,words", [
    (signal.SIGTERM, 143, "terminated (SIGTERM)"),
    (signal.SIGINT, 130, "interrupted"),
    (signal.SIGHUP, 129, "terminated (SIGHUP)"),
], ids=["SIGTERM", "SIGINT", "SIGHUP"])
def test_signal_inside_the_compiler_ends_the_run(tmp_path, signum, status, words):
    out = tmp_path / "out"
    proc = _run_child(tmp_path, signum, ["simulate", "--model", str(MY_ARM), "--out", str(out),
                                         "--no-progress"])
    assert "signal sent from the compiler's callback" in proc.stdout, proc.stdout
    assert proc.returncode == status, (proc.returncode, proc.stderr[-3000:])
    assert words in proc.stderr
    assert "Exception ignored" not in proc.stderr and "Traceback" not in proc.stderr
    assert "wrote" not in proc.stdout and "checks:" not in proc.stdout   # never completed
    assert not list(out.glob("*.csv")) and not list(out.glob("*.png"))
