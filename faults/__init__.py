"""Fault injection against `gpme verify` (issue 23): physics faults planted in a copy of the
sources, on the path the runs use, each of which verify must fail (docs/mutation.md)."""
