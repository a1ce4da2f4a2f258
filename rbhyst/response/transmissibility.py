"""Top layer: ``rbhyst.response.transmissibility``, the documented path of :mod:`rbhyst.analyses.transmissibility`."""

from rbhyst.analyses.transmissibility import *  # noqa: F401,F403
