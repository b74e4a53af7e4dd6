"""The paper's crane runs written out: each case's history and the paper's figures
(gpme_io.paper_figures), for `gpme simulate` without --model and the paper step of
`gpme verify` (the runs themselves are gpme_examples.paper.run_case)."""
from pathlib import Path

from gpme_examples.crane import CraneParameters

from . import paper_figures
from .atomic import HISTORY_DIGITS, atomic_save_figure, atomic_write_csv


def write_outputs(runs, out_dir, params=CraneParameters(), compressed=False):
    """The history of each case and the PNG figures into out_dir; returns {name: path}.

    runs   : {case: history DataFrame of gpme_examples.paper.run_case}
    params : the crane's parameters (the target ellipse and programme of Fig. 3)
    Histories: <case>.csv in full precision, or with ``compressed`` (verify's report)
    <case>.csv.gz with gpme_io.atomic.HISTORY_DIGITS significant digits."""
    out = Path(out_dir)
    paths = {}
    for case, df in runs.items():
        name = f"{case}.csv.gz" if compressed else f"{case}.csv"
        paths[name] = out / name
        atomic_write_csv(df, paths[name], HISTORY_DIGITS if compressed else None)
    figs = {"fig2_joint_coordinates.png": paper_figures.joint_coordinates(runs),
            "fig3_end_effector.png": paper_figures.end_effector(runs, params),
            "constraint_violation.png": paper_figures.constraint_violation(runs)}
    for name, fig in figs.items():
        paths[name] = out / name
        atomic_save_figure(fig, paths[name])
    return paths
