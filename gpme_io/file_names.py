"""Names from model files and URDFs made into file names, and paths kept inside --out.

Every name that reaches a file or folder name (a model, link, joint, frame, constraint or
check name) comes from input nobody has read: ``../../x``, ``/abs``, ``a#b``, ``CON``, a
300-character name, two names that differ only in case.  :func:`file_stem` is the one
function that turns such a name into a file-name stem; :func:`inside` is the one check
that a path about to be written lies inside the output root.

The stem of a name is the name itself when it is already plain: only ``[a-z0-9_.-]``
(lower case, so that two names differing only in case cannot meet on a case-insensitive
file system), not starting with '.' or '-', at most :data:`MAX_READABLE` characters and
not a Windows device name (CON, PRN, AUX, NUL, COM1-9, LPT1-9, with any extension).
Any other name keeps its readable part ([A-Za-z0-9_.-] runs, others replaced by '_', at
most MAX_READABLE characters) followed by '-' and 8 hex digits of the SHA-1 of the whole
name, so different names get different stems (a collision of the 8 digits is about 1 in
4e9 for a pair).  Stems are safe in a URL and an HTML ``src`` without escaping ('#', '?',
'%' and spaces never appear).
"""
import hashlib
import re
from pathlib import Path

from gpme_core.errors import GpmeError

MAX_READABLE = 60              # characters of the readable part (a 255-byte name limit)
_UNSAFE = re.compile(r"[^A-Za-z0-9_.-]+")
_PLAIN = re.compile(r"[a-z0-9_][a-z0-9_.-]*")
# Windows device names: reserved as the part before the first '.', whatever follows
_DEVICES = re.compile(r"(con|prn|aux|nul|com[0-9]|lpt[0-9]|conin\$|conout\$)", re.IGNORECASE)
DIGEST_DIGITS = 8


class UnsafePathError(GpmeError):
    """A path to be written lies outside the output root (a bug: names go through
    :func:`file_stem`); the message names both paths."""


def digest(name: str) -> str:
    """8 hex digits of the SHA-1 of ``name`` (UTF-8; lone surrogates escaped)."""
    data = name.encode("utf-8", errors="surrogatepass")
    return hashlib.sha1(data).hexdigest()[:DIGEST_DIGITS]


def is_plain(name: str) -> bool:
    """True when ``name`` is its own stem (see the module docstring)."""
    return (len(name) <= MAX_READABLE and _PLAIN.fullmatch(name) is not None
            and not _is_device(name))


def _is_device(stem: str) -> bool:
    """True when Windows reads ``stem`` (and any file name starting with it) as a device."""
    return _DEVICES.fullmatch(stem.split(".", 1)[0]) is not None


def readable_part(name: str, joiner: str = "_") -> str:
    """The [A-Za-z0-9_.-] runs of ``name`` joined by ``joiner``, without leading or
    trailing '.', '_', '-', at most MAX_READABLE characters (may be empty)."""
    return _UNSAFE.sub(joiner, name).strip("._-")[:MAX_READABLE].rstrip("._-")


def hashed_stem(name: str, joiner: str = "_") -> str:
    """readable_part(name) + '-' + digest(name) (the digest alone when nothing is
    readable): unique for any name, used where a stem must never equal the name."""
    readable = readable_part(name, joiner)
    if _is_device(readable):
        readable = "_" + readable
    return f"{readable}-{digest(name)}" if readable else digest(name)


def file_stem(name: object) -> str:
    """A safe, unique file-name stem of ``name`` (any object, str() taken): the name
    itself when plain, else :func:`hashed_stem`."""
    name = str(name)
    return name if is_plain(name) else hashed_stem(name)


def inside(root, path) -> Path:
    """``path`` (absolute, or relative to the current directory) resolved, after checking
    that it lies inside ``root``; raises UnsafePathError otherwise.  Symbolic links are
    followed, so a link planted inside root that points out is refused too."""
    root_resolved = Path(root).resolve()
    resolved = Path(path).resolve()
    if resolved != root_resolved and root_resolved not in resolved.parents:
        raise UnsafePathError(f"refusing to write {path}: it resolves to {resolved}, outside "
                              f"the output directory {root_resolved} (names are made into "
                              "file names by gpme_io.file_names.file_stem)")
    return resolved


def named_path(root, name: object, suffix: str = "", prefix: str = "") -> Path:
    """root / (prefix + file_stem(name) + suffix), checked to lie inside root.

    prefix, suffix: fixed text of the caller (e.g. "mujoco_exact_", ".png"), not user
    input."""
    path = Path(root) / f"{prefix}{file_stem(name)}{suffix}"
    inside(root, path)
    return path
