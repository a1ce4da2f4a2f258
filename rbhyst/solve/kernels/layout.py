"""The layout the compiled loop and its Python side share: status codes, element state
columns, the running state vector, energy columns. Plain constants: importing them loads no
compiled code."""

# status codes written to info[I_STATUS]
OK = 0
UNRESOLVED = 1  # the stiffness needs more substeps than allowed
OVERFLOW = 2  # an element left its calibrated range (exp overflow)
NONFINITE = 3  # a NaN or Inf appeared in the state
NOT_CONVERGED = 4  # Newton iterations failed even at the finest substep level

#: "bad element" a step returns when its Newton iterations did not converge: the loop
#: retries the compute step with twice the substeps
NEWTON_FAILED = -2

# the kinematics a kernel runs (its argument ``rot``): a coordinate's index >= 0 is the plane
# body's rotation with exact kinematics (rbhyst.model.kinematics)
SMALL = -1  # the seed's rows, u_e = b_e . q
SPATIAL = -2  # a body in space with exact kinematics: q[3:6] its rotation vector (rbhyst.model.rotations)
#: the seed's rows, each element's turn put within the step where it falls (the vertex of the
#: parabola through its last three deformations) rather than at the node: the error estimate's
#: companion (rbhyst.solve.companion), whose motion must not carry the run's O(h^2) branch origins
LOCATED = -3

#: the methods whose modified equation the companion's load is written for
#: (rbhyst.solve.kernels.modified), as that kernel's ``method``
MODIFIED = {"newmark": 0, "central-difference": 1, "chang": 2}

# element state columns: displacement, force, branch sign, gap, tangent, antiderivative
U, F, S, G, K, A, UP, FB = range(8)  # UP: the deformation a step before (LOCATED)
#: FB (LOCATED): where the step turned the element before the node it started from, that node's
#: force re-driven on the new branch (the turn put before the node, not after it); else NaN
#: a stop (rbhyst.model.stop): the peaks of its lower and upper side's current contacts, its force
#: (the element's is F + FS: F stays the VRM's, which its next step starts from), the energy its
#: impacts lost, how many contacts began, its largest force and penetration (all 0 without one)
DL, DU, FS, IMP, NI, PF, PD = range(8, 15)
N_STATE = 15

#: what kernels.estimate.companion_estimate returns: the companion's estimate alone (at most
#: ``check``), with the probe's, past ``largest``, or where the adaptive solutions must say it: a
#: step whose Newton iterations split it further than the run's (the companion's or the probe's),
#: an element the re-driven forces took out of its range; ESTIMATE_FAILED: the loop failed
#: (``info`` says how). Here, not in that kernel's module, which imports numba: a run whose
#: kernels were built at install reads them without it (rbhyst.solve.companion)
(ESTIMATE_DONE, ESTIMATE_PROBED, ESTIMATE_TOO_LARGE, ESTIMATE_COMPANION_SPLIT, ESTIMATE_OUT_OF_RANGE,
 ESTIMATE_PROBE_SPLIT, ESTIMATE_FAILED) = range(7)

# info: how a chunk ended
I_STATUS, I_ELEMENT, I_TIME, I_STIFFNESS, I_OMEGA, I_DISP, I_BRANCH = range(7)
INFO_SIZE = 7

# the loop's running state, carried from chunk to chunk (state vector): counters first, then
# the displacement, velocity and acceleration of the n coordinates (x[X_Q + k n + i])
X_E_IN, X_E_HYST, X_E_VISC = 0, 1, 2  # cumulative input, hysteretic and viscous work
X_STEPS, X_ITER, X_SUBSTEPS, X_LEVEL_USED, X_OMEGA_DT2, X_LEVEL = 3, 4, 5, 6, 7, 8
X_CUR = 9  # which of the two element-state buffers holds the current state
X_Q = 10


def n_x(n: int) -> int:
    """Length of the state vector of a body of n coordinates."""
    return X_Q + 3 * n


def x_slice(n: int, k: int) -> slice:
    """Where the displacement (k = 0), velocity (1) or acceleration (2) sits in the state vector."""
    return slice(X_Q + k * n, X_Q + (k + 1) * n)


# the loop's work space: rows of n values each (one (N_W, n) array from the caller, since
# compiled code here allocates nothing), and one (n, n) matrix
W_D, W_V, W_A = 0, 1, 2  # the state at the start of a step
W_DN, W_VN, W_AN = 3, 4, 5  # the state a step reaches
W_SD, W_SV, W_SA = 6, 7, 8  # the start of a compute step, to redo it with more substeps
W_PA, W_PB = 9, 10  # the load at the start and the end of a (sub)step
W_R, W_RN = 11, 12  # the elements' resultant at the end and at the start of a step
W_X, W_Y, W_Z = 13, 14, 15  # intermediate vectors of a step
W_Q = 16  # sqrt of M^-1 (the monitor's normalization)
N_W = 17

# energy columns the loop writes per row
E_IN, E_KIN, E_HYST, E_VISC = range(4)
N_E = 4

# CSV text (csvfmt): significant digits, and how close to a tie (in units of the last kept
# digit) a rounding is settled by exact formatting instead
DIGITS = 10
TIE_MARGIN = 1e-4
