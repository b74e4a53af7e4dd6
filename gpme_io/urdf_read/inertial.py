"""A link's <inertial> -> its RigidBodyInertia in the link frame, every problem named."""
import numpy as np

from gpme_core.inertia import RigidBodyInertia

from .attributes import _floats, _origin_transform

# kg m^2: the largest inertia about the root (sum of m |lever|^2 + tr I) the reader
# accepts.  The mass matrix's entries are at most this; its eigenvalue check and the
# integrators square them, and the square must stay below double precision's 1.8e308.
# Real machines are below 1e12 kg m^2; anything near this limit is a unit error or junk.
_MAGNITUDE = 1e150

def _read_inertial(link_el, problems, link_label):
    """RigidBodyInertia of a <link> in the link frame, or None (no inertial, zero mass and
    zero tensor, or invalid: the problem is appended, starting with ``link_label``)."""
    el = link_el.find("inertial")
    if el is None:
        return None
    label = f"{link_label} <inertial>"
    t = _origin_transform(el, label, problems)
    mass_el, inertia_el = el.find("mass"), el.find("inertia")
    keys = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
    bad = []
    if mass_el is None:
        bad.append(f"{label}: missing <mass value=...>")
    if inertia_el is None:
        bad.append(f"{label}: missing <inertia {' '.join(keys)}>")
    if bad:
        problems.extend(bad)
        return None
    n_before = len(problems)
    if mass_el.get("value") is None:
        problems.append(f"{label}: <mass> without value=... (kg)")
    missing = [k for k in keys if inertia_el.get(k) is None]
    if missing:
        problems.append(f"{label}: <inertia> without {', '.join(missing)} (kg m^2; URDF "
                        f"needs all six: {', '.join(keys)})")
    mass = float(_floats(mass_el.get("value"), 1, f"{label} <mass value>", problems,
                         (np.nan,))[0])
    vals = [_floats(inertia_el.get(k), 1, f"{label} <inertia {k}>", problems, (np.nan,))[0]
            for k in keys]
    if len(problems) > n_before:
        return None
    ixx, ixy, ixz, iyy, iyz, izz = vals
    i_com = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    with np.errstate(over="ignore", invalid="ignore"):
        size = abs(mass) * float(t[:3, 3] @ t[:3, 3]) + float(np.abs(i_com).sum())
    if not size < _MAGNITUDE:
        problems.append(f"{label}: mass {mass!r} kg, centre of mass {t[:3, 3].tolist()} m and "
                        f"inertia {[float(v) for v in vals]} kg m^2 give an inertia of "
                        f"{size:.3g} kg m^2 about the link frame, too large to compute with "
                        f"(at most {_MAGNITUDE:g}; real machines have < 1e12): check the units "
                        "(kg, m, kg m^2)")
        return None
    r = t[:3, :3]
    inertia = RigidBodyInertia(mass, t[:3, 3], r @ i_com @ r.T)
    bad = inertia.problems(label)
    if bad:
        # the tensor as written, not rotated, is what the user can find in the file
        problems.extend(b.replace(str(np.linalg.eigvalsh(r @ i_com @ r.T).tolist()),
                                  str(np.linalg.eigvalsh(i_com).tolist())) for b in bad)
        return None
    if mass == 0.0 and not np.any(i_com):
        return None                   # the usual way of writing "no mass"
    return inertia
