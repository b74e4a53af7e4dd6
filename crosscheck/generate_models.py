"""Generate the committed model files, or check that they match the generator.

    python -m crosscheck.generate_models urdf            # (re)write models/urdf/
    python -m crosscheck.generate_models urdf --check    # exit 1 if a file drifted

URDF part: the crane with the rigid arm and with the RFEM arm for n = 1, 3, 10
segments, each as ``<name>.urdf`` plus its side file ``<name>.gpme.json``
(gpme_io/urdf.py, docs/urdf.md).
"""
import argparse
import sys
from pathlib import Path

from gpme_examples.crane import build_crane
from gpme_io.atomic import atomic_write_text
from gpme_io.file_names import named_path

from gpme_io.urdf import side_file_path, side_file_text, urdf_documents

REPO_ROOT = Path(__file__).resolve().parent.parent
URDF_DIR = REPO_ROOT / "models" / "urdf"
# n_rfe of the committed crane files: 0 = rigid arm
URDF_CRANE_SEGMENTS = (0, 1, 3, 10)


def generate_urdf(out_dir=URDF_DIR):
    """{file name: text} of every generated URDF and side file (nothing is written).

    out_dir is only used to name the side files beside the URDFs; the names are the
    model names (``crane_rigid``, ``crane_flexible_n<k>``).
    """
    files = {}
    for n in URDF_CRANE_SEGMENTS:
        model = build_crane(n)
        urdf_path = named_path(out_dir, model.name, ".urdf")
        text, side = urdf_documents(model, urdf_name=urdf_path.stem)
        files[urdf_path.name] = text
        files[side_file_path(urdf_path).name] = side_file_text(side)
    return files


def check_files(out_dir, files):
    """Problems (list of str) where the files in out_dir differ from ``files``."""
    problems = []
    for name, text in files.items():
        path = Path(out_dir) / name
        if not path.exists():
            problems.append(f"{path}: missing")
        elif path.read_text(encoding="utf-8") != text:
            problems.append(f"{path}: differs from the generator")
    return problems


def write_files(out_dir, files):
    """Write every file atomically; returns the paths written."""
    paths = []
    for name, text in files.items():
        path = Path(out_dir) / name
        atomic_write_text(path, text)
        paths.append(path)
    return paths


def main(argv=None):
    parser = argparse.ArgumentParser(prog="python -m crosscheck.generate_models",
                                     description=__doc__.splitlines()[0])
    parser.add_argument("kind", choices=["urdf"], help="which model files")
    parser.add_argument("--check", action="store_true",
                        help="compare the committed files with the generator; exit 1 on drift")
    parser.add_argument("--out", type=Path, default=None, help="directory (default models/<kind>)")
    args = parser.parse_args(argv)
    out_dir = args.out or URDF_DIR
    files = generate_urdf(out_dir)
    if args.check:
        problems = check_files(out_dir, files)
        for p in problems:
            print(p, file=sys.stderr)
        if problems:
            print("regenerate with: python -m crosscheck.generate_models urdf", file=sys.stderr)
            return 1
        print(f"{len(files)} files in {out_dir} match the generator")
        return 0
    for path in write_files(out_dir, files):
        print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
