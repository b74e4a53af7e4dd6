"""Command-line front end of the gpme package (gpme_core + crosscheck)."""
