"""Compiled time stepping: plain arrays and floats in, preallocated buffers out.

- :mod:`.elements`: the element rows at a new configuration (VRM, seed eqs. 5-17), the
  stiffness bounds the monitor needs;
- :mod:`.loop`: the loop shared by every fixed-step method (substeps, monitor, energy,
  chunked output); a method's own step lives beside its coefficients in
  :mod:`rbhyst.integrators`.

Everything here is called through :func:`rbhyst.simulate.simulate`. This module holds only
the layout constants shared by the loop and the Python side, so that importing it loads
no compiled code.
"""

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


def cached(dispatchers) -> bool:
    """Whether numba's cache holds compiled code for these dispatchers' current sources.

    A cold cache (a fresh install, an edited kernel) means seconds of compiling before the
    first run: the command line says so once. Any doubt (numba's cache layout is its own)
    counts as cached, so that nothing false is said.
    """
    try:
        return all(bool(d._cache._cache_file._load_index()) for d in dispatchers)
    except Exception:  # pragma: no cover - a numba without this layout
        return True


def run_kernels():
    """The dispatchers a fixed-step run loads (none when they were built ahead of time)."""
    from .compiled import ahead_of_time

    if ahead_of_time():
        return ()
    from .csvfmt import _decompose, _render
    from .dop853 import _integrate
    from .loop import run_chunk
    from .reduce import reduce_rows

    return run_chunk, _decompose, _render, reduce_rows, _integrate
