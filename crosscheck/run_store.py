"""The run directories of `gpme verify` under --out: a run is made in a hidden staging
directory and published whole, `latest` points at the newest, dead runs' leftovers are
removed, old runs pruned on request.

root/.<run_id>.<random>.partial  a run in progress (owner file: pid and host)
root/<run_id>[-k]                a published run (it has a summary.json)
root/latest                      symbolic link to the newest published run, replaced atomically
"""
import json
import os
import shutil
import socket
import tempfile
import time
from pathlib import Path

from gpme_core.errors import OutputWriteError
from gpme_io.atomic import atomic_write_text
from gpme_io.out_lock import exclusive_output

from .reports import run_diff

PARTIAL_SUFFIX = ".partial"
OWNER_FILE = ".owner.json"
# s: a staging directory without a readable owner (or from another host) older than this is
# taken as dead
STALE_AFTER_S = 2 * 86400.0


def claim_run_dir(root, run_id):
    """A fresh hidden staging directory root/.<run_id>.*.partial (mkdtemp: unique even for
    runs started in the same second) with an owner file naming this process (so that a
    later run can tell a dead run's leftovers from a live run's); publish picks the final
    name."""
    staging = None
    try:
        root.mkdir(parents=True, exist_ok=True)
        staging = Path(tempfile.mkdtemp(prefix=f".{run_id}.", suffix=PARTIAL_SUFFIX, dir=root))
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(staging, 0o777 & ~umask)  # mkdtemp's 0700 would hide the report from others
        atomic_write_text(staging / OWNER_FILE, json.dumps({"pid": os.getpid(),
                                                            "host": socket.gethostname()}))
    except OSError as exc:
        if staging is not None:
            shutil.rmtree(staging, ignore_errors=True)
        if isinstance(exc, OutputWriteError):
            raise
        raise OutputWriteError(staging or root, exc) from None
    return staging


def _owner_alive(staging):
    """Whether the run that made ``staging`` may still be running: its process exists on this
    host (or it belongs to another host, or says nothing, and is younger than STALE_AFTER_S)."""
    try:
        owner = json.loads((staging / OWNER_FILE).read_text())
        pid, host = int(owner["pid"]), owner["host"]
    except (OSError, ValueError, KeyError, TypeError):
        return time.time() - staging.stat().st_mtime < STALE_AFTER_S
    if host != socket.gethostname():
        return time.time() - staging.stat().st_mtime < STALE_AFTER_S
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:       # exists, another user's
        return True
    return True


def remove_dead_partials(root):
    """Remove root/.*.partial staging directories whose run is dead (killed with SIGKILL, a
    power cut: a run that could clean up did); returns their names."""
    removed = []
    for staging in sorted(Path(root).glob(f".*{PARTIAL_SUFFIX}")):
        if staging.is_dir() and not _owner_alive(staging):
            shutil.rmtree(staging, ignore_errors=True)
            removed.append(staging.name)
    return removed


def _run_dirs(root):
    """Published run directories of root (those with a summary.json), oldest first."""
    runs = [d for d in Path(root).iterdir()
            if d.is_dir() and not d.is_symlink() and not d.name.startswith(".")
            and (d / "summary.json").is_file()]
    return sorted(runs, key=lambda d: (d.stat().st_mtime, d.name))


def prune_runs(root, keep):
    """Keep the ``keep`` newest published runs of root (and whatever `latest` points at);
    remove the older ones; returns their names."""
    if keep is None:
        return []
    latest = root / "latest"
    current = latest.resolve() if latest.is_symlink() else None
    runs = _run_dirs(root)
    removed = []
    for d in runs[:max(0, len(runs) - keep)]:
        if current is not None and d.resolve() == current:
            continue
        shutil.rmtree(d, ignore_errors=True)
        removed.append(d.name)
    return removed


def publish(root, staging, run_id):
    """Rename staging to root/run_id (or run_id-2, -3, ... if taken); returns the path."""
    for k in range(1, 1000):
        name = run_id if k == 1 else f"{run_id}-{k}"
        final = root / name
        try:
            os.rename(staging, final)      # fails when final exists and is not empty
            return final, name
        except OSError:
            if not final.exists():
                raise
    raise FileExistsError(f"no free run directory name for {run_id} in {root}")


def previous_report(root, compare_to=None):
    """(summary.json document or None, where it was looked for, one-line note or None): the
    report to diff this run against, read before the run starts: ``compare_to`` (a report
    directory or its summary.json) or the run root/latest points at."""
    if compare_to is not None:
        data, note = run_diff.load_previous(compare_to)
        return data, str(compare_to), note
    latest = Path(root) / "latest"
    if not (latest.is_symlink() or latest.exists()):
        return None, str(latest), (f"no previous run in {root} ({latest} does not exist): "
                                   "nothing to compare with")
    data, note = run_diff.load_previous(latest)
    target = os.readlink(latest) if latest.is_symlink() else latest.name
    return data, str(Path(root) / target), note


def point_latest(root, run_id):
    tmp = root / f".latest.{os.getpid()}.tmp"
    try:
        if tmp.is_symlink() or tmp.exists():
            tmp.unlink()
        os.symlink(run_id, tmp)
        os.replace(tmp, root / "latest")
    except OSError as exc:
        raise OutputWriteError(root / "latest", exc) from None


def publish_run(root, staging, run_id):
    """Publish the complete run in ``staging`` as root/run_id (or run_id-k) and point
    `latest` at it, one publisher at a time (the --out lock); returns its path."""
    (staging / OWNER_FILE).unlink()
    with exclusive_output(root):            # one publisher at a time: name and `latest`
        final, run_id = publish(root, staging, run_id)
        point_latest(root, run_id)
    return final
