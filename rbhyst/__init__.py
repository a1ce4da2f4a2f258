"""rbhyst: nonlinear dynamics of rigid bodies, in the plane or in space, on Vaiana-Rosati hysteretic supports.

The Python API (docs/reference/api.md): ``load_deck``, ``run``, and the ``Result`` they give;
``modes``, the body's natural frequencies and mode shapes.
"""

from rbhyst._version import __version__

__all__ = ["load_deck", "run", "modes", "InputError", "AnalysisError", "AccuracyWarning", "ModelWarning",
           "__version__"]


def __getattr__(name):
    # the API is imported on first use: `import rbhyst` stays cheap for the command line
    if name in ("load_deck", "run", "modes"):
        from rbhyst import api

        return getattr(api, name)
    if name in ("InputError", "AnalysisError", "AccuracyWarning", "ModelWarning"):
        from rbhyst import errors

        return getattr(errors, name)
    raise AttributeError(f"module 'rbhyst' has no attribute {name!r}")
