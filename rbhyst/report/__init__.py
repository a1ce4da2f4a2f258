"""Plots (the only package that imports matplotlib, Agg backend, PNG files) and the console's tables."""
