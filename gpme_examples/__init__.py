"""Examples built on the public gpme_core API: the paper's crane and its two runs (their
figures and files are written by gpme_io.paper_outputs)."""
