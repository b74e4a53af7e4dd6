"""What a report must name so it can be trusted later: versions, machine, date, commit."""
import os
import platform
import subprocess
import sys
import time
from importlib import metadata
from pathlib import Path


def _version(dist):
    try:
        return metadata.version(dist)
    except metadata.PackageNotFoundError:
        return "not installed"


def git_commit():
    """HEAD commit of the source tree (with '-dirty' for uncommitted changes) or 'unknown'."""
    src = Path(__file__).resolve().parent.parent
    try:
        head = subprocess.run(["git", "rev-parse", "HEAD"], cwd=src, capture_output=True,
                              text=True, timeout=10, check=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"],
                               cwd=src, capture_output=True, text=True, timeout=10).stdout.strip()
        return head + ("-dirty" if dirty else "")
    except (OSError, subprocess.SubprocessError):
        return "unknown"


def versions():
    """Versions of what can change a check's numbers: gpme, the four engines (Drake and
    Exudyn "not installed" when their optional extras are missing), the numerical
    libraries, the robot descriptions of the examples and Python (the diff against the
    previous run lists those that changed)."""
    return {"gpme": _version("gpme"), "pinocchio (pin)": _version("pin"),
            "mujoco": _version("mujoco"), "drake": _version("drake"),
            "exudyn": _version("exudyn"), "numpy": _version("numpy"),
            "scipy": _version("scipy"), "sympy": _version("sympy"), "numba": _version("numba"),
            "example-robot-data": _version("example-robot-data"),
            "python": sys.version.split()[0]}


def environment(**extra):
    """Dict of versions, machine, date and commit (plus ``extra``)."""
    return {
        "date_utc": time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime()),
        "git_commit": git_commit(),
        "versions": versions(),
        "machine": {"node": platform.node(), "platform": platform.platform(),
                    "processor": platform.processor() or platform.machine(),
                    "cpus": os.cpu_count()},
        **extra,
    }
