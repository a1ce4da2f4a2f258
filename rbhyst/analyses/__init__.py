"""Analyses built on the cases of a sweep: fragility curves."""
