"""One writer per --out (gpme_io/out_lock.py, filelock): a lock held by another process
refuses a second writer, naming the holder's pid; a killed holder leaves no stale lock;
busy_problem creates nothing."""
import os
import subprocess
import sys
import textwrap
import time

import pytest

from gpme_io.out_lock import (HOLDER_NAME, LOCK_NAME, OutputBusyError, busy_problem,
                              exclusive_output)

HOLD = textwrap.dedent("""
    import sys, time
    from gpme_io.out_lock import exclusive_output
    with exclusive_output(sys.argv[1]):
        print("held", flush=True)
        time.sleep(600)
""")


@pytest.fixture
def holder(tmp_path):
    """A child process holding tmp_path/out's lock (killed at the end)."""
    out = tmp_path / "out"
    child = subprocess.Popen([sys.executable, "-c", HOLD, str(out)], stdout=subprocess.PIPE,
                             text=True)
    assert child.stdout.readline().strip() == "held"
    yield out, child
    child.kill()
    child.wait(timeout=60)


def test_a_second_writer_is_refused_naming_the_holder(holder):
    out, child = holder
    with pytest.raises(OutputBusyError, match=f"another gpme run \\(pid {child.pid} on "):
        with exclusive_output(out):
            pass
    assert f"pid {child.pid}" in busy_problem(out)


def test_a_killed_holder_leaves_no_stale_lock(holder):
    out, child = holder
    child.kill()
    child.wait(timeout=60)
    assert busy_problem(out) is None
    with exclusive_output(out):
        assert (out / LOCK_NAME).exists()
        assert str(os.getpid()) in (out / HOLDER_NAME).read_text()


def test_busy_problem_creates_nothing(tmp_path):
    assert busy_problem(tmp_path / "new") is None
    assert not (tmp_path / "new").exists()


def test_the_same_process_cannot_write_twice(tmp_path):
    with exclusive_output(tmp_path):
        with pytest.raises(OutputBusyError):
            with exclusive_output(tmp_path):
                pass
    with exclusive_output(tmp_path):      # released after the block
        time.sleep(0)
