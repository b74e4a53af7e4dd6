"""Validation harness: gpme_core against Pinocchio (term by term) and MuJoCo (full runs)."""
