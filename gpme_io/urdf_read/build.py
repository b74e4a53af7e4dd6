"""The gpme Model of a placed chain: joints, bodies, beams, frames, drives, RFEM records.

Input is what the earlier stages found (gpme_io.urdf_read.placement: the chain and where
every link sits; beams: the flexible links' plans; side_match: the side file's springs,
drives and RFEM records).  The ChainBuilder checks the assembled model; its problems come
back as a ModelError.
"""
import numpy as np
from numpy.typing import NDArray

from gpme_core import transforms as tf
from gpme_core.model import (REVOLUTE, STANDARD_GRAVITY, WORLD, ChainBuilder, Model,
                             validate_model)
from gpme_core.rfem import BeamProperties, FlexibleLinkInfo

from ..side_file import drive_function
from .joint import _MOVING


def _builder(robot, side, gravity, name, notes) -> ChainBuilder:
    """An empty ChainBuilder named ``name``, else the side file's model name, else the
    <robot> name, else "urdf" (noted); gravity (3,) m/s^2 ``gravity``, else the side
    file's, else (0, 0, -9.81)."""
    g = gravity if gravity is not None else side.get("gravity", STANDARD_GRAVITY)
    robot_name = (robot.get("name") or "").strip()
    if not (name or side.get("model") or robot_name):
        notes.line("<robot> without a name: the model is named 'urdf'")
    return ChainBuilder(name or side.get("model") or robot_name or "urdf", gravity=g)


def _assemble(builder, chain, parents, placement, side_use, inertias, flexible, plans,
              notes, shapes=None) -> tuple:
    """(Model, frame names): the chain's joints with the side file's springs, each chain
    link's body or beam, the links merged into it (mass and frame), the side file's drives
    and RFEM records; raises ModelError with the built model's problems.

    parents  : [parent index of each chain joint, -1 the world] (a chain: k - 1)
    inertias : {link: RigidBodyInertia or None}
    flexible : {link: FlexibleSpec}; plans: {link: beam plan or None (invalid spec)}
    shapes   : {link: [gpme_io.urdf_read.shapes.link_shapes tuple]}: what the moving links
               look like, placed on their chain link like their mass
    """
    shapes = shapes or {}
    frames = []
    # {k: (builder link that ends URDF link k: its beam's last segment if flexible, the
    # correction of link k's frame for what hangs on it: the beam tip)}
    ends = {}
    for k, j in enumerate(chain.joints):
        spring = side_use.joints.get(j.name, {})
        p = parents[k]
        end_link, after_p = ends.get(p, (WORLD, np.eye(4)))
        if end_link == (builder.current_link or WORLD):
            end_link = None              # continues the newest link: a serial chain's joint
        builder.add_joint(j.name, _MOVING.get(j.type, REVOLUTE), j.axis,
                          origin=after_p @ placement.chain_origin[k],
                          stiffness=spring.get("stiffness", 0.0),
                          spring_reference=spring.get("spring_reference", 0.0),
                          damping=j.damping, link=j.child, limits=j.limits, parent=end_link)
        after = _add_link_mass(builder, j.child, flexible, plans.get(j.child), inertias, notes)
        ends[k] = (builder.current_link, after)
        # a chain link's own shapes (a flexible link has none: its elements' instead)
        _add_shapes(builder, shapes.get(j.child, ()), np.eye(4))
        for x in placement.attached.get(k, []):
            if inertias.get(x) is not None:
                builder.add_body(inertias[x], origin=after @ placement.pose[x])
            _add_shapes(builder, shapes.get(x, ()), after @ placement.pose[x])
            builder.add_frame(x, after @ placement.pose[x])
            frames.append(x)
    for rec in side_use.drives:
        builder.add_drive(rec["joint"], drive_function(rec))
    for rec in side_use.point_springs:
        builder.add_point_spring(rec["name"], rec["frame"], rec["anchor"], rec["stiffness"],
                                 rec["free_length"], rec.get("damping", 0.0))
    model = builder.build()
    return _with_flexible_records(model, side_use.flexible, flexible), tuple(frames)


def _add_shapes(builder, shapes, placed) -> None:
    """Attach ``shapes`` (link_shapes tuples, each in its URDF link's frame) to the
    builder's newest link, that URDF link's frame being ``placed`` (4, 4) in it."""
    for role, kind, size, origin, mesh, rgba in shapes:
        builder.add_shape(kind, size, placed @ origin, role=role, mesh=mesh, rgba=rgba)


def _add_link_mass(builder, link, flexible, plan, inertias, notes) -> NDArray[np.float64]:
    """Add chain link ``link``'s own mass to the builder's newest link: its RFEM beam
    (``plan``, noted) when it is flexible, else its <inertial> if any (also for a flexible
    link whose spec has problems, reported already: built rigid so that the model's own
    problems, if any, are not artefacts of the missing beam).  Returns the (4, 4)
    correction of the link frame for what hangs on it: inv(B @ translation(L)) for a
    beam (its tip), identity otherwise."""
    if link in flexible and plan is not None:
        beam, n, t_beam = plan
        builder.add_beam(link, beam, n, frame=t_beam)
        after = tf.inverse(t_beam @ tf.translation(beam.length))
        was = inertias.get(link)
        notes.line(f"link {link}: URDF inertial "
                   f"{'none' if was is None else f'{was.mass:g} kg'} replaced by "
                   f"the RFEM beam {beam.mass:.6g} kg ({n} segments, length "
                   f"{beam.length:.6g} m)")
        return after
    if inertias.get(link) is not None:
        builder.add_body(inertias[link])
    return np.eye(4)


def _with_flexible_records(model, side_flex, flexible) -> Model:
    """Add the side file's RFEM records (beams not re-discretised on reading; their joints
    and links checked to be in the chain)."""
    records = list(model.flexible_links)
    link_names = [lk.name for lk in model.links]
    for name, rec in side_flex.items():
        if name in flexible:
            continue
        joints = tuple(model.index(j) for j in rec["joints"])
        links = tuple(link_names.index(lk) for lk in rec["links"])
        records.append(FlexibleLinkInfo(name, BeamProperties(**rec["beam"]), rec["n_segments"],
                                        joints, links))
    if len(records) == len(model.flexible_links):
        return model
    order = {lk.name: k for k, lk in enumerate(model.links)}
    records.sort(key=lambda r: order.get(r.name, -1))
    out = Model(model.joints, model.links, model.frames, model.drives, model.gravity, records,
                model.name, model.geometry, model.point_springs)
    validate_model(out)
    return out
