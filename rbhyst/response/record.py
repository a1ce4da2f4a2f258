"""Top layer: ``rbhyst.response.record``, the documented path of :mod:`rbhyst.analyses.record_spectrum`."""

from rbhyst.analyses.record_spectrum import *  # noqa: F401,F403
