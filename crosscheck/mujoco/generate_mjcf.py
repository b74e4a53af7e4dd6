"""Write or check the committed MJCF files under models/mjcf/.

    python -m crosscheck.mujoco.generate_mjcf            # (re)write every file
    python -m crosscheck.mujoco.generate_mjcf --check    # exit 1 when a committed file drifted

Files (each written by crosscheck.mujoco.mjcf through ElementTree, compared byte for byte by
--check, and loaded with mujoco.MjModel.from_xml_path by tests/test_mjcf.py):

* crane_rigid.xml, crane_flexible_n{1,2,3}.xml: the crane alone, keyframe "start" = the
  paper's off-manifold initial state (at rest).
* crane_rigid_programmed.xml, crane_flexible_n{1,2,3}_programmed.xml: with the auxiliary
  mechanism enforcing the programmed constraints, keyframe "start" = the consistent
  initial state at t = 0 (auxiliary coordinates included, crank turning at 2 pi / T).

The timestep is the largest RK4 step at which the model is stable and accurate (measured:
n = 0, 1: 1e-4 s; n = 2: 2.5e-5 s; n = 3: 1e-5 s; the RFEM's Kelvin-Voigt damping of the
stiff torsion modes limits it) and the mechanism's timeconst equals it.
"""
import argparse
import sys
from pathlib import Path

from gpme_examples.crane import build_crane, crane_constraints, crane_system, initial_state
from gpme_io.atomic import atomic_write_text

from .mjcf import mjcf_text
from .mechanism import MechanismSettings

DEFAULT_DIR = Path(__file__).resolve().parents[2] / "models" / "mjcf"
TIMESTEPS = {0: 1e-4, 1: 1e-4, 2: 2.5e-5, 3: 1e-5}   # s, by number of RFEM segments
KEYFRAME_DIGITS = 12   # round the keyframe so round-off changes in gpme_core do not drift it


def _rounded(v):
    return [float(f"{x:.{KEYFRAME_DIGITS}g}") for x in v]


def mjcf_documents():
    """{file name: MJCF text} of every committed model."""
    docs = {}
    for n, dt in TIMESTEPS.items():
        stem = "crane_rigid" if n == 0 else f"crane_flexible_n{n}"
        model = build_crane(n)
        q0, qd0 = initial_state(model)
        docs[f"{stem}.xml"] = mjcf_text(model, dt, initial_state=(_rounded(q0), _rounded(qd0)))
        system = crane_system(n)
        q, qd = system.consistent_state(0.0, q0, qd0)
        docs[f"{stem}_programmed.xml"] = mjcf_text(
            model, dt, crane_constraints(), MechanismSettings(timeconst=dt),
            initial_state=(_rounded(q), _rounded(qd)))
    return docs


def generate_mjcf(out_dir=DEFAULT_DIR):
    """Write every document to out_dir (atomically); returns {file name: text}."""
    docs = mjcf_documents()
    for name, text in docs.items():
        atomic_write_text(Path(out_dir) / name, text)
    return docs


def drift(out_dir=DEFAULT_DIR):
    """List of problems: files missing, differing from the generator, or extra."""
    out_dir = Path(out_dir)
    problems = []
    docs = mjcf_documents()
    for name, text in docs.items():
        path = out_dir / name
        if not path.exists():
            problems.append(f"{path}: missing")
        elif path.read_bytes() != text.encode("utf-8"):
            old = path.read_bytes().decode("utf-8", errors="replace").splitlines()
            new = text.splitlines()
            first = next((k for k, (a, b) in enumerate(zip(old, new)) if a != b), min(len(old), len(new)))
            problems.append(f"{path}: differs from the generator from line {first + 1}")
    for path in sorted(out_dir.glob("*.xml")):
        if path.name not in docs:
            problems.append(f"{path}: not produced by the generator (remove it)")
    return problems


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="fail when committed files drifted")
    parser.add_argument("--out", type=Path, default=DEFAULT_DIR)
    args = parser.parse_args(argv)
    if args.check:
        problems = drift(args.out)
        if problems:
            print("MJCF drift (run python -m crosscheck.mujoco.generate_mjcf):\n  " + "\n  ".join(problems))
            return 1
        print(f"{len(mjcf_documents())} MJCF files in {args.out} match the generator")
        return 0
    try:
        docs = generate_mjcf(args.out)
    except OSError as exc:
        print(f"error: cannot write the MJCF files to {args.out}: {exc.strerror or exc}",
              file=sys.stderr)
        return 2
    print(f"wrote {len(docs)} MJCF files to {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
