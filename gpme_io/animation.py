"""The motion of a run in 3D: one self-contained HTML file that plays it offline.

Made with Meshcat, the viewer Pinocchio's and Drake's visualisers use: its three.js viewer
(the ``meshcat`` package's ``viewer/dist/main.min.js``, inlined) replays a list of
drawing commands embedded in the page, as Meshcat's own static HTML export does, so nothing
is fetched and no server runs.  The scene:

- every visual shape of the model (gpme_core.geometry; mesh files STL, OBJ, DAE embedded
  while they fit the size budget, else left out; a model without shapes as a stick figure
  of its joints) on its link, the links moved through the run's recorded states;
- the elastic deflection magnified ``magnification`` times: every RFEM coordinate drawn at
  spring_reference + magnification x (q - spring_reference), the rigid coordinates as
  recorded (the page's title says the factor; 1 draws the motion as computed);
- the path of every constrained frame (the recorded x_F, y_F, z_F) as a line, the
  programmed path once the Baumgarte transient has passed;
- a second run of the same model (another engine's, ``overlay``) as a translucent ghost.

Frames are subsampled so the file stays under ``max_bytes`` (default 3 MB).
"""
import base64
import json
import logging
from pathlib import Path

import numpy as np

from gpme_core.geometry import ELEMENT_RGBA, RIGID_RGBA, Shape, member
from gpme_core import transforms as tf
from gpme_core.kinematics import link_transforms

from .atomic import atomic_write_text

log = logging.getLogger("gpme.animation")

# the largest page written (bytes): the viewer is ~0.85 MB, the rest the scene and frames
MAX_BYTES = 3_000_000
# frames per second of the replay and the most frames kept (subsampled evenly)
FPS = 30
MAX_FRAMES = 600
# bytes of embedded mesh files at most (beyond, meshes are left out and the page says so)
MAX_MESH_BYTES = 1_200_000
DEFAULT_MAGNIFICATION = 20.0
_MESH_FORMATS = {".stl": "stl", ".obj": "obj", ".dae": "dae"}


def _meshcat():
    """meshcat's modules (an optional dependency: the `animation` extra)."""
    import meshcat.animation as animation     # meshcat: imported when a page is written
    import meshcat.commands as commands
    import meshcat.geometry as geometry
    import meshcat.path as path
    import umsgpack
    return animation, commands, geometry, path, umsgpack


def viewer_script() -> str:
    """The text of Meshcat's viewer bundle (three.js included)."""
    import meshcat                            # meshcat: imported when a page is written
    return (Path(meshcat.__file__).parent / "viewer" / "dist" / "main.min.js").read_text(
        encoding="utf-8")


def _colour(rgba):
    r, g, b = (int(round(255 * c)) for c in (rgba or (0.7, 0.7, 0.7, 1.0))[:3])
    return (r << 16) | (g << 8) | b


def _material(mc_geometry, shape, opacity):
    """The shape's colour, at ``opacity`` (a ghost run is translucent)."""
    return mc_geometry.MeshLambertMaterial(color=_colour(shape.rgba), opacity=opacity,
                                           transparent=opacity < 1.0)


def _shape_object(shape, mc_geometry, mesh_budget):
    """(meshcat geometry, (4, 4) correction) of a shape, or None when it cannot be drawn
    (a mesh over the budget or of another format)."""
    fix = np.eye(4)
    if shape.kind == "box":
        return mc_geometry.Box(list(shape.size)), fix
    if shape.kind == "sphere":
        return mc_geometry.Sphere(shape.size[0]), fix
    if shape.kind == "cylinder":
        # three.js cylinders run along y, URDF's along z: turned +90 deg about x
        return mc_geometry.Cylinder(shape.size[1], shape.size[0]), tf.rot_x(np.pi / 2)
    fmt = _MESH_FORMATS.get(Path(shape.mesh).suffix.lower())
    path = Path(shape.mesh)
    if fmt is None or not path.is_file() or path.stat().st_size > mesh_budget[0]:
        return None
    mesh_budget[0] -= path.stat().st_size
    # the files' classmethods, not the format classes (whose constructors fail in
    # meshcat 0.3.2): STL as bytes, OBJ and DAE as text
    reader = {"stl": mc_geometry.StlMeshGeometry, "obj": mc_geometry.ObjMeshGeometry,
              "dae": mc_geometry.DaeMeshGeometry}[fmt]
    scale = np.diag(list(shape.size) + [1.0])
    return reader.from_file(str(path)), scale


def stick_shapes(model):
    """Shapes of a model that has none (a URDF without <visual>): a sphere at every joint
    and a rod from each joint to the next (and to every named frame), sized from the
    model's reach at its spring references, so that every model can be watched."""
    n = model.n_coordinates
    ends = {k: [] for k in range(n)}
    for k in range(n - 1):
        ends[k].append(np.asarray(model.joints[k + 1].origin, float)[:3, 3])
    for frame in model.frames.values():
        ends[frame.link_index].append(np.asarray(frame.transform, float)[:3, 3])
    reach = sum(np.linalg.norm(e) for tips in ends.values() for e in tips) or 1.0
    radius = 0.015 * reach
    shapes = []
    for k in range(n):
        shapes.append(Shape(k, "sphere", (1.5 * radius,), role="visual", rgba=RIGID_RGBA))
        for tip in ends[k]:
            length = float(np.linalg.norm(tip))
            if length < 1e-9:
                continue
            x = tip / length                          # the rod's axis, a frame with x on it
            y = np.cross(x, [0.0, 0.0, 1.0] if abs(x[2]) < 0.9 else [1.0, 0.0, 0.0])
            y /= np.linalg.norm(y)
            frame = np.eye(4)
            frame[:3, :3] = np.column_stack([x, y, np.cross(x, y)])
            kind, size, origin = member(length, radius, radius, True, frame)
            shapes.append(Shape(k, kind, size, origin, "visual", rgba=ELEMENT_RGBA))
    return shapes


def _drawn_shapes(shapes, mc_geometry, budget):
    """[(shape, (geometry, correction))] of what is seen, each mesh read once: each link's visual shapes, or its collision shapes
    when a visual one cannot be drawn (a mesh over the size budget, as a robot's detailed
    .dae often is, or of a format the viewer does not read; collision meshes are usually
    the coarse ones)."""
    by_link = {}
    for shape in shapes:
        by_link.setdefault(shape.link_index, []).append(shape)
    out = []
    for group in by_link.values():
        visual = [s for s in group if s.is_visual]
        drawn = [(s, _shape_object(s, mc_geometry, budget)) for s in visual]
        if not visual or any(d is None for _, d in drawn):
            collision = [s for s in group if s.is_collision and not s.is_visual]
            if collision:
                drawn = [(s, _shape_object(s, mc_geometry, budget)) for s in collision]
        out += [(s, d) for s, d in drawn if d is not None]
    return out


def displayed(model, q, magnification):
    """(n,) coordinates drawn: the RFEM ones magnified about their spring reference."""
    q = np.array(q, dtype=float)
    flex = [model.index(c) for c in model.flexible_coordinates]
    ref = model.spring_reference[flex]
    q[flex] = ref + magnification * (q[flex] - ref)
    return q


def frame_rows(n_rows, max_frames=MAX_FRAMES):
    """Indices of the recorded rows drawn: all, or ``max_frames`` spread evenly with the
    first and the last."""
    if n_rows <= max_frames:
        return np.arange(n_rows)
    return np.unique(np.linspace(0, n_rows - 1, max_frames).round().astype(int))


def motion_page(model, df, title, magnification=DEFAULT_MAGNIFICATION, constrained=(),
                overlay=None, max_bytes=MAX_BYTES) -> str:
    """The HTML text of the animation of run ``df`` (a history DataFrame of ``model``,
    gpme_core.integrate.simulate's columns); ``constrained``: frame names whose recorded
    path is drawn; ``overlay``: (label, DataFrame with the same coordinate columns) drawn
    as a ghost.  Raises ValueError when even the fewest frames exceed ``max_bytes``."""
    script = viewer_script()
    for frames in (MAX_FRAMES, MAX_FRAMES // 4, MAX_FRAMES // 16):
        commands = _scene_commands(model, df, magnification, constrained, overlay, frames)
        page = _page(script, commands, title, magnification, model, overlay)
        if len(page.encode("utf-8")) <= max_bytes:
            return page
    raise ValueError(f"the animation of {model.name} needs {len(page) / 1e6:.1f} MB with "
                     f"{MAX_FRAMES // 16} frames, above {max_bytes / 1e6:g} MB")


def _scene_commands(model, df, magnification, constrained, overlay, max_frames) -> list:
    """msgpack-packed Meshcat commands: the objects, their shape offsets, the path lines
    and the animation of every link."""
    animation, commands, mc_geometry, mc_path, umsgpack = _meshcat()
    names = list(model.coordinate_names)
    rows = frame_rows(len(df), max_frames)
    out = []
    anim = animation.Animation(default_framerate=FPS)
    runs = [("gpme", df, 1.0)] + ([(overlay[0], overlay[1], 0.35)] if overlay else [])
    shapes = model.geometry or stick_shapes(model)
    # every run embeds the meshes again (one object per run): the budget is shared out
    drawn = _drawn_shapes(shapes, mc_geometry, [MAX_MESH_BYTES // len(runs)])
    for label, run, opacity in runs:
        base = mc_path.Path(("meshcat", "robot", _safe(label)))
        for k, (shape, (geometry, fix)) in enumerate(drawn):
            where = base.append(f"link{shape.link_index}/shape{k}")
            material = _material(mc_geometry, shape, opacity)
            out.append(commands.SetObject(geometry, material, where).lower())
            out.append(commands.SetTransform(shape.origin_array @ fix, where).lower())
        q_all = run[names].to_numpy(float)
        links = sorted({s.link_index for s in shapes})
        for frame, r in enumerate(frames_of(rows, len(run))):
            t_links = link_transforms(model, displayed(model, q_all[r], magnification))
            for link in links:
                animation.AnimationFrameVisualizer(
                    anim, base.append(f"link{link}"), frame).set_transform(t_links[link])
    for name in constrained:
        cols = [f"{a}_{name}" for a in "xyz"]
        if all(c in df for c in cols):
            points = df[cols].to_numpy(float).T
            line = mc_geometry.Line(mc_geometry.PointsGeometry(points),
                                    mc_geometry.LineBasicMaterial(color=0xd62728))
            out.append(commands.SetObject(line, path=mc_path.Path(
                ("meshcat", "paths", _safe(name)))).lower())
    out.append(_camera(commands, mc_path, model, df[names].to_numpy(float)[rows]))
    out.append(commands.SetAnimation(anim, play=True, repetitions=1000).lower())
    return [umsgpack.packb(c) for c in out]


def _camera(commands, mc_path, model, q_rows):
    """The camera placed to see every link's origin over the run: from the front-right and
    above the middle of their bounding box, at about twice its size (the path
    /Cameras/default/rotated/<object> takes world coordinates, z up)."""
    origins = np.array([t[:3, 3] for q in q_rows[:: max(1, len(q_rows) // 20)]
                        for t in link_transforms(model, q)])
    low, high = origins.min(axis=0), origins.max(axis=0)
    size = max(float(np.linalg.norm(high - low)), 0.5)
    eye = 0.5 * (low + high) + size * np.array([0.9, -1.2, 0.7])
    return commands.SetProperty("position", [float(v) for v in eye],
                                mc_path.Path(("Cameras", "default", "rotated",
                                              "<object>"))).lower()


def frames_of(rows, n_rows):
    """The drawn rows that exist in a run of ``n_rows`` rows (an overlay may be shorter)."""
    return [int(r) for r in rows if r < n_rows]


def _safe(label):
    return "".join(ch if ch.isalnum() or ch in "-_" else "_" for ch in str(label)) or "run"


def _page(script, packed, title, magnification, model, overlay) -> str:
    """The HTML page: the viewer script, then each command replayed in order."""
    blobs = json.dumps([base64.b64encode(p).decode("ascii") for p in packed])
    note = (f"{model.name}: {title}; elastic deflection x{magnification:g} "
            f"(RFEM coordinates magnified about their spring reference)"
            if model.flexible_coordinates else f"{model.name}: {title}")
    if overlay:
        note += f"; ghost: {overlay[0]}"
    return f"""<!DOCTYPE html>
<html><head><meta charset="utf-8"><title>{_html(note)}</title>
<style>body{{margin:0;overflow:hidden}} #meshcat-pane{{width:100vw;height:100vh}}
#note{{position:absolute;left:8px;bottom:8px;font:13px sans-serif;background:#fffc;padding:4px}}
</style></head>
<body><div id="meshcat-pane"></div><div id="note">{_html(note)}</div>
<script>{script}</script>
<script>
var viewer = new MeshCat.Viewer(document.getElementById("meshcat-pane"));
var blobs = {blobs};
for (var i = 0; i < blobs.length; i++) {{
  var bin = atob(blobs[i]); var bytes = new Uint8Array(bin.length);
  for (var j = 0; j < bin.length; j++) bytes[j] = bin.charCodeAt(j);
  viewer.handle_command_bytearray(bytes);
}}
window.gpmeReady = true;
</script></body></html>
"""


def _html(text):
    return (str(text).replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")
            .replace('"', "&quot;"))


def write_motion(model, df, path, title, magnification=DEFAULT_MAGNIFICATION,
                 constrained=(), overlay=None):
    """Write :func:`motion_page` to ``path`` atomically; returns the path, or None when the
    page would exceed MAX_BYTES (a warning says so: no page is better than a run or a
    report step lost for it)."""
    try:
        page = motion_page(model, df, title, magnification, constrained, overlay)
    except ValueError as exc:
        log.warning("%s: no 3D animation: %s", model.name, exc)
        return None
    atomic_write_text(Path(path), page)
    return Path(path)
