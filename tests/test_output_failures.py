"""A full disk, a read-only file system or a folder removed mid-run (issue 24): one error line
naming the file that could not be written and the space left, exit status 74 (EX_IOERR,
docs/ci.md), nothing half-written, the last good report and ``latest`` unchanged.

Real file systems where the machine allows it (a 64 kB tmpfs, mounted as root; skipped
otherwise), and the error paths of gpme_io.atomic with the operating system's errors
injected in-process.
"""
import errno
import os
import subprocess
import sys
from pathlib import Path

import pytest

from gpme_io import atomic
from gpme_core.errors import GpmeError, OutputWriteError

ROOT = Path(__file__).resolve().parents[1]
MY_ARM = ROOT / "examples" / "my_arm" / "my_arm.toml"
EXIT_WRITE = 74
TIMEOUT_S = 600                 # hang guard only


# ------------------------------------------------------------------ atomic writes, in-process
@pytest.mark.parametrize("code,words", [(errno.ENOSPC, "No space left on device"),
                                        (errno.EROFS, "Read-only file system"),
                                        (errno.EDQUOT, "quota")])
def test_failed_write_names_the_file_and_keeps_the_old_one(tmp_path, monkeypatch, code, words):
    target = tmp_path / "report.csv"
    target.write_text("the good report")

    def failing_fsync(fd):
        raise OSError(code, os.strerror(code))
    monkeypatch.setattr(atomic.os, "fsync", failing_fsync)
    with pytest.raises(OutputWriteError) as info:
        atomic.atomic_write_text(target, "a new report that does not fit")
    message = str(info.value)
    assert message.startswith(f"cannot write {target}: ") and words.lower() in message.lower()
    assert "free in" in message
    assert isinstance(info.value, GpmeError) and isinstance(info.value, OSError)
    assert info.value.errno == code
    assert target.read_text() == "the good report"
    assert [p.name for p in tmp_path.iterdir()] == ["report.csv"]     # no temporary left


def test_folder_removed_mid_run(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    os.rmdir(out)
    (tmp_path / "out").write_text("a file where the folder was")     # mkdir cannot recreate it
    with pytest.raises(OutputWriteError, match=r"cannot write .*out/run\.csv"):
        atomic.atomic_write_text(out / "run.csv", "x")


# ------------------------------------------------------------------ real small file systems
@pytest.fixture
def tiny_fs(tmp_path):
    """A 64 kB tmpfs at tmp_path/fs (root only; skipped where mounting is not allowed)."""
    mount = tmp_path / "fs"
    mount.mkdir()
    done = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", str(mount)],
                          capture_output=True, text=True)
    if done.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {done.stderr.strip()}")
    yield mount
    subprocess.run(["umount", "-l", str(mount)], capture_output=True)


def _gpme(argv, timeout=TIMEOUT_S):
    return subprocess.run([sys.executable, "-m", "gpme.cli", *argv, "--no-progress"],
                          cwd=ROOT, capture_output=True, text=True, timeout=timeout)


def _one_error_line(proc):
    err = proc.stderr.strip()
    assert "Traceback" not in err and "please report it" not in err, err
    lines = [ln for ln in err.splitlines() if ln.startswith("error:")]
    assert len(lines) == 1, err
    return lines[0]


def test_simulate_on_a_full_disk(tiny_fs):
    proc = _gpme(["simulate", "--model", str(MY_ARM), "--t-end", "0.5", "--out",
                  str(tiny_fs / "out")])
    assert proc.returncode == EXIT_WRITE, proc.stderr[-2000:]
    line = _one_error_line(proc)
    assert "cannot write" in line and "No space left on device" in line and "free in" in line
    assert not list(tiny_fs.rglob(".*.tmp"))          # nothing half-written


def test_simulate_on_a_read_only_file_system(tiny_fs):
    (tiny_fs / "out").mkdir()
    subprocess.run(["mount", "-o", "remount,ro", str(tiny_fs)], check=True)
    proc = _gpme(["simulate", "--model", str(MY_ARM), "--t-end", "0.2", "--out",
                  str(tiny_fs / "out")])
    assert proc.returncode in (EXIT_WRITE, 2), proc.stderr[-2000:]
    line = _one_error_line(proc)
    assert "Read-only file system" in line


@pytest.mark.parametrize("left", [4096, 30000], ids=["at-the-start", "mid-report"])
def test_verify_on_a_full_disk_keeps_latest(tiny_fs, left):
    """A good report in place (latest points at it), then the disk is filled up to ``left`` bytes:
    the run stops with one line, its partial directory is removed, latest unchanged."""
    out = tiny_fs / "reports"
    out.mkdir()
    good = out / "20260101-000000-quick"
    good.mkdir()
    (good / "summary.json").write_text("{}")
    os.symlink(good.name, out / "latest")
    free = os.statvfs(tiny_fs).f_bavail * os.statvfs(tiny_fs).f_frsize
    (tiny_fs / "filler").write_bytes(b"\0" * max(0, free - left))
    proc = _gpme(["verify", "--quick", "--only", "gpme", "--model", str(MY_ARM), "--out",
                  str(out)])
    assert proc.returncode == EXIT_WRITE, (proc.stdout[-2000:], proc.stderr[-2000:])
    line = _one_error_line(proc)
    assert "cannot write" in line and "free in" in line
    assert os.readlink(out / "latest") == good.name
    assert (good / "summary.json").read_text() == "{}"
    assert sorted(p.name for p in out.iterdir() if not p.name.startswith(".gpme.lock")) == \
        sorted(["latest", good.name])
