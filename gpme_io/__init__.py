"""Model descriptions (URDF reader and writer with the gpme side file, the TOML model file,
scenarios), the run service, and what the engine leaves to the layer above: output writers
(atomic files, CSV, compact PNGs, figures) and progress on the terminal."""
