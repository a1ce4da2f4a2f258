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

# element state columns: displacement, force, branch sign, gap, tangent, antiderivative
U, F, S, G, K, A = range(6)
N_STATE = 6

# info: how a chunk ended
I_STATUS, I_ELEMENT, I_TIME, I_STIFFNESS, I_OMEGA, I_DISP, I_BRANCH = range(7)
INFO_SIZE = 7

# the loop's running state, carried from chunk to chunk (state vector)
X_D, X_V, X_A = 0, 3, 6  # displacement, velocity, acceleration (3 each)
X_E_IN, X_E_HYST, X_E_VISC = 9, 10, 11  # cumulative input, hysteretic and viscous work
X_STEPS, X_ITER, X_SUBSTEPS, X_LEVEL_USED, X_OMEGA_DT2, X_LEVEL = 12, 13, 14, 15, 16, 17
X_CUR = 18  # which of the two element-state buffers holds the current state
N_X = 19

# energy columns the loop writes per row
E_IN, E_KIN, E_HYST, E_VISC = range(4)
N_E = 4

# CSV text (csvfmt): significant digits, and how close to a tie (in units of the last kept
# digit) a rounding is settled by exact formatting instead
DIGITS = 10
TIE_MARGIN = 1e-4
