"""The catalogue of planted physics faults (issue 23: the harness's own sensitivity).

Each :class:`Fault` is one exact text substitution in one source file: ``anchor`` must occur
exactly once in that file (:func:`anchor_problem`), and is replaced by ``replacement`` in a
copy of the sources (faults.run), never in the work tree.  A fault whose anchor has gone
(the code was edited) or occurs twice is refused with a message naming it, so the catalogue
cannot rot silently: tests/test_fault_catalogue.py checks every anchor against the current
sources.

The faults sit on the path the runs take: the numba kernels (gpme_core/fast.py: chain
kinematics, trace-form M, h, g, point kinematics, multipliers, the free solve of a serial
chain; gpme_core/kernels.py: the fused right-hand side with springs, dampers, drives,
constraint rows, kappa, Baumgarte, the reduced solve and the RK4 loop) and the Python code
whose numbers those kernels are given (gpme_core/rfem.py: section constants, sde springs and
dampers, the rigid elements' mass).  faults.run shows for each fault that it changes a
compiled run (its probe), so none of them sits on the numpy reference path only
(``chain-articulated-inertia``, on the free solve, through the probe's free crane run).

Sizes are relative (a factor 1.001 is 1e-3) unless the fault is an offset; every fault is
at most 1e-3 of the term it changes: subtle, far above round-off (1e-16) and the engines'
integration errors, far below what a look at a plot would show.

:data:`CONTROLS` are not faults: each changes a number of the crane's *description* by the
same 1e-3 (a stiffer steel, a denser one), a different but correct model that every engine
is given alike.  verify should pass them.  A check that fails under a control fails on a
correct model; a fault "caught" only by such checks has not been shown to be wrong.
"""
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType

# the terms of the equations a catalogue must span (tests/test_fault_catalogue.py)
MASS_MATRIX = "mass matrix M (trace form)"
VELOCITY_PRODUCTS = "velocity products h"
GRAVITY = "gravity g"
JOINT_SPRINGS = "joint springs f = K (q - q_ref)"
JOINT_DAMPERS = "joint dampers d = D q_dot"
DRIVES = "drives t(t)"
RFEM_BENDING_SPRING = "RFEM bending spring E I / dl"
RFEM_TORSION_SPRING = "RFEM torsion spring G J / dl"
RFEM_BENDING_DAMPER = "RFEM bending damper eta_E I / dl"
RFEM_TORSION_DAMPER = "RFEM torsion damper eta_G J / dl"
SECTION_CIRCLE = "section constants: solid circle"
SECTION_TUBE = "section constants: tube"
SECTION_RECTANGLE = "section constants: rectangle"
SECTION_HOLLOW_RECTANGLE = "section constants: hollow rectangle"
RFEM_MASS_SPLIT = "RFEM mass split (rigid elements)"
RFEM_ELEMENT_INERTIA = "RFEM rigid element inertia"
REVOLUTE_KINEMATICS = "revolute joint kinematics"
PRISMATIC_KINEMATICS = "prismatic joint kinematics"
POINT_DRIFT = "point kinematics: drift"
PHI = "constraint value Phi"
ROW = "constraint Jacobian row A"
KAPPA_DRIFT = "kappa: grad(phi).drift"
KAPPA_HESSIAN = "kappa: p_dot^T Hess(phi) p_dot"
KAPPA_GRAD_T = "kappa: factor 2 of 2 grad(phi_t).p_dot"
KAPPA_PHI_TT = "kappa: phi_tt"
JOINT_PROGRAMME = "joint programme f''"
COORDINATE_PROGRAMME = "coordinate programme f'' (cosine)"
BAUMGARTE_ALPHA = "Baumgarte 2 alpha Phi_dot"
BAUMGARTE_BETA = "Baumgarte beta^2 Phi"
TREE_BRANCHES = "tree: no inertial coupling between branches"
PAIR_ROW = "two-frame constraint row (second frame's part)"
POINT_SPRINGS = "point springs (elastic force)"
REDUCED_SOLVE = "reduced solve N^T (h + Q - M p)"
FREE_CHAIN_SOLVE = "free solve of a serial chain M^-1 (h + Q) (articulated-body recursion)"
MULTIPLIERS = "multiplier recovery lambda = A_dc^-T F_dc"
RK4_WEIGHTS = "RK4 stage weights"

REQUIRED_TERMS = (
    MASS_MATRIX, VELOCITY_PRODUCTS, GRAVITY, JOINT_SPRINGS, JOINT_DAMPERS, DRIVES,
    RFEM_BENDING_SPRING, RFEM_TORSION_SPRING, RFEM_BENDING_DAMPER, RFEM_TORSION_DAMPER,
    SECTION_CIRCLE, SECTION_TUBE, SECTION_RECTANGLE, RFEM_MASS_SPLIT, REVOLUTE_KINEMATICS,
    PRISMATIC_KINEMATICS, PHI, ROW, KAPPA_DRIFT, KAPPA_HESSIAN, KAPPA_GRAD_T, KAPPA_PHI_TT,
    JOINT_PROGRAMME, BAUMGARTE_ALPHA, BAUMGARTE_BETA, REDUCED_SOLVE, FREE_CHAIN_SOLVE,
    MULTIPLIERS, RK4_WEIGHTS)

# the largest relative size a fault of the catalogue may have
MAX_SIZE = 1e-3


@dataclass(frozen=True)
class Fault:
    """One planted fault.

    id          : short unique name (``--only ID``)
    term        : the term of the equations it falsifies (one of the constants above)
    file        : source file, relative to the repository root
    anchor      : exact text, occurring exactly once in ``file``
    replacement : what replaces it
    size        : relative size of the change of the term (1e-3 for a factor 1.001), or
                  the offset in the term's own units for an offset
    what        : one line: what is wrong, in words
    """

    id: str
    term: str
    file: str
    anchor: str
    replacement: str
    size: float
    what: str


class AnchorError(Exception):
    """A fault's anchor is missing from its file or not unique there (the message says
    which fault, which file and how often the anchor occurs)."""


FAST = "gpme_core/fast.py"
KERNELS = "gpme_core/kernels.py"
RFEM = "gpme_core/rfem.py"

CATALOGUE = (
    # ------------------------------------------------ trace-form terms (gpme_core/fast.py)
    Fault("M-composite", MASS_MATRIX, FAST,
          "column[i] = (s6[0, i] * e0",
          "column[i] = 1.001 * (s6[0, i] * e0", 1e-3,
          "the composite world pseudo-inertias Hc_j that M is formed from are 1.001 x too "
          "large (M only; h and g use their own sums)"),
    Fault("h-coriolis", VELOCITY_PRODUCTS, FAST,
          "tmp[i, j] = 2.0 * v_all[p, i, j] + sw",
          "tmp[i, j] = 1.998 * v_all[p, i, j] + sw", 1e-3,
          "the factor 2 of the Coriolis products 2 V_p(l) S_l q_dot_l in the velocity-"
          "product accelerations B_l is 1.998"),
    Fault("g-scale", GRAVITY, FAST,
          "g[j] = -gj",
          "g[j] = -1.001 * gj", 1e-3,
          "the generalized gravity forces are 1.001 x too large"),
    Fault("revolute-angle", REVOLUTE_KINEMATICS, FAST,
          "s, c = np.sin(q[k]), np.cos(q[k])",
          "s, c = np.sin(1.001 * q[k]), np.cos(1.001 * q[k])", 1e-3,
          "a revolute joint turns its link by 1.001 q (Rodrigues' rotation; the twist S "
          "is left as it was)"),
    Fault("prismatic-stroke", PRISMATIC_KINEMATICS, FAST,
          "motion[i, 3] = generators[k, i, 3] * q[k]",
          "motion[i, 3] = 1.001 * generators[k, i, 3] * q[k]", 1e-3,
          "a prismatic joint moves its link by 1.001 q"),
    Fault("point-drift-coriolis", POINT_DRIFT, FAST,
          "acc += (2.0 * v_prev[a, c] + s_all[l, a, c] * w) * col[c]",
          "acc += (1.998 * v_prev[a, c] + s_all[l, a, c] * w) * col[c]", 1e-3,
          "the factor 2 of the Coriolis part of a constrained point's drift "
          "(p_ddot at q_ddot = 0) is 1.998"),
    Fault("multipliers", MULTIPLIERS, FAST,
          "acc += inv_dc[p, i] * f",
          "acc += 1.001 * inv_dc[p, i] * f", 1e-3,
          "the multipliers lambda = A_dc^-T (M q_ddot - h - Q)_dc are 1.001 x too large "
          "(the motion is unchanged)"),
    # ------------------------------------ the fused right-hand side (gpme_core/kernels.py)
    Fault("spring-stiffness", JOINT_SPRINGS, KERNELS,
          "- stiffness[i] * (q[i] - q_ref[i])",
          "- 1.001 * stiffness[i] * (q[i] - q_ref[i])", 1e-3,
          "every joint spring force (chain joints and RFEM sdes) is 1.001 x too large"),
    Fault("spring-reference", JOINT_SPRINGS, KERNELS,
          "* (q[i] - q_ref[i])",
          "* (q[i] - 1.001 * q_ref[i])", 1e-3,
          "the springs pull towards 1.001 q_ref instead of q_ref"),
    Fault("damper", JOINT_DAMPERS, KERNELS,
          "d_i = damping[i] * q_dot[i]",
          "d_i = 1.001 * damping[i] * q_dot[i]", 1e-3,
          "every joint damper force (chain joints and RFEM sdes) is 1.001 x too large"),
    Fault("drive", DRIVES, KERNELS,
          "rhs[d_coord[i]] += tf[0]",
          "rhs[d_coord[i]] += 1.001 * tf[0]", 1e-3,
          "drive forces enter the equations 1.001 x too large (their recorded work is "
          "left as it was)"),
    Fault("phi-offset", PHI, KERNELS,
          "phi[c] = lt[0]",
          "phi[c] = lt[0] + 1e-4", 1e-4,
          "a point constraint's value is off by 1e-4 (m for a position, 1e-4 of the "
          "normalised ellipse): the run is held on a shifted surface"),
    Fault("row-x", ROW, KERNELS,
          "a[c, j] = lt[1] * jac[pt, 0, j]",
          "a[c, j] = 1.001 * lt[1] * jac[pt, 0, j]", 1e-3,
          "the x part of a point constraint's Jacobian row, dphi/dx C_x, is 1.001 x too "
          "large"),
    Fault("kappa-drift", KAPPA_DRIFT, KERNELS,
          "kappa[c] = (lt[1] * drift[pt, 0] + lt[2] * drift[pt, 1] + lt[3] * drift[pt, 2]",
          "kappa[c] = (1.001 * (lt[1] * drift[pt, 0] + lt[2] * drift[pt, 1]"
          " + lt[3] * drift[pt, 2])", 1e-3,
          "the piece grad(phi).drift of kappa is 1.001 x too large"),
    Fault("kappa-hessian", KAPPA_HESSIAN, KERNELS,
          "quad += v[i] * lt[4 + 3 * i + j] * v[j]",
          "quad += 1.001 * v[i] * lt[4 + 3 * i + j] * v[j]", 1e-3,
          "the piece p_dot^T Hess(phi) p_dot of kappa is 1.001 x too large"),
    Fault("kappa-grad-t", KAPPA_GRAD_T, KERNELS,
          "+ quad + 2.0 * (lt[14] * v[0]",
          "+ quad + 1.998 * (lt[14] * v[0]", 1e-3,
          "the factor 2 of 2 grad(phi_t).p_dot in kappa is 1.998"),
    Fault("kappa-phi-tt", KAPPA_PHI_TT, KERNELS,
          "+ lt[17])",
          "+ 1.001 * lt[17])", 1e-3,
          "the piece phi_tt of kappa is 1.001 x too large"),
    Fault("joint-programme-ftt", JOINT_PROGRAMME, KERNELS,
          "kappa[c] = -tf[2]",
          "kappa[c] = -1.001 * tf[2]", 1e-3,
          "a joint programme's kappa = -f''(t) is 1.001 x too large"),
    Fault("cosine-ftt", COORDINATE_PROGRAMME, KERNELS,
          "-amp * omega * s, -amp * omega * omega * c",
          "-amp * omega * s, -1.001 * amp * omega * omega * c", 1e-3,
          "the second derivative of a cosine time function (the crane's height "
          "programme) is 1.001 x too large"),
    Fault("baumgarte-alpha", BAUMGARTE_ALPHA, KERNELS,
          "- 2.0 * alpha * phi_dot[i]",
          "- 1.998 * alpha * phi_dot[i]", 1e-3,
          "the Baumgarte velocity term 2 alpha Phi_dot has the factor 1.998"),
    Fault("baumgarte-beta", BAUMGARTE_BETA, KERNELS,
          "- beta * beta * phi[i]",
          "- 1.001 * beta * beta * phi[i]", 1e-3,
          "the Baumgarte position term beta^2 Phi is 1.001 x too large"),
    Fault("reduced-rhs", REDUCED_SOLVE, KERNELS,
          "s += f * r[dc[p]]",
          "s += 1.001 * f * r[dc[p]]", 1e-3,
          "the dependent part Gamma^T r_dc of the reduced right-hand side N^T (h + Q - M p) "
          "is 1.001 x too large"),
    # the free solve of a serial chain (gpme_core/fast.py chain_solve, issue 29): the runs of
    # models without programmed constraints (verify's free runs, the benchmarks); the
    # probe's runs (faults.probe) are all programmed and take the reduced solve instead
    Fault("chain-articulated-inertia", FREE_CHAIN_SOLVE, FAST,
          "articulated[a, c] -= (fa * joint_force[i, c]) * inv_d",
          "articulated[a, c] -= 1.001 * (fa * joint_force[i, c]) * inv_d", 1e-3,
          "the articulated-inertia update I^A - U U^T / D of the free chain solve removes "
          "1.001 x the joint's projection: M^-1 (h + Q) of a slightly different M"),
    Fault("rk4-weight", RK4_WEIGHTS, KERNELS,
          "(k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])",
          "(k1[i] + 2.002 * k2[i] + 2.0 * k3[i] + k4[i])", 1e-3,
          "RK4's weight of the second stage is 2.002/6 (the weights sum to 1 + 1/3000: "
          "not consistent)"),
    Fault("rk4-order", RK4_WEIGHTS, KERNELS,
          "(k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])",
          "(k1[i] + 2.002 * k2[i] + 1.998 * k3[i] + k4[i])", 1e-3,
          "RK4's weights of stages 2 and 3 are 2.002/6 and 1.998/6: consistent and of "
          "second order, but no longer of third and fourth"),
    # ------------------------------------------------- RFEM constants (gpme_core/rfem.py)
    Fault("rfem-bending-z", RFEM_BENDING_SPRING, RFEM,
          "stiff = (self.youngs_modulus * self.second_moment_z / dl,",
          "stiff = (1.001 * self.youngs_modulus * self.second_moment_z / dl,", 1e-3,
          "the sde bending spring s_psi = E I_z / dl is 1.001 x too stiff"),
    Fault("rfem-bending-y", RFEM_BENDING_SPRING, RFEM,
          "                 self.youngs_modulus * self.second_moment_y / dl,",
          "                 1.001 * self.youngs_modulus * self.second_moment_y / dl,", 1e-3,
          "the sde bending spring s_theta = E I_y / dl is 1.001 x too stiff"),
    Fault("rfem-torsion", RFEM_TORSION_SPRING, RFEM,
          "self.shear_modulus * self.torsion_constant / dl)",
          "1.001 * self.shear_modulus * self.torsion_constant / dl)", 1e-3,
          "the sde torsion spring s_phi = G J / dl is 1.001 x too stiff"),
    Fault("rfem-bending-damper", RFEM_BENDING_DAMPER, RFEM,
          "damp = (self.bending_viscosity * self.second_moment_z / dl,",
          "damp = (1.001 * self.bending_viscosity * self.second_moment_z / dl,", 1e-3,
          "the sde bending damper d_psi = eta_E I_z / dl is 1.001 x too large"),
    Fault("rfem-torsion-damper", RFEM_TORSION_DAMPER, RFEM,
          "self.eta_g * self.torsion_constant / dl)",
          "1.001 * self.eta_g * self.torsion_constant / dl)", 1e-3,
          "the sde torsion damper d_phi = eta_G J / dl is 1.001 x too large"),
    Fault("section-circle", SECTION_CIRCLE, RFEM,
          "i = np.pi * r ** 4 / 4.0\n        return cls(np.pi * r ** 2, i, i, 2.0 * i,",
          "i = np.pi * r ** 4 / 4.004\n        return cls(np.pi * r ** 2, i, i, 2.0 * i,",
          1e-3,
          "a solid circle's second moments I = pi r^4 / 4 (and J = 2 I) are 1/1.001 of "
          "their value"),
    Fault("section-tube", SECTION_TUBE, RFEM,
          "i = np.pi * (r_o ** 4 - r_i ** 4) / 4.0",
          "i = np.pi * (r_o ** 4 - r_i ** 4) / 4.004", 1e-3,
          "a tube's second moments I = pi (r_o^4 - r_i^4) / 4 (and J = 2 I) are 1/1.001 "
          "of their value"),
    Fault("section-rectangle-bending", SECTION_RECTANGLE, RFEM,
          "return cls(w * h, w * h ** 3 / 12.0, h * w ** 3 / 12.0, j,",
          "return cls(w * h, w * h ** 3 / 12.012, h * w ** 3 / 12.0, j,", 1e-3,
          "a solid rectangle's I_y = w h^3 / 12 is 1/1.001 of its value"),
    Fault("section-rectangle-torsion", SECTION_RECTANGLE, RFEM,
          "j = a * b ** 3 * (1.0 / 3.0 - 0.21 * (b / a)",
          "j = a * b ** 3 * (1.0 / 3.0 - 0.2102 * (b / a)", 1e-3,
          "Roark's 0.21 in a solid rectangle's torsion constant is 0.2102 (J lower by "
          "4.6e-4 for the SCARA forearm's 2:1 bar, at most 1e-3 for any aspect)"),
    Fault("section-hollow-rectangle", SECTION_HOLLOW_RECTANGLE, RFEM,
          "j = 2.0 * t * (w - t) ** 2 * (h - t) ** 2 / (w + h - 2.0 * t)",
          "j = 1.998 * t * (w - t) ** 2 * (h - t) ** 2 / (w + h - 2.0 * t)", 1e-3,
          "Bredt's torsion constant of a hollow rectangle is 1/1.001 of its value"),
    Fault("rfem-mass-split", RFEM_MASS_SPLIT, RFEM,
          "builder.add_body(beam.element_inertia(0.5 * dl), origin=t_link_beam)  # rfe 0",
          "builder.add_body(beam.element_inertia(0.5005 * dl), origin=t_link_beam)  # rfe 0",
          1e-3,
          "the first rigid element of a discretised beam has length dl / 2 x 1.001 (its "
          "mass, centre and inertia)"),
    # ------------------------------------ trees, two-frame rows, point springs (issue 26)
    Fault("tree-branch-coupling", TREE_BRANCHES, FAST,
          "v = column[i] if moves[i, j] else 0.0",
          "v = column[i] if moves[i, j] else 1e-3 * column[i]", 1e-3,
          "joints on different branches of a tree couple in M by 1e-3 of the trace "
          "tr(S_i Hc_j S_j^T) the mask sets to zero (a serial chain is unchanged)"),
    Fault("pair-row-second-frame", PAIR_ROW, KERNELS,
          "acc += terms[1 + i] * ja[i, j] + terms[4 + i] * jb[i, j]",
          "acc += terms[1 + i] * ja[i, j] + 1.001 * terms[4 + i] * jb[i, j]", 1e-3,
          "the second frame's part grad_b(phi) J_b of a two-frame constraint's Jacobian row "
          "is 1.001 x too large"),
    Fault("point-spring-stiffness", POINT_SPRINGS, KERNELS,
          "elastic = s_par[s, 0] * (length - s_par[s, 1])",
          "elastic = 1.001 * s_par[s, 0] * (length - s_par[s, 1])", 1e-3,
          "every point spring's elastic force is 1.001 x too large"),
    Fault("rfem-element-inertia", RFEM_ELEMENT_INERTIA, RFEM,
          "ix = self.density * (self.second_moment_y + self.second_moment_z) * piece_length",
          "ix = 1.001 * self.density * (self.second_moment_y + self.second_moment_z)"
          " * piece_length", 1e-3,
          "a rigid element's moment of inertia about the beam axis is 1.001 x too large"),
)

CRANE = "gpme_examples/crane.py"
CONTROL = "control: a correct model 1e-3 away"
CONTROLS = (
    Fault("control-steel-E", CONTROL, CRANE,
          "steel_youngs_modulus: float = 210e9 ",
          "steel_youngs_modulus: float = 210.21e9 ", 1e-3,
          "the crane arm's Young's modulus is 1.001 x larger (bending springs and "
          "dampers' counterpart of rfem-bending-*)"),
    Fault("control-steel-G", CONTROL, CRANE,
          "steel_shear_modulus: float = 81e9 ",
          "steel_shear_modulus: float = 81.081e9 ", 1e-3,
          "the crane arm's shear modulus is 1.001 x larger (counterpart of rfem-torsion)"),
    Fault("control-arm-viscosity", CONTROL, CRANE,
          "arm_viscosity: float = 5e6 ",
          "arm_viscosity: float = 5.005e6 ", 1e-3,
          "the crane arm's material viscosity is 1.001 x larger (counterpart of the RFEM "
          "dampers)"),
    Fault("control-steel-density", CONTROL, CRANE,
          "steel_density: float = 7850.0 ",
          "steel_density: float = 7857.85 ", 1e-3,
          "the crane arm's density is 1.001 x larger (counterpart of the RFEM mass split "
          "and element inertia)"),
)

BY_ID = MappingProxyType({f.id: f for f in CATALOGUE + CONTROLS})


def anchor_problem(fault: Fault, root: Path):
    """None when ``fault``'s anchor occurs exactly once in its file under ``root``, else a
    message saying what is wrong (file missing, anchor missing, anchor repeated)."""
    path = Path(root) / fault.file
    if not path.is_file():
        return f"fault {fault.id!r}: its file {fault.file} does not exist under {root}"
    count = path.read_text(encoding="utf-8").count(fault.anchor)
    if count == 1:
        return None
    where = "is missing from" if count == 0 else f"occurs {count} times in"
    return (f"fault {fault.id!r} ({fault.term}): its anchor {fault.anchor!r} {where} "
            f"{fault.file}; it must occur exactly once (update the catalogue to the "
            "current source)")


def check_anchors(faults, root: Path):
    """Raise AnchorError listing every fault of ``faults`` whose anchor is not unique in
    its file under ``root``."""
    problems = [p for p in (anchor_problem(f, root) for f in faults) if p]
    if problems:
        raise AnchorError("\n".join(problems))


def apply(fault: Fault, root: Path) -> None:
    """Plant ``fault`` in the file under ``root`` (a copy of the sources): the one anchor
    replaced; AnchorError when the anchor is not there exactly once."""
    problem = anchor_problem(fault, root)
    if problem:
        raise AnchorError(problem)
    path = Path(root) / fault.file
    text = path.read_text(encoding="utf-8")
    path.write_text(text.replace(fault.anchor, fault.replacement, 1), encoding="utf-8")
