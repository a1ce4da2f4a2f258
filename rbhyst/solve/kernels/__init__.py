"""Compiled time stepping: plain arrays and floats in, preallocated buffers out.

- :mod:`.layout`: the constants the loop and the Python side share;
- :mod:`.elements`: the element rows at a new configuration (VRM, seed eqs. 5-17), the
  stiffness bounds the monitor needs;
- :mod:`.loop`: the loop shared by every fixed-step method (substeps, monitor, energy,
  chunked output), and :mod:`.through`, a whole run stepped again in one call of it (the
  estimate's companion and its probe); a method's own step lives beside its coefficients in
  :mod:`rbhyst.solve.integrators`;
- :mod:`.dop853`: the adaptive integration; :mod:`.csvfmt`: CSV text; :mod:`.reduce`: peaks;
- :mod:`.modified`, :mod:`.redrive`: the error estimate's companion (its load from the
  method's modified equation; its forces with every reversal located, where the loop split
  a step: elsewhere the loop's rows report them, :mod:`.elements` ``LOCATED``);
- :mod:`.compiled`: the kernels built ahead of time at install, or numba's JIT.

Everything here is called through :mod:`rbhyst.solve.plan` and :mod:`rbhyst.solve.companion`.
Importing this package loads no compiled code.
"""
