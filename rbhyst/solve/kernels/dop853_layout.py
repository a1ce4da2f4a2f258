"""Layout shared by the adaptive integration's compiled kernel (rbhyst.solve.kernels.dop853) and its
driver (rbhyst.solve.integrators.reference): state vector, samples, info slots. No compiled code."""

NS = 8  # samples of b . v per step when looking for a crossing
SIMULTANEOUS = 1e-9  # reversals this close (fraction of the step) are one event
NY = 8  # q (3), v (3), input energy, viscous work
NERR = 6  # components under error control (not the energies)

# info layout
R_STATUS, R_TIME, R_ELEMENT, R_STEPS, R_REJECTED, R_EVENTS, R_FEV, R_HMIN, R_HMAX, R_START_FLIPS = range(10)
R_INFO = 10
ST_OK, ST_OVERFLOW, ST_STEP_TOO_SMALL, ST_TOO_MANY_STEPS, ST_NONFINITE = range(5)
