"""The event-located adaptive integration as a user's integrator, to ``analysis.rtol``.

The same solver as ``reference`` (rbhyst.solve.integrators.reference: DOP853 between reversals,
every reversal located as an event and stepped to exactly, the load fitted exactly between
its breakpoints), at a tolerance the user chooses (default 1e-8) instead of 1e-12. Its only
error is the Runge-Kutta pair's: order 8 between events, so its error falls about a
hundredfold per hundredfold of rtol (1.4e-4 at 1e-6, 3e-6 at 1e-8, 4e-8 at 1e-10 on the
seed deck). Explicit and adaptive: no stability limit to watch, no numerical dissipation
beyond the tolerance; its cost grows with the number of reversals (each is an event), where
the fixed-step methods win (many elements, near-sharp yield: see docs/how-to/accuracy.md, "Which method").
"""

from rbhyst.solve.integrators import Method
from rbhyst.solve.integrators.reference import solve_with_stats


def solve(system, settings, keep: bool = True, csv=None):
    return solve_with_stats(system, settings, rtol=settings.rtol, keep=keep, csv=csv)[0]


METHOD = Method(
    name="adaptive",
    summary="adaptive DOP853 between reversals located as events, to analysis.rtol (default 1e-8)",
    order=8,
    explicit=True,
    solve=solve,
)
