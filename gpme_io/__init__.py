"""Model files: URDF reader and writer with the gpme side file, and the TOML model file."""
