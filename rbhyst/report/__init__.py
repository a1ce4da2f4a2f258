"""Layer 6, report: everything drawn or formatted for people: the figures (the only package
that imports matplotlib, Agg backend, PNG files) and the console's tables."""
