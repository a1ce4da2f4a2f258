"""Layer 5, analyses: what is built on runs. The response spectrum of a record,
transmissibility, the convergence study, calibration of hysteresis parameters, sweeps,
fragility curves from a sweep's cases, and qualification to the standards (required response
spectra, spectrum-compatible motions, the verdict)."""
