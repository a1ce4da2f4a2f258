"""Shock qualification (``rbhyst shock``): the drive (rbhyst.analyses.shock.drive), the runs along
each direction of each axis and their verdict (rbhyst.analyses.shock.verdict)."""
