"""Read a URDF (any tree, through a chosen chain) into a gpme Model.

:func:`load_urdf` reads the descriptions people have: trees with grippers and sensors,
extension tags, friction and actuator limits.  What it does, in order (docs/urdf.md):

* **Chain.**  ``chain=(root, tip)``: the revolute, continuous (both -> gpme revolute)
  and prismatic joints on the path from link ``root`` to link ``tip`` are the gpme
  coordinates, in path order.  ``root`` defaults to the URDF's root link; ``tip`` may be
  omitted when the moving joints below ``root`` lie on one path.  gpme's world frame is
  the URDF root link's frame: everything fixed to it (links above ``root``, branches that
  do not move) is dropped, and the pose of ``root`` goes into the first joint's origin.
* **Frozen joints.**  Every other moving joint is frozen at ``frozen[name]`` (rad or m,
  default 0.0): it becomes a fixed joint with origin @ motion(value).  A mimic joint off
  the chain without a value follows the joint it mimics: multiplier * value + offset.
  Joints above ``root`` must be frozen explicitly (they would move the whole chain).
* **Merging.**  Every link hanging on a chain link through fixed or frozen joints adds its
  inertia to that chain link and becomes a named frame of the model.
* **Flexible links.**  ``flexible={link: FlexibleLink(...)}`` replaces the link's
  <inertial> by an RFEM beam (gpme_core.rfem); see :class:`FlexibleLink` for the beam's
  axis, length and section frame.  ``{link: (BeamProperties, n)}`` (beam along +x) still
  works.
* **Ignored, and said so.**  <dynamics friction>, effort and velocity limits,
  <safety_controller>, <calibration>, <transmission>, <gazebo>, <mujoco> and other
  extension tags, <mimic> on fixed joints, <visual> and <collision>, inertials on links
  that do not move: each class is named once in :attr:`UrdfReadResult.notes`.  A <limit>
  with lower == upper (URDF's default 0 = 0 when a <limit> gives only effort and
  velocity) is read as no range (unlimited) and noted.

Every problem, from every stage (XML, side file, inertials, joints, chain, frozen values,
flexible specs, the built model), comes in one :class:`gpme_core.errors.ModelFileError`.

The package, one module per stage (in the order of a read; docs/urdf.md):

* ``load``        : the entry points :func:`load_urdf`, :func:`read_urdf`, :func:`parse_urdf`
* ``read``        : one read stage by stage, :class:`UrdfReadResult`, the one ModelFileError
* ``parse``       : XML -> links, inertials and joints (``attributes``: numbers in attribute
                    text; ``inertial``: a link's <inertial>; ``joint``: a <joint>)
* ``notes``       : what was ignored or changed, one line per class of element
* ``tree``        : the tree (no cycle, no link the child of two joints), paths, the chain
* ``frozen``      : the values of the joints off the chain (given, mimicked or 0)
* ``placement``   : the chain and the chain link (or the world) every link is fixed to
* ``masses``      : which <inertial> problems matter, merged and dropped masses, sizes
* ``side_match``  : the side file's records against the chain
* ``beams``       : :class:`FlexibleLink` and the flexible links' beam plans
* ``build``       : the Model (ChainBuilder joints, bodies, beams, frames, drives)
* ``link_frames`` : :func:`with_link_frames`

The package is ``urdf_read``, not ``urdf``: ``gpme_io/urdf.py`` is already the module of
URDF in and out (reader, writer and side file in one import), and a package of the same
name would shadow it.  ``gpme_io.urdf_reader`` re-exports the names below, as before.
"""
from .beams import FlexibleLink, FlexibleSpec
from .link_frames import with_link_frames
from .load import load_urdf, parse_urdf, read_urdf
from .read import UrdfReadResult

__all__ = ["FlexibleLink", "FlexibleSpec", "UrdfReadResult", "load_urdf", "parse_urdf",
           "read_urdf", "with_link_frames"]
