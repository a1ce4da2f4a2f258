"""Layer 6, report: everything drawn or formatted for people; the only package that imports
matplotlib (Agg backend, PNG files)."""
