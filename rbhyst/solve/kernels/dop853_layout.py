"""Layout shared by the adaptive integration's compiled kernel (rbhyst.solve.kernels.dop853) and its
driver (rbhyst.solve.integrators.reference): state vector, samples, info slots. No compiled code."""

NS = 8  # samples of b . v per step when looking for a crossing
SIMULTANEOUS = 1e-9  # reversals this close (fraction of the step) are one event


def ny(n: int) -> int:
    """Length of the state of a body of n coordinates: q (n), v (n), input energy, viscous work;
    the first 2 n are under error control (not the energies)."""
    return 2 * n + 2


# info layout
R_STATUS, R_TIME, R_ELEMENT, R_STEPS, R_REJECTED, R_EVENTS, R_FEV, R_HMIN, R_HMAX, R_START_FLIPS = range(10)
R_INFO = 10
ST_OK, ST_OVERFLOW, ST_STEP_TOO_SMALL, ST_TOO_MANY_STEPS, ST_NONFINITE, ST_PAUSED = range(6)

# the integration a window of output rows at a time: where a call paused and what it had counted
# (its caller passes the same work space back, which holds the state and the branches)
(P_T, P_H, P_PIECE, P_IO, P_STEPS, P_REJECTED, P_EVENTS, P_FEV, P_START_FLIPS, P_HMIN, P_HMAX, P_PHASE, P_ROWS,
 P_FIRST) = range(14)
P_SIZE = 14
#: where a call begins: from rest; at a piece's start; within a piece (a step not yet taken); the last rows
PH_REST, PH_PIECE, PH_STEP, PH_END = range(4)
