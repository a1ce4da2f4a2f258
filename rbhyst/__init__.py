"""rbhyst: nonlinear dynamics of 2D rigid bodies on Vaiana-Rosati hysteretic supports."""

__version__ = "0.1.0"
