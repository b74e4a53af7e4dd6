"""Examples built on the public gpme_core API: the paper's crane, its two runs and figures."""
