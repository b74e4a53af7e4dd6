"""Examples built on the public gpme_core API: the paper's crane (crane.py) and what is
special about its two runs (paper.py: which runs are the paper's, their names in its
figures; the runs go through gpme_io.runs like every model's, the figures are written by
gpme_io.example_outputs)."""
