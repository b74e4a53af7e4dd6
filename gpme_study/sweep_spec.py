"""A sweep description, read and validated: the built-in crane's (gpme_study.spec) or, with
a top-level ``model = "path/to/file.toml"``, a model file's (gpme_study.model_spec).  The
one place that chooses between them."""
from pathlib import Path

from .model_spec import model_spec_from_dict
from .spec import crane_spec_from_dict
from .spec_points import read_spec_file


def spec_from_dict(data, base_dir=None):
    """Validated gpme_study.spec_points.SweepSpec from a dict (TOML/YAML schema:
    gpme_study.spec's docstring; docs/sweep.md).

    base_dir : folder a relative ``model`` path is taken from (default: the current one)
    """
    data = dict(data or {})
    if "model" in data:
        return model_spec_from_dict(data, base_dir)
    return crane_spec_from_dict(data)


def load_spec(path):
    """SweepSpec from a TOML (.toml) or YAML (.yaml, .yml) file (a ``model`` path in it is
    relative to the file's folder)."""
    return spec_from_dict(read_spec_file(path), base_dir=Path(path).parent)
