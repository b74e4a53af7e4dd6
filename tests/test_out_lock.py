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


def test_a_finished_writer_leaves_no_lock_files(tmp_path):
    """issue 28: `.gpme.lock` and its holder file do not stay in the user's folder."""
    with exclusive_output(tmp_path):
        assert (tmp_path / LOCK_NAME).exists() and (tmp_path / HOLDER_NAME).exists()
    assert not (tmp_path / LOCK_NAME).exists() and not (tmp_path / HOLDER_NAME).exists()
    with exclusive_output(tmp_path):     # and the folder can be taken again
        pass
    assert sorted(p.name for p in tmp_path.iterdir()) == []


def test_a_lock_on_a_removed_file_is_seen_and_retaken(tmp_path, monkeypatch):
    """The race that removing lock files opens: a taker that locked the file a finishing
    holder removed must not think it holds the folder (a third process holds the new file).
    The inode check sees it, and the taker retakes the lock on the file the path names."""
    from filelock import FileLock

    from gpme_io import out_lock
    path = tmp_path / LOCK_NAME
    early = FileLock(str(path), timeout=0, is_singleton=False, thread_local=False)
    early.acquire()                                  # opened before the holder removed it
    inode = out_lock._locked_inode(early)
    assert inode is not None and out_lock._names_file(path, inode)
    path.unlink()
    path.write_text("")                             # the new lock file of a third process
    assert not out_lock._names_file(path, inode)     # the taker sees it holds a removed file
    early.release()
    seen = []
    real = out_lock._names_file

    def first_removed(p, i):
        seen.append(i)
        return len(seen) > 1 and real(p, i)
    monkeypatch.setattr(out_lock, "_names_file", first_removed)
    with exclusive_output(tmp_path):
        assert len(seen) == 2                        # taken, found removed, taken again
