"""The overview matrix of index.html: for each engine a block of quantities x models, each
cell the worst check of that pair, coloured by its error / tolerance on a log scale.

Quantities that differ only in the coordinate or constraint they compare ("exact programmed
run psi2", "... z4") are one row of the matrix ("exact programmed run q"): the coordinate
and constraint names of the models are replaced by their kind (:func:`quantity_family`), so
a model with 60 coordinates still gives a matrix of a few rows; each cell links to the
worst check of its group in the full table.
"""
import math
from dataclasses import dataclass

import numpy as np

from ..compare import CRASH_QUANTITY, FAIL, INFO
from .rows import check_id
from .tables import checks_worst_first

# log10(error / tolerance) from GREEN_AT (far inside the tolerance) to 0 (at the
# tolerance): hue from green to amber; failures red, information grey
GREEN_AT = -8.0
HUE_GREEN, HUE_AMBER = 120.0, 40.0
FAIL_COLOUR, INFO_COLOUR, CRASH_COLOUR = "#d73027", "#e4e4e4", "#333333"
KINDS = (("q_dot", "velocity"), ("q", "coordinate"), ("Phi_dot", "constraint rate"),
         ("Phi", "constraint"), ("lambda", "multiplier"), ("viol", "constraint violation"))


def _word_kind(word, coordinates, constraints):
    """``word`` with a coordinate / constraint name replaced by its kind (q, q_dot, Phi,
    Phi_dot, lambda, viol); punctuation after the word is kept."""
    core = word.rstrip(":,;")
    tail = word[len(core):]
    base = core[:-4] if core.endswith("_dot") else None
    if core in coordinates:
        return "q" + tail
    if base in coordinates:
        return "q_dot" + tail
    if core in constraints:
        return "Phi" + tail
    if base in constraints:
        return "Phi_dot" + tail
    if core.startswith("lambda_") and core[len("lambda_"):] in constraints:
        return "lambda" + tail
    if core.startswith("viol_") and len(core) > len("viol_"):
        return "viol" + tail
    return word


def quantity_family(quantity, coordinates=(), constraints=()):
    """The matrix row of ``quantity``: each word naming a coordinate or constraint of the
    models replaced by its kind ("exact programmed run psi2_dot" -> "exact programmed run
    q_dot")."""
    coordinates, constraints = set(coordinates), set(constraints)
    return " ".join(_word_kind(w, coordinates, constraints) for w in str(quantity).split(" "))


def ratio_colour(ratio, status):
    """CSS colour of a cell: red for a failure, grey for information, else from green
    (error/tolerance <= 10**GREEN_AT) to amber (at the tolerance) on a log scale."""
    if status == FAIL:
        return FAIL_COLOUR
    if status == INFO or ratio is None or not np.isfinite(ratio):
        return INFO_COLOUR
    level = GREEN_AT if ratio <= 0 else min(0.0, max(GREEN_AT, math.log10(ratio)))
    hue = HUE_GREEN + (HUE_AMBER - HUE_GREEN) * (level - GREEN_AT) / -GREEN_AT
    return f"hsl({hue:.0f},65%,72%)"


def ratio_text(ratio, status):
    """Short text of a cell: "i" for information, the ratio as 3e-5, "0" when exact."""
    if status == INFO or ratio is None or not np.isfinite(ratio):
        return "FAIL" if status == FAIL else "i"
    if ratio == 0:
        return "0"
    mantissa, exponent = f"{ratio:.0e}".split("e")
    return f"{mantissa}e{int(exponent)}"


@dataclass
class Cell:
    text: str
    colour: str
    status: str
    href: str
    title: str
    n_checks: int


def _cell(group):
    """The cell of a group of checks (summary rows): its worst check."""
    worst = checks_worst_first(group).iloc[0]
    ratio = worst["error_over_tolerance"]
    ratio = None if ratio is None or (isinstance(ratio, float) and ratio != ratio) else ratio
    status = worst["status"]
    crashed = worst["quantity"] == CRASH_QUANTITY
    lines = [worst["check"],
             f"worst |error| {worst['worst_abs_error']:.3g}, tolerance "
             f"{worst['tolerance']:.3g}" if ratio is not None else "information only: no tolerance",
             f"error / tolerance {ratio:.3g}" if ratio is not None else "",
             f"{len(group)} check(s) in this cell" if len(group) > 1 else ""]
    return Cell(ratio_text(ratio, status), CRASH_COLOUR if crashed else ratio_colour(ratio, status),
                status, "#" + check_id(worst["check"]), "\n".join(x for x in lines if x),
                len(group))


def matrix_blocks(summary, coordinates=(), constraints=(), titles=None):
    """One block per engine (in the summary's order): {"engine", "title", "models",
    "sections": [{"section", "rows": [{"family", "cells": [Cell or None per model]}]}],
    "n_fail"}.  ``summary``: verify's summary (check, engine, section, model, quantity,
    status, error_over_tolerance, worst_abs_error, tolerance)."""
    titles = titles or {}
    fam = summary.assign(family=[quantity_family(q, coordinates, constraints)
                                 for q in summary["quantity"]])
    blocks = []
    for engine, eg in fam.groupby("engine", sort=False):
        models = list(dict.fromkeys(eg["model"]))
        sections = []
        for section, sg in eg.groupby("section", sort=False):
            rows = []
            for family, fg in sg.groupby("family", sort=False):
                by_model = {m: _cell(g) for m, g in fg.groupby("model", sort=False)}
                rows.append({"family": family, "cells": [by_model.get(m) for m in models]})
            sections.append({"section": section, "rows": rows})
        blocks.append({"engine": engine, "title": titles.get(engine, engine),
                       "models": models, "sections": sections,
                       "n_fail": int((eg["status"] == FAIL).sum())})
    return blocks


def legend():
    """(text, colour) pairs of the colour scale, for the legend under the matrix."""
    steps = [(f"1e{k}", ratio_colour(10.0 ** k, "pass")) for k in range(int(GREEN_AT), 1, 2)]
    return steps + [("fail (> 1)", FAIL_COLOUR), ("information", INFO_COLOUR)]
