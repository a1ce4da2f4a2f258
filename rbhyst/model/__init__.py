"""Layer 2, model: what a scene is. The deck schema and its loading, records and excitation
signals, body geometry and mass properties, the hysteresis law (VRM, seed eqs. 14-17),
elements and dampers, the points of interest, and the assembled :class:`~rbhyst.model.system.System`.
Imports only ``errors`` and ``files``."""
