"""Crosscheck against MuJoCo: terms, free runs, programmed runs (exact and soft)."""
