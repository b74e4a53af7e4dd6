"""What a URDF read ignored or changed: the lines of :attr:`UrdfReadResult.notes`.

Each class of ignored element (friction, effort limits, extension tags, ...) is one line
naming every element of that class; free lines (dropped links, merged branches, replaced
inertias) follow in the order they were written.
"""

# the line of each class of ignored element; {n} the count of names, {s} its plural "s"
_NOTE_TEXT = {
    "friction": "<dynamics friction> on {n} joint{s} ignored (gpme has no Coulomb friction): ",
    "effort": "effort/velocity <limit> on {n} joint{s} ignored (gpme has no actuator limits): ",
    "equal_limits": "<limit lower == upper> on {n} joint{s} read as no range (unlimited; "
                    "URDF's default lower = upper = 0 when a <limit> gives only effort and "
                    "velocity): ",
    "safety": "<safety_controller> on {n} joint{s} ignored (controller settings, not "
              "dynamics): ",
    "calibration": "<calibration> on {n} joint{s} ignored (encoder reference, not dynamics): ",
    "mimic_fixed": "<mimic> on {n} joint{s} ignored (a fixed joint does not move): ",
    "bad_shape": "<visual>/<collision> that cannot be read left out ({n}; geometry only, the "
                 "dynamics are the same): ",
    "unresolved_mesh": "mesh file{s} not found, kept as written ({n}; a viewer given the "
                       "package's folder finds them): ",
    "world_shapes": "<visual>/<collision> of {n} link{s} fixed to the world left out (they do "
                    "not move; the model has no world body): ",
    "flexible_shapes": "<visual>/<collision> of {n} flexible link{s} replaced by the RFEM "
                       "elements' shapes (cylinders or boxes of the section): ",
    "tags": "extension elements of {n} kind{s} ignored (not URDF dynamics): ",
    "axis": "<axis xyz> not of unit length on {n} joint{s}, normalised (as URDF readers "
            "do): ",
}


class _Notes:
    """Names per class of ignored element, formatted once at the end."""

    def __init__(self):
        self._names = {}
        self._free = []

    def add(self, key: str, name: str) -> None:
        """Name ``name`` under the class ``key`` of _NOTE_TEXT (once)."""
        names = self._names.setdefault(key, [])
        if name not in names:
            names.append(name)

    def line(self, text: str) -> None:
        """A free line, kept as written."""
        self._free.append(text)

    def lines(self) -> tuple:
        """One line per class of element (in the order first named), then the free lines."""
        out = []
        for key, names in self._names.items():
            n = len(names)
            out.append(_NOTE_TEXT[key].format(n=n, s="" if n == 1 else "s")
                       + ", ".join(names))
        return tuple(out + self._free)
