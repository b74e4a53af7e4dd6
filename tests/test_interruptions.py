"""Interruptions: SIGINT and SIGTERM end a command with one line and exit 130 / 143, and no
half-written file is left in place of a good one; a run killed outright (SIGKILL) leaves
its partial directory behind, which the next run removes.  The signals arrive at seeded
random moments of real runs (subprocesses)."""
import hashlib
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
MY_ARM = ROOT / "examples" / "my_arm" / "my_arm.toml"
RNG_SEED = 20261122


def _start(argv, cwd):
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    return subprocess.Popen([sys.executable, "-m", "gpme.cli", *argv, "--no-progress"],
                            cwd=cwd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)


def _wait_for_line(proc, prefix, timeout=120.0):
    """Read the child's stdout until a line starting with ``prefix`` (the run has begun)."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        line = proc.stdout.readline()
        if not line:
            break
        if line.lstrip().startswith(prefix):
            return
    raise AssertionError(f"the child never printed {prefix!r}")


def _tree_digest(directory):
    """{relative path: sha256} of every file under directory."""
    return {str(p.relative_to(directory)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(Path(directory).rglob("*")) if p.is_file()}


@pytest.mark.parametrize("signum,code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)],
                         ids=["SIGINT", "SIGTERM"])
def test_simulate_interrupted_mid_run(signum, code, tmp_path):
    out = tmp_path / "out"
    proc = _start(["simulate", "--case", "rigid", "--t-end", "30", "--out", str(out)],
                  tmp_path)
    _wait_for_line(proc, "estimate:")
    time.sleep(np.random.default_rng(RNG_SEED + signum).uniform(0.2, 1.5))
    proc.send_signal(signum)
    stdout, stderr = proc.communicate(timeout=60)
    assert proc.returncode == code, stderr
    assert "Traceback" not in stderr
    lines = [ln for ln in stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and ("interrupted" in lines[0] or "terminated (SIGTERM)" in lines[0])
    # nothing half-written: the history and figures are written only when the run is done
    assert not list(out.glob("*.csv")) and not list(out.glob("*.png"))
    assert not [p for p in out.iterdir() if not p.name.startswith(".gpme.lock")]


def test_verify_killed_at_random_moments_keeps_the_last_good_report(tmp_path):
    """A good report first; then runs stopped by SIGTERM at random moments (each must exit
    143 and leave neither a partial directory nor a changed report or `latest`), one killed
    by SIGKILL (its partial directory stays), and a last run that completes, removes the
    dead run's leftovers and is published whole."""
    root = tmp_path / "reports"
    argv = ["verify", "--quick", "--only", "gpme", "--model", str(MY_ARM), "--out", str(root)]
    first = subprocess.run([sys.executable, "-m", "gpme.cli", *argv, "--no-progress"],
                           cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert first.returncode == 0, first.stderr
    good = (root / "latest").resolve()
    digest = _tree_digest(good)
    rng = np.random.default_rng(RNG_SEED)
    for delay in rng.uniform(0.1, 4.0, size=2):
        proc = _start(argv, tmp_path)
        _wait_for_line(proc, "estimated cost")
        time.sleep(delay)
        proc.send_signal(signal.SIGTERM)
        _, stderr = proc.communicate(timeout=120)
        if proc.returncode == 0:        # finished before the signal: a whole new report
            good = (root / "latest").resolve()
            digest = _tree_digest(good)
            continue
        assert proc.returncode == 143, stderr
        assert "Traceback" not in stderr and "terminated (SIGTERM)" in stderr
        assert not list(root.glob(".*.partial")), f"partial left after {delay:.2f} s"
        assert (root / "latest").resolve() == good
        assert _tree_digest(good) == digest
    proc = _start(argv, tmp_path)
    _wait_for_line(proc, "[gpme]")
    time.sleep(rng.uniform(0.1, 1.0))
    proc.kill()
    proc.communicate(timeout=60)
    assert (root / "latest").resolve() == good and _tree_digest(good) == digest
    last = subprocess.run([sys.executable, "-m", "gpme.cli", *argv, "--no-progress"],
                          cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert last.returncode == 0, last.stderr
    assert not list(root.glob(".*.partial"))
    new = (root / "latest").resolve()
    assert new != good and _tree_digest(good) == digest
    summary = json.loads((new / "summary.json").read_text())
    assert summary["passed"] and (new / "index.html").stat().st_size > 0


def test_interrupt_inside_a_compiled_kernel_is_given_back():
    """numba turns an exception raised by a signal handler while a kernel returns into
    SystemError chained to it; gpme_core.fast.run gives the interrupt back, so an
    ``except Exception`` never takes Ctrl-C for a failed computation."""
    from gpme.cli import Terminated
    from gpme_core import fast

    def kernel_interrupted_by(exc):
        def kernel(*args):
            raise SystemError("returned a result with an exception set") from exc
        return kernel

    with pytest.raises(KeyboardInterrupt):
        fast.run(kernel_interrupted_by(KeyboardInterrupt()))
    with pytest.raises(Terminated):
        fast.run(kernel_interrupted_by(Terminated(signal.SIGTERM)))
    def unpickling_interrupted(*args):          # three SystemErrors deep, as numba does
        try:
            kernel_interrupted_by(KeyboardInterrupt())()
        except SystemError as first:
            try:
                raise SystemError("returned a result with an exception set") from first
            except SystemError as second:
                raise SystemError("returned a result with an exception set") from second
    with pytest.raises(KeyboardInterrupt):
        fast.run(unpickling_interrupted)
    with pytest.raises(SystemError):            # any other SystemError stays what it is
        fast.run(kernel_interrupted_by(ValueError("x")))
    assert fast.run(lambda a, b: a + b, 2, 3) == 5


def test_lock_taker_removes_a_killed_writers_temporary_files(tmp_path):
    from gpme_io.out_lock import exclusive_output
    stale = tmp_path / ".history.csv.k3j2h1.tmp"
    stale.write_text("half a history")
    good = tmp_path / "history.csv"
    good.write_text("t,q\n0,0\n")
    with exclusive_output(tmp_path):
        assert not stale.exists() and good.read_text() == "t,q\n0,0\n"
