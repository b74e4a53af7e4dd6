"""Mutation testing of the physics modules of gpme_core (see docs/mutation.md)."""
