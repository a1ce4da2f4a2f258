"""rbhyst's version (base layer: imports nothing)."""

__version__ = "0.2.0"
