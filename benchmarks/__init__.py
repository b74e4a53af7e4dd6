"""Benchmarks of gpme against Pinocchio and MuJoCo (run: python -m benchmarks.bench)."""
