"""What a built-in example adds to the outputs of its runs: the hook through which the
paper's crane, run like every model (gpme_io.runs), gets the paper's figures.

`gpme simulate` (without --model) writes them next to the runs' histories, the gpme step of
`gpme verify` into the report's paper/ folder.  Which runs are the paper's and their names
in the figures are gpme_examples.paper's; the figures are gpme_io.paper_figures'.
"""
from pathlib import Path

from gpme_examples import paper
from gpme_examples.crane import CraneParameters

from . import paper_figures
from .atomic import atomic_save_figure

# the paper's figures, in the report's order: (file name, caption, draw(cases, params))
PAPER_FIGURES = (
    ("fig2_joint_coordinates.png",
     "Joint coordinates against time, rigid and flexible crane (paper Fig. 2)",
     lambda cases, params: paper_figures.joint_coordinates(cases)),
    ("fig3_end_effector.png",
     "End-effector path over the target ellipse and z_E(t) over z_a(t) (paper Fig. 3)",
     lambda cases, params: paper_figures.end_effector(cases, params)),
    ("constraint_violation.png", "|Phi_1| and |Phi_2| against time (log scale)",
     lambda cases, params: paper_figures.constraint_violation(cases)))


def write_example_outputs(runs, out_dir, params=CraneParameters()) -> dict:
    """The paper's figures of the crane's runs among ``runs`` into ``out_dir``; returns
    {file name: path}, empty when no run is the paper's.

    runs   : sequence of (gpme_io.scenario.Scenario, history DataFrame) pairs
    params : the crane's parameters (the target ellipse and programme of Fig. 3), those of
             gpme_io.scenario.crane_scenario
    """
    cases = paper.figure_runs(runs)
    paths = {}
    for name, _, draw in PAPER_FIGURES if cases else ():
        paths[name] = Path(out_dir) / name
        atomic_save_figure(draw(cases, params), paths[name])
    return paths
