"""Frames named after links: what a model file's constraint on a moving link refers to."""
import numpy as np

from gpme_core.errors import ModelError
from gpme_core.model import Frame, Model, validate_model


def with_link_frames(model: Model, names) -> Model:
    """``model`` with a frame named after each link in ``names`` at that link's own frame
    (identity transform), for the links that have no frame of that name yet: the frames a
    model file gives a constraint on a moving link, which gpme_io.urdf_writer leaves implicit
    in the URDF link itself (ModelError for a name that is not a link)."""
    index = {lk.name: k for k, lk in enumerate(model.links)}
    missing = [n for n in names if n not in model.frames]
    unknown = [n for n in missing if n not in index]
    if unknown:
        raise ModelError(f"no links named {unknown} to give a frame; the links are "
                         f"{sorted(index)}")
    if not missing:
        return model
    frames = dict(model.frames)
    frames.update({n: Frame(n, index[n], np.eye(4)) for n in missing})
    out = Model(model.joints, model.links, frames, model.drives, model.gravity,
                model.flexible_links, model.name, model.geometry, model.point_springs)
    validate_model(out)
    return out
