"""Analyses built on runs: what a question about a deck needs beyond one time history."""
