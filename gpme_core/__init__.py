"""gpme_core: generalized programmed motion equations (GPME) in trace form."""
__version__ = "0.1.0"
