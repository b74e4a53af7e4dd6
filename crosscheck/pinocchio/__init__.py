"""Crosscheck against Pinocchio: term by term and exactly realised programmed runs."""
