"""Top layer: ``rbhyst.response.ground``, the documented path of :mod:`rbhyst.solve.ground`."""

from rbhyst.solve.ground import *  # noqa: F401,F403
