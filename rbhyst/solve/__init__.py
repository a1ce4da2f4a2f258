"""Layer 3, solve: from a System and its settings to histories. The compiled kernels, the
integrators, the stepping plan (substeps, monitor), the static equilibrium, the adaptive
reference, the error estimate, response spectra streamed as the run goes, and the
:class:`~rbhyst.solve.result.Result` they fill. Writes no file itself: where rows go is
given to it (a writer object)."""
